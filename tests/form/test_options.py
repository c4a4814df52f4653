"""The form through the commands: --form, --returns and --mirror-returns, `choreo info`'s sections,
the dance's metadata, loops and both backends."""

import json

import pytest
import soundfile

import choreo
from choreo.formats import read_motion
from choreo.metrics.form import return_ratio
from choreo.metrics.loops import seam
from choreo.music import Music
from choreo.music.form import parse_form
from tests.helpers import assert_one_line_error, run_cli
from tests.music.helpers import form_song

SONG = "examples/drum_and_bass_174bpm.wav"
FORM = "0:00=A,0:02.8=B,0:05.5=A,0:08.3=B"  # bars of the example song at 174 bpm (1.38 s a bar)


@pytest.fixture(scope="module")
def music():
    return Music.from_file(SONG, log_mel=True)


@pytest.mark.parametrize("generator", ["sgmd", "graph"])
def test_both_backends_bring_a_returning_sections_phrase_back(generator, music):
    form = parse_form(FORM, music.duration)
    kwargs = dict(style="cha-cha", seed=2, threads=1, form=FORM)
    returned = choreo.dance(music, generator, **kwargs)
    fresh = choreo.dance(music, generator, **{**kwargs, "returns": 0.0})
    assert [entry["section"] for entry in returned.metadata["returns"]] == [2, 3]
    assert returned.metadata["form"][1] == {"start": 2.8, "end": 5.5, "label": "B"}
    ratios = return_ratio(returned.joint_positions(), returned.fps, form, music.beat_times)
    assert max(ratios) < 0.35 < min(return_ratio(fresh.joint_positions(), fresh.fps, form, music.beat_times))
    assert "returns" not in fresh.metadata


def test_a_loop_with_a_form_keeps_its_seam(music):
    dance = choreo.dance(music, "sgmd", style="cha-cha", seed=1, loop=True, threads=1, form=FORM)
    step, velocity = seam(dance)
    assert step <= 1.0 and velocity <= 1.0, (step, velocity)
    assert dance.metadata["returns"] and dance.metadata["loop"]


def test_generate_writes_the_form_and_info_shows_it(tmp_path, capsys):
    out = tmp_path / "dance.npz"
    glb = tmp_path / "dance.glb"
    code, _, err = run_cli(capsys, "generate", SONG, "-o", out, "-o", glb, "--form", FORM, "--mirror-returns",
                           "--threads", "1")
    assert code == 0, err
    assert read_motion(glb).metadata["form"] == read_motion(out).metadata["form"]  # the glb keeps it
    metadata = read_motion(out).metadata
    assert [s["label"] for s in metadata["form"]] == list("ABAB")
    assert [entry["mirrored"] for entry in metadata["returns"]] == [True, True]  # each letter's first return
    code, out_text, err = run_cli(capsys, "info", out)
    assert code == 0 and "A 0:00, B 0:03, A 0:06, B 0:08" in out_text, err


def test_info_shows_a_songs_sections_as_json(capsys):
    code, out, err = run_cli(capsys, "info", SONG, "--json", "--form", FORM)
    assert code == 0, err
    facts = json.loads(out)
    assert [s["label"] for s in facts["form"]] == list("ABAB") and facts["kind"] == "audio"
    code, out, err = run_cli(capsys, "info", SONG, "--json")
    assert code == 0 and json.loads(out)["form"][0]["start"] == 0.0, err


@pytest.mark.parametrize("args, message", [
    (["--returns", "1.5"], "--returns must be 0 to 1"),
    (["--form", "0:00=A,0:30=B"], "past the song's end"),
    (["--form", "A B A"], "TIME=LETTER"),
])
def test_bad_form_flags_are_one_line_errors_and_write_nothing(tmp_path, capsys, args, message):
    out = tmp_path / "dance.bvh"
    code, _, err = run_cli(capsys, "generate", SONG, "-o", out, *args)
    assert_one_line_error(code, err)
    assert message in err and not out.exists()


def test_the_form_plot_draws_both_self_similarities(tmp_path, capsys):
    song, dance = tmp_path / "song.wav", tmp_path / "dance.npz"
    soundfile.write(song, form_song("AB", bars_per_section=4), 22050)  # 16 s: 8 bars
    assert run_cli(capsys, "generate", song, "-o", dance, "--threads", "1")[0] == 0
    code, _, err = run_cli(capsys, "render", dance, "--music", song, "--plot", "form", "-o", tmp_path / "form.png")
    assert code == 0 and (tmp_path / "form.png").stat().st_size > 10_000, err
    code, _, err = run_cli(capsys, "render", dance, "--plot", "form", "-o", tmp_path / "no.png")
    assert_one_line_error(code, err)
    assert not (tmp_path / "no.png").exists()


def test_the_form_is_off_unless_asked_for_and_auto_analyses_it(tmp_path, capsys):
    song = tmp_path / "song.wav"
    soundfile.write(song, form_song("ABAB"), 22050)  # 64 s: A B A B of 8 bars
    plain, auto = tmp_path / "plain.npz", tmp_path / "auto.npz"
    assert run_cli(capsys, "generate", song, "-o", plain, "--threads", "1")[0] == 0
    code, _, err = run_cli(capsys, "generate", song, "-o", auto, "--form", "auto", "--threads", "1")
    assert code == 0, err
    assert "form" not in read_motion(plain).metadata
    assert [s["label"] for s in read_motion(auto).metadata["form"]] == list("ABAB")
    assert [entry["returns_to"] for entry in read_motion(auto).metadata["returns"]] == [0, 1]
    assert "form A B A B: 2 returns danced as the first" in err
