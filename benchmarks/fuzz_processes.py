"""Process-level fuzzing (issue 38): interrupt timing and output targets, each case a fresh `choreo`.

benchmarks/fuzz_inputs.py fuzzes file contents in-process; this script fuzzes what only a real
process shows. Every case runs ``python -m choreo ...`` in a fresh temporary folder.

  interrupt  a command that does real work on a small generated input (convert BVH->NPZ, NPZ->glb,
             render a GIF, info of a WAV) gets SIGINT or SIGTERM after a random delay (0-1.5 s).
             clean: exit 0 with its output complete, or exit 130/143 with at most one stderr line,
             no output file, no hidden temporary (``.*.tmp*``) and no process left with its cwd in
             the folder. "early": the signal arrived during Python's start-up, before choreo
             installed its handlers (roughly the first second): the default action ended the
             process (exit -2/-15, or a bare KeyboardInterrupt traceback) with nothing written.
             Not a finding; the window exists and cannot be closed from inside choreo.
  target     ``convert dance.bvh TARGET`` where TARGET is a missing folder, an existing folder, a
             FIFO, a symlink to a folder, a dangling symlink, a symlink loop, a read-only folder
             (skipped as root), a name with a newline or control characters, a 300-character name,
             an existing file (replaced atomically: new inode, content changed, mode kept) or a
             read-only (0444) file. clean: exit 0 and ``choreo info`` reads the output back, or exit
             2/3 with exactly one stderr line; either way nothing else in the folder changed.

Anything else (another exit code, a traceback, a leftover temporary or process, a multi-line
error, a hang past 60 s) is a finding, saved as a .txt in the findings folder.

    nice -n 19 .venv/bin/python benchmarks/fuzz_processes.py --seconds 300 --seed 0
    .venv/bin/python benchmarks/fuzz_processes.py --cases 4 --seed 1
"""

from __future__ import annotations

import argparse
import hashlib
import io
import os
import random
import shutil
import signal
import stat
import subprocess
import sys
import tempfile
import time
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
DEFAULT_FINDINGS = Path(tempfile.gettempdir()) / "choreo-process-findings"
SURFACES = ("interrupt", "target")
HANG = 60.0  # seconds a case may run before it is a finding
MAX_DELAY = 1.5
INTERRUPT_COMMANDS = {
    "convert-bvh-npz": (["convert", "dance.bvh", "out.npz"], "out.npz"),
    "convert-npz-glb": (["convert", "dance.npz", "out.glb"], "out.glb"),
    "render-gif": (["render", "dance.npz", "-o", "out.gif", "--size", "160x120"], "out.gif"),
    "info-wav": (["info", "song.wav"], None),
}
TARGET_KINDS = ("missing_parent", "existing_folder", "fifo", "link_to_folder", "dangling_link", "link_loop",
                "readonly_folder", "control_chars", "long_name", "existing_file", "readonly_file")


# -- inputs ------------------------------------------------------------------------------------------
def make_inputs(folder: Path, frames: int = 3000) -> None:
    """dance.bvh (100 s), dance.npz (its first 20 s) and song.wav (8 s of clicks over a tone)."""
    import soundfile as sf

    from choreo.formats.bvh import write_bvh
    from choreo.formats.npz import write_npz
    from choreo.motion import Motion

    rng = np.random.default_rng(0)
    root = np.zeros((frames, 3)) + [0.0, 0.9, 0.0] + np.cumsum(rng.normal(scale=0.005, size=(frames, 3)), 0)
    rotations = np.cumsum(rng.normal(scale=0.02, size=(frames, 24, 3)), 0)
    motion = Motion.from_axis_angle(root, rotations, fps=30.0)
    with open(folder / "dance.bvh", "wb") as handle:
        write_bvh(motion, handle)
    with open(folder / "dance.npz", "wb") as handle:  # shorter: render draws every frame
        write_npz(motion[:600], handle)
    rate = 22050
    t = np.arange(8 * rate) / rate
    song = 0.2 * np.sin(2 * np.pi * 220 * t) + 0.5 * (t * 2 % 1 < 0.02) * rng.normal(size=t.size)
    buffer = io.BytesIO()
    sf.write(buffer, song.astype(np.float32), rate, format="WAV", subtype="PCM_16")
    (folder / "song.wav").write_bytes(buffer.getvalue())


