"""A returning section's dance: the first occurrence's phrase, re-timed onto the new section's beats,
placed where the dancer stands and facing the way the dancer faces, and joined at both ends
without a seam.

Why a copy of the finished dance rather than a second take: every backend's dance can take it (the
graph replays its own material, SGMD its own phrase), it costs no second sampling, the copy keeps
what the finishing passes made of the phrase (its beats on the music's: beat k of the return is
beat k of the first occurrence), and the joins are bent the way a loop's seam is
(choreo.motion.seam: pose and velocity meet).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..motion import Motion
from ..motion.augment import mirrored
from ..motion.seam import bent_into
from ..motion.stitch import facing_yaw, rotate_about_y, turned_and_moved
from ..music.form import Form
from ..skeleton import rotations as rot

JOIN_SECONDS = 1.0  # the dance before each join bent into what follows it over this long (experiments/form_seams.py)
REPLANT_SECONDS = 1 / 3  # around each bend, the feet may be planted again (experiments/form_seams.py)


@dataclass(frozen=True)
class Return:
    """One returning section: its dance's first ``len(source_frames)`` frames from ``start`` are
    the first occurrence's, read at those fractional frames of the dance as the backend made it."""

    section: int
    first: int  # the section it returns to
    start: int  # frame
    source_frames: np.ndarray
    mirrored: bool

    @property
    def stop(self) -> int:
        return self.start + len(self.source_frames)


def section_beats(beats: np.ndarray, start: float, stop: float) -> np.ndarray:
    """The beats (frames) of the section [start, stop): a beat a quarter period early still
    counts as its first (a section starts on a bar line, the tracker's beat may lead it)."""
    early = 0.25 * float(np.median(np.diff(beats))) if len(beats) >= 2 else 0.0
    return beats[(beats >= start - early) & (beats < stop - early)]


def source_frames(target: tuple[int, int], source: tuple[int, int], beats: np.ndarray) -> tuple[int, np.ndarray]:
    """(the first target frame copied, for it and each next target frame the source frame at the
    same beat-phase): beat k of the target section onto beat k of the source, linear between
    beats and at the nearest beats' spacing beyond them; only where the source section is."""
    target_beats, source_beats = section_beats(beats, *target), section_beats(beats, *source)
    count = min(len(target_beats), len(source_beats))
    frames = np.arange(target[0], target[1], dtype=np.float64)
    if count < 2:
        mapped = source[0] + (frames - target[0])
    else:
        target_beats, source_beats = target_beats[:count], source_beats[:count]
        mapped = np.interp(frames, target_beats, source_beats)
        for ends, outside in (((0, 1), frames < target_beats[0]), ((-2, -1), frames > target_beats[-1])):
            slope = np.diff(source_beats[list(ends)])[0] / max(np.diff(target_beats[list(ends)])[0], 1e-9)
            anchor = 0 if ends[0] == 0 else -1
            mapped[outside] = source_beats[anchor] + (frames[outside] - target_beats[anchor]) * slope
    keep = (mapped >= source[0]) & (mapped <= source[1] - 1)
    if not keep.any():
        return target[0], mapped[:0]
    first = int(np.argmax(keep))
    stop = first + (int(np.argmin(keep[first:])) if not keep[first:].all() else len(keep) - first)
    return target[0] + first, mapped[first:stop]


def style_at(schedule, seconds: float) -> str | None:
    """The style a schedule (choreo.constraints.parse_style_schedule) dances at ``seconds``."""
    for start, stop, style in schedule:
        if start <= seconds and (stop is None or seconds < stop):
            return style
    return None


def plan_returns(form: Form, beat_times: np.ndarray, fps: float, num_frames: int, *, mirror: bool = False,
                 fixed: np.ndarray | None = None, schedule=None, join_seconds: float = JOIN_SECONDS) -> list[Return]:
    """Every section that returns, with the frames it copies. Left danced afresh: a return that
    would touch a frame the user fixed (``fixed``, (T,) bool; the frame wins) or its joins, and
    one whose style the schedule changes from its first occurrence's (the schedule is followed).
    ``mirror``: every other return of a letter comes back mirrored."""
    beats = np.asarray(beat_times, dtype=np.float64) * fps
    spans = [(int(round(a * fps)), min(int(round(b * fps)), num_frames), label) for a, b, label in form.spans()]
    seam = int(round(join_seconds * fps))
    plan, seen = [], {}
    for section, first in form.returns():
        (start, stop, label), (first_start, first_stop, _) = spans[section], spans[first]
        seen[label] = seen.get(label, 0) + 1
        if min(stop - start, first_stop - first_start) < seam:
            continue
        if fixed is not None and fixed[max(0, start - seam):min(num_frames, stop + seam)].any():
            continue
        if schedule and style_at(schedule, start / fps) != style_at(schedule, first_start / fps):
            continue
        begin, frames = source_frames((start, stop), (first_start, first_stop), beats)
        if len(frames) >= seam:
            plan.append(Return(section, first, begin, frames, mirror and seen[label] % 2 == 1))
    return plan


