"""`ChoreoGraphGenerator`: music in, a dance assembled from the repertoire out."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Callable

import numpy as np

from choreo.constraints import Constraints
from choreo.constraints.displacement import displace_motion
from choreo.errors import ParameterError
from choreo.generator import GenerationRequest, Generator
from choreo.options import parse_options
from choreo.motion import Motion
from choreo.music.mel import music_log_mel

from . import plugin
from .config import FPS, NODE_FRAMES, GraphConfig
from .graph import DynamicGraph, Node, assemble, music_windows, played_clips, select_candidates, warp_candidates
from .guide import Guide
from .model import ChoreoGraphModel, load_checkpoint
from .repertoire import Repertoire

CHUNK_SECONDS = 32  # seconds of the song selected and warped at once (bounds memory)


class ChoreoGraphGenerator(Generator):
    name = "graph"
    listens_to_spectrum = plugin.listens_to_spectrum  # style and tempo encoders read the log-mel ...
    reads_timbre = plugin.reads_timbre  # ... and nothing else of the music (its beats go to the beat lock)

    def __init__(self, model: ChoreoGraphModel, repertoire: Repertoire, config: GraphConfig = GraphConfig(),
                 names: tuple[str, str] = ("", "")):
        if repertoire.style.shape[1] != model.config.style.style_dim:
            raise ParameterError("the repertoire was described by another model (style size differs); rebuild it")
        self.model, self.repertoire, self.config = model, repertoire, config
        self.checkpoint_name, self.repertoire_name = names

    @classmethod
    def from_files(cls, checkpoint: str | Path, repertoire: str | Path | None = None,
                   config: GraphConfig = GraphConfig()) -> "ChoreoGraphGenerator":
        from . import DEFAULT_REPERTOIRE

        repertoire = Path(repertoire) if repertoire is not None else DEFAULT_REPERTOIRE
        model, _ = load_checkpoint(checkpoint)
        return cls(model, Repertoire.load(repertoire), config, (Path(checkpoint).name, repertoire.name))

    def options(self, request: GenerationRequest) -> GraphConfig:
        return parse_options("graph", GraphConfig, request.options, base=self.config)

    def allowed_clips(self, style: str | None) -> tuple[np.ndarray | None, str | None]:
        """Repertoire clips a style prompt allows: a genre the repertoire has, or all of them."""
        if style is None or not style.strip():
            return None, None
        genres = sorted({g for g in self.repertoire.genres if g})
        match = next((g for g in genres if g.lower() == style.strip().lower()), None)
        if match is None:
            known = ", ".join(genres) or "none: it has no genre labels"
            raise ParameterError(f"the graph backend picks styles from music; --style must be a repertoire genre ({known})")
        return self.repertoire.genre_mask(match), match

    def generate(self, request: GenerationRequest, progress: Callable[[float], None] | None = None) -> Motion:
        config = self.options(request)
        allowed, genre = self.allowed_clips(request.style)
        report = progress or (lambda fraction: None)
        mel = music_log_mel(request.music)
        guide = self.guide(request.constraints, len(mel), config)
        path = self.walk(mel, config, allowed, report, seed=request.seed or 0, guide=guide)
        motion = self.assemble(path, mel, config, guide)  # as many frames as the mel, i.e. the music
        walk_error = None
        if guide is not None and guide.constrained:  # what the walk did not reach exactly, bent onto the constraints
            walk_error = guide.root_error(motion)
            motion = displace_motion(motion, request.constraints, root_reach=len(mel))
        report(1.0)
        motion.metadata = {
            "generator": "graph", "checkpoint": self.checkpoint_name, "repertoire": self.repertoire_name,
            "style": request.style, "genre": genre, "seed": request.seed, "top_k": config.top_k,
            "dynamic_graph": config.dynamic, "retempo": config.retempo,
            "clips": played_clips(path, self.repertoire),
            "constrained_fraction": None if walk_error is None else round(request.constraints.known_fraction(), 4),
            "walk_root_error_m": None if walk_error is None else round(walk_error, 4),
        }  # fmt: skip
        return motion

    def guide(self, constraints: Constraints | None, num_frames: int, config: GraphConfig) -> Guide | None:
        """The walk's guide under ``constraints``, or keeping a free walk on its floor (None: neither)."""
        if constraints is None or constraints.is_empty:
            if not config.keeps_floor:
                return None
            constraints = Constraints.none(num_frames, FPS)
        if constraints.num_frames != num_frames:
            raise ParameterError(f"constraints cover {constraints.num_frames} frames, the song {num_frames}")
        return Guide(constraints, self.repertoire, config)

    def dance(self, mel: np.ndarray, config: GraphConfig, allowed: np.ndarray | None = None,
              progress: Callable[[float], None] = lambda fraction: None) -> Motion:
        """The whole pipeline on a (T, n_mels) log-mel: T frames of motion."""
        motion = self.assemble(self.walk(mel, config, allowed, progress), mel, config)
        progress(1.0)
        return motion

    def assemble(self, path: list[Node], mel: np.ndarray, config: GraphConfig, guide: Guide | None = None) -> Motion:
        start = {} if guide is None else {"start": guide.start}
        return assemble(path, self.repertoire, config.blend_frames, **start).slice_frames(0, len(mel))

    def walk(self, mel: np.ndarray, config: GraphConfig, allowed: np.ndarray | None = None,
             progress: Callable[[float], None] = lambda fraction: None, seed: int = 0,
             guide: Guide | None = None) -> list[Node]:
        """The graph's path, one node per second of the (T, n_mels) log-mel.

        Seconds are processed in chunks (select, warp, then walk the graph through them), so only
        a chunk's candidates and warps are ever held, whatever the song's length.
        """
        seconds = max(1, math.ceil(len(mel) / NODE_FRAMES))
        graph, path = DynamicGraph(self.repertoire, config, seed, guide), []
        for first in range(0, seconds, CHUNK_SECONDS):
            chunk = range(first, min(seconds, first + CHUNK_SECONDS))
            windows = music_windows(self.model, mel, chunk)
            candidates = select_candidates(windows, self.repertoire, config.top_k, self.model.config.style, allowed)
            warps = warp_candidates(windows, candidates, self.repertoire, config)
            for i, t in enumerate(chunk):
                graph.insert(t, candidates[i], warps[i])
                path.append(graph.step(t, windows.style[i]))
            progress(0.9 * chunk.stop / seconds)
        return path
