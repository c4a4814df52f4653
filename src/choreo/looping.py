"""Dances that loop: emotes and idle dances, which a game plays over and over.

A loop covers a whole number of bars from the song's start (the song's length rounded down; a bar
is 4 beats, 3 for a waltz), so that the music loops with it. It ends where it began, in pose and in
motion, up to where it stands and faces: an engine adds that per-cycle travel and turn itself
(``metadata["loop"]``). The backend leads the dance back into its own opening with its own
machinery, not a cross-fade (which slides the feet). The loop is danced as a loop plays it: its
last seconds first (a lead-in, so the opening is danced mid-dance), the loop, then a second of its
opening again. The first take's lead-in and opening are kept for a second take, and its opening, turned
the way the first take faced at the loop's end, is given as the frames after the end (its pose
and height, not where on the floor: the second take returns from wherever it went): SGMD
in-betweens into them, the graph's guided walk picks the way back to its first node. The
finishing passes run over the loop with its end before it and its opening after it, as an
endless loop plays it, so steps and beats carry on across the seam (the re-timing leaves the
seam's frames at their times); what the seam is then off by, in pose and in velocity, is closed
over the last half second by a smooth displacement, each foot taking its share while it moves
(choreo.motion.seam).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from .errors import ParameterError
from .motion import Motion
from .motion.filters import low_pass
from .motion.seam import CLOSING_SECONDS, bent_into, closed
from .motion.stitch import facing_yaw, rotate_about_y, turned_and_moved
from .motion.travel import TRACK_CUTOFF_HZ, ground_track
from .music.form import beats_per_bar

RETURN_SECONDS = 0.25  # the opening given again after the end: a pose and its motion, a few model frames
AFTER_SECONDS = 1.0  # the opening's music danced past the loop's end: 4 s made SGMD's return slide more (docs/results.md)
LEAD_IN_SECONDS = 4.0  # the loop's end danced before its opening, as it will be in a loop: the opening is mid-dance


@dataclass(frozen=True)
class Loop:
    """Where a song's loop ends: ``frames`` of dance (``bars`` bars of ``beats_per_bar`` beats)."""

    frames: int
    bars: int
    beats_per_bar: int
    returning: int  # frames of the opening given again after the end
    lead_in: int  # frames of the loop's end danced before its opening (and, finishing it, of its opening after)
    after: int  # frames of the opening's music the two takes dance past the loop's end

    @classmethod
    def of(cls, music, style: str | None) -> "Loop":
        """The longest whole number of bars the song holds, measured on its beats from the start."""
        per_bar = beats_per_bar(style)
        beats = heard = np.asarray(music.beat_times, dtype=np.float64)
        if len(beats) > 1:  # beats the tracker did not hear before the song's end, at the tempo's own spacing
            spacing = float(np.median(np.diff(beats)))
            missing = int(np.ceil(max(music.duration - beats[-1], 0.0) / spacing)) + per_bar
            beats = np.r_[beats, beats[-1] + spacing * np.arange(1, missing + 1)]
        bar_starts = beats[::per_bar]
        lengths = bar_starts - beats[0] if len(beats) else bar_starts
        fits = np.flatnonzero(lengths <= music.duration + 1e-9)
        bars = int(fits[-1]) if len(fits) else 0
        if bars < 1:
            raise ParameterError(f"--loop needs a whole bar ({per_bar} beats) in the song; it is shorter than one "
                                 f"({len(heard)} beat{'' if len(heard) == 1 else 's'} heard in {music.duration:.1f} s)")
        frames = min(int(round(lengths[bars] * music.fps)), music.num_frames)
        returning = max(2, int(round(RETURN_SECONDS * music.fps)))
        return cls(frames, bars, per_bar, returning, min(frames, int(round(LEAD_IN_SECONDS * music.fps))),
                   max(returning, int(round(AFTER_SECONDS * music.fps))))

    @property
    def span(self) -> slice:
        """The loop's own frames within what is danced (lead-in, loop, return)."""
        return slice(self.lead_in, self.lead_in + self.frames)

    def music(self, music, after: int | None = None):
        """The loop's music as a loop plays it: its end, the loop, then its opening again (``after``
        frames of it; default: as many as the lead-in)."""
        after = self.lead_in if after is None else after
        order = np.r_[np.arange(self.frames - self.lead_in, self.frames), np.arange(self.frames), np.arange(after)]
        times = np.asarray(music.beat_times)
        times = times[times < self.frames / music.fps]
        lead = self.lead_in / music.fps
        beats = np.r_[times[times >= (self.frames - self.lead_in) / music.fps] - self.frames / music.fps + lead,
                      times + lead, times[times < after / music.fps] + lead + self.frames / music.fps]
        return replace(music, features=music.features[order], beat_times=beats, duration=len(order) / music.fps,
                       log_mel=None if music.log_mel is None else music.log_mel[order],
                       loudness=None if music.loudness is None else music.loudness[order])

    def constraints(self, first: Motion, cycle: tuple[float, np.ndarray]):
        """``first``'s lead-in and opening kept, and its opening given again, turned and moved by
        ``cycle`` (:meth:`cycle`), as the frames after the loop's end."""
        from .constraints import Constraints

        kept = first.slice_frames(0, self.lead_in + self.returning)
        back = turned_and_moved(kept.slice_frames(self.lead_in), *cycle)
        end = self.lead_in + self.frames
        given = Constraints.none(first.num_frames, first.fps).fix_motion(kept).fix_motion(back, at=end, root=False)
        given.root[end:end + self.returning, 1] = back.root_positions[:, 1]  # its height, not where on the floor:
        given.root_known[end:end + self.returning, 1] = True  # the second take returns from where it went
        return given

    def cycle(self, motion: Motion) -> tuple[float, np.ndarray]:
        """(angle, offset): the per-cycle turn about the vertical and the floor offset that carry
        frame 0 onto where ``motion`` is at the loop's end (its ground track and facing there)."""
        track = ground_track(motion.root_positions, motion.fps)
        yaw = np.unwrap(facing_yaw(motion.joint_positions()))
        yaw = low_pass(yaw, motion.fps, TRACK_CUTOFF_HZ)
        first, last = self.span.start, self.span.stop
        angle = float(yaw[last] - yaw[first])
        start = np.array([track[first, 0], 0.0, track[first, 1]])
        end = np.array([track[last, 0], 0.0, track[last, 1]])
        return angle, end - rotate_about_y(start, angle)

    def periodic(self, second: Motion, cycle: tuple[float, np.ndarray]) -> Motion:
        """The second take's loop, its last half second bent into the return (a model's in-between
        may meet given frames at another speed), as an endless loop would play it around one
        cycle: its end before it and its opening after it, moved by ``cycle``. What the
        finishing passes run over, so that they treat the seam as any other frame."""
        end = self.span.stop
        own = second.slice_frames(self.span.start, end)
        angle = cycle[0]
        offset = second.root_positions[end] - rotate_about_y(own.root_positions[0], angle)
        offset[1] = 0.0  # the turn the opening was given with, the travel the second take went
        back = turned_and_moved(own.slice_frames(0, 2), angle, offset)
        own = bent_into(own, back, self.frames, int(round(CLOSING_SECONDS * second.fps)))
        before = turned_and_moved(own.slice_frames(self.frames - self.lead_in), -angle, -rotate_about_y(offset, -angle))
        after = turned_and_moved(own.slice_frames(0, self.lead_in), angle, offset)
        return Motion.concatenate([before, own, after]).replace(metadata=dict(second.metadata))

    def anchors(self, num_frames: int) -> np.ndarray:
        """(T,) the loop's first frame and its return: where the re-timing must leave the dance."""
        anchors = np.zeros(num_frames, bool)
        anchors[[self.span.start, self.span.stop]] = True
        return anchors

    def cut(self, motion: Motion) -> Motion:
        """The loop's own frames of the finished ``motion``, closed onto its next cycle, with the
        per-cycle turn and travel in the metadata (``loop``)."""
        angle, offset = self.cycle(motion)
        loop = {"bars": self.bars, "beats_per_bar": self.beats_per_bar, "seconds": round(self.frames / motion.fps, 4),
                "turn_degrees": float(np.degrees(angle)), "travel_m": [float(offset[0]), float(offset[2])]}
        own = motion.slice_frames(self.span.start, self.span.stop).replace(metadata=dict(motion.metadata, loop=loop))
        return closed(own, int(round(CLOSING_SECONDS * motion.fps)))
