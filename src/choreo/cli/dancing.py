"""What the dancing commands share: their options, declared here once, the request they build
from them (``choreo.pipeline.DanceRequest``, which ``choreo.dance`` builds too) and the writing of each
song's dance. The CLI only parses, checks output paths before any work, and prints."""

from __future__ import annotations

import functools
import inspect
import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Callable, Optional

import typer

from ..finishing import Finishing
from ..form.options import FormOptions
from ..motion.delivery_options import Delivery
from ..music.beat_options import BeatOptions
from ..pipeline import DanceRequest
from .flags import flag_parameters, given_values, with_parameters
from .progress import progress_bar, stderr_console
from .text import markup

SONG = typer.Argument(..., help="Audio file: wav, mp3, ogg, flac or opus.")
OUTPUT = typer.Option(..., "-o", "--output",
                      help="Output motion file (.bvh, .npz, .json, .npy, .glb, .fbx) or - for stdout; repeat for several.")
GENERATOR = typer.Option("sgmd", help="Backend (see choreo generators).")
PREVIEW = typer.Option(False, "--preview", help="Also render OUTPUT-stem.mp4 (the dancer with the music) beside the output.")
LOOP = typer.Option(False, "--loop", help="A dance that loops, for emotes and idle dances: the song's whole bars from its "
                    "start, led back into its own opening (the turn and travel per cycle are in the file's metadata).")


def shared_options(
    checkpoint: Optional[Path] = typer.Option(None, help="Trained checkpoint (from choreo train); default: the bundled one."),
    format: Optional[str] = typer.Option(None, "--format", "-f", help="Output format; default from the extension "
                                         "(generate --out-dir: a list like bvh,npz)."),
) -> None:
    """The options every dancing command takes besides the request's, the beats', the delivery's,
    the finishing passes' and the backend's (its signature is what counts)."""


@dataclass(frozen=True, kw_only=True)
class DanceFlags:
    """A dancing command's shared flags, as parsed; each group is the dataclass that declares it."""

    generator: str
    checkpoint: Path | None
    format: str | None
    asked: dict[str, Any]  # DanceRequest's own flags given (style, seed, threads)
    beats: BeatOptions
    form: FormOptions
    delivery: Delivery
    finishing: Finishing
    options: dict[str, Any]  # the backend option flags given; the rest: the backend's defaults

    def outputs(self, paths: list[str], preview: bool = False, format: bool = True, fps: float | None = None,
                inputs: tuple = ()) -> "Outputs":
        """Where and how a song's dance is written (``format``: --format names one file's format;
        ``fps``: the rate of the motion the dance continues or edits, which --fps overrides;
        ``inputs``: the files it reads besides the song, none of which it may write over)."""
        from ..errors import ParameterError
        from ..motion.delivery_options import MAX_DELIVERY_FPS, MIN_DELIVERY_FPS

        delivery = self.delivery
        if delivery.fps is None and fps is not None:
            if not MIN_DELIVERY_FPS <= fps <= MAX_DELIVERY_FPS:
                raise ParameterError(f"the given motion is at {fps:g} fps: give --fps ({MIN_DELIVERY_FPS:g} to "
                                     f"{MAX_DELIVERY_FPS:g}) for the dance")
            delivery = replace(delivery, fps=fps)
        return Outputs(paths=paths, format=self.format if format else None, delivery=delivery, preview=preview,
                       inputs=[*inputs, self.beats.beats, self.checkpoint])

    def request(self, constrained: bool = False, loop: bool = False, **factory_options) -> "DanceRequest":
        """The checked request (before any song is read): an unknown backend, a flag it does not
        take, a value it refuses, unreadable --beats, constraints it cannot keep."""
        from ..pipeline import Backend

        backend = Backend(self.generator, self.checkpoint, **factory_options)
        return DanceRequest(backend=backend, **self.asked, options=self.options, finishing=self.finishing,
                            beats=self.beats.source(), constrained=constrained, loop=loop, form=self.form)


def dancing_command(backend: str, choose_generator: bool = True) -> Callable:
    """Decorator of a dancing command: its signature gains the shared options, the finishing
    flags (Finishing's fields) and ``backend``'s option flags (its plugin's options dataclass),
    which it receives as one :class:`DanceFlags` argument, ``dance``. ``choose_generator``: the
    command takes ``--generator`` (default ``backend``)."""
    from ..generator import available_plugins

    plugin = available_plugins().get(backend)
    options_type = plugin.options if plugin is not None else None
    extra = flag_parameters(DanceRequest, given_only=False)
    extra += [p.replace(kind=inspect.Parameter.KEYWORD_ONLY) for p in inspect.signature(shared_options, eval_str=True).parameters.values()]
    extra += flag_parameters(Delivery, given_only=False) + flag_parameters(BeatOptions, given_only=False)
    extra += flag_parameters(FormOptions, given_only=False, panel="The song's form")
    if choose_generator:
        extra.append(inspect.Parameter("generator", inspect.Parameter.KEYWORD_ONLY, default=GENERATOR, annotation=str))
    extra += flag_parameters(Finishing, given_only=False, panel="Finishing passes")
    extra += flag_parameters(options_type, panel=f"{backend} options") if options_type else []

    def decorate(command: Callable) -> Callable:
        @functools.wraps(command)
        def run(**values):
            flags = DanceFlags(generator=values.pop("generator", backend), asked=given_values(DanceRequest, values),
                               beats=BeatOptions(**given_values(BeatOptions, values)),
                               form=FormOptions(**given_values(FormOptions, values)),
                               delivery=Delivery(**given_values(Delivery, values)),
                               finishing=Finishing(**given_values(Finishing, values)),
                               options=given_values(options_type, values) if options_type else {},
                               **{name: values.pop(name) for name in inspect.signature(shared_options).parameters})
            return command(**values, dance=flags)

        own = [p for p in inspect.signature(command, eval_str=True).parameters.values() if p.name != "dance"]
        run.__signature__ = inspect.Signature(own)
        return with_parameters(run, extra)

    return decorate


