"""Mutation testing of the numerical core: plant one small bug at a time, see whether a test fails.

    python scripts/mutation_score.py                 # every area below (about 2 hours on one core)
    python scripts/mutation_score.py metrics motion  # some areas
    python scripts/mutation_score.py --list          # the areas, their files and their tests

Each area is mutated by mutmut 3 in its own throw-away clone under /tmp (mutmut rewrites the
sources it mutates), against the test files that guard it, one child at a time. Prints, per
area, killed / survived / timeout / untested counts and the names of the surviving mutants, and
writes the lot to ``--out`` (JSON). ``mutmut show NAME`` inside the printed clone shows one
mutant's diff. docs/dev/mutation.md keeps the last scores and why each survivor is harmless.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
MUTMUT = REPO / ".venv" / "bin" / "mutmut"
STATUSES = ("killed", "survived", "timeout", "no tests", "suspicious", "skipped", "segfault")


@dataclass(frozen=True)
class Area:
    files: tuple[str, ...]  # globs of the files mutated, as they lie under src/ in the clone
    tests: tuple[str, ...]  # the test files that guard them
    skip: str = ""  # a pytest -k expression leaving out tests too slow to run once per mutant
    # modules whose functools caches are emptied before every test: mutmut forks each mutant's run from
    # a process whose caches its own test runs filled, so a cached result would hide the mutated code
    clear_caches: tuple[str, ...] = ()

# mutmut 3 imports mutated code from mutants/src only: the backend packages are moved there (in the
# clone), where they shadow the installed ones (which point at the live checkout).
PLUGINS = ("choreo_sgmd", "choreo_graph")


AREAS: dict[str, Area] = {
    "metrics": Area(("src/choreo/metrics/*",),
                    ("tests/metrics/test_beats.py", "tests/metrics/test_evaluate.py", "tests/metrics/test_fid.py",
                     "tests/metrics/test_genre.py", "tests/metrics/test_geometric.py", "tests/metrics/test_kinetic.py",
                     "tests/metrics/test_pfc.py", "tests/metrics/test_reference_loops.py", "tests/motion/test_beats.py"),
                    skip="not with_a_warning"),  # they check the warning names the caller's line: mutmut's trampoline is one frame more
    "constraints": Area(("src/choreo/constraints/*",),
                        ("tests/constraints/test_displacement.py", "tests/constraints/test_mask.py",
                         "tests/constraints/test_parse.py", "tests/constraints/test_constraints.py"),
                        skip="not masked_sampling and not root_path_is_followed and not controllable_commands"
                             " and not give_one_line and not generate_preview and not fuzz"),  # sampling, CLI, hypothesis
    "motion": Area(("src/choreo/motion/*",),
                   ("tests/motion/test_motion.py", "tests/motion/test_augment.py", "tests/motion/test_beats.py",
                    "tests/motion/test_contacts.py", "tests/motion/test_stitch.py", "tests/motion/test_vector.py",
                    "tests/skeleton/test_rotations.py", "tests/skeleton/test_smpl.py", "tests/skeleton/test_kinematics.py",
                    "tests/metrics/test_beats.py", "tests/metrics/test_fid.py", "tests/metrics/test_pfc.py",
                    "tests/sgmd/test_controls.py", "tests/graph/test_generator.py"),
                   skip="not training and not cli and not checkpoints"),
    "formats": Area(("src/choreo/formats/*",),
                    ("tests/formats/test_aistpp.py", "tests/formats/test_bvh.py", "tests/formats/test_fbx.py",
                     "tests/formats/test_gltf.py", "tests/formats/test_json_format.py", "tests/formats/test_npy.py",
                     "tests/formats/test_npz.py", "tests/formats/test_registry.py", "tests/formats/test_rigs.py",
                     "tests/formats/test_safe_arrays.py", "tests/formats/test_safe_pickle.py",
                     "tests/formats/test_smpl_params.py", "tests/sgmd/test_checkpoint.py"),
                    skip="not fuzz"),  # hypothesis: hundreds of examples per mutant (and the fuzz_finding-marked tests)
    "spectrum": Area(("src/choreo/music/spectrum.py",), ("tests/music/test_spectrum.py",)),
    "finishing": Area(("src/choreo/finishing/*",),
                      ("tests/finishing/test_beat_lock.py", "tests/finishing/test_foot_lock.py",
                       "tests/finishing/test_speed_limit.py", "tests/finishing/test_footsteps.py",
                       "tests/finishing/test_root_path.py", "tests/finishing/test_pace.py",
                       "tests/finishing/test_finish.py")),
    "sgmd-sampling": Area(("src/choreo_sgmd/sampling.py", "src/choreo_sgmd/guidance.py", "src/choreo_sgmd/schedule.py"),
                          ("tests/sgmd/test_sampling.py", "tests/sgmd/test_controls.py", "tests/sgmd/test_generator.py"),
                          skip="not training and not free_text and not batch and not generate_ and not inference"
                               " and not never_trained_on"),  # reads the bundled weights, which the clone moves
    "graph": Area(("src/choreo_graph/graph.py", "src/choreo_graph/warp.py", "src/choreo_graph/tempo.py"),
                  ("tests/graph/test_config.py", "tests/graph/test_graph.py", "tests/graph/test_tempo.py",
                   "tests/graph/test_warp.py")),  # tests/graph/test_generator.py builds a repertoire: too slow per mutant
    "speed-limit": Area(("src/choreo/finishing/speed_limit.py",), ("tests/finishing/test_speed_limit.py",)),  # also in finishing; alone: minutes
    "graph-guide": Area(("src/choreo_graph/guide.py", "src/choreo/constraints/displacement.py"),
                        ("tests/graph/test_constraints.py", "tests/graph/test_guide.py", "tests/constraints/test_displacement.py",
                         "tests/constraints/test_mask.py", "tests/constraints/test_parse.py")),
    "beats": Area(("src/choreo/music/beats.py", "src/choreo/music/rhythm.py"),
                  ("tests/music/test_beats.py", "tests/music/test_rhythm.py", "tests/music/test_music.py",
                   "tests/music/test_spectrum.py", "tests/motion/test_augment.py")),
    "music-features": Area(("src/choreo/music/chroma.py", "src/choreo/music/features.py", "src/choreo/music/music.py"),
                           ("tests/music/test_chroma.py", "tests/music/test_music.py", "tests/music/test_spectrum.py"),
                           clear_caches=("choreo.music.chroma",)),  # the constant-Q filter bank is cached
    "skeleton": Area(("src/choreo/skeleton/*",),
                     ("tests/skeleton/test_rotations.py", "tests/skeleton/test_smpl.py", "tests/skeleton/test_kinematics.py",
                      "tests/datasets/test_ik.py", "tests/motion/test_motion.py", "tests/motion/test_augment.py",
                      "tests/motion/test_beats.py", "tests/motion/test_contacts.py", "tests/motion/test_stitch.py",
                      "tests/motion/test_vector.py"),
                     skip="not training and not cli and not checkpoints"),
}


def configure(clone: Path, area: Area) -> None:
    """Append the area's mutmut settings to the clone's pyproject.toml."""
    quoted = lambda items: "[" + ", ".join(json.dumps(i) for i in items) + "]"  # noqa: E731
    for plugin in PLUGINS:  # every package from the clone's commit, none from the live checkout
        subprocess.run(["git", "mv", f"generators/{plugin}", f"src/{plugin}"], cwd=clone, check=True)
    with open(clone / "pyproject.toml", "a") as f:
        f.write("\n[tool.mutmut]\n")
        f.write('source_paths = ["src"]\n')
        f.write('also_copy = ["examples"]\n')  # tests read the example song from there
        f.write(f"only_mutate = {quoted(area.files)}\n")
        f.write(f"pytest_add_cli_args_test_selection = {quoted(area.tests)}\n")
        selection = ["-x", "-q", "-p", "no:cacheprovider", "-m", "not slow"] + (["-k", area.skip] if area.skip else [])
        f.write(f"pytest_add_cli_args = {quoted(selection)}\n")
    if area.clear_caches:
        with open(clone / "tests" / "conftest.py", "a") as f:
            f.write(CACHE_CLEARING.format(modules=list(area.clear_caches)))


CACHE_CLEARING = """

