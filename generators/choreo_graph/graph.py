"""Selection, warping and the dynamic motion graph (paper 3.1-3.3), vectorised over candidates.

For every second t of the song the 4 s music window starting at t picks K repertoire clips by
style (eq. 1 as a cost), each is re-timed onto the window's predicted tempo-density, and its four
1 s nodes become active at t..t+3. Every second the graph moves to the active node with the least
style + action-completeness + transition cost (eqs. 4-7); segments older than 3 s drop out.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import torch

from choreo.metrics.beats import motion_beats
from choreo.motion import Motion
from choreo.motion.stitch import crossfade, facing_yaw, placement_onto, turned_and_moved

from .config import NODE_FRAMES, WINDOW_FRAMES, GraphConfig, StyleConfig
from .model import ChoreoGraphModel
from .repertoire import MIDDLE, Repertoire
from .warp import warp_frames

NODES_PER_SEGMENT = WINDOW_FRAMES // NODE_FRAMES  # 4
REPEAT_OVERLAP = NODE_FRAMES // 4  # source frames two nodes may share before one repeats the other
if TYPE_CHECKING:
    from .guide import Guide

WARP_CHUNK = 4096  # candidate pairs warped at once (bounds memory: ~4096 x 60 x 120 floats)


@dataclass
class MusicWindows:
    """What the models hear in each 4 s window, one window per second of the song."""

    style: np.ndarray  # (n, style_dim)
    beats: np.ndarray  # (n,) predicted motion beats
    tempo: np.ndarray  # (n, 120) predicted motion tempo-density


@dataclass(frozen=True, eq=False)
class Node:
    segment: tuple[int, int]  # (second it was inserted, candidate rank): one warped 4 s segment
    index: int  # 0..3, which second of the segment
    clip: int  # repertoire clip
    frames: np.ndarray  # (30,) fractional clip frames it plays

    def continues(self, other: "Node | None") -> bool:
        return other is not None and self.segment == other.segment and self.index == other.index + 1


def music_windows(model: ChoreoGraphModel, mel: np.ndarray, seconds: range) -> MusicWindows:
    """Style, beat count and tempo-density of the 4 s windows starting at each of ``seconds``
    (past the end of the song the last frame is held)."""
    def window(t: int) -> np.ndarray:
        piece = mel[t * NODE_FRAMES : t * NODE_FRAMES + WINDOW_FRAMES]
        return np.concatenate([piece, np.repeat(mel[-1:], WINDOW_FRAMES - len(piece), axis=0)]) if len(piece) < WINDOW_FRAMES else piece

    style, beats, tempo = [], [], []
    for first in range(0, len(seconds), 64):
        batch = torch.from_numpy(np.stack([window(t) for t in seconds[first : first + 64]]))
        s, b = model.music_style(batch)
        style.append(s.numpy())
        beats.append(b.numpy())
        tempo.append(model.music_tempo_density(batch).numpy())
    return MusicWindows(np.concatenate(style), np.concatenate(beats), np.concatenate(tempo))


def select_candidates(windows: MusicWindows, repertoire: Repertoire, top_k: int, weights: StyleConfig,
                      allowed: np.ndarray | None = None) -> np.ndarray:
    """(n, K) repertoire clips with the least style loss (eq. 1) for each window, best first."""
    cost = (weights.style_weight * np.square(windows.style[:, None] - repertoire.style[None]).sum(-1)
            + weights.beat_weight * np.square(windows.beats[:, None] - repertoire.beat_counts[None]))
    if allowed is not None:
        cost[:, ~allowed] = np.inf
    k = int(min(top_k, len(repertoire) if allowed is None else allowed.sum()))
    nearest = np.argpartition(cost, k - 1, axis=1)[:, :k]
    order = np.take_along_axis(cost, nearest, 1).argsort(1)
    return np.take_along_axis(nearest, order, 1)


def warp_candidates(windows: MusicWindows, candidates: np.ndarray, repertoire: Repertoire,
                    config: GraphConfig) -> np.ndarray:
    """(n, K, 120) clip frames that make each candidate's 4 s segment (re-timed, or its middle)."""
    n, k = candidates.shape
    if not config.retempo:
        return np.broadcast_to(np.arange(MIDDLE.start, MIDDLE.stop, dtype=np.float64), (n, k, WINDOW_FRAMES))
    queries = np.repeat(windows.tempo, k, axis=0)
    references = repertoire.tempo[candidates.reshape(-1)]
    frames = np.concatenate([warp_frames(queries[i : i + WARP_CHUNK], references[i : i + WARP_CHUNK], config.dtw_stride, config.warp_smoothing)
                             for i in range(0, len(queries), WARP_CHUNK)])
    return frames.reshape(n, k, WINDOW_FRAMES)