@dataclass(frozen=True, kw_only=True)
class Outputs:
    """Where one song's dance goes, and how."""

    paths: list[str]  # files, or - for stdout
    format: str | None = None  # overrides the extension (one output)
    delivery: Delivery = Delivery()  # frame rate, travel, rig
    preview: bool = False  # also an MP4 with the music beside the first file
    inputs: list = field(default_factory=list)  # files read besides the song (None: not given)

    @property
    def preview_path(self) -> str | None:
        written = [path for path in self.paths if path != "-"]
        return str(Path(written[0]).with_suffix(".mp4")) if self.preview and written else None

    def check(self, song: Path | None = None) -> None:
        """Every output checked before any work or any file: a writable folder, a known format, and
        none of them an input (``song`` or ``inputs``) or another of them."""
        from ..errors import ParameterError
        from ..fileio import check_outputs_apart, output_target
        from ..formats import check_output_format

        if self.paths.count("-") > 1 or (len(self.paths) > 1 and self.format):
            raise ParameterError("with several outputs, name each by its extension (and at most one '-')")
        for path in self.paths:
            if path != "-":
                output_target(path)  # a writable folder, and nothing there that is not a regular file
            check_output_format(path, self.format, self.delivery.rig, self.delivery.root_motion)
        check_outputs_apart(self.paths + [self.preview_path] * bool(self.preview_path), [song, *self.inputs])


def dance_one(request: "DanceRequest", song: Path, outputs: Outputs, constraints: Callable | None = None) -> dict:
    """Dance one song, write every output atomically, print a line; a summary for --json."""
    from ..formats import write_motions

    outputs.check(song)
    with progress_bar(f"analysing {song.name}") as update:
        music = request.analyse(song, progress=lambda done, total: update(round(done), round(total)))
    fixed = constraints(music) if constraints else None
    started = time.perf_counter()
    with progress_bar("dancing", 100) as update:
        motion = request.dance(music, fixed, progress=lambda fraction: update(round(fraction * 100), 100))
    seconds = time.perf_counter() - started
    motion = outputs.delivery.of(motion)
    meta = motion.metadata
    if meta.get("style_notice"):
        stderr_console.print(f"[yellow]note:[/yellow] {markup(meta['style_notice'])}", highlight=False)
    written = [path for path in outputs.paths if path != "-"]
    companions = {}
    if outputs.preview_path:  # the video joins the motions' all or nothing
        from ..render import RenderConfig
        from .preview import render_preview

        companions[outputs.preview_path] = lambda temporary: render_preview(motion, Path(outputs.preview_path),
                                                                            RenderConfig(), song, into=temporary)
    write_motions(motion, outputs.paths, format=outputs.format, rig=outputs.delivery.rig, companions=companions,
                  root_motion=outputs.delivery.root_motion)
    written += list(companions)
    if written:
        kept = f", {fixed.describe()}" if fixed else ""
        describe = request.backend.plugin.describe
        how = describe(meta) if describe else ""
        loop = meta.get("loop")
        bars = loop and (f"{loop['bars']} bar" if loop["bars"] == 1 else f"{loop['bars']} bars")
        looped = f", a loop of {bars} of {loop['beats_per_bar']} beats" if loop else ""
        returns = len(meta.get("returns") or [])
        if meta.get("form"):
            letters = " ".join(section["label"] for section in meta["form"])
            looped += (f", form {letters}: {returns} return{'' if returns == 1 else 's'} danced as the first" if returns
                       else f", form {letters}: every section danced afresh")
        done = (f"wrote {', '.join(written)}: {motion.duration:.1f} s of {meta.get('genre') or 'dance'} at "
                f"{motion.fps:g} fps{looped} ({request.backend.name}, {how}{kept}; {seconds:.1f} s)")
        stderr_console.print(markup(done), highlight=False)
    return {"song": str(song), "ok": True, "outputs": written, "seconds_of_dance": round(motion.duration, 3),
            "frames": motion.num_frames, "fps": motion.fps, "genre": meta.get("genre"), "seed": request.seed,
            "steps": meta.get("steps"), "generation_seconds": round(seconds, 3)}