def with_returns(dance: Motion, plan: list[Return], exactness: float = 1.0, keep_path: bool = False,
                 join_seconds: float = JOIN_SECONDS) -> Motion:
    """``dance`` with each planned return pasted in, in time order. ``exactness`` (0-1) blends the
    copied phrase over the dance the backend made there; ``keep_path``: a root path the user gave
    stays where it is (the copy brings its pose, not its travel), else the rest of the dance moves on
    from where the copy ends."""
    if not plan or exactness <= 0:
        return dance
    out = dance
    seam = int(round(join_seconds * dance.fps))
    for entry in plan:
        piece = dance.sample_frames(entry.source_frames)
        piece = mirrored(piece).replace(metadata=dict(piece.metadata)) if entry.mirrored else piece
        start, stop = entry.start, entry.stop
        piece = placed_at(piece, out, start)
        if exactness < 1:
            piece = blended(out.slice_frames(start, stop), piece, exactness)
        rest = out.slice_frames(stop)
        if rest.num_frames and not keep_path:
            rest = continuing(rest, out.slice_frames(stop - 1, stop), piece.slice_frames(piece.num_frames - 1))
        bend = min(seam, piece.num_frames // 4)  # a short section keeps most of its phrase
        head = joined(out.slice_frames(0, start), piece, bend)
        if rest.num_frames:
            piece = joined(piece, rest, bend)
        out = Motion.concatenate([head, piece, rest] if rest.num_frames else [head, piece])
    if keep_path:  # the path is the user's: only the poses (and the height) come from the copies
        root = out.root_positions.copy()
        root[:, [0, 2]] = dance.root_positions[:, [0, 2]]
        out = out.replace(root_positions=root)
    fps = dance.fps
    danced = [{"section": e.section, "returns_to": e.first, "seconds": [round(e.start / fps, 3), round(e.stop / fps, 3)],
               "mirrored": e.mirrored} for e in plan]
    return out.replace(metadata={**dance.metadata, "returns": danced})


def away_from_joins(plan: list[Return], num_frames: int, fps: float, join_seconds: float = JOIN_SECONDS) -> np.ndarray:
    """(T,) True but for each join's bend and a third of a second around it: the frames a footsteps
    pass must leave as they were copied, while it plants the feet that a bend made slide."""
    kept = np.ones(num_frames, bool)
    bend, margin = int(round(join_seconds * fps)), int(round(REPLANT_SECONDS * fps))
    for entry in plan:
        for join in (entry.start, entry.stop):
            kept[max(0, join - bend - margin):min(num_frames, join + margin)] = False
    return kept


def placed_at(piece: Motion, dance: Motion, frame: int) -> Motion:
    """``piece`` turned and moved so that its first frame stands where ``dance``'s ``frame`` does,
    facing the same way (height kept)."""
    return rigidly_onto(piece, piece.slice_frames(0, 1), dance.slice_frames(frame, frame + 1))


def continuing(rest: Motion, before: Motion, now: Motion) -> Motion:
    """``rest`` moved with the frame before it: it follows ``now`` as it followed ``before``."""
    return rigidly_onto(rest, before, now)


def rigidly_onto(motion: Motion, reference: Motion, target: Motion) -> Motion:
    """``motion`` turned about the vertical and shifted on the floor by what takes ``reference``'s
    one frame onto ``target``'s (root over root, facing as facing)."""
    angle = float(facing_yaw(target.joint_positions()[0]) - facing_yaw(reference.joint_positions()[0]))
    turned_root = rotate_about_y(reference.root_positions[0], angle)
    offset = np.array([target.root_positions[0, 0] - turned_root[0], 0.0, target.root_positions[0, 2] - turned_root[2]])
    return turned_and_moved(motion, angle, offset)


def blended(fresh: Motion, copied: Motion, weight: float) -> Motion:
    """``copied`` at ``weight`` over ``fresh`` (same length): root lerped, rotations slerped."""
    root = (1 - weight) * fresh.root_positions + weight * copied.root_positions
    rotations = rot.quaternion_slerp(fresh.rotations, copied.rotations,
                                     np.full(fresh.rotations.shape[:2], float(weight)))
    return copied.replace(root_positions=root, rotations=rotations)


def joined(before: Motion, after: Motion, frames: int) -> Motion:
    """``before`` with its end bent to run into ``after``'s opening as into its own next frames,
    pose and velocity (choreo.motion.seam.bent_into). Not also each foot moved while it steps, as a
    loop's seam is: at a return's joins that left the change of velocity above the dance's own
    (experiments/form_seams.py)."""
    if before.num_frames < 4 or after.num_frames < 2:
        return before
    return bent_into(before, after.slice_frames(0, 2), before.num_frames, frames)
