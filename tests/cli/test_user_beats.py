"""Beats the user gives (issue 36, part 1): ``--bpm N`` and ``--beats FILE`` on every dancing
command, ``choreo info`` and ``choreo.dance``; bad input is one line, exit 2, and no output."""

import time
import tracemalloc

import numpy as np
import pytest
import soundfile as sf
from tests.helpers import EXAMPLE_SONG, assert_one_line_error, run_cli

from choreo.errors import InputError, ParameterError
from choreo.formats import read_motion
from choreo.music import BEAT_COLUMN, SAMPLE_RATE, BeatOptions, Music
from choreo.music.beat_file import parse_beats, read_beat_file
from tests.music.helpers import click_track

CLICK_BPM = 120.0


@pytest.fixture(scope="module")
def click_song(tmp_path_factory):
    """8 s of clicks at 120 bpm, as a wav file."""
    path = tmp_path_factory.mktemp("song") / "clicks.wav"
    sf.write(path, click_track(CLICK_BPM, 8.0, SAMPLE_RATE), SAMPLE_RATE)
    return path


# --- parsing -------------------------------------------------------------------------------------

def test_a_plain_list_of_times():
    beats = parse_beats("0.5\n1.0\n\n1.52\n2.01\n", "beats.txt")
    np.testing.assert_allclose(beats.times, [0.5, 1.0, 1.52, 2.01])
    assert beats.downbeats is None and beats.name == "beats.txt"


@pytest.mark.parametrize("text", ["time\n0.5\n1.0\n1.5\n", "beat_time,\n0.5,\n1.0,\n1.5,\n",
                                  '"Time (s)"\n0.5\n1.0\n1.5\n'])
def test_a_csv_with_a_header(text):
    np.testing.assert_allclose(parse_beats(text, "b.csv").times, [0.5, 1.0, 1.5])


@pytest.mark.parametrize("text", [
    "time,beat\n0.5,1\n1.0,2\n1.5,3\n2.0,4\n2.5,1\n",  # a beat's number in its bar
    "beat_time,downbeat\n0.5,1\n1.0,0\n1.5,0\n2.0,0\n2.5,1\n",  # a 0/1 flag
    "beat_time;downbeat\n0.5;true\n1.0;false\n1.5;false\n2.0;false\n2.5;true\n",
    "time\tbeat\n0.5\t1\n1.0\t2\n1.5\t3\n2.0\t4\n2.5\t1\n",
])
def test_a_csv_with_a_downbeat_column(text):
    beats = parse_beats(text, "b.csv")
    np.testing.assert_allclose(beats.times, [0.5, 1.0, 1.5, 2.0, 2.5])
    np.testing.assert_array_equal(beats.downbeats, [True, False, False, False, True])


BAD_FILES = {
    "empty": ("", "has no beats"),
    "a header alone": ("time,downbeat\n", "has no beats"),
    "unsorted": ("0.5\n1.5\n1.0\n", "must increase"),
    "negative": ("-0.5\n0.5\n1.0\n", "negative"),
    "too close": ("0.5\n0.6\n1.0\n", "0.2 to 3 s apart"),
    "too far": ("0.5\n4.0\n", "0.2 to 3 s apart"),
    "non-numeric": ("time\n0.5\nabc\n1.5\n", "not a number"),
    "non-numeric downbeat": ("time,beat\n0.5,1\n1.0,x\n", "not a number"),
    "three columns": ("0.5,1,2\n1.0,2,2\n", "two"),
    # issue 48, item 12: numbers Python reads that no beats file means, and a beat with no tempo
    "nan first": ("nan\n0.5\n1.0\n", "line 1: 'nan' is not a number"),  # was dropped as a header
    "inf": ("0.5\ninf\n", "line 2: 'inf' is not a number"),
    "underscore": ("0.5\n1_0\n1.5\n", "line 2: '1_0' is not a number"),  # float() reads 10
    "fullwidth digits": ("0.5\n\uff11.0\n", "is not a number"),
    "fullwidth downbeat": ("time,beat\n0.5,\uff11\n1.0,2\n", "is not a number"),
    "one beat": ("0.5\n", "has one beat"),  # info said "tempo 0.0 bpm"
}


@pytest.mark.parametrize("case", BAD_FILES)
def test_bad_beat_files_are_refused_in_one_line(tmp_path, case):
    text, words = BAD_FILES[case]
    (tmp_path / "beats.csv").write_text(text)
    with pytest.raises(InputError, match=words):
        read_beat_file(tmp_path / "beats.csv")


