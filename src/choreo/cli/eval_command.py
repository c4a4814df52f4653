"""`choreo eval`: the field's metrics on folders of motion files."""

from __future__ import annotations

import json
import warnings
from pathlib import Path
from typing import Optional

import typer

from .numbers import Number
from .progress import progress_bar, stderr_console, stdout_console


def _find_music(motion_path: Path, music_dir: Path | None) -> Path | None:
    from ..datasets.bvh_folder import find_audio_beside

    if music_dir is not None:
        return find_audio_beside(music_dir / motion_path.name)
    return find_audio_beside(motion_path)


def _load_dances(files: list[Path], fps: float, up: str, music_dir: Path | None, update, offset: int, total: int):
    import numpy as np

    from ..metrics import Dance, resample_positions
    from ..formats import read_joint_positions
    from ..music import Music
    from ..music.form import music_self_similarity
    from ..metrics.pfc import from_z_up

    dances, notes = [], []
    for i, path in enumerate(files):
        positions, file_fps = read_joint_positions(path)
        if up == "z":  # the metrics take Y up
            positions = from_z_up(positions)
        if file_fps is not None and not np.isclose(file_fps, fps):
            positions = resample_positions(positions, file_fps, fps)
            notes.append(f"{path.name}: resampled from {file_fps:g} to {fps:g} fps")
        audio = _find_music(path, music_dir)
        beats = bars = None
        if audio is not None:
            music = Music.from_file(audio)
            beats = np.round(music.beat_times * fps).astype(int)
            beats = beats[beats < len(positions)]
            lines, alike = music_self_similarity(music, 4)
            bars = (lines * fps, alike)
        dances.append(Dance(path.stem, positions, beats, bars))
        update(offset + i + 1, total, path.name)
    return dances, notes


def evaluate(
    generated: Path = typer.Argument(..., help="Generated motion: a file or a folder of .bvh/.npz/.pkl/.json/.npy."),
    gt: Path = typer.Option(..., "--gt", help="Ground-truth motion: a file or a folder, same formats."),
    music: Optional[Path] = typer.Option(None, help="Folder of songs named like the motions (default: beside them)."),
    fps: float = typer.Option(30.0, parser=Number("--fps"), help="Evaluation frame rate (10 to 240); other files are resampled, .npy are taken as this."),
    up: str = typer.Option("y", help="Up axis of .npy joint arrays and all inputs: y (ours, AIST++) or z (EDGE)."),
    json_path: Optional[Path] = typer.Option(None, "--json", help="Write every figure and per-file scores here."),
) -> None:
    """Score dances with BeatAlign, PFC, FID_k, FID_g, Div_k, Div_g, the two beat distances, stepping,
    the legs, a classifier test and the form score (docs/metrics.md).

    FID and diversity features are normalised by the ground-truth set, as in Bailando.
    BeatAlign and the form score need music: a song with the motion's name beside it or in --music
    (the form score reads bars of four beats).

    Examples:
      choreo eval out/ --gt data/test_clips/ --music songs/
      choreo eval dance.npy --gt reference/ --json scores.json
    """
    from ..errors import ParameterError
    from ..metrics import MetricWarning
    from ..metrics import evaluate as run_evaluation
    from ..metrics.evaluate import collect_motion_files
    from ..motion.delivery_options import check_fps
    from .text import markup

    if up not in ("y", "z"):
        raise ParameterError(f"--up must be y or z, got {up!r}")
    check_fps(fps)  # the range every command takes (inf overflowed the resampling: exit 70)
    if music is not None and not music.is_dir():
        raise ParameterError(f"--music {music} is not a folder")
    generated_files, truth_files = collect_motion_files(generated), collect_motion_files(gt)
    total = len(generated_files) + len(truth_files)
    with warnings.catch_warnings(record=True) as caught, progress_bar("reading motions", total) as update:
        warnings.simplefilter("always", MetricWarning)
        dances, notes = _load_dances(generated_files, fps, up, music, update, 0, total)
        truth, truth_notes = _load_dances(truth_files, fps, up, music, update, len(generated_files), total)
        report = run_evaluation(dances, truth, fps)
    messages = sorted({str(w.message) for w in caught if issubclass(w.category, MetricWarning)})
    for message in messages:
        stderr_console.print(f"[yellow]warning:[/yellow] {markup(message)}")
    _print_report(report)
    if json_path is not None:
        from ..fileio import atomic_output, json_safe

        document = {"generated": str(generated), "ground_truth": str(gt), **report.to_dict(),
                    "notes": notes + truth_notes, "warnings": messages}
        with atomic_output(json_path) as handle:
            handle.write(json.dumps(json_safe(document), indent=1, default=_json_default).encode())
        stderr_console.print(f"wrote {markup(json_path)}")


def _json_default(value):
    import numpy as np

    if isinstance(value, (np.floating, np.integer)):
        return value.item()
    raise TypeError(type(value))


def _fmt(value) -> str:
    import math

    return "-" if value is None or (isinstance(value, float) and not math.isfinite(value)) else f"{value:.4g}"


def _print_report(report) -> None:
    from rich.table import Table

    table = Table("metric", f"generated ({report.generated_count})", f"ground truth ({report.ground_truth_count})")
    rows = [
        ("BeatAlign (higher is better)", report.beat_align, report.ground_truth_beat_align),
        ("PFC x 10^4 (lower is better)", report.pfc, report.ground_truth_pfc),
        ("FID_k", report.fid_k, None), ("FID_g", report.fid_g, None),
        ("Div_k", report.div_k, report.ground_truth_div_k), ("Div_g", report.div_g, report.ground_truth_div_g),
        ("beat distance motion->music (frames^2)", report.motion_to_music, None),
        ("beat distance music->motion (frames^2)", report.music_to_motion, None),
        ("planted foot, share of frames", report.planted_share, report.ground_truth_planted_share),
        ("faster foot ~ root speed (correlation)", report.foot_root_correlation, report.ground_truth_foot_root_correlation),
        ("support foot slide (m per m travelled)", report.support_slide, report.ground_truth_support_slide),
        ("feet speed around the pelvis (m/s)", report.legs.feet_speed, report.ground_truth_legs.feet_speed),
        ("ankle lift (m)", report.legs.ankle_lift, report.ground_truth_legs.ankle_lift),
        ("pelvis speed (m/s)", report.legs.pelvis_speed, report.ground_truth_legs.pelvis_speed),
        ("foot jerk (m/s^3)", report.legs.foot_jerk, report.ground_truth_legs.foot_jerk),
        ("classifier test, balanced accuracy (0.5: indistinguishable)", report.classifier.accuracy, None),
        ("form score (bar self-similarity ~ the music's)", report.form_score, report.ground_truth_form_score),
    ]  # fmt: skip
    for name, generated, truth in rows:
        table.add_row(name, _fmt(generated), _fmt(truth))
    stdout_console.print(table)
    stdout_console.print(f"{report.fps:g} fps, mean clip {report.mean_clip_seconds:.1f} s; "
                         "FID/Div features normalised by the ground truth set")
