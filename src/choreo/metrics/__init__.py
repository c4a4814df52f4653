"""The field's dance metrics: BeatAlign, PFC, FID_k/FID_g, Div_k/Div_g, beat distances.

The scoring protocol on datasets (`choreo.metrics.protocol`) is imported on its own: it needs the
dataset readers, which the metrics themselves do not.
"""

from .beats import (MetricWarning, beat_align_score, beat_autocorrelation, beat_distances, mean_joint_speed, motion_beats,
                    salience_at, same_pulse, tempo_salience)
from .evaluate import Dance, DanceScore, EvaluationReport, evaluate, resample_positions
from .fid import diversity, frechet_distance, motion_features, normalise_by_reference, prepare_positions
from .geometric import geometric_features
from .kinetic import kinetic_features
from .pfc import foot_contact_score, physical_foot_contact

__all__ = [
    "Dance", "DanceScore", "EvaluationReport", "MetricWarning", "beat_align_score", "beat_autocorrelation", "beat_distances",
    "diversity", "evaluate", "foot_contact_score", "frechet_distance", "geometric_features", "kinetic_features",
    "mean_joint_speed", "motion_beats", "motion_features", "normalise_by_reference", "physical_foot_contact",
    "prepare_positions", "resample_positions", "salience_at", "same_pulse", "tempo_salience",
]  # fmt: skip
