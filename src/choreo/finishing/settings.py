"""Which finishing passes run, and with what settings: :class:`Finishing`, the one switchboard
``choreo.finishing.finish`` reads and every dancing command builds its flags from."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Mapping

from ..options import option


@dataclass(frozen=True, kw_only=True)
class Finishing:
    """The passes every dance goes through after its backend (choreo.finishing.finish runs them;
    why each is on or off by default: docs/results.md, "Finishing passes")."""

    speed_limit: bool = option(True, "Spread turns and dashes faster than real dancers move over the frames around them.")
    root_path: bool = option(True, "Smooth the root's travel on the floor, removing its wobble (given frames stay).")
    pace: bool = option(True, "Bring a whole song's travel toward the real pace of its genre (short dances keep theirs).")
    accent: bool = option(True, "Ease into and out of each motion beat, marking it as clearly as real dancers do.")
    footsteps: bool = option(True, "Plan steps: each foot stands until the body leaves it, then steps (legs by IK).")
    beat_lock: bool = option(True, "Re-time the dance so its motion beats land on the music's beats (given frames stay).")
    rest: bool = option(True, "Wait through a song's opening silence and come to rest in its closing silence.")
    foot_lock: bool = option(False, "Let planted feet carry the body instead of sliding (docs/results.md, \"Feet\").")
    # A pass's settings by its name, e.g. {"footsteps": FootstepsConfig(strength=0.8)}; absent: its defaults.
    configs: Mapping[str, Any] = field(default_factory=dict)
