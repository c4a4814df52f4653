"""Does the dance have the song's form? When a section returns (A B A B), a choreographed dance
brings its phrase back; one danced afresh does not, and one looping a phrase has no form at all.

Joint positions (T, J, 3), metres, Y up, joint 0 the pelvis; poses are compared with the pelvis's
floor position subtracted and the facing removed (the hips' heading, as choreo.motion.stitch reads
it, averaged over a bar or a second), so where in the room and which way a phrase is danced do not
count.

- bar self-similarity and form score: the dance's bar-by-bar self-similarity against the music's,
  Pearson over the bar pairs off the diagonal. Copying the music's returns scores high, a bar
  looped throughout 0.
- phrase distance: mean joint distance between two sections, aligned beat by beat, without their
  first second (the transition into a section is not its phrase); optionally one un-mirrored.
- return ratio: a returning section's phrase distance to its first occurrence over its distance to
  the nearest section of another letter. Target <= 0.35; a dance danced afresh gives 0.5-1.3.
- seam steps: the pose step and velocity change at the joins into and out of a copied phrase, over
  the dance's own 95th percentile (the definition of choreo.metrics.loops.seam).
"""

from __future__ import annotations

import numpy as np

from ..errors import ParameterError
from ..motion.augment import MIRROR_AXIS, mirror_joint_order
from ..motion.motion import positions_at
from ..motion.stitch import facing_yaw, rotate_about_y
from ..music.form import Form
from ..skeleton import SMPL24

BAR_SAMPLES = 8  # poses per bar in a bar's feature: two per beat in 4/4, enough for a bar's shape
MIN_LAG = 2  # bar pairs closer than this are left out of the form score (see form_score)
SKIP_SECONDS = 1.0  # a section's first second is its transition, not its phrase
FACING_SECONDS = 1.0  # the facing removed from a phrase's poses: the hips' heading averaged over this
SEAM_PERCENTILE = 95.0
FLAT = 1e-9  # a self-similarity (values in [0, 1]) varying less than this is constant
SAME_METRES = 0.01  # bars whose poses differ by less (RMS over joints and samples) are one bar: capture jitter


# -- poses without place and facing ----------------------------------------------------------------

def floor_local(positions) -> tuple[np.ndarray, np.ndarray]:
    """(poses with the pelvis's floor position subtracted, the hips' heading unwrapped (T,))."""
    positions = np.asarray(positions, dtype=np.float64)
    return positions - positions[:, :1] * np.array([1.0, 0.0, 1.0]), np.unwrap(facing_yaw(positions))


def facing_free(positions, window: int) -> np.ndarray:
    """(T, J, 3) poses over the pelvis, turned so the hips' heading averaged over ``window`` frames
    faces +z. Averaged, not frame by frame: the heading from two hip joints 12 cm apart turns a few
    millimetres of jitter into centimetres at the hands, and a fast turn is part of a phrase."""
    local, yaw = floor_local(positions)
    if window > 1 and len(yaw) > 1:
        half = window // 2
        padded = np.pad(yaw, half, mode="edge")
        yaw = np.convolve(padded, np.ones(2 * half + 1) / (2 * half + 1), mode="valid")
    return rotate_about_y(local, -yaw[:, None])


# -- bars ----------------------------------------------------------------------------------------

def dance_bar_features(positions, bars, samples: int = BAR_SAMPLES) -> np.ndarray:
    """(B, samples * J * 3): each bar's poses at ``samples`` evenly spaced instants, the pelvis's
    floor position subtracted frame by frame and the bar's mean heading (the hips') turned to +z,
    flattened. Resampling each bar to the same count lets bars of a changing tempo be compared
    pose for pose; removing place and facing makes a phrase danced elsewhere the same; one heading
    per bar keeps a turn inside the bar as part of it, and averages the hips' jitter away."""
    local, yaw = floor_local(positions)
    bars = np.asarray(bars, dtype=np.float64)
    if len(bars) < 2:
        return np.zeros((0, samples * local.shape[1] * 3))
    starts, ends = bars[:-1], bars[1:]
    frames = starts[:, None] + (ends - starts)[:, None] * (np.arange(samples) / samples)
    poses = positions_at(local, frames.ravel()).reshape(len(starts), samples, -1, 3)
    headings = np.array([yaw[int(a):max(int(b), int(a) + 1)].mean() for a, b in zip(starts, ends)])
    return rotate_about_y(poses, -headings[:, None, None]).reshape(len(starts), -1)


