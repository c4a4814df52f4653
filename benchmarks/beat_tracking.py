"""Beat tracking side by side on songs whose beat grid is known exactly (LMMS's demo songs).

    python benchmarks/beat_tracking.py [--external beatnet.json] [--m2d ../shared/data/m2d]

Ground truth: an LMMS project plays at one stated tempo from tick 0, so its beats are at
k * 60 / bpm seconds (the onset strength folded at that period peaks 8-26 ms after the grid in
19 of the 25 songs; the other six have their strongest onsets between beats). Scores, as MIREX
reports them: Acc1 = tempo within 4 %, Acc2 = also at 2, 1/2, 3 or 1/3 of it, and the beat
F-measure with a 70 ms window (mir_eval; beats in the first 5 s are left out).

Trackers: choreo (choreo.music: 96 fps envelope, metrical tempo, percussive phase), choreo's
previous tracker (30 fps envelope, tempogram tempo, the same dynamic programme), librosa's
beat_track with its defaults, librosa's PLP (peaks of the predominant local pulse), and, where
the madmom extra is installed, madmom's RNN + DBN (``--beat-tracker madmom``).
``--external FILE`` adds trackers that cannot be installed cleanly here, from a JSON of beat
times per song stem ({"song": {"name_beats": [...]}}): BeatNet was measured that way.
``--m2d`` also prints real M2D dancers' BeatAlign against each choreo tracker's beats.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import librosa
import mir_eval
import numpy as np

from choreo.errors import ParameterError
from choreo.music import Music, load_audio
from choreo.music import madmom_tracker

from outside_songs import outside_songs

ACC2_MULTIPLES = (1.0, 2.0, 0.5, 3.0, 1.0 / 3.0)


def tempo_matches(estimate: float, truth: float, multiples=(1.0,)) -> bool:
    return any(abs(estimate - truth * m) <= 0.04 * truth * m for m in multiples)


def beat_f_measure(estimate: np.ndarray, truth: np.ndarray) -> float:
    trim = mir_eval.beat.trim_beats
    return float(mir_eval.beat.f_measure(trim(np.asarray(truth, float)), trim(np.asarray(estimate, float)), 0.07))


def previous_tracker(music: Music) -> tuple[float, np.ndarray]:
    """choreo's tracker before the 96 fps one: tempogram tempo on the 30 fps onset column."""
    onset = music.features[:, 0].astype(np.float64)
    sr = music.fps * 512
    tempogram = librosa.feature.tempogram(onset_envelope=onset, sr=sr, hop_length=512).mean(axis=1, keepdims=True)
    tempo = float(np.atleast_1d(librosa.feature.tempo(tg=tempogram, sr=sr, hop_length=512, start_bpm=120.0))[0])
    _, beats = librosa.beat.beat_track(onset_envelope=onset, sr=sr, hop_length=512, bpm=tempo, tightness=100.0, units="time")
    return tempo, beats


def librosa_default(samples: np.ndarray) -> tuple[float, np.ndarray]:
    tempo, beats = librosa.beat.beat_track(y=samples, sr=22050, units="time")
    return float(np.atleast_1d(tempo)[0]), beats


def librosa_plp(samples: np.ndarray) -> tuple[float, np.ndarray]:
    pulse = librosa.beat.plp(y=samples, sr=22050)
    beats = librosa.frames_to_time(np.flatnonzero(librosa.util.localmax(pulse)), sr=22050)
    return tempo_of(beats), beats


def tempo_of(beats: np.ndarray) -> float:
    return 60.0 / float(np.median(np.diff(beats))) if len(beats) > 1 else 0.0


def madmom_available() -> bool:
    try:
        madmom_tracker.load_madmom()
    except ParameterError:
        print("madmom not installed: its row is left out (pip install \"choreo[madmom]\")")
        return False
    return True


