"""Songs from outside M2D whose tempo is known: the demo songs Debian's LMMS package ships.

`apt-get install lmms` brings about twenty finished songs by their authors (house, reggae,
chiptune, rock...) as LMMS projects; each project states its tempo, and none of them automates
it. They are rendered to WAV with LMMS itself, into a cache folder outside the repository (they
are not ours to commit), once.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import zlib
from dataclasses import dataclass
from pathlib import Path

LMMS_PROJECTS = Path("/usr/share/lmms/projects")
CACHE = Path(os.environ.get("CHOREO_CACHE_DIR", Path.home() / ".cache" / "choreo")) / "lmms-songs"


@dataclass(frozen=True)
class OutsideSong:
    name: str
    path: Path
    bpm: float  # as the project file states it


def project_xml(project: Path) -> str:
    """An LMMS project's XML: .mmp is plain, .mmpz is zlib with a 4-byte length in front."""
    data = project.read_bytes()
    return (zlib.decompress(data[4:]) if project.suffix == ".mmpz" else data).decode("utf-8", "replace")


def project_bpm(project: Path) -> float | None:
    """The tempo the project plays at, or None when it is automated (then it has no one tempo)."""
    xml = project_xml(project)
    head = re.search(r"<head\b[^>]*>", xml)
    if head is None or re.search(r"<bpm\b", xml):
        return None
    bpm = re.search(r'\bbpm="([0-9.]+)"', head.group(0))
    return float(bpm.group(1)) if bpm else None


def render(project: Path, out: Path) -> Path:
    """Render one project to WAV with LMMS (headless; as root it needs --allowroot)."""
    if not out.is_file():
        out.parent.mkdir(parents=True, exist_ok=True)
        partial = out.with_suffix(".partial.wav")
        command = ["lmms", "--render", str(project), "--format", "wav", "--output", str(partial)]
        if os.geteuid() == 0:
            command.insert(1, "--allowroot")
        for attempt in range(3):  # LMMS 1.2 now and then crashes while it starts headless
            if subprocess.run(command, capture_output=True, timeout=600).returncode == 0:
                break
        else:
            raise RuntimeError(f"LMMS failed three times to render {project}")
        partial.replace(out)
    return out


def outside_songs(cache: Path = CACHE) -> list[OutsideSong]:
    """Every demo and short song LMMS ships with a fixed tempo, rendered; [] without LMMS."""
    if shutil.which("lmms") is None or not LMMS_PROJECTS.is_dir():
        return []
    songs = []
    for folder in ("demos", "shorties"):
        for project in sorted((LMMS_PROJECTS / folder).rglob("*.mmp*")):
            bpm = project_bpm(project)
            if bpm is not None:
                songs.append(OutsideSong(project.stem, render(project, cache / f"{project.stem}.wav"), bpm))
    return songs