def pairwise_distances(features, same_below: float = SAME_METRES) -> np.ndarray:
    """(B, B) Euclidean distances between bars' features (metres, points of 3 coordinates), those
    whose RMS point distance is under ``same_below`` set to exactly 0: a phrase repeated with a few
    millimetres of jitter is the same bar, not noise that the median's scaling would blow up into
    a pattern of full size."""
    features = np.asarray(features, dtype=np.float64)
    distances = np.linalg.norm(features[:, None, :] - features[None, :, :], axis=-1)
    points = max(features.shape[-1] / 3, 1.0)
    distances[distances < same_below * np.sqrt(points)] = 0.0
    return distances


def self_similarity(features, same_below: float = SAME_METRES) -> np.ndarray:
    """(B, B) bar self-similarity exp(-d / median d), d the Euclidean distance between bar features.

    Distance, not cosine on centred features: centring makes every bar's similarity depend on the
    whole dance's mean bar (an unrelated section elsewhere changes it) and turns a near-still bar
    into noise of full size, while a distance in metres keeps "the same shape, smaller" apart from
    "the same". Dividing by the median off-diagonal distance makes dances of different size
    comparable; all bars equal give all ones (no form: a form score of 0). ``same_below``: see
    pairwise_distances (metres; 0 for features in other units)."""
    distances = pairwise_distances(features, same_below)
    count = len(distances)
    off = distances[~np.eye(count, dtype=bool)]
    if not off.size or off.max() == 0.0:
        return np.ones((count, count))
    scale = np.median(off)
    if scale == 0.0:  # most bars equal: the mean of the differing ones sets the scale
        scale = off[off > 0].mean()
    return np.exp(-distances / scale)


def form_score(dance_ssm, music_ssm, min_lag: int = MIN_LAG) -> float:
    """Pearson correlation of the two self-similarities over bar pairs at least ``min_lag`` bars
    apart (upper triangle). The diagonal is 1 in both; neighbouring bars are alike in any smooth
    dance and any music, so they are left out too (min_lag 2) and the score is about the bars that
    are far apart: the returns. 0 when either is constant (a phrase looped bar by bar); NaN when no
    pair is left (too few bars)."""
    dance, music = np.asarray(dance_ssm, dtype=np.float64), np.asarray(music_ssm, dtype=np.float64)
    if dance.shape != music.shape or dance.ndim != 2 or dance.shape[0] != dance.shape[1]:
        raise ParameterError(f"self-similarities must be square and of one size, got {dance.shape} and {music.shape}")
    rows, cols = np.triu_indices(len(dance), k=max(int(min_lag), 1))
    if len(rows) < 2:
        return float("nan")
    x, y = dance[rows, cols], music[rows, cols]
    x, y = x - x.mean(), y - y.mean()
    if x.std() < FLAT or y.std() < FLAT:  # constant but for rounding: no pattern to follow
        return 0.0
    return float(np.clip((x @ y) / np.sqrt((x @ x) * (y @ y)), -1.0, 1.0))


def bar_similarities(positions, bar_lines, music_ssm) -> tuple[np.ndarray, np.ndarray] | None:
    """(the dance's, the music's) bar self-similarity over the bars the dance covers whole, the
    music's bars starting at frames ``bar_lines`` (B,) and sounding alike as ``music_ssm`` (B, B)
    says (choreo.music.form.music_self_similarity). None with under four whole bars."""
    lines = np.asarray(bar_lines, dtype=np.float64)
    if len(lines) < 2:
        return None
    lines = np.append(lines, lines[-1] + np.median(np.diff(lines)))
    whole = int(np.sum(lines[1:] <= len(positions)))
    if whole < 4:
        return None
    return self_similarity(dance_bar_features(positions, lines[:whole + 1])), np.asarray(music_ssm)[:whole, :whole]


