"""How a finished dance is written, as the flags of every command that writes one declare it:
:class:`Delivery` (the frame rate, the travel, the rig), checked when made. The work is
choreo.motion.delivery's; this module stays free of numpy, so that building the command line
does not load it."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from ..errors import ParameterError
from ..options import option

if TYPE_CHECKING:
    from .motion import Motion

MIN_DELIVERY_FPS, MAX_DELIVERY_FPS = 10.0, 240.0  # the rates --fps takes (film 24 to mocap 120, and a margin)


@dataclass(frozen=True, kw_only=True)
class Delivery:
    """How a finished dance is written (the flags of every command that writes one, declared here
    once), checked when made."""

    fps: float | None = option(None, "Write at this frame rate, e.g. 24, 60 or 120 (10 to 240; default: the dance's "
                                     "own): resampled after the finishing passes, so beats and steps keep their times.",
                               "--fps")
    in_place: bool = option(False, "Take the travel out: the dancer stays where it started, its sway, height and facing "
                                   "kept (for a game engine that moves the character itself).", "--in-place")
    root_motion: bool = option(False, "Write .bvh/.glb/.fbx under a root bone at floor level that carries the travel "
                                      "and the facing, the hips moving relative to it (game engines' root motion).",
                               "--root-motion")
    rig: str | None = option(None, "Write .bvh/.fbx on another rig's bones and T-pose: mixamo (default: SMPL-24).",
                             "--rig")

    def __post_init__(self):
        if self.fps is not None:
            check_fps(self.fps)  # before resampling allocates the frames
        check_travel(self.in_place, self.root_motion)

    def of(self, motion: "Motion") -> "Motion":
        """``motion`` as the file gets it (choreo.motion.delivery.delivered)."""
        from .delivery import delivered

        return delivered(motion, self.fps, self.in_place)


def check_fps(fps: float) -> None:
    """Refuse, in one line, a frame rate a file is not written at."""
    if not MIN_DELIVERY_FPS <= fps <= MAX_DELIVERY_FPS:
        raise ParameterError(f"--fps must be {MIN_DELIVERY_FPS:g} to {MAX_DELIVERY_FPS:g}, got {fps:g}")


def check_travel(in_place: bool, root_motion: bool) -> None:
    """Refuse, in one line, both ways of handing the travel to an engine at once."""
    if in_place and root_motion:
        raise ParameterError("--in-place and --root-motion exclude each other: one takes the travel out, "
                             "the other moves it onto a root bone")
