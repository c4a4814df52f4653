"""choreo.dance(): the library entry point the CLI, scripts and benchmarks share."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import choreo
from choreo.constraints import Constraints
from choreo.music import Music
from choreo.pipeline import Finishing, load_backend

SONG = Path(__file__).parents[1] / "examples" / "drum_and_bass_174bpm.wav"


@pytest.fixture(scope="module")
def music():
    return Music.from_file(SONG, end=6.0)


def test_dance_returns_the_song_long_dance_and_seeds_decide_it(music, tiny_checkpoint):
    first = choreo.dance(music, checkpoint=tiny_checkpoint, seed=1)
    assert first.num_frames == music.num_frames and first.fps == music.fps
    again = choreo.dance(music, checkpoint=tiny_checkpoint, seed=1)
    other = choreo.dance(music, checkpoint=tiny_checkpoint, seed=2)
    np.testing.assert_array_equal(first.rotations, again.rotations)
    assert not np.allclose(first.rotations, other.rotations)


def test_dance_takes_a_file_and_the_same_options_as_the_cli(tiny_checkpoint, tmp_path):
    from choreo.cli import main
    from choreo.formats import read_motion

    assert main(["generate", str(SONG), "-o", str(tmp_path / "d.npz"), "--checkpoint", str(tiny_checkpoint),
                 "--seed", "4", "--steps", "3", "--guidance", "1.5", "--no-beat-lock"]) == 0
    written = read_motion(tmp_path / "d.npz")
    danced = choreo.dance(SONG, checkpoint=tiny_checkpoint, seed=4, options={"steps": 3, "guidance": 1.5},
                          finishing=Finishing(beat_lock=False))
    np.testing.assert_allclose(danced.joint_positions(), written.joint_positions(), atol=1e-5)


def test_constraints_built_from_the_music_are_kept(music, tiny_checkpoint):
    pose = choreo.dance(music, checkpoint=tiny_checkpoint, seed=0).slice_frames(0, 1)

    def opening(m):
        return Constraints.none(m.num_frames, m.fps).fix_motion(pose, at=30)

    danced = choreo.dance(music, checkpoint=tiny_checkpoint, seed=9, constraints=opening)
    np.testing.assert_allclose(danced.joint_positions()[30], pose.joint_positions()[0], atol=1e-4)


def test_a_backend_loads_once_and_dances_every_song(music, tiny_checkpoint):
    from choreo.pipeline import Backend, DanceRequest

    backend = Backend("sgmd", tiny_checkpoint)
    request = DanceRequest(backend=backend, options={"steps": 2})
    request.dance(music)
    loaded = backend.loaded()
    request.dance(music)
    assert backend.loaded() is loaded
    # and no process-wide cache keeps every model ever loaded alive
    assert load_backend("sgmd", tiny_checkpoint) is not load_backend("sgmd", tiny_checkpoint)


def test_every_way_a_backend_can_be_missing_is_one_error(monkeypatch, tmp_path):
    from dataclasses import replace

    import choreo.generator
    from choreo.cli import main
    from choreo.errors import ParameterError
    from choreo.generator import GeneratorPlugin

    real = choreo.generator.available_plugins()
    plugins = {**real, "broken": GeneratorPlugin(name="broken", summary="", ready=False, status="no weights"),
               "unweighted": replace(real["sgmd"], name="unweighted", default_checkpoint=tmp_path / "missing.pt")}
    monkeypatch.setattr(choreo.generator, "available_plugins", lambda: plugins)
    for name in ("nope", "broken", "unweighted"):
        with pytest.raises(ParameterError, match=name):
            choreo.dance(SONG, generator=name)
        assert main(["generate", str(SONG), "-o", str(tmp_path / "d.bvh"), "--generator", name]) == 2
        assert not (tmp_path / "d.bvh").exists()


def test_a_request_is_checked_when_it_is_made_and_loads_nothing(tiny_checkpoint):
    from choreo.errors import ParameterError
    from choreo.pipeline import Backend, DanceRequest

    backend = Backend("sgmd", tiny_checkpoint)
    for bad in ({"guidance": 1e308}, {"nonsense": 1}, {"steps": 0}):
        with pytest.raises(ParameterError):
            DanceRequest(backend=backend, options=bad)
    with pytest.raises(ParameterError, match="seed"):
        DanceRequest(backend=backend, seed=2**40)
    with pytest.raises(ParameterError, match="steps"):  # the bundled checkpoint's chain is known before it loads
        DanceRequest(backend=Backend("sgmd"), options={"steps": 1001})
    DanceRequest(backend=backend, options={"steps": 1001})  # another checkpoint's chain is checked once it loads
    assert backend._loaded is None


def test_settings_dataclasses_are_keyword_only():
    from choreo.finishing import FootstepsConfig
    from choreo_graph import GraphConfig
    from choreo_sgmd import SamplingOptions

    for settings in (Finishing, GraphConfig, SamplingOptions, FootstepsConfig):
        with pytest.raises(TypeError):
            settings(True)


def test_unknown_backend_is_a_parameter_error(music):
    from choreo.errors import ParameterError

    with pytest.raises(ParameterError, match="not available"):
        choreo.dance(music, "no-such-backend")


def test_importing_choreo_does_not_import_torch_or_librosa():
    code = "import sys, choreo; choreo.dance; print('torch' in sys.modules, 'librosa' in sys.modules)"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.split() == ["False", "False"]


def test_loading_the_default_sgmd_model_imports_neither_librosa_nor_sympy():
    """The weights are checked against a layout on torch's meta device; drawing random values
    there imports torch's reference decompositions and sympy (about 3 s per process, measured)."""
    code = ("import sys, choreo_sgmd; from choreo_sgmd.generator import SGMDGenerator; "
            "SGMDGenerator(choreo_sgmd.DEFAULT_CHECKPOINT); print('sympy' in sys.modules, 'librosa' in sys.modules)")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.split() == ["False", "False"]