def run(external: dict) -> dict[str, list]:
    rows: dict[str, list] = {}
    with_madmom = madmom_available()
    for song in outside_songs():
        truth = np.arange(0.0, librosa.get_duration(path=song.path), 60.0 / song.bpm)
        samples = load_audio(song.path, 22050)
        started = time.perf_counter()
        music = Music.from_file(song.path)
        seconds = time.perf_counter() - started
        results = {"choreo": (music.tempo, music.beat_times, seconds)}
        for name, tracker, arg in (("previous", previous_tracker, music), ("librosa", librosa_default, samples),
                                   ("plp", librosa_plp, samples)):
            started = time.perf_counter()
            tempo, beats = tracker(arg)
            results[name] = (tempo, beats, time.perf_counter() - started + (seconds if name == "previous" else 0.0))
        if with_madmom:
            started = time.perf_counter()
            beats = madmom_tracker.track_file(song.path)
            results["madmom"] = (tempo_of(beats), beats, time.perf_counter() - started)
        for key, beats in external.get(song.path.stem, {}).items():
            if key.endswith("_beats"):
                results[key.removesuffix("_beats")] = (tempo_of(np.asarray(beats)), np.asarray(beats), float("nan"))
        for name, (tempo, beats, secs) in results.items():
            rows.setdefault(name, []).append((song.name, song.bpm, tempo, tempo_matches(tempo, song.bpm),
                                              tempo_matches(tempo, song.bpm, ACC2_MULTIPLES),
                                              beat_f_measure(beats, truth), secs))
        print(f"{song.name:42s} {song.bpm:5.0f} bpm  " + "  ".join(
            f"{name} {tempo:5.1f} F {rows[name][-1][5]:.2f}" for name, (tempo, _, _) in results.items()), flush=True)
    return rows


def m2d_beat_align(data: str) -> None:
    """Real M2D dancers' BeatAlign against the beats each choreo tracker hears in their music."""
    from choreo.datasets import load_dataset
    from choreo.metrics import beat_align_score, motion_beats

    clips = [c for c in load_dataset(data) if c.audio_path]
    scores: dict[str, list[float]] = {"choreo": [], "previous": []}
    with_madmom = madmom_available()
    for clip in clips:
        start, end = clip.audio_offset, clip.audio_offset + clip.motion.duration
        music = Music.from_file(clip.audio_path, start=start, end=end)
        dance = motion_beats(clip.motion.joint_positions())
        trackers = [("choreo", (music.tempo, music.beat_times)), ("previous", previous_tracker(music))]
        if with_madmom:
            trackers.append(("madmom", (None, madmom_tracker.track_file(clip.audio_path, start, end))))
        for name, (_, beats) in trackers:
            frames = np.round(np.asarray(beats) * clip.motion.fps).astype(int)
            scores.setdefault(name, []).append(beat_align_score(frames, dance))
    for name, values in scores.items():
        print(f"M2D real motion BeatAlign, {name} tracker's beats: {np.mean(values):.4f} over {len(values)} clips")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--external", type=Path, help="JSON of other trackers' beat times per song stem")
    parser.add_argument("--m2d", help="also score real M2D motion's BeatAlign against each tracker")
    args = parser.parse_args()
    rows = run(json.loads(args.external.read_text()) if args.external else {})
    if not rows:
        raise SystemExit("no LMMS songs: apt-get install lmms, then run benchmarks/outside_songs.py")
    print("\n| tracker | Acc1 | Acc2 | beat F (70 ms) | seconds per song |\n| --- | ---: | ---: | ---: | ---: |")
    for name, values in rows.items():
        acc1, acc2 = sum(r[3] for r in values), sum(r[4] for r in values)
        f = np.mean([r[5] for r in values])
        secs = np.nanmean([r[6] for r in values]) if not all(np.isnan(r[6]) for r in values) else float("nan")
        print(f"| {name} | {acc1}/{len(values)} | {acc2}/{len(values)} | {f:.3f} | {secs:.2f} |")
    if args.m2d:
        m2d_beat_align(args.m2d)


if __name__ == "__main__":
    main()
