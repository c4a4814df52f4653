"""AIST++ (Li et al. 2021) in its published layout.

```
root/motions/gBR_sBM_cAll_d04_mBR0_ch01.pkl   SMPL parameters at 60 fps (see choreo.formats.aistpp)
root/wavs/mBR0.wav                           the music, named by the sequence's music id
root/splits/crossmodal_{train,val,test}.txt  sequence names, one per line
root/ignore_list.txt                         sequences with broken fits, skipped
```
The genre is the sequence name's ``g..`` field; the music id its ``m...`` field.
"""

from __future__ import annotations

import re
from pathlib import Path

from ..errors import DatasetError
from ..formats.aistpp import read_aistpp_pkl
from .base import TEST, TRAIN, Clip, ProgressCallback, select_split
from .cache import cached_music
from .clips import align_music_and_motion

GENRES = {
    "BR": "break", "PO": "pop", "LO": "lock", "MH": "middle hip-hop", "LH": "LA-style hip-hop",
    "HO": "house", "WA": "waack", "KR": "krump", "JS": "street jazz", "JB": "ballet jazz",
}  # fmt: skip
SEQUENCE_NAME = re.compile(r"^g(?P<genre>[A-Z]{2})_s\w+?_c\w+?_d\d+_m(?P<music>[A-Z]{2}\d)_ch\d+$")
SPLIT_FILES = {TRAIN: "crossmodal_train.txt", "val": "crossmodal_val.txt", TEST: "crossmodal_test.txt"}


def parse_sequence_name(name: str) -> tuple[str, str]:
    """(genre, music id) of a sequence name such as gBR_sBM_cAll_d04_mBR0_ch01."""
    match = SEQUENCE_NAME.match(name)
    if not match or match.group("genre") not in GENRES:
        raise DatasetError(f"{name!r} is not an AIST++ sequence name (like gBR_sBM_cAll_d04_mBR0_ch01)")
    return GENRES[match.group("genre")], "m" + match.group("music")


def _read_list(path: Path) -> list[str]:
    return [line.strip() for line in path.read_text().splitlines() if line.strip()] if path.is_file() else []


def read_splits(root: Path) -> dict[str, str]:
    """Sequence name -> split: train, test or val.

    Training uses the train list only: EDGE ships just crossmodal_train and crossmodal_test, so its
    models never see the validation sequences, and ours match it.
    """
    splits = {}
    for split, filename in SPLIT_FILES.items():
        for name in _read_list(root / "splits" / filename):
            splits[name] = split
    return splits


def load_aistpp(root: str | Path, split: str | None = None, fps: float = 30.0,
                progress: ProgressCallback | None = None) -> list[Clip]:
    """Every usable sequence as a Clip at ``fps`` with aligned music features."""
    root = Path(root)
    motions = sorted((root / "motions").glob("*.pkl"))
    if not motions:
        raise DatasetError(f"{root}: no motions/*.pkl files (not an AIST++ folder?)")
    ignored = set(_read_list(root / "ignore_list.txt"))
    splits = read_splits(root)
    wanted = [m for m in motions if m.stem not in ignored and (split in (None, "all") or splits.get(m.stem) == split)]
    clips = []
    for done, path in enumerate(wanted):
        if progress:
            progress(done, len(wanted), path.stem)
        genre, music_id = parse_sequence_name(path.stem)
        audio = root / "wavs" / f"{music_id}.wav"
        if not audio.is_file():
            raise DatasetError(f"{path.stem}: music file {audio} is missing")
        motion = read_aistpp_pkl(path).resample(fps)
        motion, features = align_music_and_motion(motion, cached_music(audio).features, path.stem)
        clips.append(Clip(path.stem, motion, features, genre=genre, split=splits.get(path.stem),
                          audio_path=str(audio), info={"source_fps": 60.0, "music_id": music_id}))
    if progress:
        progress(len(wanted), len(wanted), "")
    return select_split(clips, split)
