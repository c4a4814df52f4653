"""The step planner with the dance's glide and its quick foot moves weighed apart (not kept).

    python scripts/experiments/footsteps_detail.py --strength 1 --detail 0.5 [--detail-hz 2] \
        [--genres cha-cha rumba] -- --split validation --checkpoint runs/holdout/last.pt --json feet.json

Issue 45 (docs/results.md, "What the feet and the beats still miss"). Today each ankle goes
``strength`` of the way from where the dance puts it to the plan, so ``1 - strength`` of both its
glide (the slow part, which follows the body) and its quick moves stays. Here the ankle gets the
plan, plus ``1 - strength`` of the dance's ankle motion slower than ``detail_hz`` and ``detail`` of
the quicker rest; ``detail = 1 - strength`` is today's planner. With ``--genres``, only dances of
those genres are planned this way, the others as `choreo generate` plans them. Everything after ``--`` goes to
scripts/evaluate_whole_songs.py, which dances and scores the songs.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from pathlib import Path

from choreo.motion.filters import low_pass

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "scripts"))
import evaluate_whole_songs  # noqa: E402

footsteps = importlib.import_module("choreo.finishing.footsteps")  # the module: the package exports the function


def split_planner(strength: float, detail: float, detail_hz: float, genres: list[str] | None):
    """A plan_steps whose result, pulled ``strength`` of the way by the pass, lands where this
    experiment aims the ankles (for a dance of ``genres``, or any dance when None). The pass asks
    for the dance's strength just before it plans, which is where the genre is seen."""
    plan_steps, genre_strength = footsteps.plan_steps, footsteps.stepping_strength
    split = {"now": True}

    def strength_of(motion, config):
        split["now"] = genres is None or motion.metadata.get("genre") in genres
        return strength if split["now"] else genre_strength(motion, config)

    def aimed(wanted, fps, config=footsteps.FootstepsConfig()):
        plan = plan_steps(wanted, fps, config)
        if not split["now"]:
            return plan
        slow = low_pass(wanted, fps, detail_hz)
        target = plan + (slow - plan) * (1.0 - strength) + (wanted - slow) * detail
        return wanted + (target - wanted) / strength

    footsteps.stepping_strength = strength_of
    return aimed


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--strength", type=float, required=True)
    parser.add_argument("--detail", type=float, required=True)
    parser.add_argument("--detail-hz", type=float, default=2.0)
    parser.add_argument("--genres", nargs="+", help="plan only these genres' dances so (default: every dance)")
    args, rest = parser.parse_known_args()
    footsteps.plan_steps = split_planner(args.strength, args.detail, args.detail_hz, args.genres)
    sys.argv = [sys.argv[0], *[a for a in rest if a != "--"]]
    evaluate_whole_songs.main()


if __name__ == "__main__":
    main()
