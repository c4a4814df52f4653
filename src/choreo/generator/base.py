"""What a generator backend is, as far as the core is concerned.

Backends never read files or parse flags: they take a :class:`GenerationRequest` built from
already-loaded :class:`~choreo.music.Music` and return a :class:`~choreo.motion.Motion`. The CLI
and the writers do the rest, identically for every backend.
"""

from __future__ import annotations

import abc
from pathlib import Path
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Callable, Sequence

if TYPE_CHECKING:  # keep `choreo generators` fast: no torch/librosa import for type hints
    from ..constraints import Constraints
    from ..motion import Motion
    from ..music import Music


# Seeds any backend takes: numpy's generators refuse negatives and torch's overflow past 64 bits, and
# SGMD derives a block's seed as seed x 1,000,003 + block; 32 bits of takes is more than anyone dances.
MAX_SEED = 2**32 - 1


def check_seed(seed: int | None) -> None:
    """Refuse a seed outside +-MAX_SEED in one line (it overflowed inside the backends: exit 70)."""
    from ..errors import ParameterError

    if seed is not None and not -MAX_SEED <= seed <= MAX_SEED:
        raise ParameterError(f"seed must be {-MAX_SEED} to {MAX_SEED}, got {str(seed)[:24]}")


@dataclass(frozen=True)
class GenerationRequest:
    music: "Music"
    style: str | None = None  # a genre name, one-hot index or free-text description
    seed: int | None = None  # within +-MAX_SEED
    options: dict[str, Any] = field(default_factory=dict)  # backend-specific, validated by it
    constraints: "Constraints | None" = None  # known frames/joints/root path (controllable generation)

    def __post_init__(self):
        check_seed(self.seed)


class Generator(abc.ABC):
    """A loaded backend, ready to turn music into motion."""

    name: str = ""
    listens_to_spectrum: bool = False  # True: it reads music.log_mel, analysed in the same decode as the rest
    reads_timbre: bool = True  # False: it needs only the rhythm (and log-mel), so MFCC and chroma are skipped

    @abc.abstractmethod
    def generate(self, request: GenerationRequest, progress: Callable[[float], None] | None = None) -> "Motion":
        """Dance to ``request.music``; ``progress`` receives the fraction done in [0, 1]."""

    def generate_windows(self, requests: Sequence[GenerationRequest]) -> list["Motion"]:
        """Dances for many short excerpts at once (scoring protocols, batch tools).

        This default dances them one by one. A backend that can batch overrides it; its dances
        are then deterministic for the same requests but need not equal ``generate`` called on each.
        """
        return [self.generate(request) for request in requests]


@dataclass
class TrainProgress:
    """What a backend's training loop reports to `choreo train`'s progress bar."""

    step: int
    max_steps: int
    loss: float
    windows_per_second: float
    validation_loss: float | None
    stage: str = ""  # for backends trained in stages (e.g. "style", "tempo")


@dataclass(frozen=True, kw_only=True)
class GeneratorPlugin:
    """What a backend package registers under the ``choreo.generators`` entry-point group."""

    name: str
    summary: str
    ready: bool = True  # False while the backend is a placeholder
    status: str = ""  # shown when not ready: what is missing and where it is tracked
    factory: Callable[..., Generator] | None = None  # builds a Generator (e.g. from a checkpoint)
    train: Callable[..., object] | None = None  # train(data_dir, out_dir, options, resume, progress, load_progress)
    train_options: type | None = None  # dataclass of what `choreo train NAME` takes: its option() fields are the flags
    default_checkpoint: Path | None = None  # shipped weights used when the user names none
    options: type | None = None  # dataclass of its generation options, checked before any work; option() fields are flags
    # the few words a command prints about a run, from the dance's metadata ("ddim 10 steps, guidance 2, seed 0")
    describe: Callable[[dict], str] | None = None
    constraints: bool = False  # whether it dances under constraints (keys, seed motion, inpainting, a root path)
    # what it reads of the music (its Generator's attributes of the same names), known before it
    # loads, so the song is analysed before the weights are read (choreo.pipeline.Backend)
    listens_to_spectrum: bool = False
    reads_timbre: bool = True