# --- every bad input through the CLI: one line, exit 2, no output file ---------------------------

@pytest.mark.parametrize("case", BAD_FILES)
def test_bad_beat_files_stop_generate_before_any_work(tmp_path, capsys, case):
    (tmp_path / "beats.csv").write_text(BAD_FILES[case][0])
    out = tmp_path / "dance.npz"
    code, _, err = run_cli(capsys, "generate", EXAMPLE_SONG, "-o", out, "--beats", tmp_path / "beats.csv")
    assert_one_line_error(code, err)
    assert BAD_FILES[case][1] in err and str(tmp_path) not in err and not out.exists()


@pytest.mark.parametrize("flags, words", [
    (("--bpm", "10"), "--bpm must be 20 to 300"),
    (("--bpm", "400"), "--bpm must be 20 to 300"),
    (("--bpm", "nan"), "--bpm takes a finite number"),
    (("--bpm", "120", "--beats", "beats.csv"), "not both"),
    (("--beats", "missing.csv"), "no such beats file"),
])
@pytest.mark.parametrize("command", [
    ("generate",), ("graph",), ("inbetween", "--key", "1.0=pose.bvh"), ("inpaint", "--motion", "dance.bvh"),
    ("trajectory", "--path", "path.csv"), ("info",),
])
def test_bad_beat_options_on_every_command(tmp_path, capsys, monkeypatch, command, flags, words):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "beats.csv").write_text("0.5\n1.0\n")
    outputs = () if command[0] == "info" else ("-o", "dance.npz")
    code, _, err = run_cli(capsys, command[0], EXAMPLE_SONG, *command[1:], *outputs, *flags)
    assert_one_line_error(code, err)
    assert words in err and not (tmp_path / "dance.npz").exists()


def test_beats_past_the_songs_end_are_refused(tmp_path, capsys, click_song):
    (tmp_path / "beats.txt").write_text("\n".join(f"{t:g}" for t in np.arange(0.5, 10.0, 0.5)))  # the song is 8 s
    out = tmp_path / "dance.npz"
    code, _, err = run_cli(capsys, "generate", click_song, "-o", out, "--beats", tmp_path / "beats.txt")
    assert_one_line_error(code, err)
    assert "past the song's end" in err and not out.exists()


def test_the_python_entry_point_checks_its_beats_before_any_work():
    import choreo

    with pytest.raises(ParameterError, match="20 to 300"):
        choreo.dance("no_such_song.wav", bpm=1000)
    with pytest.raises(ParameterError, match="not both"):
        choreo.dance("no_such_song.wav", bpm=120, beats="beats.csv")


# --- the beats drive the analysis ----------------------------------------------------------------

def test_bpm_gives_beats_exactly_its_period_apart_on_the_onsets(click_song):
    music = Music.from_file(click_song, timbre=False, beats=BeatOptions(bpm=100).source())
    np.testing.assert_allclose(np.diff(music.beat_times), 0.6, atol=1e-9)  # not the clicks' 0.5 s
    assert music.tempo == 100 and music.beat_source == "bpm 100" and len(music.beat_times) >= 10
    clicks = np.arange(0.0, 8.0, 60.0 / CLICK_BPM)
    on_clicks = np.abs(music.beat_times[:, None] - clicks[None]).min(axis=1) < 0.03
    assert on_clicks.mean() >= 0.15  # 0.6 s and 0.5 s meet every 3 s: one beat in five is a click
    tracked = Music.from_file(click_song, timbre=False)
    assert tracked.tempo == pytest.approx(CLICK_BPM, rel=0.01) and tracked.beat_source == "tracked"


def test_given_beats_fill_the_features_beat_column(tmp_path, click_song):
    times = np.arange(0.3, 7.5, 0.7)
    (tmp_path / "beats.txt").write_text("\n".join(f"{t:.3f}" for t in times))
    music = Music.from_file(click_song, timbre=False, beats=BeatOptions(beats=tmp_path / "beats.txt").source())
    np.testing.assert_allclose(music.beat_times, times, atol=1e-9)
    np.testing.assert_array_equal(np.flatnonzero(music.features[:, BEAT_COLUMN]), np.round(times * 30).astype(int))
    assert music.tempo == pytest.approx(60 / 0.7) and music.beat_source == "beats.txt"


