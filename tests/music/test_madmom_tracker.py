"""madmom's trained tracker, opt-in (issue 36, part 2): ``--beat-tracker madmom`` on every command
that dances and on ``choreo info``; without the extra, one line naming it; its licence in the
output's metadata. The tests that run madmom skip where the extra is not installed."""

import numpy as np
import pytest
import soundfile as sf
from tests.helpers import AISTPP_FIXTURES, EXAMPLE_SONG, assert_one_line_error, run_cli

from choreo.errors import ParameterError
from choreo.formats import read_motion
from choreo.music import BEAT_COLUMN, SAMPLE_RATE, BeatOptions, Music
from choreo.music import madmom_tracker
from tests.music.helpers import click_track

CLICK_BPM = 120.0


def madmom_installed() -> bool:
    try:
        madmom_tracker.load_madmom()
    except ParameterError:
        return False
    return True


needs_madmom = pytest.mark.skipif(not madmom_installed(), reason='needs the madmom extra: pip install "choreo[madmom]"')


@pytest.fixture(scope="module")
def click_song(tmp_path_factory):
    path = tmp_path_factory.mktemp("song") / "clicks.wav"
    sf.write(path, click_track(CLICK_BPM, 12.0, SAMPLE_RATE), SAMPLE_RATE)
    return path


@pytest.fixture
def without_madmom(monkeypatch):
    """madmom made unimportable, as on an install without the extra."""
    monkeypatch.setitem(__import__("sys").modules, "madmom", None)
    madmom_tracker.load_madmom.cache_clear()
    yield
    madmom_tracker.load_madmom.cache_clear()


@pytest.mark.parametrize("command", [
    ("generate",), ("graph",), ("inbetween", "--key", "1.0=pose.bvh"), ("inpaint", "--motion", "dance.bvh"),
    ("trajectory", "--path", "path.csv"), ("info",),
])
def test_a_missing_extra_is_one_line_naming_it(tmp_path, capsys, monkeypatch, without_madmom, command):
    monkeypatch.chdir(tmp_path)
    outputs = () if command[0] == "info" else ("-o", "dance.npz")
    code, _, err = run_cli(capsys, command[0], EXAMPLE_SONG, *command[1:], *outputs, "--beat-tracker", "madmom")
    assert_one_line_error(code, err)
    assert 'pip install "choreo[madmom]"' in err and "CC BY-NC-SA 4.0" in err
    assert not (tmp_path / "dance.npz").exists()


@pytest.fixture
def broken_madmom(tmp_path, monkeypatch):
    """A madmom that fails while it loads, as old madmom on NumPy 2 (``np.float`` is gone)."""
    package = tmp_path / "site" / "madmom"
    package.mkdir(parents=True)
    (package / "__init__.py").write_text("import numpy\nnumpy.float\n")
    modules = __import__("sys").modules
    for name in [name for name in modules if name == "madmom" or name.startswith("madmom.")]:
        monkeypatch.delitem(modules, name)
    monkeypatch.syspath_prepend(str(tmp_path / "site"))
    madmom_tracker.load_madmom.cache_clear()
    yield
    madmom_tracker.load_madmom.cache_clear()


@pytest.mark.parametrize("command", [("generate",), ("info",)])
def test_a_madmom_that_breaks_on_import_is_one_line_as_a_missing_one(tmp_path, capsys, monkeypatch, broken_madmom, command):
    """Issue 48, item 11: the AttributeError was exit 70."""
    monkeypatch.chdir(tmp_path)
    outputs = () if command[0] == "info" else ("-o", "dance.npz")
    code, _, err = run_cli(capsys, command[0], EXAMPLE_SONG, *outputs, "--beat-tracker", "madmom")
    assert_one_line_error(code, err)
    assert "fails to import (AttributeError)" in err and 'pip install "choreo[madmom]"' in err
    assert not (tmp_path / "dance.npz").exists()


