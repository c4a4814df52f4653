"""FBX for game engines (Unity, Unreal), written by Blender: choreo does not pack FBX itself.

FBX is a closed format with no well-kept pure-Python writer, so the dance goes to Blender as BVH
(SMPL-24, or retargeted onto a rig such as Mixamo's, see :mod:`choreo.formats.rigs`) and Blender's
own FBX exporter writes the file (script: ``blender_scripts/bvh_to_fbx.py``): armature only, the
animation baked at every frame, -Z forward and Y up (Blender's defaults for Unity and Unreal, so the
dancer stands Y up facing +Z in the engine, as in choreo), real size with ``apply_unit_scale`` (the
file is in centimetres, as Mixamo's own files are).

Blender is found at run time, in this order: ``blender`` on PATH (run headless), then a Python
module ``bpy`` importable by this interpreter (PyPI ``bpy``, run in a child process so Blender's
global state never touches ours). Without either, :class:`~choreo.errors.OutputError` says how to get one.
"""

from __future__ import annotations

import importlib.util
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from ..children import child_process
from ..errors import MotionFormatError, OutputError
from ..motion import Motion
from ..skeleton import SMPL24
from .bvh import write_bvh
from .rigs import Rig, get_rig, write_bvh_rig

SCRIPT = Path(__file__).parent / "blender_scripts" / "bvh_to_fbx.py"
NO_BLENDER = ("FBX export needs Blender: install it (apt install blender, or blender.org, with `blender` on PATH) "
              "or its Python module (pip install bpy)")
BASE_TIMEOUT_S, TIMEOUT_S_PER_FRAME = 300.0, 0.1  # Blender's start plus a generous per-frame bake


def blender_command(script: str | os.PathLike = SCRIPT) -> list[str] | None:
    """The command that runs ``script`` in Blender headless, its arguments to follow; None without Blender."""
    binary = shutil.which("blender")
    if binary:
        return [binary, "--background", "--factory-startup", "--python-exit-code", "1", "--python", str(script), "--"]
    if importlib.util.find_spec("bpy") is not None:  # found, not imported: importing bpy is slow and global
        return [sys.executable, str(script), "--"]
    return None


def _numpy_dir() -> str:
    """Folder holding our numpy, offered to a Blender whose Python lacks it (Debian's; same Python minor)."""
    return str(Path(np.__file__).parent.parent)


def write_fbx(motion: Motion, path: str | os.PathLike, rig: Rig | str | None = None, root_motion: bool = False) -> str:
    """Write ``motion`` (SMPL-24) as FBX at ``path``, on SMPL-24 or retargeted onto ``rig`` ("mixamo"),
    under a floor-level root bone with ``root_motion``."""
    if not motion.skeleton.same_topology(SMPL24):
        raise MotionFormatError("FBX export supports the SMPL-24 skeleton only")
    if motion.num_frames == 0:
        raise MotionFormatError("FBX export needs at least one frame")
    rig = get_rig(rig)
    command = blender_command()
    if command is None:
        raise OutputError(NO_BLENDER)
    path = Path(path)
    with tempfile.TemporaryDirectory(prefix="choreo-fbx-") as folder:
        bvh_path, fbx_path = Path(folder) / "dance.bvh", Path(folder) / "dance.fbx"
        with open(bvh_path, "wb") as handle:
            if rig is None:
                write_bvh(motion, handle, root_motion=root_motion, root_tip=True)
            else:
                write_bvh_rig(motion, handle, rig, root_motion=root_motion, root_tip=True)
        _run_blender(command + [str(bvh_path), str(fbx_path), str(motion.num_frames), _numpy_dir()],
                     BASE_TIMEOUT_S + TIMEOUT_S_PER_FRAME * motion.num_frames)
        if not fbx_path.is_file() or fbx_path.stat().st_size == 0:
            raise OutputError("Blender ran but wrote no FBX file")
        try:
            shutil.move(str(fbx_path), str(path))
        except OSError as error:
            raise OutputError(f"{path}: cannot write ({error.strerror or error})") from None
    return str(path)


def write_fbx_stream(motion: Motion, handle, rig: Rig | str | None = None, root_motion: bool = False) -> None:
    """Write FBX bytes to a binary handle (the registry's writer signature): Blender writes a file, we copy it."""
    with tempfile.TemporaryDirectory(prefix="choreo-fbx-") as folder:
        path = Path(folder) / "dance.fbx"
        write_fbx(motion, path, rig, root_motion)
        with open(path, "rb") as source:
            shutil.copyfileobj(source, handle)


def _run_blender(command: list[str], timeout: float) -> None:
    """Run Blender, turning a failure or a hang into one OutputError line with Blender's last words."""
    try:  # child_process waits for Blender to be gone, also on Ctrl-C (subprocess.run waits 0.25 s then)
        with child_process(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                           stdin=subprocess.DEVNULL, errors="replace") as blender:
            stdout, stderr = blender.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        raise OutputError(f"Blender took longer than {timeout:.0f} s to write the FBX") from None
    except OSError as error:
        raise OutputError(f"cannot run Blender ({error.strerror or error})") from None
    if blender.returncode != 0:
        lines = [line.strip() for line in (stderr + "\n" + stdout).splitlines() if line.strip()]
        errors = [line for line in lines if "Error" in line] or lines
        raise OutputError(f"Blender could not write the FBX: {errors[-1] if errors else f'exit {blender.returncode}'}")
