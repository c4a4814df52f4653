"""Command implementations: parse, validate, call the library, print."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from ..motion.delivery_options import Delivery
from ..form.options import FormOptions
from ..music.beat_options import BeatOptions
from .flags import flag_parameters, given_values, with_parameters
from .progress import progress_bar, stderr_console, stdout_console
from .text import markup

AUDIO_EXTENSIONS = (".wav", ".mp3", ".ogg", ".flac", ".opus")


def _require_file(path: Path) -> Path:
    from ..errors import InputError

    if str(path) == "-":  # stdin: the motion readers take it
        return path
    if not path.exists():
        raise InputError(f"{path}: no such file")
    if path.is_dir():
        raise InputError(f"{path} is a folder, expected a file")
    return path


def info(
    path: Path = typer.Argument(..., help="A motion file (bvh, npz, pkl, npy, json, glb; - reads stdin) or an audio file."),
    json_output: bool = typer.Option(False, "--json", help="Print the facts as one JSON object on stdout."),
    **flags,
) -> None:
    """Describe a motion file (duration, fps, joints) or a song (duration, tempo, beats, form).

    A song's beats are the ones the dancing commands would use with the same --bpm, --beats or
    --beat-tracker; its form (sections as letters, a letter that comes back is a return) the one
    they would dance to, or the one --form gives.

    Examples:
      choreo info dance.bvh
      choreo info examples/drum_and_bass_174bpm.wav
      choreo info song.mp3 --bpm 128                      # the beats choreo generate --bpm 128 dances to
      choreo info song.mp3 --beat-tracker madmom          # madmom's beats (the madmom extra; non-commercial)
      choreo info song.mp3 --json                         # sections with their times, for a script
      choreo generate song.mp3 -o - -f npz | choreo info -
    """
    _require_file(path)
    from ..errors import ParameterError

    is_song = path.suffix.lower() in AUDIO_EXTENSIONS
    beat_options = BeatOptions(**given_values(BeatOptions, flags))
    form_options = FormOptions(form=flags.pop("form", None))
    if not is_song and (beat_options.given or form_options.given):
        raise ParameterError("--bpm, --beats, --beat-tracker and --form describe a song, not a motion file")
    facts = song_facts(path, beat_options, form_options) if is_song else motion_facts(path)
    if json_output:
        import json

        from ..fileio import json_safe

        print(json.dumps(json_safe({key: value for key, (value, _) in facts.items()}), indent=1))
        return
    from rich.table import Table

    table = Table(show_header=False, box=None)
    for key, (_, shown) in facts.items():
        table.add_row(key, markup(shown))
    stdout_console.print(table)


def song_facts(path: Path, beat_options: BeatOptions, form_options) -> dict:
    """A song's facts: name -> (value for --json, text for the table)."""
    from ..music import Music
    from ..music.form import analyse_form

    source = beat_options.source()
    with progress_bar(f"analysing {path.name}") as update:
        music = Music.from_file(path, progress=lambda done, total: update(round(done), round(total)),
                                timbre=not form_options.given, beats=source)
    first, stop = music.audible
    form = form_options.of(music) if form_options.given else analyse_form(music)
    return {
        "file": (str(path), str(path)),
        "kind": ("audio", "audio"),
        "duration": (round(music.duration, 3), f"{music.duration:.2f} s"),
        "tempo": (round(music.tempo, 2), f"{music.tempo:.1f} bpm"),
        "beats": (len(music.beat_times), f"{len(music.beat_times)} ({music.beat_source})"),
        "beat times": ([round(float(t), 3) for t in music.beat_times], _first_times(music.beat_times)),
        "music": ([round(first / music.fps, 3), round(stop / music.fps, 3)],
                  f"{first / music.fps:.2f}-{stop / music.fps:.2f} s (quieter around it: 40 dB under its loud parts)"),
        "form": (form.as_json(), f"{form.describe()} ({form.source})"),
        "feature frames": (music.num_frames, f"{music.num_frames} at {music.fps:g} fps"),
    }


def motion_facts(path: Path) -> dict:
    """A motion file's facts: name -> (value for --json, text for the table)."""
    from ..formats import read_motion

    motion = read_motion(path)
    positions = motion.joint_positions()
    extent = positions.max(axis=(0, 1)) - positions.min(axis=(0, 1))
    facts = {
        "file": (str(path), str(path)),
        "kind": ("motion", "motion"),
        "frames": (motion.num_frames, str(motion.num_frames)),
        "fps": (motion.fps, f"{motion.fps:g}"),
        "duration": (round(motion.duration, 3), f"{motion.duration:.2f} s"),
        "joints": (list(motion.skeleton.names), f"{motion.num_joints} ({', '.join(motion.skeleton.names[:4])}, ...)"),
        "extent": ([round(float(e), 3) for e in extent], f"x {extent[0]:.2f} m, y {extent[1]:.2f} m, z {extent[2]:.2f} m"),
    }
    form = motion.metadata.get("form")
    if form:
        from ..music.form import clock

        facts["form"] = (form, ", ".join(f"{section['label']} {clock(section['start'])}" for section in form))
    return facts


