"""Process-level fuzzing (issue 38): interrupt timing and output targets, each case a fresh `choreo`.

tests/fuzz/inputs.py fuzzes file contents in-process; this script fuzzes what only a real
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

  options    (issue 48) a command with an odd number (NaN, inf, 1e308, 0_5, fullwidth digits, 5,000
             digits, 2^63) in a numeric option (--seed, --guidance, --style-guidance, --bpm, --steps,
             --threads, --fps of convert and eval, render --size, graph --warp-smoothing and
             --take-variation, inbetween --key), OMP_NUM_THREADS, --sampler with --steps, a --beats
             file (one beat, nan first, 0_5, fullwidth, a 5,000-digit cell, 28 MB, a sparse 1.5 GB),
             a batch (--out-dir with --format lists such as `,` or `bvh,BVH,.bvh`, --shard, or
             --skip-existing over a zero-byte or truncated output) or a --checkpoint that is a zip
             bomb or a folder (--repertoire too). clean: exit 0 (1 for a batch with failed songs)
             with every output `choreo info` reads, or 2/3 with one stderr line and nothing written;
             never exit 0 on a value no option may take, a stderr line over 1,000 characters, "does
             not exist" for what exists, a peak RSS over 1 GiB, or a write outside the named outputs
             and CHOREO_CACHE_DIR.

Anything else (another exit code, a traceback, a leftover temporary or process, a multi-line
error, a hang past 60 s) is a finding, saved as a .txt in the findings folder.

    nice -n 19 .venv/bin/python -m tests.fuzz.processes --seconds 300 --seed 0
    .venv/bin/python -m tests.fuzz.processes --cases 4 --seed 1
    nice -n 10 .venv/bin/python -m tests.fuzz.processes --surfaces options --seed 48
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

REPO = Path(__file__).resolve().parents[2]
DEFAULT_FINDINGS = Path(tempfile.gettempdir()) / "choreo-process-findings"
SURFACES = ("interrupt", "target", "options")
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
    peak: int = 0  # bytes: the process's peak resident memory (ru_maxrss from wait4)


def _env(extra: dict[str, str] | None = None) -> dict[str, str]:
    env = dict(os.environ)
    env.pop("CHOREO_DEBUG", None)
    env["PYTHONPATH"] = os.pathsep.join([str(REPO / "src"), env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
    env.setdefault("COLUMNS", "100")
    env.update(extra or {})
    return env


def choreo(args: list[str], cwd: Path, signum: int | None = None, delay: float = 0.0,
           timeout: float = HANG, env: dict[str, str] | None = None) -> Result:
    """Run ``python -m choreo ARGS`` in ``cwd`` (with ``env`` added to the environment); send
    ``signum`` after ``delay`` if it still runs. Output goes to files (nothing blocks on a full
    pipe) and the process is reaped by wait4. Its peak memory is its own address space's high-water
    mark (/proc's VmHWM), sampled while it runs: wait4's ru_maxrss also counts the pages of the
    process it was forked from (a test runner of a gigabyte made every child "peak" at a gigabyte)."""
    start = time.monotonic()
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        process = subprocess.Popen([sys.executable, "-m", "choreo", *args], cwd=cwd, env=_env(env),
                                   stdin=subprocess.DEVNULL, stdout=out, stderr=err, start_new_session=True)
        signalled, code, peak = False, None, 0
        while True:
            peak = max(peak, resident_peak(process.pid))
            pid, status, _ = os.wait4(process.pid, os.WNOHANG)
            if pid:
                code = process.returncode = os.waitstatus_to_exitcode(status)
                break
            elapsed = time.monotonic() - start
            if signum is not None and not signalled and elapsed >= delay:
                process.send_signal(signum)
                signalled = True
            if elapsed > timeout:
                with _suppress():
                    os.killpg(process.pid, signal.SIGKILL)
                _, status, _ = os.wait4(process.pid, 0)
                process.returncode = os.waitstatus_to_exitcode(status)
                break
            time.sleep(0.01)
        out.seek(0)
        err.seek(0)
        result = Result(code, out.read().decode("utf-8", "replace"), err.read().decode("utf-8", "replace"),
                        signalled, time.monotonic() - start, peak=peak)
    result.stray = stray_processes(cwd)
    return result


def resident_peak(pid: int) -> int:
    """Bytes of the process's peak resident memory so far (0 once it is gone or unreadable)."""
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    return 0


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


# -- options: numbers, threads, steps, beat files, batch flags and checkpoints (issue 48) -------------
NUMBER_VALUES = ("nan", "inf", "-inf", "1e308", "-1e308", "1e30", "1e6", "-1", "0", "3", "0_5", "\uff11\uff12",
                 "9" * 5000, "9223372036854775808", "2147483648", "99999", "")
NEVER_NUMBERS = {"nan", "inf", "-inf", "0_5", "\uff11\uff12", ""}  # no option may take these
GENERATE = ["generate", "song.wav", "-o", "out.bvh"]
GRAPH = ["graph", "song.wav", "-o", "out.bvh"]
NUMBER_OPTIONS = {  # name: (arguments, option, how the value is written, the outputs)
    "convert --fps": (["convert", "dance.npz", "out.bvh"], "--fps", "{}", ["out.bvh"]),
    "eval --fps": (["eval", "dance.npz"], "--fps", "{}", []),
    "render --size": (["render", "dance.npz", "-o", "out.gif"], "--size", "{0}x{0}", ["out.gif"]),
    "generate --seed": (GENERATE, "--seed", "{}", ["out.bvh"]),
    "generate --guidance": (GENERATE, "--guidance", "{}", ["out.bvh"]),
    "generate --style-guidance": (GENERATE + ["--style", "waltz"], "--style-guidance", "{}", ["out.bvh"]),
    "generate --bpm": (GENERATE, "--bpm", "{}", ["out.bvh"]),
    "generate --steps": (GENERATE, "--steps", "{}", ["out.bvh"]),
    "generate --threads": (GENERATE, "--threads", "{}", ["out.bvh"]),
    "graph --seed": (GRAPH, "--seed", "{}", ["out.bvh"]),
    "graph --warp-smoothing": (GRAPH, "--warp-smoothing", "{}", ["out.bvh"]),
    "graph --take-variation": (GRAPH, "--take-variation", "{}", ["out.bvh"]),
    "inbetween --key": (["inbetween", "song.wav", "--start", "dance.npz", "--end", "dance.npz", "-o", "out.bvh"],
                        "--key", "{}=dance.npz", ["out.bvh"]),
}
OMP_VALUES = ("99999", "2147483648", "0", "-3", "x", "4,99999", "1")
STEP_VALUES = ("1", "10", "1000", "1001", "100001", "9223372036854775808", "0", "-1")
BEAT_FILES = {  # name: (bytes or a size for a sparse file, must it be refused)
    "plain": (b"beat_time,downbeat\n0.5,1\n1.0,0\n1.5,0\n2.0,0\n2.5,1\n", False),
    "one_beat": (b"0.5\n", True), "nan_first": (b"nan\n0.5\n1.0\n1.5\n", True),
    "underscore": (b"0.5\n1_0\n1.5\n", True), "fullwidth": ("0.5\n\uff11\n1.5\n".encode(), True),
    "long_cell": (b"0.5\n1.0\n" + b"9" * 5000 + b"\n", True), "huge": (None, False), "sparse": (3 << 29, False),
}
BATCH_FORMATS = (",", "", "bvh,BVH,.bvh", "nope", "bvh,nope", "npz", "bvh", "glb,npz")
SHARDS = ("1/" + "9" * 5000, "0/2", "3/2", "1/0", "nan/2", "1/2", "2/2", "\uff11/2", "1/1")
OPTION_KINDS = ("number", "threads", "steps", "beats", "batch", "checkpoint")
PEAK = 1 << 30  # bytes of resident memory a case may take
LONGEST_LINE = 1000  # characters of one stderr line


def _input_fuzzer():
    """tests/fuzz/inputs.py, for its forged checkpoint and its big beat file."""
    from tests.fuzz import inputs

    return inputs


def make_option_inputs(folder: Path) -> None:
    """song2.wav (a second song for batches), bomb.pt (the bundled checkpoint with a tensor record
    forged into 1.25 GiB of deflated zeros) and huge.csv (28 MB of beats)."""
    fuzz = _input_fuzzer()
    shutil.copy(folder / "song.wav", folder / "song2.wav")
    bundled = REPO / "generators" / "choreo_sgmd" / "weights" / "sgmd-cpu-m2d.pt"
    (folder / "bomb.pt").write_bytes(fuzz.checkpoint_bomb(random.Random(0), bundled.read_bytes(), []))
    (folder / "huge.csv").write_bytes(fuzz.huge_beats(random.Random(0), b"", []))


def _option_setup(rng: random.Random, folder: Path, inputs: Path) -> tuple[str, list[str], dict, list[str], bool]:
    """(label, arguments, environment, named outputs, must it be refused) of one case, its files made in ``folder``."""
    for name in ("dance.npz", "song.wav"):
        shutil.copy(inputs / name, folder / name)
    kind = rng.choice(OPTION_KINDS)
    if kind == "number":
        name = rng.choice(sorted(NUMBER_OPTIONS))
        args, option, form, outputs = NUMBER_OPTIONS[name]
        value = rng.choice(NUMBER_VALUES)
        return f"number {name} {value[:24]!r}", [*args, f"{option}={form.format(value)}"], {}, outputs, \
            value in NEVER_NUMBERS
    if kind == "threads":
        value = rng.choice(OMP_VALUES)
        if rng.random() < 0.5:
            return f"threads OMP_NUM_THREADS={value}", GENERATE, {"OMP_NUM_THREADS": value}, ["out.bvh"], False
        return f"threads --threads={value}", [*GENERATE, f"--threads={value}"], {}, ["out.bvh"], value == "x"
    if kind == "steps":
        sampler, steps = rng.choice(("ddpm", "ddim")), rng.choice(STEP_VALUES)
        command = rng.choice((GENERATE, ["inbetween", "song.wav", "--start", "dance.npz", "-o", "out.bvh"]))
        return f"steps {command[0]} --sampler {sampler} --steps {steps}", \
            [*command, "--sampler", sampler, f"--steps={steps}"], {}, ["out.bvh"], False
    if kind == "beats":
        name = rng.choice(sorted(BEAT_FILES))
        content, refuse = BEAT_FILES[name]
        if name == "huge":
            shutil.copy(inputs / "huge.csv", folder / "beats.csv")
        elif isinstance(content, int):
            with open(folder / "beats.csv", "wb") as handle:
                handle.truncate(content)  # sparse: no disk used
        else:
            (folder / "beats.csv").write_bytes(content)
        return f"beats {name}", [*GENERATE, "--beats", "beats.csv"], {}, ["out.bvh"], refuse
    if kind == "batch":
        shutil.copy(inputs / "song.wav", folder / "song2.wav")
        formats = rng.choice(BATCH_FORMATS)
        args = ["generate", "song.wav", "song2.wav", "--out-dir", "outs", f"--format={formats}"]
        label = f"batch --format {formats!r}"
        extra = rng.random()
        if extra < 0.4:
            shard = rng.choice(SHARDS)
            args.append(f"--shard={shard}")
            label += f" --shard {shard[:24]!r}"
        elif extra < 0.8:
            (folder / "outs").mkdir()
            ext = rng.choice(("bvh", "npz"))
            source = (inputs / ("dance.bvh" if ext == "bvh" else "dance.npz")).read_bytes()
            left = rng.choice((0, len(source) // 2, len(source) - 1))
            (folder / "outs" / f"song.{ext}").write_bytes(source[:left])
            args.append("--skip-existing")
            label += f" --skip-existing over a {left}-byte song.{ext}"
        return label, args, {}, ["outs"], formats in (",", "")
    choice = rng.randrange(4)
    if choice < 2:
        shutil.copy(inputs / "bomb.pt", folder / "bomb.pt")
        args = [*(GENERATE if choice == 0 else GRAPH), "--checkpoint", "bomb.pt"]
    else:
        (folder / "afolder").mkdir()
        args = [*GENERATE, "--checkpoint", "afolder"] if choice == 2 else [*GRAPH, "--repertoire", "afolder"]
    return f"checkpoint {args[0]} {args[-2]} {args[-1]}", args, {}, ["out.bvh"], True


def option_case(rng: random.Random, inputs: Path) -> Case:
    """One command with an odd option, environment, beat file, batch flag or checkpoint. Clean: exit
    0 (1 for a batch with failed songs) with every named output readable, or 2/3 with one stderr
    line and nothing written; never a traceback, a line over 1,000 characters, "does not exist" for
    something that exists, 1 GiB of memory, an exit 0 on a value no option may take, or a write
    outside the named outputs and the cache (CHOREO_CACHE_DIR=cache)."""
    with tempfile.TemporaryDirectory(prefix="choreo-proc-") as tmp:
        folder = Path(tmp)
        label, args, env, outputs, refuse = _option_setup(rng, folder, inputs)
        before = snapshot(folder)
        result = choreo(args, folder, env={"CHOREO_CACHE_DIR": str(folder / "cache"), **env})
        after = snapshot(folder)
        code, lines, problems = result.returncode, stderr_lines(result.stderr), []
        batch = "--out-dir" in args
        if result.stray:
            problems.append(f"processes left: {result.stray}")
        if temporaries(folder):
            problems.append(f"temporaries left: {temporaries(folder)}")
        if result.peak > PEAK:
            problems.append(f"peak memory {result.peak >> 20} MiB")
        if any("Traceback" in line for line in lines):
            problems.append("traceback on stderr")
        if any(len(line) > LONGEST_LINE for line in lines):
            problems.append(f"a stderr line of {max(map(len, lines))} characters")
        if "does not exist" in result.stderr and any((folder / a).exists() for a in args[1:] if "/" not in a):
            problems.append("says 'does not exist' of something that exists")
        named = lambda rel: rel == "cache" or rel.startswith("cache/") or \
            any(rel == o or rel.startswith(o + "/") for o in outputs)  # noqa: E731
        changed = sorted(rel for rel in set(before) | set(after) if before.get(rel) != after.get(rel))
        if code is None:
            problems.insert(0, f"hung past {HANG:.0f} s")
        elif code == 0 or (batch and code == 1):
            if code == 0 and refuse:
                problems.append("exit 0: accepted what it must refuse")
            made = [rel for rel, entry in after.items() if entry[0] == "file" and before.get(rel) != entry
                    and any(rel == o or rel.startswith(o + "/") for o in outputs)]
            if code == 0 and outputs and not made:
                problems.append("exit 0 but nothing written")
            for rel in made:
                check = choreo(["info", rel], folder)
                if check.returncode != 0:
                    problems.append(f"`choreo info {rel}` exit {check.returncode}: {check.stderr.strip()[:200]}")
            if code == 1 and not lines:
                problems.append("exit 1 without a message")
        elif code in (2, 3):
            if len(lines) != 1:  # click's usage errors too: one line since round four
                problems.append(f"exit {code} with {len(lines)} stderr lines")
            outside = [rel for rel in changed if not (rel == "cache" or rel.startswith("cache/"))]
            if outside:
                problems.append(f"exit {code} but changed: {outside[:5]}")
        else:
            problems.insert(0, f"exit {code}")
        outside = [rel for rel in changed if not named(rel)]
        if outside:
            problems.append(f"changed outside the outputs and the cache: {outside[:5]}")
        verdict = "FINDING" if problems else "clean"
        detail = "; ".join(problems) or f"exit {code}"
        return Case("options", label, ["choreo", *args], verdict, detail, result)


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
        if "options" in surfaces:
            make_option_inputs(inputs)
        if verbose:
            for note in notes:
                print(note)
        makers = {"interrupt": lambda: interrupt_case(rng, inputs, commands), "target": lambda: target_case(rng, inputs),
                  "options": lambda: option_case(rng, inputs)}
        for case in in_turn(surfaces, makers, cases, seconds):
            done.append(case)
            if case.verdict == "FINDING":
                path = save_finding(findings, len(done), case)
                if verbose:
                    print(f"FINDING {case.surface} {case.name}: {case.detail[:200]}\n    {path}", flush=True)
    return done


def in_turn(surfaces, makers: dict, cases: int | None, seconds: float | None):
    """One case of each surface in turn (``makers[surface]()``), until each has ``cases`` or
    ``seconds`` have passed."""
    start, counts, turn = time.monotonic(), Counter(), 0
    while True:
        active = [s for s in surfaces if cases is None or counts[s] < cases]
        if not active or (seconds is not None and time.monotonic() - start > seconds):
            return
        surface = active[turn % len(active)]
        turn += 1
        counts[surface] += 1
        yield makers[surface]()


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


def surface_main(argv: list[str] | None, doc: str, surfaces: tuple[str, ...], findings: Path, run, report) -> int:
    """The command line of a surface fuzzer (this one and tests/fuzz/surfaces.py): exit 1 on a finding."""
    parser = argparse.ArgumentParser(description=doc.split("\n\n")[0])
    parser.add_argument("--seconds", type=float, default=None, help="stop after this long (60 s without --cases)")
    parser.add_argument("--cases", type=int, default=None, help="stop after this many cases of each surface")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--surfaces", default=",".join(surfaces), help="comma list of " + ", ".join(surfaces))
    parser.add_argument("--findings", type=Path, default=findings)
    args = parser.parse_args(argv)
    seconds = 60.0 if args.seconds is None and args.cases is None else args.seconds
    chosen = tuple(s for s in args.surfaces.split(",") if s)
    unknown = set(chosen) - set(surfaces)
    if unknown:
        parser.error(f"unknown surfaces: {', '.join(sorted(unknown))}")
    start = time.monotonic()
    done = run(seconds, args.cases, args.seed, args.findings, chosen)
    report(done, time.monotonic() - start, args.findings)
    return 1 if any(c.verdict == "FINDING" for c in done) else 0


def main(argv: list[str] | None = None) -> int:
    return surface_main(argv, __doc__, SURFACES, DEFAULT_FINDINGS, run, print_report)


if __name__ == "__main__":
    sys.exit(main())