def completeness_cost(current: Node, segment_warp: np.ndarray, repertoire: Repertoire, scale: float) -> float:
    """Eq. 6 for the node that continues ``current``'s segment: low while an action runs across
    the seam (beats far from it), towards 1 once it has come to rest near it."""
    start = current.index * NODE_FRAMES
    frames = np.rint(segment_warp[start : start + 2 * NODE_FRAMES]).astype(int)
    beats = motion_beats(repertoire.poses[current.clip, frames].astype(np.float32))
    before, after = beats[beats < NODE_FRAMES], beats[beats >= NODE_FRAMES]
    gap = after[0] - before[-1] if len(before) and len(after) else 2 * NODE_FRAMES
    return float(1.0 / (1.0 + np.exp(-(NODE_FRAMES - gap) / scale)))


class DynamicGraph:
    """The graph as it moves through the song: the segments of second t enter at t and leave
    after t + 3, so memory does not grow with the song (the paper's node removal).

    One cost the paper does not have: a node that replays source frames danced in the last
    ``repeat_memory`` seconds costs ``repeat_cost`` more. Without it a clip that tops the style
    ranking every second, and whose end joins its own start, is replayed second after second
    (a 30 s rumba excerpt got one node 24 times in a row)."""

    def __init__(self, repertoire: Repertoire, config: GraphConfig, seed: int = 0, guide: "Guide | None" = None):
        self.repertoire, self.config, self.guide = repertoire, config, guide
        # Every seed of a free dance is a take; under constraints seed 0 is the greedy walk, which keeps closer to
        # them with lower PFC (docs/results.md, "The graph under constraints").
        varied = config.take_variation > 0 and (seed != 0 or guide is None or not guide.constrained)
        # numpy's generators take no negative seed, and generate takes -1: the same 64 bits, wrapped
        self.rng = np.random.default_rng(seed % 2**64) if varied else None
        self.segments: dict[int, tuple[np.ndarray, np.ndarray]] = {}  # second -> (clips (K,), warps (K, 120))
        self.current: Node | None = None
        self.played: deque[tuple[int, np.ndarray]] = deque()  # (second, source span of the node played)

    def insert(self, second: int, clips: np.ndarray, warps: np.ndarray) -> None:
        self.segments[second] = (clips, warps)

    def step(self, t: int, music_style: np.ndarray) -> Node:
        """Move to the cheapest active node for second ``t`` (eq. 4), greedily as in the paper."""
        config, repertoire, current = self.config, self.repertoire, self.current
        oldest = t - NODES_PER_SEGMENT + 1 if config.dynamic else t
        for second in [s for s in self.segments if s < oldest]:
            del self.segments[second]
        inserted = sorted(s for s in self.segments if s <= t)
        clips = np.concatenate([self.segments[s][0] for s in inserted])
        warps = np.concatenate([self.segments[s][1] for s in inserted])
        segment_time = np.concatenate([np.full(len(self.segments[s][0]), s) for s in inserted])
        rank = np.concatenate([np.arange(len(self.segments[s][0])) for s in inserted])
        index = t - segment_time
        first = np.rint(warps[np.arange(len(clips)), index * NODE_FRAMES]).astype(int)
        cost = np.zeros(len(clips))
        follows = np.zeros(len(clips), bool)
        if config.dynamic:
            cost += config.style_cost * np.square(repertoire.style[clips] - music_style).sum(-1)
        if current is not None:
            pose = repertoire.poses[current.clip, int(round(current.frames[-1]))].astype(np.float32)
            step = np.square(repertoire.poses[clips, first].astype(np.float32) - pose).sum(-1).mean(-1)
            cost += config.transition_cost * step
            follows = (segment_time == current.segment[0]) & (rank == current.segment[1]) & (index == current.index + 1)
            if config.dynamic:
                completeness = np.ones(len(clips))
                if follows.any():
                    own = warps[np.flatnonzero(follows)[0]]
                    completeness[follows] = completeness_cost(current, own, repertoire, config.completeness_scale)
                cost += config.completeness_cost * completeness
        last = warps[np.arange(len(clips)), index * NODE_FRAMES + NODE_FRAMES - 1]
        cost += self.repeat_cost(t, source_spans(repertoire, clips, first, last))
        spread = cost.std()  # the dance's own costs: a take varies the dance, not how closely it keeps to constraints
        if self.guide is not None:
            played = warps[np.arange(len(clips))[:, None], (index * NODE_FRAMES)[:, None] + np.arange(NODE_FRAMES)]
            cost += self.guide.cost(t, clips, played, follows, current)
        if self.rng is not None:  # this take: near-equal choices fall one way or another
            cost += config.take_variation * spread * self.rng.standard_normal(len(cost))
        best = int(cost.argmin())
        if self.guide is not None:
            self.guide.chose(best)
        start = int(index[best]) * NODE_FRAMES
        self.current = Node((int(segment_time[best]), int(rank[best])), int(index[best]), int(clips[best]),
                            warps[best, start : start + NODE_FRAMES].copy())
        self.remember(t, self.current)
        return self.current

    def repeat_cost(self, t: int, spans: np.ndarray) -> np.ndarray:
        """``repeat_cost`` for each node (``source_spans``) replaying frames played recently."""
        while self.played and self.played[0][0] <= t - self.config.repeat_memory:
            self.played.popleft()
        if not self.played or self.config.repeat_cost == 0:
            return np.zeros(len(spans))
        return self.config.repeat_cost * replaying(spans, np.array([span for _, span in self.played]))

    def remember(self, t: int, node: Node) -> None:
        self.played.append((t, source_spans(self.repertoire, node.clip, node.frames[0], node.frames[-1])))