@pytest.fixture(autouse=True)
def _empty_caches_for_mutmut():  # written by scripts/mutation_score.py into its clone only
    import importlib
    for name in {modules!r}:
        for value in vars(importlib.import_module(name)).values():
            if callable(getattr(value, "cache_clear", None)):
                value.cache_clear()
    yield
"""


def parse_results(text: str) -> dict[str, list[str]]:
    """mutmut's `results --all true` lines ("    name: status") grouped by status."""
    grouped: dict[str, list[str]] = {status: [] for status in STATUSES}
    for line in text.splitlines():
        match = re.match(r"\s*(\S+): (.+)$", line)
        if match and match.group(2).strip() in grouped:
            grouped[match.group(2).strip()].append(match.group(1))
    return grouped


def run_area(name: str, area: Area, seconds: int) -> dict:
    clone = Path(tempfile.mkdtemp(prefix=f"choreo-mutants-{name}-"))
    subprocess.run(["git", "clone", "--quiet", str(REPO), str(clone)], check=True)
    configure(clone, area)
    started = time.perf_counter()
    run = subprocess.Popen([str(MUTMUT), "run", "--max-children", "1"], cwd=clone, start_new_session=True,
                           stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        run.wait(timeout=seconds)
        finished = True
    except subprocess.TimeoutExpired:  # stop mutmut and the test child it forked
        os.killpg(run.pid, signal.SIGKILL)
        run.wait()
        finished = False
    listing = subprocess.run([str(MUTMUT), "results", "--all", "true"], cwd=clone, capture_output=True, text=True)
    grouped = parse_results(listing.stdout)
    counted = {status: len(names) for status, names in grouped.items()}
    decided = counted["killed"] + counted["survived"] + counted["timeout"]
    return {"area": name, "clone": str(clone), "finished": finished, "minutes": (time.perf_counter() - started) / 60,
            "counts": counted, "score": (counted["killed"] + counted["timeout"]) / decided if decided else None,
            "survived": grouped["survived"], "no tests": grouped["no tests"]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("areas", nargs="*", help=f"areas to mutate (default: all of {', '.join(AREAS)})")
    parser.add_argument("--seconds", type=int, default=3600, help="time limit per area")
    parser.add_argument("--out", type=Path, default=REPO / "runs" / "mutation-results.json")
    parser.add_argument("--list", action="store_true")
    args = parser.parse_args()
    if args.list:
        for name, area in AREAS.items():
            print(f"{name:14s} {' '.join(area.files)}\n{'':14s} tests: {' '.join(area.tests)}")
        return
    unknown = [a for a in args.areas if a not in AREAS]
    if unknown:
        sys.exit(f"unknown area(s): {', '.join(unknown)} (known: {', '.join(AREAS)})")
    if not MUTMUT.exists():
        subprocess.run([str(REPO / ".venv" / "bin" / "python"), "-m", "pip", "install", "--quiet", "mutmut"], check=True)
    results = []
    for name in args.areas or list(AREAS):
        result = run_area(name, AREAS[name], args.seconds)
        results.append(result)
        c = result["counts"]
        score = "-" if result["score"] is None else f"{100 * result['score']:.1f} %"
        print(f"{name}: killed {c['killed']}, timeout {c['timeout']}, survived {c['survived']}, "
              f"untested {c['no tests']}, score {score}, {result['minutes']:.0f} min"
              f"{'' if result['finished'] else ' (time limit: partial)'}  [{result['clone']}]", flush=True)
        for mutant in result["survived"]:
            print(f"  survived: {mutant}")
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(json.dumps(results, indent=1))
    if shutil.which("git"):
        print(f"results: {args.out}")


if __name__ == "__main__":
    main()
