"""A song in, a finished dance out: the pipeline every command, script and benchmark shares.

    import choreo
    motion = choreo.dance("song.mp3", style="waltz", seed=3)
    motion = choreo.dance("song.mp3", generator="graph", options={"top_k": 128})

Steps: analyse the song (or take a :class:`~choreo.music.Music`), build the constraints against
its frames, let the backend dance, then the finishing passes (beat lock on, foot lock off, as
measured in docs/results.md). Writing files is the caller's business (``choreo.formats``).
The beats are the tracker's unless the caller knows them: ``bpm=128`` or ``beats="beats.csv"``
(choreo.music.beat_source); the dance's metadata says which (``"beats"``).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Union

if TYPE_CHECKING:
    from .constraints import Constraints
    from .generator import Generator
    from .motion import Motion
    from .music import Music

ConstraintsFor = Callable[["Music"], "Constraints | None"]  # built once the song's frames are known


@dataclass(frozen=True)
class Finishing:
    """The passes every dance goes through after its backend (choreo.finishing)."""

    beat_lock: bool = True  # motion beats re-timed onto the music's beats (given frames stay)
    foot_lock: bool = False  # planted feet's drift moved onto the root (halves PFC, doubles FID_g)
    speed_limit: bool = True  # turns and dashes faster than real dancers' spread over neighbouring frames
    footsteps: bool = True  # feet stand until the body leaves them, then step (legs by IK; docs/results.md, "Feet")
    root_path: bool = True  # the root's travel low-passed, its wobble removed (choreo.finishing.root_path)
    pace: bool = True  # a free dance's travel brought toward its genre's real pace (choreo.finishing.pace)


_BACKENDS: dict[tuple, "Generator"] = {}


def load_backend(name: str = "sgmd", checkpoint: str | os.PathLike | None = None, **factory_options) -> "Generator":
    """The backend ``name`` loaded from ``checkpoint`` (default: its bundled one), kept for reuse:
    a script dancing many songs loads the weights once."""
    return PendingBackend(name, checkpoint, **factory_options).result()


class PendingBackend:
    """A backend checked now and loaded when first needed: after the song is analysed, so a song
    that cannot be read fails before torch is imported. What the backend reads of the music comes
    from its plugin, so the analysis does not wait for the weights. An unknown backend or a
    missing bundled checkpoint is refused at once. (Loading on a thread during the analysis saved
    2-5 % of a `choreo generate`, measured on 2026-12-04: removed, docs/results.md.)
    """

    def __init__(self, name: str, checkpoint: str | os.PathLike | None = None, **factory_options):
        self.name, self.plugin = name, _available_plugin(name)
        if checkpoint is None:
            checkpoint = self.plugin.default_checkpoint
            if checkpoint is None or not Path(checkpoint).is_file():
                from .errors import ChoreoError

                raise ChoreoError(f"{name} has no bundled checkpoint; pass a checkpoint")
        self._checkpoint, self._options = checkpoint, factory_options
        self._key = (name, str(checkpoint), tuple(sorted((k, str(v)) for k, v in factory_options.items())))

    @property
    def listens_to_spectrum(self) -> bool:
        return self.plugin.listens_to_spectrum

    @property
    def reads_timbre(self) -> bool:
        return self.plugin.reads_timbre

    def result(self) -> "Generator":
        """The loaded backend (loaded now if no earlier call has)."""
        if self._key not in _BACKENDS:
            _BACKENDS[self._key] = self.plugin.factory(self._checkpoint, **self._options)
        return _BACKENDS[self._key]


def _available_plugin(name: str):
    from .errors import ChoreoError, ParameterError
    from .generator import available_plugins

    plugin = available_plugins().get(name)
    if plugin is None:
        raise ParameterError(f"generator {name!r} is not available (see choreo generators)")
    if plugin.factory is None:
        raise ChoreoError(f"generator {name!r} is not available: {plugin.status or 'it cannot generate'}")
    return plugin


def check_request(backend: str, options: dict[str, Any], constrained: bool) -> None:
    """Refuse, before any work, options the backend does not have and constraints it cannot keep."""
    from .errors import ParameterError
    from .generator import available_plugins
    from .generator.options import parse_options

    plugin = available_plugins().get(backend)
    if plugin is None:
        return  # a backend object built by hand: it checks its own request
    if plugin.options is not None:
        parse_options(backend, plugin.options, options)
    if constrained and not plugin.constraints:
        raise ParameterError(f"the {backend} backend does not take constraints (keys, seed motion, inpainting, a path);"
                             " use sgmd")


def dance(
    song: Union[str, os.PathLike, "Music"],
    generator: Union[str, "Generator", PendingBackend] = "sgmd",
    *,
    style: str | None = None,
    seed: int = 0,
    options: dict[str, Any] | None = None,
    constraints: Union["Constraints", ConstraintsFor, None] = None,
    checkpoint: str | os.PathLike | None = None,
    finishing: Finishing = Finishing(),
    analysis_progress: Callable[[float, float], None] | None = None,
    progress: Callable[[float], None] | None = None,
    bpm: float | None = None,
    beats: str | os.PathLike | None = None,
    threads: int | None = None,
    beat_tracker: str = "choreo",
) -> "Motion":
    """Dance to ``song`` (an audio file or an analysed :class:`Music`) with one backend.

    ``generator`` is a backend name (see `choreo generators`; it loads while the song is analysed),
    a :class:`PendingBackend` or a loaded backend; ``options`` are that backend's own (sgmd:
    steps, guidance, sampler; graph: top_k, ...); ``constraints``
    (or a function building them from the analysed music) fix frames, joints or a root path.
    ``analysis_progress(done, total)`` and ``progress(fraction)`` report the two long steps.
    ``bpm`` (the tempo; the phase is still tracked) or ``beats`` (a file of beat times, see
    choreo.music.beat_file) replace the tracked beats everywhere: features, beat lock, backend;
    ``beat_tracker="madmom"`` has madmom's trained tracker hear them (the madmom extra; its models
    are CC BY-NC-SA 4.0, non-commercial).
    ``threads``: torch threads for the dance (default: the CPUs other work leaves idle, choreo.threads).
    """
    from .errors import ParameterError
    from .finishing import PaceConfig, RootPathConfig, finish
    from .finishing.steps import TURNED_JOINTS
    from .generator import GenerationRequest
    from .threads import use_threads
    from .music import BeatSource, Music

    check_request(generator if isinstance(generator, str) else generator.name, options or {},
                  constraints is not None)  # before any work
    beat_source = BeatSource.from_options(bpm, beats, beat_tracker)
    if isinstance(song, Music) and (bpm is not None or beats is not None or beat_tracker != "choreo"):
        raise ParameterError("the music is already analysed: give its beats to Music.from_file instead")
    backend = PendingBackend(generator, checkpoint) if isinstance(generator, str) else generator
    music = song if isinstance(song, Music) else Music.from_file(song, progress=analysis_progress,
                                                                  log_mel=backend.listens_to_spectrum,
                                                                  timbre=backend.reads_timbre, beats=beat_source)
    if isinstance(backend, PendingBackend):
        backend = backend.result()
    fixed = constraints(music) if callable(constraints) else constraints
    request = GenerationRequest(music, style=style, seed=seed, options=dict(options or {}), constraints=fixed)
    use_threads(threads)  # chosen now, beside whatever else runs now
    frames = None if fixed is None else fixed.fixed_frames()
    legs = None if fixed is None else fixed.frames_fixing(TURNED_JOINTS)
    # The backend's dance goes straight into finish, which lets go of it after the first pass: an
    # hour's raw dance kept here beside the finished one would add to the peak memory.
    finished = finish(backend.generate(request, progress=progress), music.beat_frames, frames,
                      beat=finishing.beat_lock, foot=finishing.foot_lock, speed=finishing.speed_limit,
                      footsteps=finishing.footsteps, legs_fixed=legs,
                      root_path=RootPathConfig() if finishing.root_path else None,
                      pace=PaceConfig() if finishing.pace else None)
    finished.metadata = {**finished.metadata, "beats": music.beat_source, "tempo": round(float(music.tempo), 3)}
    return finished
