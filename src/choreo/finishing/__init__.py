"""Passes every generated dance goes through after its backend: speed limit (no joint faster
than real dancers move), root path (travel without wobble), pace (a whole song's travel at its
genre's pace), accent (motion beats as pronounced as real dancers'), footsteps (feet that stand
and step instead of gliding), beat lock (re-timing onto the music's beats), rest (still through
the silence before and after the music) and, when asked, foot lock (planted feet carry the
body). Each pass has a module, a function and a config of one name; ``Finishing``
(choreo.finishing.settings) turns them on and off."""

from __future__ import annotations

import importlib
import sys
import types
from typing import TYPE_CHECKING

from .settings import Finishing

if TYPE_CHECKING:
    import numpy as np

    from ..constraints import Constraints
    from ..motion import Motion

PASSES = ("speed_limit", "root_path", "pace", "accent", "footsteps", "beat_lock", "rest", "foot_lock")
_DEFINED_IN = {**{name: name for name in PASSES},
               **{"".join(part.title() for part in name.split("_")) + "Config": name for name in PASSES},
               "BeatLockResult": "beat_lock", "lock_warp": "beat_lock"}
_loaded = False


def __getattr__(name: str):
    """The passes load when first used: the command line builds its flags from ``Finishing``
    alone, and `choreo --help` need not import numpy."""
    if name not in _DEFINED_IN:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    _load()
    return globals()[name]


def _load() -> None:
    """Every pass's names into this package, once. Each is bound after its module is imported,
    which binds the module under the same name first (the pass ``pace`` lives in ``pace.py``)."""
    global _loaded
    if _loaded:
        return
    for name, module in _DEFINED_IN.items():
        globals()[name] = getattr(importlib.import_module(f".{module}", __name__), name)
    _loaded = True


class _Package(types.ModuleType):
    """This package: the import system binds a pass's module under its name (``pace.py`` as
    ``pace``) when anything imports it; the name stays the pass's function."""

    def __setattr__(self, name: str, value) -> None:
        if name in PASSES and isinstance(value, types.ModuleType):
            return
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package


def finish(motion: "Motion", music_beat_frames: "np.ndarray", finishing: "Finishing | None" = None,
           constraints: "Constraints | np.ndarray | None" = None, anchors: "np.ndarray | None" = None,
           audible: tuple[int, int] | None = None) -> "Motion":
    """``motion`` through the passes ``finishing`` turns on (default: as `choreo generate` does);
    frames the ``constraints`` give (or a (T,) mask of fixed frames) stay. ``anchors``, a (T,) mask,
    are frames the re-timing leaves at their times (a loop's seam) while every pass still works on
    them. ``audible``, frames [first, stop) with music (Music.audible), lets the dancer wait before
    them and rest after them; None: music throughout. Each pass runs with the settings
    ``finishing.configs`` gives it, or its own defaults.

    The order: the speed limit first, so that a glitch is not taken for a motion beat, and last,
    since re-timing stretches speeds. The root path and the pace before the footsteps, which plant
    the feet along the travel as it will be. The accent before the footsteps and the beat lock, which
    plan the feet and lock the beats of the dance as it will be timed. Footsteps before the beat lock: they move the motion
    beats (a leg's swing is part of the body's speed), and a re-timing keeps a standing foot
    standing (docs/results.md, "Feet"). Rest after the beat lock: it re-times only the quiet ends,
    so the beats locked in between stay."""
    import numpy as np

    _load()
    on = finishing or Finishing()
    settings = on.configs
    fixed = constraints.fixed_frames() if hasattr(constraints, "fixed_frames") else constraints
    timed = fixed if anchors is None else np.asarray(anchors, bool) | (False if fixed is None else np.asarray(fixed, bool))
    passes = ((on.speed_limit, speed_limit, fixed), (on.root_path, root_path, fixed), (on.pace, pace, fixed),
              (on.accent, accent, timed), (on.footsteps, footsteps, constraints), (on.beat_lock, beat_lock, timed),
              (on.rest and audible is not None, rest, timed), (on.foot_lock, foot_lock, fixed))
    for enabled, run, kept in passes:
        if enabled:
            motion = _run(run, motion, music_beat_frames, kept, settings.get(run.__name__), audible)
    if on.speed_limit and (on.beat_lock or on.foot_lock or on.footsteps):
        motion = _run(speed_limit, motion, music_beat_frames, fixed, settings.get("speed_limit"))
    return motion


def _run(run, motion: "Motion", music_beat_frames: "np.ndarray", fixed, config, audible=None) -> "Motion":
    """One pass with its config (or its default); the beat lock also takes the music's beats,
    rest the music's audible span."""
    extra = {} if config is None else {"config": config}
    if run is beat_lock:
        return run(motion, music_beat_frames, fixed, **extra).motion
    if run is rest:
        return run(motion, audible, fixed, **extra)
    return run(motion, fixed, **extra)


__all__ = ["AccentConfig", "BeatLockConfig", "BeatLockResult", "Finishing", "FootLockConfig", "FootstepsConfig", "PaceConfig", "RestConfig",
           "RootPathConfig", "SpeedLimitConfig", "accent", "beat_lock", "finish", "foot_lock", "footsteps", "lock_warp",
           "pace", "rest", "root_path", "speed_limit"]
