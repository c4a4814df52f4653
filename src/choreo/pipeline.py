"""A song in, a finished dance out: what every dancing command and ``choreo.dance`` run. (The
window-scoring protocol, the repertoire build and experiments call a backend and
``choreo.finishing.finish`` apart, to score or vary one stage.)

    import choreo
    motion = choreo.dance("song.mp3", style="waltz", seed=3)
    motion = choreo.dance("song.mp3", generator="graph", options={"top_k": 128})

A :class:`DanceRequest` is everything but the song, checked when it is made, before any song is
read. Its :meth:`~DanceRequest.dance` analyses a song, builds the constraints against its frames,
lets the backend dance and finishes the dance (:class:`Finishing`, choreo.finishing; re-exported
here, so ``choreo.pipeline.Finishing`` still imports). The dancing commands build one request and
dance every song with it; ``choreo.dance`` builds one per call. Writing files is the caller's
business (``choreo.formats``). The beats are the tracker's unless the caller knows them
(``bpm=128``, ``beats="beats.csv"``; choreo.music.beat_source); the dance's metadata says which
(``"beats"``).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Mapping, Union

from .errors import ParameterError
from .finishing import Finishing  # re-exported: choreo.pipeline.Finishing stays importable
from .form.options import FormOptions
from .generator.base import MAX_SEED, check_seed
from .options import option

if TYPE_CHECKING:
    from .constraints import Constraints
    from .generator import Generator, GeneratorPlugin
    from .motion import Motion
    from .music import BeatSource, Music

ConstraintsFor = Callable[["Music"], "Constraints | None"]  # built once the song's frames are known


class Backend:
    """A backend checked now and loaded when first used: after the song is analysed, so a song
    that cannot be read fails before torch is imported. What it reads of the music comes from its
    plugin, so the analysis does not wait for the weights. Loaded once, kept by this object (a
    batch dances every song with one load)."""

    def __init__(self, name: str = "sgmd", checkpoint: str | os.PathLike | None = None, **factory_options):
        self.name, self.plugin = name, available_plugin(name)
        if checkpoint is None:
            checkpoint = self.plugin.default_checkpoint
            if checkpoint is None or not Path(checkpoint).is_file():
                raise ParameterError(f"generator {name!r} has no bundled checkpoint; pass a checkpoint")
        self.checkpoint, self.bundled = checkpoint, checkpoint == self.plugin.default_checkpoint
        self._factory_options, self._loaded = factory_options, None

    @classmethod
    def holding(cls, generator: "Generator") -> "Backend":
        """A backend already loaded (built by hand or by :func:`load_backend`)."""
        from .generator import available_plugins

        backend = cls.__new__(cls)
        backend.name, backend.plugin, backend._loaded = generator.name, available_plugins().get(generator.name), generator
        backend.checkpoint, backend.bundled, backend._factory_options = None, False, {}
        return backend

    @property
    def listens_to_spectrum(self) -> bool:
        return self._loaded.listens_to_spectrum if self._loaded is not None else self.plugin.listens_to_spectrum

    @property
    def reads_timbre(self) -> bool:
        return self._loaded.reads_timbre if self._loaded is not None else self.plugin.reads_timbre

    def loaded(self) -> "Generator":
        """The loaded backend (loaded now if no earlier call has)."""
        if self._loaded is None:
            self._loaded = self.plugin.factory(self.checkpoint, **self._factory_options)
        return self._loaded


def available_plugin(name: str) -> "GeneratorPlugin":
    """The plugin ``name``, able to generate; one error (exit 2) for each way it can be missing."""
    from .generator import available_plugins

    plugin = available_plugins().get(name)
    if plugin is None:
        raise ParameterError(f"generator {name!r} is not available (see choreo generators)")
    if plugin.factory is None:
        raise ParameterError(f"generator {name!r} is not available: {plugin.status or 'it cannot generate'}")
    return plugin


def load_backend(name: str = "sgmd", checkpoint: str | os.PathLike | None = None, **factory_options) -> "Generator":
    """The backend ``name`` loaded from ``checkpoint`` (default: its bundled one). Keep it and pass
    it to :func:`dance` to dance many songs with one load."""
    return Backend(name, checkpoint, **factory_options).loaded()


@dataclass(frozen=True, kw_only=True)
class DanceRequest:
    """Everything about a dance but the song, checked when made: options the backend does not
    have or refuses, steps the bundled checkpoint's chain cannot take, constraints the backend
    cannot keep, a seed out of range."""

    backend: Backend
    style: str | None = option(None, "Genre (waltz, rumba, ...), its index, free text, or a schedule "
                                     "0:30=waltz,30:=cha-cha.", "--style")
    seed: int = option(0, "Random seed: same seed, same dance (the graph: another walk, another take).", "--seed",
                       bounds=(-MAX_SEED, MAX_SEED))
    options: Mapping[str, Any] = field(default_factory=dict)  # the backend's own; absent ones: its defaults
    finishing: Finishing = Finishing()
    beats: "BeatSource | None" = None  # None: choreo's tracker
    threads: int | None = option(None, "CPU threads to dance with (default: the CPUs this job may use that other work "
                                       "leaves idle; OMP_NUM_THREADS is honoured). The same seed gives the same bytes "
                                       "at any count.", "--threads", bounds=(1, math.inf))
    constrained: bool = False  # whether constraints will come (keys, seed motion, inpainting, a path)
    loop: bool = False  # a dance that loops: whole bars, led back into its opening (choreo.looping)
    form: FormOptions = FormOptions()  # the song's form and how its returns are danced (choreo.form)

    def __post_init__(self):
        check_seed(self.seed)
        if self.threads is not None and self.threads < 1:
            raise ParameterError(f"threads must be at least 1, got {self.threads}")
        if self.loop and self.constrained:
            raise ParameterError("--loop leads the dance back into its own opening: it cannot also keep given "
                                 "frames (--seed-motion, keys, a path)")
        plugin, name = self.backend.plugin, self.backend.name
        if plugin is None:
            return  # a backend object built by hand: it checks its own request
        if self.constrained and not plugin.constraints:
            raise ParameterError(f"the {name} backend does not take constraints (keys, seed motion, inpainting, "
                                 "a path); use sgmd")
        if self.loop and not plugin.constraints:  # a loop's second take is a constrained one
            raise ParameterError(f"the {name} backend cannot lead a dance back into its opening (--loop)")
        if self.options:
            check_options(name, plugin.options, self.options, self.backend.bundled)

    def analyse(self, song: str | os.PathLike, progress: Callable[[float, float], None] | None = None) -> "Music":
        """The song analysed as this request's backend reads it (one decode), with its beats."""
        from .music import BeatSource, Music

        return Music.from_file(song, progress=progress, log_mel=self.backend.listens_to_spectrum,
                               timbre=self.backend.reads_timbre or self.form.analysed, beats=self.beats or BeatSource())

    def dance(self, song: Union[str, os.PathLike, "Music"], constraints: Union["Constraints", ConstraintsFor, None] = None,
              analysis_progress: Callable[[float, float], None] | None = None,
              progress: Callable[[float], None] | None = None) -> "Motion":
        """Dance to ``song`` (an audio file, or its :meth:`analyse`). ``constraints`` (or a
        function building them from the analysed music) fix frames, joints or a root path;
        ``analysis_progress(done, total)`` and ``progress(fraction)`` report the two long steps."""
        from .finishing import finish
        from .music import Music
        from .threads import use_threads

        music = song if isinstance(song, Music) else self.analyse(song, analysis_progress)
        backend = self.backend.loaded()
        fixed = constraints(music) if callable(constraints) else constraints
        form = self.form.of(music, self.style)
        use_threads(self.threads)  # chosen now, beside whatever else runs now
        if self.loop:
            finished = self.looped(backend, music, form, progress)
        else:  # The backend's dance goes straight into finish, which lets go of it after the first pass:
            # an hour's raw dance kept here beside the finished one would add to the peak memory.
            finished = finish(backend.generate(self.generation(music, fixed), progress=progress), music.beat_frames,
                              self.finishing, fixed, audible=music.audible)
            finished = self.returned(finished, music, form, fixed)
        finished.metadata = {**finished.metadata, "beats": music.beat_source, "tempo": round(float(music.tempo), 3)}
        if form is not None:
            finished.metadata["form"] = form.as_json()
        return finished

    def returned(self, danced: "Motion", music: "Music", form, fixed: "Constraints | None" = None,
                 looped: bool = False) -> "Motion":
        """``danced`` with the song's returning sections danced as their first occurrence
        (choreo.form.returns), as exactly as --returns asks. What the user fixed stays; so does a
        loop's seam (no return reaches its ends, and none moves its travel)."""
        if form is None or not self.form.active:
            return danced
        import numpy as np

        from .constraints import parse_style_schedule
        from .form.returns import plan_returns, with_returns

        schedule = parse_style_schedule(self.style, music.duration) if self.style else None
        kept = None if fixed is None else fixed.fixed_frames()
        if looped:
            kept = np.zeros(danced.num_frames, bool)
            kept[[0, -1]] = True
        plan = plan_returns(form, music.beat_times, danced.fps, danced.num_frames, mirror=self.form.mirror_returns,
                            fixed=kept, schedule=schedule)
        keep_path = looped or (fixed is not None and bool(fixed.root_known.any()))
        returned = with_returns(danced, plan, self.form.returns, keep_path=keep_path)
        if not (plan and self.finishing.footsteps and self.form.returns > 0):
            return returned
        from .finishing import footsteps
        from .form.returns import away_from_joins

        kept = away_from_joins(plan, danced.num_frames, danced.fps) | (False if kept is None else kept)
        config = self.finishing.configs.get("footsteps")  # the feet a join's bend made slide, planted again
        return footsteps(returned, kept, **({} if config is None else {"config": config}))

    def looped(self, backend: "Generator", music: "Music", form=None,
               progress: Callable[[float], None] | None = None) -> "Motion":
        """A dance that loops (choreo.looping): danced once, then again led back into its own
        opening, finished as an endless loop plays it, and cut to its whole bars."""
        from .finishing import finish
        from .looping import Loop

        loop = Loop.of(music, self.style)
        danced = loop.music(music, loop.after)
        first = backend.generate(self.generation(danced), progress=progress and (lambda done: progress(done / 2)))
        cycle = loop.cycle(first)
        second = backend.generate(self.generation(danced, loop.constraints(first, cycle)),
                                  progress=progress and (lambda done: progress(0.5 + done / 2)))
        around = loop.periodic(second, cycle)
        looped = loop.cut(finish(around, loop.music(music).beat_frames, self.finishing,
                                 anchors=loop.anchors(around.num_frames)))
        return self.returned(looped, music, form, looped=True)

    def generation(self, music: "Music", constraints: "Constraints | None" = None):
        """What the backend is asked for one dance to ``music``."""
        from .generator import GenerationRequest

        return GenerationRequest(music, style=self.style, seed=self.seed, options=dict(self.options),
                                 constraints=constraints)