def test_options_a_backend_lacks_are_refused_before_the_song_is_read(tiny_checkpoint, tmp_path):
    from choreo.errors import ParameterError

    missing = tmp_path / "not-read.wav"  # never opened: the refusal comes first
    with pytest.raises(ParameterError, match=r"^sgmd has no option top_k \(its options: .*guidance.*\)$"):
        choreo.dance(missing, checkpoint=tiny_checkpoint, options={"top_k": 3})
    with pytest.raises(ParameterError, match="unknown sampler 'euler'"):
        choreo.dance(missing, checkpoint=tiny_checkpoint, options={"sampler": "euler"})


def test_cli_refuses_constraints_a_backend_cannot_keep_before_any_work(tmp_path, capsys, monkeypatch):
    # Both bundled backends take constraints; a plugin that declares it does not is refused first.
    import dataclasses

    import choreo.generator
    from choreo.cli import main

    plugins = choreo.generator.available_plugins()
    unconstrained = {**plugins, "graph": dataclasses.replace(plugins["graph"], constraints=False)}
    monkeypatch.setattr(choreo.generator, "available_plugins", lambda: unconstrained)

    def analysed(*args, **kwargs):
        raise AssertionError("the song was analysed before the refusal")

    monkeypatch.setattr(Music, "from_file", analysed)
    code = main(["inbetween", str(SONG), "--start", "x.bvh", "-o", str(tmp_path / "o.bvh"), "--generator", "graph"])
    err = capsys.readouterr().err
    assert code == 2 and not any(tmp_path.iterdir())
    assert err.strip().endswith("the graph backend does not take constraints (keys, seed motion, inpainting, a path); use sgmd")


def test_a_backend_that_listens_to_the_spectrum_gets_it_from_the_one_decode(monkeypatch):
    # The graph reads the log-mel; it used to decode the song a second time for it.
    import choreo.music.audio as audio
    import choreo.music.mel as mel
    import choreo.music.music as music_module

    song = Path(__file__).resolve().parents[1] / "examples" / "drum_and_bass_174bpm.wav"
    expected = mel.log_mel_from_file(song, 0.0, Music.from_file(song).num_frames)
    decodes = []

    def counted(*args, **kwargs):
        decodes.append(args[0])
        return audio.iter_audio_blocks(*args, **kwargs)

    monkeypatch.setattr(music_module, "iter_audio_blocks", counted)
    monkeypatch.setattr(mel, "iter_audio_blocks", counted)
    analysed = Music.from_file(song, log_mel=True)
    np.testing.assert_array_equal(analysed.log_mel, expected)  # the same frames as a decode of its own
    assert len(decodes) == 1
    motion = choreo.dance(song, generator="graph", finishing=Finishing(beat_lock=False))
    assert len(decodes) == 2 and motion.num_frames == analysed.num_frames  # one more song, one more decode
    assert load_backend("graph").listens_to_spectrum and not Music.from_file(song).log_mel


