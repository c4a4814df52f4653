"""The field's dance metrics."""

from .beats import MetricWarning, beat_align_score, beat_distances, mean_joint_speed, motion_beats

__all__ = ["MetricWarning", "beat_align_score", "beat_distances", "mean_joint_speed", "motion_beats"]
