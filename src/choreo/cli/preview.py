"""A dance's preview (video, GIF or picture strip) rendered under a progress bar: what `choreo render`
and the dancing commands' --preview write."""

from __future__ import annotations

from pathlib import Path

from .progress import progress_bar


def render_preview(motion, output: Path, config, music: Path | None, into: Path | None = None) -> None:
    """``into``: the temporary an all-or-none write gave for ``output`` (choreo.render.render_motion)."""
    from ..render import render_motion

    with progress_bar(f"rendering {output.name}") as update:
        render_motion(motion, output, config, music, progress=lambda done, total: update(done, total), into=into)