@pytest.mark.parametrize("flags, words", [
    (("--beat-tracker", "beatnet"), "must be one of choreo, madmom"),
    (("--beat-tracker", "madmom", "--bpm", "120"), "without --beat-tracker"),
    (("--beat-tracker", "madmom", "--beats", "beats.csv"), "without --beat-tracker"),
])
def test_contradicting_beat_options_are_refused(tmp_path, capsys, monkeypatch, flags, words):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "beats.csv").write_text("0.5\n1.0\n")
    code, _, err = run_cli(capsys, "generate", EXAMPLE_SONG, "-o", "dance.npz", *flags)
    assert_one_line_error(code, err)
    assert words in err and not (tmp_path / "dance.npz").exists()


def test_a_motion_file_takes_no_beat_tracker(tmp_path, capsys):
    code, _, err = run_cli(capsys, "info", AISTPP_FIXTURES / "motions" / "gBR_sBM_cAll_d04_mBR0_ch01.pkl",
                           "--beat-tracker", "madmom")
    assert_one_line_error(code, err)
    assert "describe a song" in err


def test_the_help_names_the_licence(capsys):
    code, out, _ = run_cli(capsys, "generate", "--help")
    text = " ".join(out.replace("│", " ").split())  # the panel's text, unwrapped
    assert code == 0 and "--beat-tracker" in text and "CC BY-NC-SA 4.0" in text


@needs_madmom
def test_madmom_hears_a_click_track_at_its_tempo(click_song):
    music = Music.from_file(click_song, timbre=False, beats=BeatOptions(beat_tracker="madmom").source())
    clicks = np.arange(0.0, 12.0, 60.0 / CLICK_BPM)
    assert music.tempo == pytest.approx(CLICK_BPM, rel=0.04)
    assert np.abs(music.beat_times[:, None] - clicks[None]).min(axis=1).max() < 0.05  # every beat on a click
    assert len(music.beat_times) >= 20
    np.testing.assert_array_equal(np.flatnonzero(music.features[:, BEAT_COLUMN]),
                                  np.unique(np.round(music.beat_times * 30).astype(int)))
    assert "madmom" in music.beat_source and "CC BY-NC-SA 4.0" in music.beat_source


@needs_madmom
def test_an_excerpt_is_tracked_in_its_own_time(click_song):
    music = Music.from_file(click_song, start=3.25, end=9.0, timbre=False, beats=BeatOptions(beat_tracker="madmom").source())
    clicks = np.arange(0.0, 12.0, 60.0 / CLICK_BPM) - 3.25
    assert music.beat_times.max() <= music.duration + 0.05 and music.beat_times.min() >= 0
    assert np.abs(music.beat_times[:, None] - clicks[None]).min(axis=1).max() < 0.05


@needs_madmom
def test_an_array_is_tracked_like_a_file(click_song):
    samples, sr = sf.read(click_song, dtype="float32")
    from_array = Music.from_array(samples, sr, timbre=False, beats=BeatOptions(beat_tracker="madmom").source())
    from_file = Music.from_file(click_song, timbre=False, beats=BeatOptions(beat_tracker="madmom").source())
    np.testing.assert_allclose(from_array.beat_times, from_file.beat_times, atol=0.011)  # one activation frame


@needs_madmom
def test_generate_records_madmom_and_its_licence(tmp_path, capsys, click_song):
    out = tmp_path / "dance.npz"
    code, _, err = run_cli(capsys, "generate", click_song, "--steps", "2", "--beat-tracker", "madmom", "-o", out)
    assert code == 0, err
    beats = read_motion(out).metadata["beats"]
    assert beats.startswith("madmom") and "non-commercial" in beats


@needs_madmom
def test_info_shows_madmoms_beats(capsys, click_song):
    code, out, err = run_cli(capsys, "info", click_song, "--beat-tracker", "madmom")
    assert code == 0, err
    assert "madmom" in out and "120.0 bpm" in out