def check_options(backend: str, options_type: type | None, given: Mapping[str, Any], bundled: bool) -> None:
    """Refuse options ``options_type`` does not have (None: a backend without options) or refuses;
    on the bundled checkpoint, also steps its noise chain cannot take (an options type with
    ``bundled_timesteps`` and ``on_chain``), so that they fail now rather than after the song's analysis."""
    from .options import parse_options

    if options_type is None:
        raise ParameterError(f"{backend} has no options (given: {', '.join(sorted(given))})")

    chosen = parse_options(backend, options_type, given)
    chain = getattr(chosen, "bundled_timesteps", None)
    if bundled and chain is not None:
        try:
            chosen.on_chain(chain, "steps" in given)  # --steps 1001, or ddpm with --steps 10
        except ValueError as error:
            raise ParameterError(f"{backend}: {error}") from None


def dance(
    song: Union[str, os.PathLike, "Music"],
    generator: Union[str, "Generator", Backend] = "sgmd",
    *,
    style: str | None = None,
    seed: int = 0,
    options: Mapping[str, Any] | None = None,
    constraints: Union["Constraints", ConstraintsFor, None] = None,
    checkpoint: str | os.PathLike | None = None,
    finishing: Finishing = Finishing(),
    analysis_progress: Callable[[float, float], None] | None = None,
    progress: Callable[[float], None] | None = None,
    bpm: float | None = None,
    beats: str | os.PathLike | None = None,
    threads: int | None = None,
    beat_tracker: str = "choreo",
    loop: bool = False,
    form: str | None = None,
    returns: float = FormOptions.returns,
    mirror_returns: bool = False,
) -> "Motion":
    """Dance to ``song`` (an audio file or an analysed :class:`Music`) with one backend.

    ``generator`` is a backend name (see `choreo generators`; loaded from ``checkpoint`` once the
    song is analysed), a :class:`Backend` or a loaded backend (:func:`load_backend`); ``options``
    are that backend's own (sgmd: steps, guidance, sampler; graph: top_k, ...). ``bpm`` (the tempo;
    the phase is still tracked) or ``beats`` (a file of beat times, see choreo.music.beat_file)
    replace the tracked beats everywhere: features, beat lock, backend; ``beat_tracker="madmom"``
    has madmom's trained tracker hear them (the madmom extra; its models are CC BY-NC-SA 4.0,
    non-commercial). ``loop``: a dance of whole bars that ends where it began (choreo.looping).
    ``form`` ("0:00=A,0:16=B,0:32=A", or "auto": analysed; default None: every section danced
    afresh), ``returns`` (0: returning sections danced afresh, 1: their first occurrence's phrase)
    and ``mirror_returns``: choreo.form.
    The rest: :class:`DanceRequest` and its ``dance``.
    """
    from .music import BeatOptions, Music

    if isinstance(generator, str):
        backend = Backend(generator, checkpoint)
    else:
        backend = generator if isinstance(generator, Backend) else Backend.holding(generator)
    beat_options = BeatOptions(bpm=bpm, beats=beats, beat_tracker=beat_tracker)
    if beat_options.given and isinstance(song, Music):
        raise ParameterError("the music is already analysed: give its beats to Music.from_file instead")
    request = DanceRequest(backend=backend, style=style, seed=seed, options=dict(options or {}), finishing=finishing,
                           beats=beat_options.source() if beat_options.given else None,
                           threads=threads, constrained=constraints is not None, loop=loop,
                           form=FormOptions(form=form, returns=returns, mirror_returns=mirror_returns))
    return request.dance(song, constraints, analysis_progress, progress)