def source_spans(repertoire: Repertoire, clips, first, last) -> np.ndarray:
    """(..., 3) what nodes play in source terms: motion id, first and last frame in that motion
    (clips cut from one motion overlap, so a replay can come from another clip)."""
    sources, starts = repertoire.origins
    return np.stack(np.broadcast_arrays(sources[clips], starts[clips] + first, starts[clips] + last), -1).astype(float)


def replaying(spans: np.ndarray, played: np.ndarray) -> np.ndarray:
    """(N,) whether each of ``spans`` (N, 3) shares more than ``REPEAT_OVERLAP`` frames of the
    same motion with any of ``played`` (M, 3)."""
    overlap = np.minimum(spans[:, None, 2], played[:, 2]) - np.maximum(spans[:, None, 1], played[:, 1])
    return ((spans[:, None, 0] == played[:, 0]) & (overlap > REPEAT_OVERLAP)).any(1)


def search_graph(windows: MusicWindows, candidates: np.ndarray, warps: np.ndarray, repertoire: Repertoire,
                 config: GraphConfig, seed: int = 0) -> list[Node]:
    """The whole path at once, for songs already cut into windows (tests, short excerpts)."""
    graph, path = DynamicGraph(repertoire, config, seed), []
    for t in range(len(candidates)):
        graph.insert(t, candidates[t], warps[t])
        path.append(graph.step(t, windows.style[t]))
    return path


def played_clips(path: list[Node], repertoire: Repertoire) -> list[dict]:
    """What a dance is made of, one entry per run of continuing nodes: the repertoire clip, the
    frames of its source motion it plays (first, last; warped in between) and the output frames."""
    _, starts = repertoire.origins
    runs: list[dict] = []
    for second, node in enumerate(path):
        source = [round(float(starts[node.clip] + node.frames[0]), 2), round(float(starts[node.clip] + node.frames[-1]), 2)]
        output = [second * NODE_FRAMES, (second + 1) * NODE_FRAMES - 1]
        if runs and node.continues(path[second - 1]):
            runs[-1]["source_frames"][1], runs[-1]["output_frames"][1] = source[1], output[1]
        else:
            name = str(repertoire.names[node.clip])
            runs.append({"clip": name, "source": name.rpartition("@")[0] or name,
                         "source_frames": source, "output_frames": output})
    return runs


def replayed_nodes(path: list[Node], repertoire: Repertoire, memory: int) -> int:
    """How many nodes of a path replay what one of the ``memory`` nodes before it played: the
    looping the repeat cost is there to prevent."""
    spans = np.stack([source_spans(repertoire, n.clip, n.frames[0], n.frames[-1]) for n in path])
    return sum(bool(replaying(spans[i : i + 1], spans[max(0, i - memory) : i])[0]) for i in range(1, len(path)))


def assemble(path: list[Node], repertoire: Repertoire, blend_frames: int,
             start: tuple[np.ndarray, float] = (np.zeros(3), 0.0)) -> Motion:
    """Play the chosen nodes end to end: a segment runs on unbroken; a jump to another segment is
    placed where the previous one would have gone next and cross-faded into it. The first node
    starts at ``start`` (root position, facing)."""
    clips: dict[int, Motion] = {}
    pieces, previous, placement = [], None, (0.0, np.zeros(3))

    def clip_motion(index: int) -> Motion:
        if index not in clips:
            clips[index] = repertoire.clip_motion(index)
        return clips[index]

    for node in path:
        piece = clip_motion(node.clip).sample_frames(node.frames)
        if previous is None:
            placement = placement_onto(piece, *start)
            piece = turned_and_moved(piece, *placement)
        elif node.continues(previous):
            piece = turned_and_moved(piece, *placement)
        else:
            before = previous.frames
            rate = max(before[-1] - before[-2], 0.5)
            ahead = clip_motion(previous.clip).sample_frames(before[-1] + rate * np.arange(1, blend_frames + 1))
            ahead = turned_and_moved(ahead, *placement)
            target = ahead.slice_frames(0, 1)
            placement = placement_onto(piece, target.root_positions[0], float(facing_yaw(target.joint_positions()[0])))
            piece = crossfade(ahead, turned_and_moved(piece, *placement))
        pieces.append(piece)
        previous = node
    return Motion.concatenate(pieces)