def test_the_graph_dances_to_music_made_from_an_array():
    from tests.music.helpers import click_track

    from choreo.music import SAMPLE_RATE

    music = Music.from_array(click_track(120.0, 8.0, SAMPLE_RATE), SAMPLE_RATE, log_mel=True)
    assert music.log_mel.shape == (music.num_frames, 96)
    assert choreo.dance(music, generator="graph").num_frames == music.num_frames
    with pytest.raises(choreo.errors.ParameterError, match="needs the song's audio file"):
        choreo.dance(Music.from_array(click_track(120.0, 8.0, SAMPLE_RATE), SAMPLE_RATE), generator="graph")


def test_the_song_is_analysed_before_the_backend_loads(monkeypatch, tiny_checkpoint):
    """A song that cannot be read fails before torch and the weights are loaded."""
    import choreo.pipeline

    order = []
    load, analyse = choreo.pipeline.Backend.loaded, Music.from_file
    monkeypatch.setattr(choreo.pipeline.Backend, "loaded", lambda self: order.append("load") or load(self))
    monkeypatch.setattr(Music, "from_file", lambda *a, **k: order.append("analyse") or analyse(*a, **k))
    motion = choreo.dance(SONG, checkpoint=tiny_checkpoint, options={"steps": 2})
    assert order == ["analyse", "load"] and motion.num_frames > 0


def test_what_a_plugin_says_it_reads_of_the_music_is_what_its_backend_reads():
    from choreo.generator import available_plugins

    for name in ("sgmd", "graph"):
        plugin, backend = available_plugins()[name], load_backend(name)
        assert (plugin.listens_to_spectrum, plugin.reads_timbre) == (backend.listens_to_spectrum, backend.reads_timbre)


def test_an_error_while_loading_reaches_the_caller(tmp_path):
    from choreo.errors import InputError
    from choreo.pipeline import Backend

    damaged = tmp_path / "damaged.pt"
    damaged.write_bytes(b"not a checkpoint")
    pending = Backend("sgmd", damaged)  # not read yet
    assert pending.reads_timbre and not pending.listens_to_spectrum  # known before the weights are read
    with pytest.raises(InputError, match="damaged.pt"):
        pending.loaded()
    with pytest.raises(InputError, match="damaged.pt"):
        choreo.dance(SONG, checkpoint=damaged)


def test_a_song_that_cannot_be_read_exits_with_one_line(tmp_path):
    bad = tmp_path / "noise.wav"
    bad.write_bytes(b"RIFF....WAVEfmt not really")
    for _ in range(3):
        done = subprocess.run([sys.executable, "-m", "choreo", "generate", str(bad), "-o", str(tmp_path / "d.bvh")],
                              capture_output=True, text=True)
        assert done.returncode == 2, done.stderr
        assert len(done.stderr.strip().splitlines()) == 1 and "noise.wav" in done.stderr
        assert not (tmp_path / "d.bvh").exists()


def test_a_song_ending_in_silence_gets_a_dancer_at_rest_there(tiny_checkpoint):
    import soundfile as sf
    from choreo.motion.beats import mean_joint_speed

    samples, sr = sf.read(SONG, dtype="float32", frames=22050 * 6)
    samples = samples.mean(axis=1) if samples.ndim > 1 else samples
    song = Music.from_array(np.concatenate([samples, np.zeros(3 * sr, np.float32)]), sr)
    assert abs(song.audible[1] - 180) <= 8
    dance = choreo.dance(song, checkpoint=tiny_checkpoint, seed=1)
    assert np.all(mean_joint_speed(dance.joint_positions())[215:] < 1e-9)  # at rest through the last seconds
    assert 5.5 <= dance.metadata["rest"]["rests_from"] <= 6.3
    dancing = choreo.dance(song, checkpoint=tiny_checkpoint, seed=1, finishing=Finishing(rest=False))
    assert mean_joint_speed(dancing.joint_positions())[215:].mean() > 1e-3
