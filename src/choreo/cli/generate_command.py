"""`choreo generate` and the controllable commands built on it: inbetween, inpaint, trajectory.

All four share one pipeline (analyse the song, build constraints against its frames, dance,
write every output atomically) and one set of sampling options.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Callable, List, Optional

import typer

from ..generator.base import MAX_SEED
from .numbers import Number
from .progress import progress_bar, stderr_console
from .text import markup

if TYPE_CHECKING:
    from ..music.beat_source import BeatSource

SONG = typer.Argument(..., help="Audio file: wav, mp3, ogg, flac or opus.")
OUTPUT = typer.Option(..., "-o", "--output",
                      help="Output motion file (.bvh, .npz, .json, .npy, .glb, .fbx) or - for stdout; repeat for several.")
STYLE = typer.Option(None, help="Genre (waltz, rumba, ...), its index, free text, or a schedule 0:30=waltz,30:=cha-cha.")
CHECKPOINT = typer.Option(None, help="Trained checkpoint (from choreo train); default: the bundled one.")
GENERATOR = typer.Option("sgmd", help="Backend (see choreo generators).")
STEPS = typer.Option(None, help="Sampling steps (default: the backend's: 10 DDIM steps for sgmd, 1000 for ddpm).")
GUIDANCE = typer.Option(None, parser=Number("--guidance"), help="sgmd: classifier-free guidance weight on the music (1 = none; the default is in docs/sgmd.md).")
STYLE_GUIDANCE = typer.Option(None, "--style-guidance", parser=Number("--style-guidance"),
                              help="sgmd: guidance weight on the --style prompt (default 2, or 1 where frames are "
                                   "given; 1 = none, a third faster).")
SAMPLER = typer.Option(None, help="sgmd: ddim (default; fast, any number of steps) or ddpm (the full chain).")
SEED = typer.Option(0, parser=Number("--seed", -MAX_SEED, MAX_SEED, whole=True), help="Random seed: same seed, same dance.")
FORMAT = typer.Option(None, "--format", "-f", help="Output format; default from the extension.")
RIG = typer.Option(None, "--rig", help="Write .bvh/.fbx on another rig's bones and T-pose: mixamo (default: SMPL-24).")
BEAT_LOCK = typer.Option(True, "--beat-lock/--no-beat-lock",
                         help="Re-time the dance so its motion beats land on the music's beats (given frames stay).")
FOOT_LOCK = typer.Option(False, "--foot-lock/--no-foot-lock",
                         help="Let planted feet carry the body instead of sliding (halves PFC, doubles FID_g: off by default).")
FOOTSTEPS = typer.Option(True, "--footsteps/--no-footsteps",
                         help="Plan steps: each foot stands until the body leaves it, then steps (legs by IK; docs/results.md, \"Feet\").")
SPEED_LIMIT = typer.Option(True, "--speed-limit/--no-speed-limit",
                           help="Spread turns and dashes faster than real dancers move over the frames around them.")
BPM = typer.Option(None, "--bpm", parser=Number("--bpm"), help="The song's tempo, if you know it (20-300): beats exactly 60/BPM s apart, "
                                       "placed on the song's onsets (default: the tracker's tempo).")
THREADS = typer.Option(None, "--threads", min=1, help="CPU threads to dance with (default: the CPUs this job may use "
                                                    "that other work leaves idle; OMP_NUM_THREADS is honoured). Set it "
                                                    "for bit-identical reruns: other thread counts round differently.")
BEATS = typer.Option(None, "--beats", help="Beat times to dance to: seconds one a line, or a CSV with a header "
                                           "(time\\[,downbeat]) as DAWs and beat trackers export.")
BEAT_TRACKER = typer.Option("choreo", "--beat-tracker",
                            help="Who hears the beats: choreo (default, licence-clean) or madmom (pip install "
                                 "\"choreo\\[madmom]\"; its models are CC BY-NC-SA 4.0: non-commercial use only).")


def generate(
    songs: List[Path] = typer.Argument(..., help="Audio files: wav, mp3, ogg, flac or opus."),
    output: Optional[List[str]] = typer.Option(
        None, "-o", "--output", help="Output motion file (.bvh, .npz, .json, .npy, .glb, .fbx) or - for stdout; repeat for several."),
    out_dir: Optional[Path] = typer.Option(None, help="Folder for one dance per song, named after the song (default: the current folder)."),
    style: Optional[str] = STYLE,
    seed_motion: Optional[Path] = typer.Option(None, help="Motion file whose frames open the dance; the rest continues it."),
    checkpoint: Optional[Path] = CHECKPOINT, generator: str = GENERATOR, steps: Optional[int] = STEPS,
    guidance: Optional[float] = GUIDANCE, style_guidance: Optional[float] = STYLE_GUIDANCE,
    sampler: Optional[str] = SAMPLER, seed: int = SEED,
    format: Optional[str] = typer.Option(None, "--format", "-f",
                                         help="Output format(s): with -o overrides the extension; with --out-dir a list like bvh,npz."),
    json_summary: bool = typer.Option(False, "--json", help="Print a machine-readable summary of every song on stdout."),
    preview: bool = typer.Option(False, "--preview", help="Also render OUTPUT-stem.mp4 (the dancer with the music) beside the output."),
    beat_lock: bool = BEAT_LOCK, foot_lock: bool = FOOT_LOCK, speed_limit: bool = SPEED_LIMIT, footsteps: bool = FOOTSTEPS,
    rig: Optional[str] = RIG, bpm: Optional[float] = BPM, beats: Optional[Path] = BEATS, beat_tracker: str = BEAT_TRACKER,
    threads: Optional[int] = THREADS,
    shard: Optional[str] = typer.Option(None, "--shard", help="With --out-dir: dance only shard K of N (K/N, 1-based) of the "
                                        "songs, e.g. 3/8 for a cluster array task; every song lands in exactly one shard."),
    skip_existing: bool = typer.Option(False, "--skip-existing", help="With --out-dir: skip songs whose outputs are all "
                                       "there already (a re-run after a failure or preemption does only what is missing)."),
) -> None:
    """Generate a dance for a song, or for many songs in one run.

    Exit codes: 0 every song danced; 1 some songs failed in a batch (each reported, the rest done);
    2 bad input or options; 3 an output cannot be written.

    Without -o or --out-dir each song's dance is written to the current folder, named after the
    song (song.mp3 -> song.bvh; --format bvh,npz for more).

    Examples:
      choreo generate song.mp3 --style waltz               # writes song.bvh here
      choreo generate song.mp3 -o dance.bvh --style waltz
      choreo generate song.mp3 -o dance.bvh -o dance.npz --style "slow, romantic, hips leading" --seed 7
      choreo generate song.mp3 -o dance.bvh --style 0:30=waltz,30:=cha-cha --seed-motion opening.bvh
      choreo generate songs/*.mp3 --out-dir out/ --format bvh,npz --json
      choreo generate songs/*.mp3 --out-dir out/ --shard 3/8 --skip-existing   # task 3 of an 8-task array
      choreo generate song.mp3 -o dance.bvh --preview      # and dance.mp4 to watch
      choreo generate song.mp3 -o dance.fbx --rig mixamo   # for a Mixamo character (needs Blender)
      choreo generate song.mp3 -o dance.bvh --bpm 128      # or --beats beats.csv: beats you know
    """
    import json

    from collections import Counter

    from ..errors import ChoreoError, OutputError, ParameterError
    from .batch import Shard, already_written, batch_formats

    if output is not None and out_dir is not None:
        raise ParameterError("give -o (one song) or --out-dir (any number of songs), not both")
    if output is None and out_dir is None:
        out_dir = Path(".")  # as whisper and most audio tools: SONG.bvh in the current folder
    if json_summary and output is not None and "-" in output:
        raise ParameterError("--json and -o - both write to standard output: choose one")
    if output is not None and len(songs) > 1:
        raise ParameterError(f"{len(songs)} songs need --out-dir, not -o")
    if out_dir is not None:
        formats = batch_formats(format, rig)
        if not out_dir.is_dir():
            raise OutputError(f"--out-dir {out_dir} is not a folder")  # an output that cannot be written: 3
        stems = Counter(song.stem for song in songs)
        clashes = sorted(stem for stem, count in stems.items() if count > 1)
        if clashes:
            raise ParameterError(f"songs named {clashes[0]!r} more than once would write the same files in --out-dir")
    elif shard is not None or skip_existing:
        raise ParameterError("--shard and --skip-existing split a batch: use them with --out-dir")
    if shard is not None:
        songs = Shard.parse(shard).select(songs)

    def outputs_for(song: Path) -> list[str]:
        return list(output) if output is not None else [str(out_dir / f"{song.stem}.{ext}") for ext in formats]

    def done_before(song: Path) -> bool:
        files = outputs_for(song)
        return already_written(files + [str(Path(files[0]).with_suffix(".mp4"))] if preview else files)

    def constraints(music):
        from ..constraints import Constraints, as_smpl
        from ..formats import read_motion

        if seed_motion is None:
            return None
        opening = as_smpl(read_motion(seed_motion), music.fps)
        return Constraints.none(music.num_frames, music.fps).fix_motion(opening.slice_frames(0, music.num_frames))

    guidance, sampler = sampling_flags(generator, steps, guidance, sampler, style_guidance, checkpoint, constrained=seed_motion is not None)
    settings = Settings(style, checkpoint, generator, steps, guidance, sampler, seed, format if output else None, preview,
                        beat_lock, foot_lock, rig=rig, speed_limit=speed_limit, footsteps=footsteps, style_guidance=style_guidance,
                        beats=beat_source(bpm, beats, beat_tracker), threads=threads)
    backend = load_backend(settings)
    summaries, failed = [], 0
    for song in songs:
        if skip_existing and done_before(song):
            summaries.append({"song": str(song), "ok": True, "skipped": True, "outputs": outputs_for(song)})
            continue
        try:
            summaries.append(dance_one(backend, song, outputs_for(song), settings, constraints))
        except Exception as error:  # noqa: BLE001 - in a batch, one song's failure, even a bug, must not stop the rest
            if len(songs) == 1 or isinstance(error, KeyboardInterrupt):
                raise
            failed += 1
            code = error.exit_code if isinstance(error, ChoreoError) else 70
            message = str(error) if isinstance(error, ChoreoError) else f"internal error ({type(error).__name__}: {error})"
            stderr_console.print(f"[red]failed[/red] {markup(song)}: {markup(message)}", highlight=False)
            summaries.append({"song": str(song), "ok": False, "error": message, "exit_code": code})
    if json_summary:
        print(json.dumps({"songs": summaries, "failed": failed}, indent=2))
    if failed:
        raise ChoreoError(f"{failed} of {len(songs)} songs failed")  # exit code 1


def inbetween(
    song: Path = SONG, output: List[str] = OUTPUT,
    start: Optional[str] = typer.Option(None, help="Pose on the first frame: FILE or FILE@FRAME (any motion file)."),
    end: Optional[str] = typer.Option(None, help="Pose on the last frame: FILE or FILE@FRAME."),
    key: List[str] = typer.Option([], help="Keyframe SECONDS=FILE\\[@FRAME]; repeat for several."),
    style: Optional[str] = STYLE, checkpoint: Optional[Path] = CHECKPOINT, generator: str = GENERATOR,
    steps: Optional[int] = STEPS, guidance: Optional[float] = GUIDANCE, style_guidance: Optional[float] = STYLE_GUIDANCE,
    sampler: Optional[str] = SAMPLER, seed: int = SEED,
    format: Optional[str] = FORMAT, beat_lock: bool = BEAT_LOCK, foot_lock: bool = FOOT_LOCK, speed_limit: bool = SPEED_LIMIT, footsteps: bool = FOOTSTEPS,
    rig: Optional[str] = RIG, bpm: Optional[float] = BPM, beats: Optional[Path] = BEATS, beat_tracker: str = BEAT_TRACKER,
    threads: Optional[int] = THREADS,
) -> None:
    """Dance between given poses: the first and last frame and keyframes at given times.

    Examples:
      choreo inbetween song.mp3 --start a.bvh --end b.bvh -o dance.bvh
      choreo inbetween song.mp3 --start a.bvh@-1 --key 4.0=pose.bvh --key 8.5=take2.npz@30 -o dance.bvh --style rumba
    """
    from ..errors import ParameterError

    if start is None and end is None and not key:
        raise ParameterError("give at least one of --start, --end or --key")

    def constraints(music):
        from ..constraints import Constraints, parse_time_key, read_pose

        fixed = Constraints.none(music.num_frames, music.fps)
        keys = [(0.0, start)] if start else []
        keys += [parse_time_key(k) for k in key]
        for seconds, spec in keys:
            frame = round(seconds * music.fps)
            if frame >= music.num_frames:
                raise ParameterError(f"keyframe at {seconds:g} s is past the song's end ({music.duration:.1f} s)")
            fixed.fix_motion(read_pose(spec), at=frame)
        if end:
            fixed.fix_motion(read_pose(end), at=music.num_frames - 1)
        return fixed

    guidance, sampler = sampling_flags(generator, steps, guidance, sampler, style_guidance, checkpoint, constrained=True)
    settings = Settings(style, checkpoint, generator, steps, guidance, sampler, seed, format, style_guidance=style_guidance,
                        beat_lock=beat_lock, foot_lock=foot_lock, rig=rig, speed_limit=speed_limit, footsteps=footsteps,
                        beats=beat_source(bpm, beats, beat_tracker), threads=threads)
    dance_one(load_backend(settings), song, output, settings, constraints)


def inpaint(
    song: Path = SONG, output: List[str] = OUTPUT,
    motion: Path = typer.Option(..., help="The dance to edit (any motion file, e.g. one this tool made)."),
    frames: Optional[str] = typer.Option(None, help="Frames to regenerate, START:END (end exclusive); default all."),
    joints: str = typer.Option("all", help="Joints to regenerate: upper, lower, all, or names/indices like l_wrist,21."),
    style: Optional[str] = STYLE, checkpoint: Optional[Path] = CHECKPOINT, generator: str = GENERATOR,
    steps: Optional[int] = STEPS, guidance: Optional[float] = GUIDANCE, style_guidance: Optional[float] = STYLE_GUIDANCE,
    sampler: Optional[str] = SAMPLER, seed: int = SEED,
    format: Optional[str] = FORMAT, beat_lock: bool = BEAT_LOCK, foot_lock: bool = FOOT_LOCK, speed_limit: bool = SPEED_LIMIT, footsteps: bool = FOOTSTEPS,
    rig: Optional[str] = RIG, bpm: Optional[float] = BPM, beats: Optional[Path] = BEATS, beat_tracker: str = BEAT_TRACKER,
    threads: Optional[int] = THREADS,
) -> None:
    """Regenerate a time range and/or a set of joints of an existing dance; the rest is kept exactly.

    Examples:
      choreo inpaint song.mp3 --motion dance.bvh --frames 60:120 -o fixed.bvh
      choreo inpaint song.mp3 --motion dance.bvh --joints upper -o new_arms.bvh --style "sharp, energetic arms"
    """
    from ..errors import ParameterError

    def constraints(music):
        from ..constraints import Constraints, as_smpl, parse_frame_range, parse_joints
        from ..formats import read_motion

        given = as_smpl(read_motion(motion), music.fps)
        fixed = Constraints.none(music.num_frames, music.fps).fix_motion(given.slice_frames(0, music.num_frames))
        region = parse_frame_range(frames, music.num_frames) if frames else slice(0, music.num_frames)
        chosen = parse_joints(joints)
        fixed.free(region, chosen, root=0 in chosen)
        if fixed.is_empty:
            raise ParameterError("nothing of the dance would be kept: use choreo generate instead")
        return fixed

    guidance, sampler = sampling_flags(generator, steps, guidance, sampler, style_guidance, checkpoint, constrained=True)
    settings = Settings(style, checkpoint, generator, steps, guidance, sampler, seed, format, style_guidance=style_guidance,
                        beat_lock=beat_lock, foot_lock=foot_lock, rig=rig, speed_limit=speed_limit, footsteps=footsteps,
                        beats=beat_source(bpm, beats, beat_tracker), threads=threads)
    dance_one(load_backend(settings), song, output, settings, constraints)


def trajectory(
    song: Path = SONG, output: List[str] = OUTPUT,
    path: Path = typer.Option(..., help="Root path on the floor: CSV (x,z or t,x,z; optional y) or a motion file."),
    style: Optional[str] = STYLE, checkpoint: Optional[Path] = CHECKPOINT, generator: str = GENERATOR,
    steps: Optional[int] = STEPS, guidance: Optional[float] = GUIDANCE, style_guidance: Optional[float] = STYLE_GUIDANCE,
    sampler: Optional[str] = SAMPLER, seed: int = SEED,
    format: Optional[str] = FORMAT, beat_lock: bool = BEAT_LOCK, foot_lock: bool = FOOT_LOCK, speed_limit: bool = SPEED_LIMIT, footsteps: bool = FOOTSTEPS,
    rig: Optional[str] = RIG, bpm: Optional[float] = BPM, beats: Optional[Path] = BEATS, beat_tracker: str = BEAT_TRACKER,
    threads: Optional[int] = THREADS,
) -> None:
    """Dance along a root path on the floor, stretched over the whole song.

    Examples:
      choreo trajectory song.mp3 --path circle.csv -o dance.bvh --style waltz
      choreo trajectory song.mp3 --path other_dance.bvh -o dance.bvh
    """
    def constraints(music):
        from ..constraints import Constraints, path_to_frames, read_root_path

        xz, heights = path_to_frames(*read_root_path(path), music.num_frames)
        return Constraints.none(music.num_frames, music.fps).fix_root_path(xz, heights)

    guidance, sampler = sampling_flags(generator, steps, guidance, sampler, style_guidance, checkpoint, constrained=True)
    settings = Settings(style, checkpoint, generator, steps, guidance, sampler, seed, format, style_guidance=style_guidance,
                        beat_lock=beat_lock, foot_lock=foot_lock, rig=rig, speed_limit=speed_limit, footsteps=footsteps,
                        beats=beat_source(bpm, beats, beat_tracker), threads=threads)
    dance_one(load_backend(settings), song, output, settings, constraints)


@dataclass(frozen=True)
class Settings:
    """The sampling options every generating command shares."""

    style: str | None
    checkpoint: Path | None
    generator: str
    steps: int | None  # None: the backend's default (as for guidance and sampler)
    guidance: float | None
    sampler: str | None
    seed: int
    format: str | None
    preview: bool = False  # render an MP4 with the music beside the first output file
    beat_lock: bool = True  # finishing: motion beats re-timed onto the music's beats
    foot_lock: bool = False  # finishing: planted feet's drift moved onto the root (measured: off)
    rig: str | None = None  # write .bvh/.fbx retargeted onto this rig (mixamo); None: SMPL-24
    speed_limit: bool = True  # finishing: joints and root no faster than real dancers move
    style_guidance: float | None = None  # None: the backend's default
    beats: BeatSource | None = None  # --bpm or --beats; None: the tracker's beats
    threads: int | None = None  # --threads; None: choreo.threads decides per dance
    footsteps: bool = True  # finishing: the step planner (choreo.finishing.steps)


def beat_source(bpm: float | None, beats: Path | None, tracker: str = "choreo") -> BeatSource:
    """The BeatSource of --bpm / --beats / --beat-tracker, checked (the file read, madmom found)
    before any work."""
    from ..music.beat_source import BeatSource

    return BeatSource.from_options(bpm, beats, tracker)


def sampling_flags(generator: str, steps: int | None, guidance: float | None, sampler: str | None,
                   style_guidance: float | None = None, checkpoint: Path | None = None, constrained: bool = False) -> tuple:
    """The sampling flags given (None: the backend's default), checked against the backend's own
    options before any work: a flag it does not take, a value it refuses, steps the bundled
    checkpoint's chain cannot take (another checkpoint's are checked once it loads), or constraints
    it cannot keep, are a one-line error naming the backend."""
    from ..errors import ParameterError
    from ..generator import available_plugins
    from ..generator.options import option_names, parse_options

    plugin = available_plugins().get(generator)
    if plugin is None or plugin.factory is None:
        raise ParameterError(f"generator {generator!r} is not available (see choreo generators)")
    takes = option_names(plugin.options) if plugin.options else []
    values = {flag: value for flag, value in (("steps", steps), ("guidance", guidance), ("sampler", sampler),
                                              ("style_guidance", style_guidance)) if value is not None}
    given = [flag for flag in values if flag not in takes]
    if given:
        flags = ", ".join(f"--{flag.replace('_', '-')}" for flag in given)
        raise ParameterError(f"{flags} {'is not an option' if len(given) == 1 else 'are not options'} of {generator}"
                             f" (its options: {', '.join(takes) or 'none'})")
    if values:
        chosen = parse_options(generator, plugin.options, values)  # their values too (--guidance 1e308), before any work
        chain = getattr(chosen, "bundled_timesteps", None)
        if checkpoint is None and chain is not None:
            try:
                chosen.on_chain(chain, steps is not None)  # --steps 1001, or ddpm with --steps 10
            except ValueError as error:
                raise ParameterError(f"{generator}: {error}") from None
    if constrained:
        from ..pipeline import check_request

        check_request(generator, {}, constrained=True)
    return guidance, sampler


def guidance_summary(meta: dict) -> str:
    """'guidance 2', plus the style's weight where a style was guided."""
    styled = meta.get("style") and meta.get("style_guidance", 1.0) != 1.0
    return f"guidance {meta['guidance']:g}" + (f", style guidance {meta['style_guidance']:g}" if styled else "")


def load_backend(settings: Settings, **factory_options):
    """The backend, checked now and loaded once the first song is analysed (PendingBackend)."""
    from ..pipeline import PendingBackend

    return PendingBackend(settings.generator, settings.checkpoint, **factory_options)


def dance_one(backend, song: Path, output: list[str], settings: Settings, build_constraints: Callable | None = None) -> dict:
    """Analyse one song, build its constraints, dance, write every output atomically; a summary."""
    from ..errors import ParameterError
    from ..fileio import output_target
    from ..formats import check_output_format, write_motions
    from ..music import BeatSource, Music
    from ..pipeline import Finishing, dance

    if output.count("-") > 1 or (len(output) > 1 and settings.format):
        raise ParameterError("with several outputs, name each by its extension (and at most one '-')")
    for path in output:
        if path != "-":
            output_target(path)  # a writable folder, and nothing there that is not a regular file
        check_output_format(path, settings.format, settings.rig)  # every output checked before any work or any file
    with progress_bar(f"analysing {song.name}") as update:
        music = Music.from_file(song, progress=lambda done, total: update(round(done), round(total)),
                                log_mel=backend.listens_to_spectrum,  # one decode for every analysis
                                timbre=backend.reads_timbre, beats=settings.beats or BeatSource())
    constraints = build_constraints(music) if build_constraints else None
    given = {"steps": settings.steps, "guidance": settings.guidance, "sampler": settings.sampler,
             "style_guidance": settings.style_guidance}
    options = {name: value for name, value in given.items() if value is not None}  # the rest: the backend's defaults
    started = time.perf_counter()
    with progress_bar("dancing", 100) as update:
        motion = dance(music, backend, style=settings.style, seed=settings.seed, options=options, constraints=constraints,
                       finishing=Finishing(settings.beat_lock, settings.foot_lock, settings.speed_limit, settings.footsteps),
                       threads=settings.threads,
                       progress=lambda fraction: update(round(fraction * 100), 100))
    seconds = time.perf_counter() - started
    meta = motion.metadata
    if meta.get("style_notice"):
        stderr_console.print(f"[yellow]note:[/yellow] {markup(meta['style_notice'])}", highlight=False)
    written = [path for path in output if path != "-"]
    companions = {}
    if settings.preview and written:  # the video joins the motions' all or nothing
        from ..render import RenderConfig
        from .render_command import render_preview

        video = str(Path(written[0]).with_suffix(".mp4"))
        companions[video] = lambda temporary: render_preview(motion, temporary, RenderConfig(), song)
    write_motions(motion, output, format=settings.format, rig=settings.rig, companions=companions)
    written += list(companions)
    if written:
        kept = f", {constraints.describe()}" if constraints else ""
        how = (f"{meta.get('sampler')} {meta.get('steps')} steps, {guidance_summary(meta)}, seed {settings.seed}"
               if meta.get("sampler") else f"K = {meta.get('top_k')}, repertoire {meta.get('repertoire')}")
        done = (f"wrote {', '.join(written)}: {motion.duration:.1f} s of {meta.get('genre') or 'dance'} at "
                f"{motion.fps:g} fps ({settings.generator}, {how}{kept}; {seconds:.1f} s)")
        stderr_console.print(markup(done), highlight=False)
    return {"song": str(song), "ok": True, "outputs": written, "seconds_of_dance": round(motion.duration, 3),
            "frames": motion.num_frames, "fps": motion.fps, "genre": meta.get("genre"), "seed": settings.seed,
            "steps": meta.get("steps"), "generation_seconds": round(seconds, 3)}
