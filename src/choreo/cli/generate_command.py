"""`choreo generate` and the controllable commands built on it: inbetween, inpaint, trajectory.

Each builds the constraints it keeps (a function of the analysed song) and hands them, with one
request, to :func:`~choreo.cli.dancing.dance_one`; the options they share are declared once, in
:mod:`choreo.cli.dancing`.
"""

from __future__ import annotations

from functools import partial
from pathlib import Path
from typing import List, Optional

import typer

from .dancing import LOOP, OUTPUT, PREVIEW, SONG, DanceFlags, dance_one, dancing_command
from .progress import stderr_console
from .text import markup


@dancing_command("sgmd")
def generate(
    songs: List[Path] = typer.Argument(..., help="Audio files: wav, mp3, ogg, flac or opus."),
    output: Optional[List[str]] = typer.Option(
        None, "-o", "--output", help="Output motion file (.bvh, .npz, .json, .npy, .glb, .fbx) or - for stdout; repeat for several."),
    out_dir: Optional[Path] = typer.Option(None, help="Folder for one dance per song, named after the song (default: the current folder)."),
    seed_motion: Optional[Path] = typer.Option(None, help="Motion file whose frames open the dance; the rest continues it, at the motion's "
                                           "frame rate unless --fps says otherwise."),
    loop: bool = LOOP,
    json_summary: bool = typer.Option(False, "--json", help="Print a machine-readable summary of every song on stdout."),
    preview: bool = PREVIEW,
    shard: Optional[str] = typer.Option(None, "--shard", help="With --out-dir: dance only shard K of N (K/N, 1-based) of the "
                                        "songs, e.g. 3/8 for a cluster array task; every song lands in exactly one shard."),
    skip_existing: bool = typer.Option(False, "--skip-existing", help="With --out-dir: skip songs whose outputs are all "
                                       "there already (a re-run after a failure or preemption does only what is missing)."),
    dance: DanceFlags = None,
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
      choreo generate song.mp3 -o emote.glb --loop --in-place --fps 60   # a looping emote for a game
    """
    import json

    from collections import Counter

    from ..errors import ChoreoError, ParameterError
    from ..fileio import json_safe, make_output_folder
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
        formats = batch_formats(dance.format, dance.delivery.rig)
        stems = Counter(song.stem for song in songs)
        clashes = sorted(stem for stem, count in stems.items() if count > 1)
        if clashes:
            raise ParameterError(f"songs named {clashes[0]!r} more than once would write the same files in --out-dir")
        make_output_folder(out_dir)  # with its parents, as mkdir -p; something else there: exit 3
    elif shard is not None or skip_existing:
        raise ParameterError("--shard and --skip-existing split a batch: use them with --out-dir")
    if shard is not None:
        songs = Shard.parse(shard).select(songs)

    def outputs_for(song: Path):
        if output is not None:
            return dance.outputs(list(output), preview, fps=fps, inputs=(seed_motion,))
        return dance.outputs([str(out_dir / f"{song.stem}.{ext}") for ext in formats], preview, format=False, fps=fps,
                             inputs=(seed_motion, *songs))

    def done_before(song: Path) -> bool:
        files = outputs_for(song).paths
        return already_written(files + [str(Path(files[0]).with_suffix(".mp4"))] if preview else files)

    from ..constraints import seed_motion as opening_with
    from ..formats import read_motion

    request = dance.request(constrained=seed_motion is not None, loop=loop)
    opening = read_motion(seed_motion) if seed_motion is not None else None  # a bad file before any work
    fps = opening.fps if opening is not None else None  # a dance that continues a motion keeps its rate
    summaries, failed = [], 0
    for song in songs:
        if skip_existing and done_before(song):
            summaries.append({"song": str(song), "ok": True, "skipped": True, "outputs": outputs_for(song).paths})
            continue
        try:
            summaries.append(dance_one(request, song, outputs_for(song),
                                       partial(opening_with, motion=opening) if opening is not None else None))
        except Exception as error:  # noqa: BLE001 - in a batch, one song's failure, even a bug, must not stop the rest
            if len(songs) == 1 or isinstance(error, KeyboardInterrupt):
                raise
            failed += 1
            code = error.exit_code if isinstance(error, ChoreoError) else 70
            message = str(error) if isinstance(error, ChoreoError) else f"internal error ({type(error).__name__}: {error})"
            stderr_console.print(f"[red]failed[/red] {markup(song)}: {markup(message)}", highlight=False)
            summaries.append({"song": str(song), "ok": False, "error": message, "exit_code": code})
    if json_summary:
        print(json.dumps(json_safe({"songs": summaries, "failed": failed}), indent=2))  # names not UTF-8: \xNN
    if failed:
        raise ChoreoError(f"{failed} of {len(songs)} songs failed")  # exit code 1


@dancing_command("sgmd")
def inbetween(
    song: Path = SONG, output: List[str] = OUTPUT,
    start: Optional[str] = typer.Option(None, help="Pose on the first frame: FILE or FILE@FRAME (any motion file)."),
    end: Optional[str] = typer.Option(None, help="Pose on the last frame: FILE or FILE@FRAME."),
    key: List[str] = typer.Option([], help="Keyframe SECONDS=FILE\\[@FRAME]; repeat for several."),
    dance: DanceFlags = None,
) -> None:
    """Dance between given poses: the first and last frame and keyframes at given times.

    Examples:
      choreo inbetween song.mp3 --start a.bvh --end b.bvh -o dance.bvh
      choreo inbetween song.mp3 --start a.bvh@-1 --key 4.0=pose.bvh --key 8.5=take2.npz@30 -o dance.bvh --style rumba
    """
    from ..constraints import between_poses, parse_time_key, read_pose
    from ..constraints.parse import pose_file
    from ..errors import ParameterError

    if start is None and end is None and not key:
        raise ParameterError("give at least one of --start, --end or --key")
    request = dance.request(constrained=True)
    timed = [parse_time_key(k) for k in key]
    poses = partial(between_poses, start=read_pose(start) if start else None, end=read_pose(end) if end else None,
                    keys=[(seconds, read_pose(spec)) for seconds, spec in timed])
    files = tuple(pose_file(spec)[0] for spec in [start, end, *(spec for _, spec in timed)] if spec)
    dance_one(request, song, dance.outputs(output, inputs=files), poses)


@dancing_command("sgmd")
def inpaint(
    song: Path = SONG, output: List[str] = OUTPUT,
    motion: Path = typer.Option(..., help="The dance to edit (any motion file, e.g. one this tool made)."),
    frames: Optional[str] = typer.Option(None, help="Frames to regenerate, START:END in the motion's own frames (end exclusive); default all. "
                                         "The dance is written at the motion's frame rate unless --fps says otherwise."),
    joints: str = typer.Option("all", help="Joints to regenerate: upper, lower, all, or names/indices like l_wrist,21."),
    dance: DanceFlags = None,
) -> None:
    """Regenerate a time range and/or a set of joints of an existing dance; the rest is kept exactly.

    Examples:
      choreo inpaint song.mp3 --motion dance.bvh --frames 60:120 -o fixed.bvh
      choreo inpaint song.mp3 --motion dance.bvh --joints upper -o new_arms.bvh --style "sharp, energetic arms"
    """
    from ..constraints import inpainting, parse_frame_range, parse_joints
    from ..formats import read_motion

    request = dance.request(constrained=True)
    given = read_motion(motion)  # a bad file before any work
    region = parse_frame_range(frames, given.num_frames) if frames else None
    edit = partial(inpainting, motion=given, frames=region, joints=parse_joints(joints))
    dance_one(request, song, dance.outputs(output, fps=given.fps, inputs=(motion,)), edit)


@dancing_command("sgmd")
def trajectory(
    song: Path = SONG, output: List[str] = OUTPUT,
    path: Path = typer.Option(..., help="Root path on the floor: CSV (x,z or t,x,z; optional y) or a motion file."),
    dance: DanceFlags = None,
) -> None:
    """Dance along a root path on the floor, stretched over the whole song.

    Examples:
      choreo trajectory song.mp3 --path circle.csv -o dance.bvh --style waltz
      choreo trajectory song.mp3 --path other_dance.bvh -o dance.bvh
    """
    from ..constraints import along_path

    dance_one(dance.request(constrained=True), song, dance.outputs(output, inputs=(path,)), partial(along_path, path=path))
