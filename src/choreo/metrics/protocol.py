"""The scoring protocol every quality table here uses: 5 s windows at 30 fps, 2.5 s apart.

Papers score AIST++ this way; the reference row, the generators' results and the benchmarks all
cut M2D the same way so their numbers sit side by side.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Sequence

import numpy as np

from ..datasets import Clip, WindowConfig, WindowedDataset, select_split
from ..errors import ParameterError
from ..generator import GenerationRequest
from ..music import BEAT_COLUMN, Music
from .beats import MetricWarning
from .evaluate import Dance, EvaluationReport, evaluate

if TYPE_CHECKING:
    from ..constraints import Constraints
    from ..generator import Generator
    from ..motion import Motion

SCORING_WINDOWS = WindowConfig(seconds=5.0, stride_seconds=2.5, fps=30.0)
TABLE_HEADER = ("| {label} | clips | BeatAlign | PFC | FID_k | FID_g | Div_k | Div_g | beat dist motion->music | "
                "music->motion | planted | foot~root | slide |\n"
                "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")


def scoring_windows(clips: Sequence[Clip]) -> list:
    """Every scoring window of ``clips`` (motion, features, genre), in a fixed order."""
    return list(WindowedDataset(list(clips), SCORING_WINDOWS))


def music_beats(features: np.ndarray) -> np.ndarray:
    return np.flatnonzero(features[:, BEAT_COLUMN] > 0.5)


def window_dance(window, motion, finished: bool = False, foot_lock: bool = False, footsteps: bool = True) -> Dance:
    """A generated ``motion`` for a scoring window as a Dance, optionally after the finishing passes
    as `choreo generate` applies them (speed limit, beat lock, footsteps unless turned off, the foot
    lock when asked)."""
    beats = music_beats(window.features)
    if finished:
        from ..finishing import Finishing, finish

        motion = finish(motion, beats, Finishing(foot_lock=foot_lock, footsteps=footsteps))
    return Dance(f"{window.clip}@{window.start_frame}", motion.joint_positions(), beats)


def windows_as_dances(clips: Sequence[Clip]) -> list[Dance]:
    """Real motion of each scoring window, with that window's music beats."""
    return [Dance(f"{w.clip}@{w.start_frame}", w.motion.joint_positions(), music_beats(w.features))
            for w in scoring_windows(clips)]


def clip_log_mels(clips: Sequence[Clip]) -> dict[str, np.ndarray]:
    """The log-mel under every clip that has audio, by clip name (windows are cut from these)."""
    from ..music.mel import log_mel_from_file

    return {c.name: log_mel_from_file(c.audio_path, max(c.audio_offset, 0.0), c.motion.num_frames)
            for c in clips if c.audio_path}


def window_music(window, log_mel: np.ndarray | None = None) -> Music:
    """A scoring window as the Music a generator dances to: the window's own features and beats
    (and the log-mel under it, for backends that listen to the spectrum)."""
    fps = SCORING_WINDOWS.fps
    beats = music_beats(window.features)
    tempo = 60.0 * fps / float(np.median(np.diff(beats))) if len(beats) > 1 else 0.0
    return Music(path=None, duration=len(window.features) / fps, fps=fps, features=window.features,
                 beat_times=beats / fps, tempo=tempo, log_mel=log_mel)


@dataclass
class ScoringSet:
    """Test windows and the reference dances they are scored against, prepared once and used for
    every generator, option and seed compared (the reference row's setup: M2D test against train)."""

    clips: list[Clip]  # the test clips (their audio gives the log-mel)
    windows: list
    reference: list[Dance]
    _log_mels: dict[str, np.ndarray] | None = field(default=None, repr=False)

    @classmethod
    def from_clips(cls, clips: Sequence[Clip], test: str = "test", reference: str = "train") -> "ScoringSet":
        """``test`` split's windows against ``reference`` split's real dances."""
        test_clips = select_split(clips, test)
        return cls(test_clips, scoring_windows(test_clips), windows_as_dances(select_split(clips, reference)))

    def log_mels(self) -> dict[str, np.ndarray]:
        if self._log_mels is None:
            self._log_mels = clip_log_mels(self.clips)
        return self._log_mels


def generate_window_motions(generator: "Generator", windows: Sequence, *, with_style: bool = True, seed: int = 0,
                            options: dict[str, Any] | None = None,
                            constraints: Sequence["Constraints"] | None = None,
                            log_mels: dict[str, np.ndarray] | None = None) -> list["Motion"]:
    """A dance for every window, from that window's music alone and its clip's genre as the style
    (``with_style``), through the backend's batch interface (`Generator.generate_windows`)."""
    if generator.listens_to_spectrum and log_mels is None:
        raise ParameterError(f"the {generator.name} backend listens to the spectrum: give the clips' log-mel "
                             "(ScoringSet.log_mels or clip_log_mels)")
    requests = []
    for i, w in enumerate(windows):
        mel = None if log_mels is None else log_mels[w.clip][w.start_frame: w.start_frame + len(w.features)]
        requests.append(GenerationRequest(window_music(w, mel), style=w.genre if with_style else None, seed=seed,
                                          options=dict(options or {}),
                                          constraints=None if constraints is None else constraints[i]))
    return generator.generate_windows(requests)


def score_generator(generator: "Generator", scoring: ScoringSet, *, with_style: bool = True, seed: int = 0,
                    options: dict[str, Any] | None = None, finished: bool = False,
                    foot_lock: bool = False, footsteps: bool = True) -> tuple[EvaluationReport, list[Dance]]:
    """Score a backend the way every quality table here is scored: its dances for the test windows
    (after the finishing passes, ``footsteps`` and ``foot_lock`` as asked) against the reference dances."""
    log_mels = scoring.log_mels() if generator.listens_to_spectrum else None
    motions = generate_window_motions(generator, scoring.windows, with_style=with_style, seed=seed, options=options,
                                      log_mels=log_mels)
    dances = [window_dance(w, m, finished, foot_lock, footsteps) for w, m in zip(scoring.windows, motions)]
    return score(dances, scoring.reference), dances


def score(dances: Sequence[Dance], ground_truth: Sequence[Dance]) -> EvaluationReport:
    """Evaluate without the per-clip warnings (clips with no music beat are expected here)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MetricWarning)
        return evaluate(list(dances), list(ground_truth), fps=SCORING_WINDOWS.fps)


def fmt(value) -> str:
    return "-" if value is None else f"{0.0 if abs(value) < 5e-4 else value:.3f}"  # no "-0.000"


def table_row(label: str, report: EvaluationReport) -> str:
    """One markdown row in TABLE_HEADER's column order."""
    values = (report.beat_align, report.pfc, report.fid_k, report.fid_g, report.div_k, report.div_g,
              report.motion_to_music, report.music_to_motion, report.planted_share, report.foot_root_correlation,
              report.support_slide)
    return f"| {label} | {report.generated_count} | " + " | ".join(fmt(v) for v in values) + " |"