# -- running choreo ------------------------------------------------------------------------------------
@dataclass
class Result:
    returncode: int | None  # None: hung, killed
    stdout: str
    stderr: str
    signalled: bool = False
    seconds: float = 0.0
    stray: list[str] = field(default_factory=list)  # processes left with their cwd in the folder


def _env() -> dict[str, str]:
    env = dict(os.environ)
    env.pop("CHOREO_DEBUG", None)
    env["PYTHONPATH"] = os.pathsep.join([str(REPO / "src"), env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
    env.setdefault("COLUMNS", "100")
    return env


def choreo(args: list[str], cwd: Path, signum: int | None = None, delay: float = 0.0,
           timeout: float = HANG) -> Result:
    """Run ``python -m choreo ARGS`` in ``cwd``; send ``signum`` after ``delay`` if it still runs."""
    start = time.monotonic()
    process = subprocess.Popen([sys.executable, "-m", "choreo", *args], cwd=cwd, env=_env(),
                               stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               start_new_session=True)
    signalled = False
    if signum is not None:
        try:
            process.wait(timeout=delay)
        except subprocess.TimeoutExpired:
            process.send_signal(signum)
            signalled = True
    try:
        out, err = process.communicate(timeout=max(timeout - (time.monotonic() - start), 1.0))
        code: int | None = process.returncode
    except subprocess.TimeoutExpired:
        with _suppress():
            os.killpg(process.pid, signal.SIGKILL)
        out, err = process.communicate()
        code = None
    result = Result(code, out.decode("utf-8", "replace"), err.decode("utf-8", "replace"), signalled,
                    time.monotonic() - start)
    result.stray = stray_processes(cwd)
    return result


class _suppress:
    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return exc[0] is not None and issubclass(exc[0], OSError)


def stray_processes(folder: Path) -> list[str]:
    """Processes whose working folder is ``folder`` or below (killed once noted: they are ours)."""
    stray, root = [], os.path.realpath(folder)
    for _ in range(3):  # a child may take a moment to exit after its parent
        stray = []
        for entry in os.listdir("/proc"):
            if not entry.isdigit() or int(entry) == os.getpid():
                continue
            with _suppress():
                cwd = os.readlink(f"/proc/{entry}/cwd")
                if cwd == root or cwd.startswith(root + "/"):
                    with open(f"/proc/{entry}/cmdline", "rb") as handle:
                        command = handle.read().replace(b"\0", b" ").decode(errors="replace")
                    stray.append(f"{entry}: {command}")
        if not stray:
            return []
        time.sleep(0.2)
    for line in stray:
        with _suppress():
            os.kill(int(line.split(":")[0]), signal.SIGKILL)
    return stray


def temporaries(folder: Path) -> list[str]:
    return sorted(str(p.relative_to(folder)) for p in folder.rglob(".*.tmp*"))


def snapshot(folder: Path) -> dict[str, tuple]:
    """Every entry under ``folder`` (not following links): kind, mode, content hash or link target."""
    entries = {}
    for dirpath, dirnames, filenames in os.walk(folder, followlinks=False):
        for name in dirnames + filenames:
            path = os.path.join(dirpath, name)
            rel = os.path.relpath(path, folder)
            info = os.lstat(path)
            mode = stat.S_IMODE(info.st_mode)
            if stat.S_ISLNK(info.st_mode):
                entries[rel] = ("link", os.readlink(path))
            elif stat.S_ISREG(info.st_mode):
                with open(path, "rb") as handle:
                    entries[rel] = ("file", mode, info.st_ino, hashlib.sha256(handle.read()).hexdigest())
            elif stat.S_ISDIR(info.st_mode):
                entries[rel] = ("dir", mode)
            else:
                entries[rel] = ("other", stat.S_IFMT(info.st_mode), mode)
    return entries


def stderr_lines(text: str) -> list[str]:
    return [line for line in text.splitlines() if line.strip()]


# -- cases ---------------------------------------------------------------------------------------------
@dataclass
class Case:
    surface: str
    name: str
    command: list[str]
    verdict: str  # clean, early, skipped or FINDING
    detail: str
    result: Result | None = None


def output_complete(name: str, output: Path, folder: Path, result: Result) -> str:
    """'' if the command's output is complete, else what is wrong with it."""
    if name == "info-wav":
        return "" if result.stdout.strip() else "no output on stdout"
    if not output.exists():
        return f"{output.name} missing"
    if name == "render-gif":
        data = output.read_bytes()
        return "" if data[:6] in (b"GIF87a", b"GIF89a") and data.endswith(b";") else "truncated GIF"
    check = choreo(["info", output.name], folder, timeout=HANG)
    return "" if check.returncode == 0 else f"`choreo info {output.name}` exit {check.returncode}: {check.stderr.strip()}"


def interrupt_case(rng: random.Random, inputs: Path, commands: list[str]) -> Case:
    name = rng.choice(commands)
    args, output_name = INTERRUPT_COMMANDS[name]
    signum = rng.choice((signal.SIGINT, signal.SIGTERM))
    delay = rng.uniform(0.0, MAX_DELAY)
    label = f"{name} {signal.Signals(signum).name} after {delay:.3f} s"
    with tempfile.TemporaryDirectory(prefix="choreo-proc-") as tmp:
        folder = Path(tmp)
        for source in inputs.iterdir():
            shutil.copy(source, folder / source.name)
        result = choreo(args, folder, signum, delay)
        code, lines = result.returncode, stderr_lines(result.stderr)
        left = temporaries(folder)
        output = folder / output_name if output_name else None
        problems = []
        if result.stray:
            problems.append(f"processes left: {result.stray}")
        if left:
            problems.append(f"temporaries left: {left}")
        if code is None:
            verdict, problems = "FINDING", [f"hung past {HANG:.0f} s"] + problems
        elif code == 0:
            wrong = output_complete(name, output, folder, result) if output or name == "info-wav" else ""
            if wrong:
                problems.append(f"exit 0 but {wrong}")
            if any("Traceback" in line for line in lines):
                problems.append("traceback on stderr")
            verdict = "FINDING" if problems else "clean"
        elif code in (-signum, 128 + signum) and not any(line.startswith("choreo:") for line in lines) \
                and (not lines or lines[-1].strip() == "KeyboardInterrupt" or not any("Traceback" in ln for ln in lines)):
            # The default action (Python re-raises an uncaught KeyboardInterrupt as SIGINT). "early":
            # during start-up, before choreo's handlers were installed, nothing written. "late": after
            # the command finished and its handlers were put back, while Python shuts down; the
            # output must then be complete.
            late = bool(result.stdout.strip()) or (bool(lines) and lines[-1].strip() != "KeyboardInterrupt")
            if late or (output is not None and output.exists()):
                wrong = output_complete(name, output, folder, result)
                if wrong:
                    problems.append(f"killed by the signal after it finished, output incomplete: {wrong}")
                late = True
            verdict = "FINDING" if problems else ("late" if late else "early")
        elif code == 128 + signum:
            if len(lines) > 1:
                problems.append(f"{len(lines)} stderr lines")
            if any("Traceback" in line for line in lines):
                problems.append("traceback on stderr")
            if output is not None and (output.exists() or output.is_symlink()):
                problems.append(f"exit {code} but {output.name} was written")
            verdict = "FINDING" if problems else "clean"
        else:
            verdict = "FINDING"
            problems.insert(0, f"exit {code}")
        if not result.signalled and verdict in ("early", "late"):
            verdict = "clean"
        detail = "; ".join(problems) or (f"exit {code}" + ("" if result.signalled else " (finished first)"))
        return Case("interrupt", label, ["choreo", *args], verdict, detail, result)


def _prepare_target(kind: str, folder: Path, ext: str, rng: random.Random) -> str | None:
    """Set up ``kind`` in ``folder``; returns the TARGET argument (None: skipped)."""
    (folder / "keep").mkdir()
    (folder / "keep" / "bystander.txt").write_text("untouched\n")
    if kind == "missing_parent":
        return f"nowhere/out{ext}"
    if kind == "existing_folder":
        (folder / f"out{ext}").mkdir()
        (folder / f"out{ext}" / "inside.txt").write_text("inside\n")
        return f"out{ext}"
    if kind == "fifo":
        os.mkfifo(folder / f"out{ext}")
        return f"out{ext}"
    if kind == "link_to_folder":
        os.symlink("keep", folder / f"out{ext}")
        return f"out{ext}"
    if kind == "dangling_link":
        os.symlink(f"elsewhere{ext}", folder / f"out{ext}")
        return f"out{ext}"
    if kind == "link_loop":
        os.symlink(f"b{ext}", folder / f"a{ext}")
        os.symlink(f"a{ext}", folder / f"b{ext}")
        return f"a{ext}"
    if kind == "readonly_folder":
        if os.geteuid() == 0:
            return None  # root writes anywhere
        (folder / "locked").mkdir()
        os.chmod(folder / "locked", 0o555)
        return f"locked/out{ext}"
    if kind == "control_chars":
        return rng.choice(["out\nx", "out\x1b[31mred", "out\r\tx", "out\x07\x7fx", "-out\n[/x]"]) + ext
    if kind == "long_name":
        return "o" * 300 + ext
    if kind in ("existing_file", "readonly_file"):
        (folder / f"out{ext}").write_bytes(b"old content\n")
        os.chmod(folder / f"out{ext}", 0o444 if kind == "readonly_file" else 0o640)
        return f"out{ext}"
    raise ValueError(kind)


def target_case(rng: random.Random, inputs: Path) -> Case:
    kind = rng.choice(TARGET_KINDS)
    ext = rng.choice((".npz", ".bvh", ".glb", ".json"))
    with tempfile.TemporaryDirectory(prefix="choreo-proc-") as tmp:
        folder = Path(tmp)
        shutil.copy(inputs / "dance.bvh", folder / "dance.bvh")
        target = _prepare_target(kind, folder, ext, rng)
        if target is None:
            return Case("target", kind, [], "skipped", "running as root")
        args = ["convert", *(["--"] if target.startswith("-") else []), "dance.bvh", target]
        before = snapshot(folder)
        result = choreo(args, folder, timeout=HANG)
        after = snapshot(folder)
        code, lines, problems = result.returncode, stderr_lines(result.stderr), []
        if (folder / "locked").exists():
            os.chmod(folder / "locked", 0o755)
        if result.stray:
            problems.append(f"processes left: {result.stray}")
        if temporaries(folder):
            problems.append(f"temporaries left: {temporaries(folder)}")
        written: set[str] = set()
        if code is None:
            problems.insert(0, f"hung past {HANG:.0f} s")
        elif code == 0:
            path = folder / target
            written = {target}
            if path.is_symlink():
                written.add(os.path.relpath(os.path.realpath(path), os.path.realpath(folder)))
            check = choreo(["info", "--", target] if target.startswith("-") else ["info", target], folder)
            if check.returncode != 0:
                problems.append(f"`choreo info` of the output: exit {check.returncode}: {check.stderr.strip()[:300]}")
            for rel in written:
                old, new = before.get(rel), after.get(rel)
                if old and old[0] == "file":
                    if not new or new[0] != "file":
                        problems.append(f"{rel!r} is no longer a regular file")
                    elif new[3] == old[3]:
                        problems.append(f"{rel!r} content unchanged")
                    else:
                        if new[1] != old[1]:
                            problems.append(f"{rel!r} mode {oct(old[1])} became {oct(new[1])}")
                        if new[2] == old[2]:
                            problems.append(f"{rel!r} rewritten in place (same inode), not replaced atomically")
            if before.get(target, ("",))[0] == "link" and after.get(target, ("",))[0] != "link":
                problems.append("the symlink was replaced instead of written through")
            if any("Traceback" in line for line in lines):
                problems.append("traceback on stderr")
        elif code in (2, 3):
            if len(lines) != 1:
                problems.append(f"exit {code} with {len(lines)} stderr lines")
        else:
            problems.insert(0, f"exit {code}")
        changed = sorted(rel for rel in set(before) | set(after)
                         if rel not in written and before.get(rel) != after.get(rel))
        if changed:
            problems.append(f"changed in the folder: {changed[:10]}")
        verdict = "FINDING" if problems else "clean"
        detail = "; ".join(problems) or f"exit {code}"
        return Case("target", f"{kind} {target!r}", ["choreo", *args], verdict, detail, result)


# -- driver --------------------------------------------------------------------------------------------
def save_finding(folder: Path, number: int, case: Case) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{case.surface}-{number:04d}.txt"
    result = case.result
    text = [f"surface: {case.surface}", f"case: {case.name}", f"command: {case.command!r}",
            f"what happened: {case.detail}"]
    if result:
        text += [f"exit code: {result.returncode}", f"signal sent: {result.signalled}",
                 f"seconds: {result.seconds:.2f}", "stderr:", result.stderr, "stdout (tail):", result.stdout[-2000:]]
    path.write_text("\n".join(text) + "\n", encoding="utf-8", errors="backslashreplace")
    return path


def usable_commands(inputs: Path, names=tuple(INTERRUPT_COMMANDS)) -> tuple[list[str], list[str]]:
    """The interrupt commands that succeed here without a signal (render needs its tools), and notes."""
    usable, notes = [], []
    for name in names:
        args = INTERRUPT_COMMANDS[name][0]
        with tempfile.TemporaryDirectory(prefix="choreo-proc-") as tmp:
            for source in inputs.iterdir():
                shutil.copy(source, Path(tmp) / source.name)
            result = choreo(args, Path(tmp))
        if result.returncode == 0:
            usable.append(name)
            notes.append(f"{name}: {result.seconds:.2f} s without a signal")
        elif name == "render-gif":
            notes.append(f"{name}: skipped, exit {result.returncode}: {result.stderr.strip()[:200]}")
        else:
            raise SystemExit(f"{name} fails without a signal: exit {result.returncode}: {result.stderr}")
    return usable, notes


def run(seconds: float | None, cases: int | None, seed: int, findings: Path,
        surfaces=SURFACES, verbose: bool = True, commands=tuple(INTERRUPT_COMMANDS)) -> list[Case]:
    rng = random.Random(seed)
    done: list[Case] = []
    with tempfile.TemporaryDirectory(prefix="choreo-proc-inputs-") as tmp:
        inputs = Path(tmp)
        make_inputs(inputs)
        commands, notes = usable_commands(inputs, commands) if "interrupt" in surfaces else ([], [])
        if verbose:
            for note in notes:
                print(note)
        start = time.monotonic()
        counts = Counter()
        turn = 0
        while True:
            active = [s for s in surfaces if cases is None or counts[s] < cases]
            if not active or (seconds is not None and time.monotonic() - start > seconds):
                break
            surface = active[turn % len(active)]
            turn += 1
            case = interrupt_case(rng, inputs, commands) if surface == "interrupt" else target_case(rng, inputs)
            counts[surface] += 1
            done.append(case)
            if case.verdict == "FINDING":
                path = save_finding(findings, len(done), case)
                if verbose:
                    print(f"FINDING {case.surface} {case.name}: {case.detail[:200]}\n    {path}", flush=True)
    return done


def print_report(done: list[Case], elapsed: float, findings: Path) -> None:
    print(f"\n{'surface':<11}{'cases':>8}{'clean':>8}{'early':>8}{'late':>8}{'skipped':>9}{'findings':>10}")
    for surface in SURFACES:
        verdicts = Counter(c.verdict for c in done if c.surface == surface)
        print(f"{surface:<11}{sum(verdicts.values()):>8}{verdicts['clean']:>8}{verdicts['early']:>8}"
              f"{verdicts['late']:>8}"
              f"{verdicts['skipped']:>9}{verdicts['FINDING']:>10}")
    kinds = Counter(c.name.split()[0] for c in done)
    print("by kind: " + ", ".join(f"{k} {n}" for k, n in sorted(kinds.items())))
    bad = sum(c.verdict == "FINDING" for c in done)
    print(f"{len(done)} cases in {elapsed:.0f} s; {bad} findings" + (f", saved under {findings}" if bad else ""))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seconds", type=float, default=None, help="stop after this long (60 s without --cases)")
    parser.add_argument("--cases", type=int, default=None, help="stop after this many cases of each surface")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--surfaces", default=",".join(SURFACES), help="comma list of interrupt, target")
    parser.add_argument("--findings", type=Path, default=DEFAULT_FINDINGS)
    args = parser.parse_args(argv)
    seconds = 60.0 if args.seconds is None and args.cases is None else args.seconds
    surfaces = tuple(s for s in args.surfaces.split(",") if s)
    unknown = set(surfaces) - set(SURFACES)
    if unknown:
        parser.error(f"unknown surfaces: {', '.join(sorted(unknown))}")
    start = time.monotonic()
    done = run(seconds, args.cases, args.seed, args.findings, surfaces)
    print_report(done, time.monotonic() - start, args.findings)
    return 1 if any(c.verdict == "FINDING" for c in done) else 0


if __name__ == "__main__":
    sys.exit(main())