def test_info_shows_the_beats_it_will_use(tmp_path, capsys, click_song):
    (tmp_path / "beats.csv").write_text("time,downbeat\n0.25,1\n0.75,0\n1.25,0\n")
    code, out, err = run_cli(capsys, "info", click_song, "--beats", tmp_path / "beats.csv")
    assert code == 0, err
    assert "3 (beats.csv)" in out and "0.250 0.750 1.250 s" in out


def test_generate_with_beats_locks_the_dance_onto_them(tmp_path, capsys, monkeypatch):
    import choreo.finishing as finishing

    times = np.round(np.arange(0.4, 11.0, 0.55), 3)  # as the file says them
    (tmp_path / "beats.csv").write_text("beat_time,downbeat\n" + "".join(f"{t:.3f},{int(i % 4 == 0)}\n"
                                                                          for i, t in enumerate(times)))
    seen = {}

    def recording_beat_lock(motion, music_beat_frames, fixed=None, **kwargs):
        result = real_beat_lock(motion, music_beat_frames, fixed, **kwargs)
        seen.update(targets=np.asarray(music_beat_frames), pairs=result.pairs)
        return result

    real_beat_lock = finishing.beat_lock
    monkeypatch.setattr(finishing, "beat_lock", recording_beat_lock)
    out = tmp_path / "dance.npz"
    code, _, err = run_cli(capsys, "generate", EXAMPLE_SONG, "--steps", "2", "--beats", tmp_path / "beats.csv",
                           "-o", out)
    assert code == 0, err
    given = np.round(times * 30).astype(int)
    np.testing.assert_array_equal(seen["targets"], given)
    assert seen["pairs"] and {music for _, music in seen["pairs"]} <= set(given.tolist())
    assert read_motion(out).metadata["beats"] == "beats.csv"


# --- issue 48, item 3: size is checked before reading, and the file is parsed as a stream --------

def test_a_beats_file_bigger_than_any_song_needs_is_refused_unread(tmp_path, capsys):
    huge = tmp_path / "beats.txt"
    with open(huge, "wb") as handle:  # 1.5 GB, sparse: nothing on disk, and nothing read
        handle.truncate(1_500_000_000)
    started = time.perf_counter()
    with pytest.raises(InputError, match="more than a beats file holds"):
        read_beat_file(huge)
    out = tmp_path / "dance.npz"
    code, _, err = run_cli(capsys, "generate", EXAMPLE_SONG, "-o", out, "--beats", huge)
    assert_one_line_error(code, err)
    assert "more than a beats file holds" in err and not out.exists()
    assert time.perf_counter() - started < 10


def test_a_beats_file_under_the_size_limit_is_read_in_little_memory(tmp_path):
    many = tmp_path / "beats.csv"
    many.write_bytes(b"time,beat\n" + b"1.0,1\n" * 1_300_000)  # 7.8 MB: 1.3 million rows
    tracemalloc.start()
    try:
        with pytest.raises(InputError, match="more than 360,000 beats"):
            read_beat_file(many)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 16 << 20, peak  # was the whole text, then a list of cells per line (> 1 GB for 28 MB)


def test_a_beats_line_longer_than_a_beat_is_refused(tmp_path):
    (tmp_path / "beats.txt").write_text("0.5\n" + "1" * 5000 + "\n")
    with pytest.raises(InputError, match="line 2: longer than 256 characters"):
        read_beat_file(tmp_path / "beats.txt")


# --- issue 48, item 12: strict numbers, short messages, no tempo from one beat -------------------

def test_a_long_cell_is_not_echoed_whole():
    with pytest.raises(InputError) as refused:
        parse_beats("0.5\n" + "9" * 250 + "\n", "beats.txt")
    assert "is not a number" in str(refused.value) and len(str(refused.value)) < 80


def test_a_one_beat_file_gives_info_no_tempo(tmp_path, capsys):
    (tmp_path / "beats.txt").write_text("0.5\n")
    code, out, err = run_cli(capsys, "info", EXAMPLE_SONG, "--beats", tmp_path / "beats.txt")
    assert_one_line_error(code, err)
    assert "has one beat" in err and "tempo" not in out


@pytest.mark.parametrize("value", ["1_20", "\uff11\uff12\uff10", "inf", "9" * 5000])
def test_bpm_takes_plain_decimals_only(tmp_path, capsys, value):
    code, _, err = run_cli(capsys, "info", EXAMPLE_SONG, "--bpm", value)
    assert_one_line_error(code, err)
    assert "--bpm takes a finite number" in err and len(err) < 100