def dance_form_score(positions, bar_lines, music_ssm) -> float | None:
    """The form score of a dance to the music (:func:`bar_similarities`); None under four whole bars."""
    both = bar_similarities(positions, bar_lines, music_ssm)
    return None if both is None else form_score(*both)


# -- phrases -------------------------------------------------------------------------------------

def beat_coordinate(times, beats, start: float, period: float) -> np.ndarray:
    """Times as beats since a section's first beat: piecewise linear between its beats, extended
    past either end at the neighbouring interval; with under two beats, (time - start) / period."""
    times = np.asarray(times, dtype=np.float64)
    if len(beats) < 2:
        return (times - start) / period
    index = np.interp(times, beats, np.arange(len(beats), dtype=np.float64))
    before, after = times < beats[0], times > beats[-1]
    index[before] = (times[before] - beats[0]) / (beats[1] - beats[0])
    index[after] = len(beats) - 1 + (times[after] - beats[-1]) / (beats[-1] - beats[-2])
    return index


def beat_time(index, beats, start: float, period: float) -> np.ndarray:
    """The inverse of :func:`beat_coordinate`: seconds at beat coordinates."""
    index = np.asarray(index, dtype=np.float64)
    if len(beats) < 2:
        return start + index * period
    times = np.interp(index, np.arange(len(beats), dtype=np.float64), beats)
    before, after = index < 0, index > len(beats) - 1
    times[before] = beats[0] + index[before] * (beats[1] - beats[0])
    times[after] = beats[-1] + (index[after] - len(beats) + 1) * (beats[-1] - beats[-2])
    return times


def _section_beats(beats: np.ndarray, span, tolerance: float) -> np.ndarray:
    start, end = span
    return beats[(beats >= start - tolerance) & (beats < end - tolerance)]


def _unmirror(local: np.ndarray, joint_names) -> np.ndarray:
    """Root-local poses mirrored back: left and right joints swapped, the lateral axis negated
    (what choreo.motion.augment.mirrored does to a body, seen in its own frame)."""
    names = tuple(joint_names) if joint_names is not None else SMPL24.names
    if len(names) != local.shape[1]:
        raise ParameterError(f"{local.shape[1]} joints but {len(names)} joint names to mirror them by")
    flip = np.ones(3)
    flip[MIRROR_AXIS] = -1.0
    return local[:, mirror_joint_order(names)] * flip


def _local_phrase_distance(local, fps, a, b, beats, skip_seconds, mirrored, joint_names) -> float:
    """phrase_distance on positions already root-local (return_ratio compares many pairs)."""
    beats = np.sort(np.asarray([] if beats is None else beats, dtype=np.float64).ravel())
    period = float(np.median(np.diff(beats))) if len(beats) >= 2 else 1.0
    tolerance = 0.25 * period  # a beat a little before a section's start is its first beat
    (a0, a1), (b0, b1) = (tuple(map(float, a)), tuple(map(float, b)))
    beats_a, beats_b = _section_beats(beats, (a0, a1), tolerance), _section_beats(beats, (b0, b1), tolerance)
    last = (len(local) - 1) / fps
    frames_b = np.arange(max(int(np.ceil((b0 + skip_seconds) * fps - 1e-6)), 0), len(local))
    times_b = frames_b / fps
    times_a = beat_time(beat_coordinate(times_b, beats_b, b0, period), beats_a, a0, period)
    keep = (times_b < b1) & (times_a >= a0 + skip_seconds) & (times_a < a1) & (times_a <= last)
    if not keep.any():
        return float("nan")
    poses_a = positions_at(local, times_a[keep] * fps)
    poses_b = local[frames_b[keep]]
    if mirrored:
        poses_b = _unmirror(poses_b, joint_names)
    return float(np.linalg.norm(poses_b - poses_a, axis=-1).mean())


