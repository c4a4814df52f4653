"""ChoreoGraph (Chen et al.): style-selected, beat-warped dynamic motion graph, the `choreo graph` backend.

The bundled models (``weights/graph-m2d.pt``) were trained on the M2D train split; the bundled
repertoire (``weights/repertoire-sgmd.npz``) holds clips the bundled SGMD model generated, not
M2D motion (which may not be redistributed). docs/graph.md has the commands for both.
"""

from __future__ import annotations

from pathlib import Path

from choreo.generator import GeneratorPlugin
from choreo.options import forwarded
from choreo.lazy import lazy_exports

from .config import CLIP_FRAMES, GraphConfig, TrainOptions

__all__ = [
    "DEFAULT_CHECKPOINT", "DEFAULT_REPERTOIRE", "plugin", "build_generator", "train_from_dataset",
    "build_repertoire_file", "GraphConfig", "TrainOptions",
    # below: what scripts and benchmarks reach past `choreo.load_backend("graph")` for (issue 39)
    "CLIP_FRAMES", "dataset_generator", "Repertoire", "SpeedLimits", "music_windows", "select_candidates",
    "replayed_nodes",
]
# GraphConfig: the generator's options (top_k, dynamic, retempo, repeat_cost...); CLIP_FRAMES: frames in one
# repertoire clip (8 s at 30 fps).

# Loaded on first use (PEP 562), so `import choreo_graph` (every CLI start finds the plugin) stays torch-free.
_LAZY = {
    "Repertoire": ".repertoire",  # a repertoire file's clips (Repertoire.load, .save)
    "SpeedLimits": ".repertoire",  # the clips `build_repertoire_file` leaves out (its ``limits``)
    "music_windows": ".graph",  # the models' reading of a log-mel, one 4 s window per second (the selector's input)
    "select_candidates": ".graph",  # the K repertoire clips the style selector picks for those windows
    "replayed_nodes": ".graph",  # how many seconds of a walk replay source frames danced shortly before
}

WEIGHTS = Path(__file__).parent / "weights"
DEFAULT_CHECKPOINT = WEIGHTS / "graph-m2d.pt"
DEFAULT_REPERTOIRE = WEIGHTS / "repertoire-sgmd.npz"


def train_from_dataset(data_dir: str | Path, out_dir: str | Path, options: TrainOptions = TrainOptions(),
                       resume: bool = False, progress=None, load_progress=None) -> Path:
    """Train the style encoders and tempo-density estimators on a dataset's train split (its test
    split is reported as validation). ``options.steps`` sets every stage's step count."""
    from dataclasses import replace

    from choreo.datasets import TEST, TRAIN, load_dataset
    from choreo.errors import ParameterError
    from choreo.metrics.protocol import clip_log_mels

    from .config import CLIP_FRAMES, WINDOW_FRAMES, TrainConfig
    from .data import paired_excerpts
    from .training import STYLE_STRIDE, train_graph

    if resume:
        raise ParameterError("graph training cannot resume (it keeps no optimiser state): start it again")
    stages = {} if options.steps is None else dict.fromkeys(("style_steps", "motion_tempo_steps", "music_tempo_steps"),
                                                             options.steps)
    config = replace(TrainConfig(), **forwarded(TrainConfig, options), **stages)
    clips = [c for c in load_dataset(data_dir, progress=load_progress) if c.audio_path]
    mels = clip_log_mels(clips)
    train = [c for c in clips if c.split in (TRAIN, None)]
    test = [c for c in clips if c.split == TEST]

    def excerpts(chosen):
        return (paired_excerpts(chosen, WINDOW_FRAMES, STYLE_STRIDE, mels),
                paired_excerpts(chosen, CLIP_FRAMES, config.clip_stride, mels))

    style_data, clip_data = excerpts(train)
    return train_graph(style_data, clip_data, excerpts(test) if test else None, out_dir, config=config, progress=progress)


def build_repertoire_file(motions, out: str | Path, source: str, stride: int, checkpoint: str | Path | None = None,
                          limits=None, progress=None):
    """Cut, describe (with the bundled or given models) and save a repertoire; returns it.

    ``motions`` are (name, motion at 30 fps, genre) triples; ``stride`` is in frames; ``limits``
    a ``SpeedLimits`` (none by default)."""
    from .model import load_checkpoint
    from .repertoire import SpeedLimits, build_repertoire

    model, _ = load_checkpoint(checkpoint or DEFAULT_CHECKPOINT)
    repertoire = build_repertoire(motions, model, stride, source, progress, limits or SpeedLimits())
    repertoire.save(out)
    return repertoire


def build_generator(checkpoint: str | Path, repertoire: str | Path | None = None, **graph_options):
    """The generator; ``graph_options`` are GraphConfig fields (top_k, dynamic, retempo...)."""
    from .config import GraphConfig
    from .generator import ChoreoGraphGenerator

    return ChoreoGraphGenerator.from_files(checkpoint, repertoire, GraphConfig(**graph_options))


def dataset_generator(clips, stride: int, source: str, checkpoint: str | Path | None = None):
    """The generator dancing from a repertoire cut from dataset ``clips`` (every 8 s clip, ``stride``
    frames apart, described by the bundled or given models) instead of a repertoire file: how
    scripts/evaluate_graph.py and benchmarks/report.py score it on M2D's test windows."""
    from .evaluation import clips_repertoire
    from .generator import ChoreoGraphGenerator
    from .model import load_checkpoint

    model, _ = load_checkpoint(checkpoint or DEFAULT_CHECKPOINT)
    return ChoreoGraphGenerator(model, clips_repertoire(model, clips, stride, source))


__getattr__, __dir__ = lazy_exports(__name__, _LAZY, globals())


def describe_run(meta: dict) -> str:
    """'K = 512, repertoire repertoire-sgmd.npz': how a dance was assembled."""
    return f"K = {meta.get('top_k')}, repertoire {meta.get('repertoire')}"


_READY = DEFAULT_CHECKPOINT.is_file() and DEFAULT_REPERTOIRE.is_file()

plugin = GeneratorPlugin(
    name="graph",
    summary="style embeddings + tempo-density DTW + dynamic motion graph (choreo graph)",
    ready=_READY,
    status="" if _READY else f"bundled models or repertoire missing under {WEIGHTS}; pass --checkpoint and --repertoire",
    factory=build_generator,
    train=train_from_dataset,
    default_checkpoint=DEFAULT_CHECKPOINT,
    options=GraphConfig,
    train_options=TrainOptions,
    constraints=True,
    listens_to_spectrum=True,
    reads_timbre=False,
    describe=describe_run,
)
