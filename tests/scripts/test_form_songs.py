"""benchmarks/form_songs.py and form_analysis.py: the truths of the form benchmark are read right
(LMMS arrangement -> sections), the scoring fails what it should, and form_songs.json is sound.
No audio is rendered or decoded here."""

import importlib
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).parents[2]

# Three 4-bar patterns on one track arranged X Y X (the third a copy: same notes, another place),
# a beat/bassline under all twelve bars, a muted track that must not count, and a 1-bar fill.
TINY_MMP = """<?xml version="1.0"?>
<lmms-project version="1.0">
 <head bpm="120" timesig_numerator="4" timesig_denominator="4"/>
 <song>
  <trackcontainer type="song">
   <track type="1" name="Beat" muted="0">
    <bbtrack><trackcontainer>
     <track type="0" name="Kick" muted="0">
      <pattern pos="0" len="192"><note pos="0" len="-192" key="57"/><note pos="48" len="-192" key="57"/></pattern>
     </track>
    </trackcontainer></bbtrack>
    <bbtco pos="0" len="2304" muted="0"/>
   </track>
   <track type="0" name="Lead" muted="0">
    <pattern pos="0" len="768" muted="0"><note pos="0" len="48" key="60"/><note pos="96" len="48" key="64"/></pattern>
    <pattern pos="768" len="768" muted="0"><note pos="0" len="96" key="65"/></pattern>
    <pattern pos="1536" len="768" muted="0"><note pos="96" len="48" key="64"/><note pos="0" len="48" key="60"/></pattern>
   </track>
   <track type="0" name="Fill" muted="0">
    <pattern pos="1344" len="192" muted="0"><note pos="0" len="48" key="40"/></pattern>
   </track>
   <track type="0" name="Muted" muted="1">
    <pattern pos="768" len="768" muted="0"><note pos="0" len="48" key="30"/></pattern>
   </track>
  </trackcontainer>
 </song>
</lmms-project>
"""


@pytest.fixture
def songs(monkeypatch):
    monkeypatch.syspath_prepend(str(REPO / "benchmarks"))
    return importlib.import_module("form_songs")


@pytest.fixture
def analysis(monkeypatch):
    monkeypatch.syspath_prepend(str(REPO / "benchmarks"))
    return importlib.import_module("form_analysis")


def test_an_arrangement_x_y_x_reads_as_a_b_a_on_bar_lines(songs):
    arrangement = songs.parse_arrangement(TINY_MMP)
    assert arrangement.ticks_per_bar == 192 and arrangement.beats_per_bar == 4
    assert arrangement.seconds_per_bar == pytest.approx(2.0)  # 4 beats at 120 bpm
    sets = songs.bar_sets(arrangement)
    assert len(sets) == 12
    assert sets[0] == sets[8] != sets[4]
    assert sets[7] != sets[6]  # the fill: one bar, too short to be a section of its own
    assert songs.bar_sections(sets) == [(0, "A"), (4, "B"), (8, "A")]


def test_short_runs_join_their_neighbour(songs):
    x, y, z = frozenset("x"), frozenset("y"), frozenset("z")
    assert songs.bar_sections([x] * 4 + [z] + [y] * 4 + [x] * 4) == [(0, "A"), (5, "B"), (9, "A")]
    assert songs.bar_sections([z] + [x] * 4 + [y] * 4) == [(0, "A"), (5, "B")]


def test_curation_keeps_only_a_clear_form(songs):
    assert songs.clear_form([(0, "A"), (8, "B"), (16, "A")], 24) is None
    assert "returns" in songs.clear_form([(0, "A"), (8, "B"), (16, "C")], 24)
    assert "sections" in songs.clear_form([(0, "A"), (8, "B")], 16)
    assert "short" in songs.clear_form([(0, "A"), (2, "B"), (4, "A"), (6, "B")], 8)


def test_a_splice_has_the_pieces_length_and_no_jump_at_the_join(songs):
    sr = 1000
    samples = np.sin(np.arange(10 * sr) * 2 * np.pi * 5 / sr).astype(np.float32)  # 5 Hz: a join at a new phase
    out = songs.splice(samples, sr, [(1.0, 3.0), (6.1, 8.1)], fade=0.02)
    assert len(out) == 4 * sr
    assert np.abs(np.diff(out)).max() < 0.1  # a hard cut would jump by ~0.6
    assert songs.spliced_truth([[1.0, 3.0], [6.1, 8.1], [1.0, 3.0]], "A B A") == [[0.0, "A"], [2.0, "B"], [4.0, "A"]]
    assert songs.spliced_truth([[1.0, 3.0], [5.0, 7.0], [3.0, 5.0]], "A A B") == [[0.0, "A"], [4.0, "B"]]


TRUTH = [(0.0, "A"), (16.0, "B"), (32.0, "A"), (48.0, "B")]  # 2 s bars, 64 s


@pytest.mark.parametrize("found, boundaries, labels", [
    ([(0.0, "X"), (15.0, "Y"), (33.5, "X"), (48.0, "Y")], True, True),  # renamed, within a bar
    ([(0.0, "A"), (20.0, "B"), (32.0, "A"), (48.0, "B")], False, True),  # a boundary 2 bars late
    ([(0.0, "A"), (16.0, "B"), (32.0, "C"), (48.0, "B")], True, False),  # the return not heard
    ([(0.0, "A"), (16.0, "B"), (24.0, "C"), (32.0, "A"), (48.0, "B")], False, True),  # one boundary too many
    ([(0.0, "A"), (16.0, "A"), (32.0, "A"), (48.0, "A")], True, False),  # all one letter
])
def test_scoring(analysis, found, boundaries, labels):
    score = analysis.score("song", "test", TRUTH, found, 64.0, 2.0)
    assert (score.boundaries_ok, score.labels_ok) == (boundaries, labels)
    assert score.passed == (boundaries and labels)


def test_the_benchmark_runs_any_analyse_form_it_is_given(analysis, songs, monkeypatch):
    """A stand-in for choreo.music.form.analyse_form that returns the truth passes every song."""
    from choreo.music.form import Form, Section

    song = songs.FormSong("s", Path("s.wav"), TRUTH, 4, 2.0, "spliced", "test")
    music = type("M", (), {"duration": 64.0})()
    monkeypatch.setattr(analysis, "cached_music", lambda path: music)
    truth = lambda m, beats_per_bar: Form(tuple(Section(s, l) for s, l in TRUTH), m.duration)  # noqa: E731
    assert analysis.analyse(song, truth).passed
    assert "1/1 pass (100 %" in analysis.report([analysis.analyse(song, truth)])


def test_form_songs_json_is_well_formed(songs):
    recipes = songs.load_recipes()
    kept = [r for r in recipes if not r["excluded"]]
    assert len({r["name"] for r in recipes}) == len(recipes)
    assert {r["split"] for r in kept} == {"validation", "test"}
    for recipe in kept:
        starts = [start for start, _ in recipe["sections"]]
        labels = [label for _, label in recipe["sections"]]
        assert starts[0] == 0 and all(a < b for a, b in zip(starts, starts[1:])), recipe["name"]
        assert len(set(labels)) < len(labels), recipe["name"]  # something returns
        assert all(a != b for a, b in zip(labels, labels[1:])), recipe["name"]  # equal neighbours are one section
        assert recipe["beats_per_bar"] in (3, 4) and recipe["seconds_per_bar"] > 0
        if recipe["kind"] == "spliced":
            assert len(recipe["pieces"]) == len(recipe["form"].split())
            assert all(0 <= a < b for a, b in recipe["pieces"])