def phrase_distance(positions, fps: float, a, b, beat_times, skip_seconds: float = SKIP_SECONDS,
                    mirrored: bool = False, joint_names=None, facing_seconds: float = FACING_SECONDS) -> float:
    """Mean joint distance (m) between sections ``a`` and ``b`` ((start, end) seconds), root-local
    with the facing removed, ``b``'s frames mapped onto ``a``'s by beat count (piecewise linear
    between the beats inside each section, so a phrase returning at another tempo still lines
    up), over the shorter of the two, without each section's first ``skip_seconds``. ``mirrored``:
    ``b`` is un-mirrored first (joint names: SMPL-24's unless given). NaN when nothing overlaps.
    The facing removed is the hips' heading averaged over ``facing_seconds`` (see facing_free)."""
    local = facing_free(positions, int(round(facing_seconds * fps)))
    return _local_phrase_distance(local, fps, a, b, beat_times, skip_seconds, mirrored, joint_names)


def return_ratio(positions, fps: float, form: Form, beat_times, skip_seconds: float = SKIP_SECONDS,
                 mirrored: bool = False, joint_names=None, facing_seconds: float = FACING_SECONDS) -> list[float]:
    """For each returning section (Form.returns order): its phrase distance to its first
    occurrence over its phrase distance to the nearest section of another letter (the smallest
    of those distances). Dividing by that nearest other phrase makes the figure about returns,
    not about how much the dancer moves. NaN where the song has one letter only, a distance
    cannot be taken, or the nearest other section is danced the same to within SAME_METRES (a
    loop: no form to return to). ``mirrored``: returns danced as mirror images, un-mirrored for every distance
    (the other letters' too, so that both sides compare alike)."""
    local = facing_free(positions, int(round(facing_seconds * fps)))
    spans = form.spans()
    ratios = []
    for section, first in form.returns():
        span, label = spans[section][:2], spans[section][2]

        def distance(other):
            return _local_phrase_distance(local, fps, spans[other][:2], span, beat_times, skip_seconds, mirrored,
                                          joint_names)

        same = distance(first)
        others = [distance(k) for k, s in enumerate(spans) if s[2] != label]
        others = [d for d in others if np.isfinite(d)]
        nearest = min(others) if others else float("nan")
        distinct = np.isfinite(same) and nearest >= SAME_METRES  # NaN fails it too
        ratios.append(same / nearest if distinct else float("nan"))
    return ratios


# -- seams ---------------------------------------------------------------------------------------

def steps_and_changes(positions) -> tuple[np.ndarray, np.ndarray]:
    """(steps, changes): steps[k] the mean joint move from frame k to k + 1, changes[k] the mean
    joint change of that move from step k to k + 1 (metres; choreo.metrics.loops.seam's figures)."""
    moves = np.diff(np.asarray(positions, dtype=np.float64), axis=0)
    return np.linalg.norm(moves, axis=-1).mean(axis=1), np.linalg.norm(np.diff(moves, axis=0), axis=-1).mean(axis=1)


def _over(value: float, scale: float) -> float:
    if not np.isfinite(scale):
        return float("nan")
    if scale > 0:
        return float(value / scale)
    return 0.0 if value == 0 else float("inf")


def seam_steps(positions, frames) -> list[tuple[float, float]]:
    """At each join frame f: (the step from frame f - 1 into f, the larger change of velocity into
    and out of that step), each over the 95th percentile of the same figure elsewhere in the dance
    (the joins' own steps left out, as loops.seam leaves its seam out). Above 1: the join is a jump
    no frame of the dance makes; NaN for a frame with no step into it (0, or past the end)."""
    steps, changes = steps_and_changes(positions)
    joins = [int(f) for f in np.asarray(frames).ravel()]
    seams = sorted({f - 1 for f in joins if 1 <= f < len(steps) + 1})
    inside = np.delete(steps, seams)
    inside_changes = np.delete(changes, sorted({k for s in seams for k in (s - 1, s) if 0 <= k < len(changes)}))
    step_scale = np.percentile(inside, SEAM_PERCENTILE) if inside.size else float("nan")
    change_scale = np.percentile(inside_changes, SEAM_PERCENTILE) if inside_changes.size else float("nan")
    out = []
    for f in joins:
        s = f - 1
        around = [changes[k] for k in (s - 1, s) if 0 <= k < len(changes)]
        if not 0 <= s < len(steps):
            out.append((float("nan"), float("nan")))
            continue
        out.append((_over(steps[s], step_scale), _over(max(around), change_scale) if around else float("nan")))
    return out