with_parameters(info, flag_parameters(BeatOptions, given_only=False) + flag_parameters(FormOptions, given_only=False)[:1])


def _first_times(times, shown: int = 8) -> str:
    """'0.52 0.87 1.22 ... s': the first beats, enough to check them against a DAW."""
    if len(times) == 0:
        return "none"
    more = " ..." if len(times) > shown else ""
    return " ".join(f"{t:.3f}" for t in times[:shown]) + more + " s"


def convert(
    source: Path = typer.Argument(..., help="Input motion: .bvh, .npz (AIST++ keys), .pkl (AIST++), .json, .glb; - reads stdin."),
    target: str = typer.Argument(..., help="Output path, or - for stdout (needs --format)."),
    format: Optional[str] = typer.Option(None, "--format", "-f", help="Output format; default from the extension."),
    **flags,
) -> None:
    """Convert a motion between BVH, NPZ, AIST++ pkl, JSON, joint-position .npy, glTF (.glb) and FBX.

    Examples:
      choreo convert gBR_sBM_cAll_d04_mBR0_ch01.pkl dance.bvh --fps 30
      choreo convert dance.bvh dance.npz
      choreo convert dance.bvh - --format json | head
      choreo convert dance.bvh dance.fbx --rig mixamo      # FBX needs Blender
      choreo convert dance.bvh idle.glb --in-place --fps 60  # for a game engine
      choreo convert dance.bvh dance.fbx --rig mixamo --root-motion  # Unreal's root motion
    """
    from ..formats import check_output_format, read_motion, write_motion
    from ..fileio import check_outputs_apart
    from ..formats.registry import dropped_metadata

    delivery = Delivery(**given_values(Delivery, flags))  # the frame rate's range before resampling allocates frames
    check_output_format(target, format, delivery.rig, delivery.root_motion)  # a bad target or rig before any reading
    check_outputs_apart([target], [source])
    motion = delivery.of(read_motion(_require_file(source)))
    written = write_motion(motion, target, format=format, rig=delivery.rig, root_motion=delivery.root_motion)
    dropped = dropped_metadata(motion, target, format)
    if dropped:
        from . import print_note

        keys = ", ".join(key[:40] for key in dropped[:6]) + (", ..." if len(dropped) > 6 else "")
        name = written if target != "-" else f"the {format.lower().lstrip('.')} on stdout"
        print_note(f"{name} cannot hold the dance's metadata ({keys}): dropped")
    if target != "-":
        stderr_console.print(f"wrote {markup(written)} ({motion.num_frames} frames at {motion.fps:g} fps)",
                             highlight=False)


with_parameters(convert, flag_parameters(Delivery, given_only=False))


def generators() -> None:
    """List the installed generator backends (plugins in the `choreo.generators` entry-point group).

    Example:
      choreo generators
    """
    from ..generator import available_plugins

    from rich.table import Table

    table = Table("name", "ready", "what it does")
    for plugin in available_plugins().values():
        ready = "yes" if plugin.ready else f"no - {plugin.status}"
        table.add_row(markup(plugin.name), markup(ready), markup(plugin.summary))
    stdout_console.print(table)


def prepare(
    root: Path = typer.Argument(..., help="Dataset folder: M2D, AIST++ or BVH files with audio beside them."),
    kind: Optional[str] = typer.Option(None, help="m2d, aistpp or bvh; detected from the layout if omitted."),
    split: Optional[str] = typer.Option(None, help="train, test or all (default all)."),
    window: float = typer.Option(5.0, help="Window length in seconds."),
    stride: float = typer.Option(2.5, help="Window stride in seconds."),
) -> None:
    """Load a dataset once (fitting rotations, computing and caching music features) and summarise it.

    Examples:
      choreo prepare ../shared/data/m2d
      choreo prepare ~/data/aistpp --split test --stride 0.5
    """
    from ..datasets import WindowConfig, WindowedDataset, load_dataset

    with progress_bar(f"loading {root.name}") as update:
        clips = load_dataset(root, kind=kind, split=split, progress=lambda done, total, name: update(done, total, name))
    windows = WindowedDataset(clips, WindowConfig(seconds=window, stride_seconds=stride))
    from rich.table import Table

    table = Table("clip", "genre", "split", "frames", "seconds")
    for clip in clips:
        table.add_row(markup(clip.name), markup(clip.genre or "-"), markup(clip.split or "-"),
                      str(clip.motion.num_frames), f"{clip.motion.duration:.1f}")
    stdout_console.print(table)
    total_seconds = sum(c.motion.duration for c in clips)
    stdout_console.print(f"{len(clips)} clips, {total_seconds / 60:.1f} min, {len(windows)} windows of {window:g} s "
                         f"(stride {stride:g} s)")
