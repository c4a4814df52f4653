"""choreo.music.form: a song's sections and which of them return, analysed or given."""

import numpy as np
import pytest

from choreo.errors import ParameterError
from choreo.music import Music
from choreo.music.form import Form, analyse_form, beats_per_bar, letters, music_self_similarity, parse_form

from .helpers import form_song


def test_a_given_form_reads_minutes_and_seconds_and_lists_its_returns():
    form = parse_form("0:00=A, 0:16=b,32=A,1:04.5=C", duration=90.0)
    assert [(s.start, s.label) for s in form.sections] == [(0.0, "A"), (16.0, "B"), (32.0, "A"), (64.5, "C")]
    assert form.returns() == [(2, 0)] and form.source == "given"
    assert form.describe() == "A 0:00, B 0:16, A 0:32, C 1:04"  # m:ss, rounded to the second
    assert form.as_json()[-1] == {"start": 64.5, "end": 90.0, "label": "C"}


@pytest.mark.parametrize("text, message", [
    ("0:16=A,0:32=B", "the first section must start at 0:00"),
    ("0:00=A,0:32=B,0:16=A", "must increase"),
    ("0:00=A,2:00=B", "past the song's end"),
    ("0:00=A;0:16=B", "every entry must look like TIME=LETTER"),
    ("0:00=verse", "every entry must look like TIME=LETTER"),
])
def test_a_bad_form_is_one_clear_error(text, message):
    with pytest.raises(ParameterError, match=message):
        parse_form(text, duration=60.0)


def test_letters_and_bars():
    assert letters(3) == ["A", "B", "C"] and letters(28)[26:] == ["AA", "AB"]
    assert beats_per_bar("Viennese waltz") == 3 and beats_per_bar("rumba") == beats_per_bar(None) == 4


def boundaries_within_a_bar(found: Form, truth: list[float], bar: float) -> bool:
    starts = [s.start for s in found.sections[1:]]
    return len(starts) == len(truth) and all(abs(a - b) <= bar for a, b in zip(starts, truth))


@pytest.mark.parametrize("form", ["ABAB", "ABA"])
def test_sections_with_their_own_chords_and_timbre_are_found_with_their_returns(form):
    music = Music.from_array(form_song(form), 22050)  # 8 bars of 2 s a section
    found = analyse_form(music)
    assert "".join(s.label for s in found.sections) == form
    assert boundaries_within_a_bar(found, [16.0 * k for k in range(1, len(form))], bar=2.0)


def test_a_song_of_one_section_or_too_short_has_one_letter():
    music = Music.from_array(form_song("AAAA", bars_per_section=1), 22050)
    assert [s.label for s in analyse_form(music).sections] == ["A"]


def test_the_analysis_needs_the_timbre_columns():
    music = Music.from_array(form_song("AB", bars_per_section=4), 22050, timbre=False)
    with pytest.raises(ParameterError, match="timbre"):
        analyse_form(music)


def test_the_music_self_similarity_is_bar_by_bar_and_sees_the_returns():
    music = Music.from_array(form_song("ABAB"), 22050)
    bars, alike = music_self_similarity(music, 4)
    assert alike.shape == (len(bars), len(bars)) and 30 <= len(bars) <= 32
    assert np.allclose(np.diag(alike), 1.0, atol=1e-6)
    first_a, second_a, first_b = 2, 18, 10  # bar indices inside the sections, away from the joins
    assert alike[first_a, second_a] > alike[first_a, first_b] + 0.3


def test_a_song_of_three_beats_has_one_section_and_no_bars_to_compare():
    music = Music.from_array(form_song("A", bars_per_section=2), 22050)
    three = music.__class__(**{**music.__dict__, "beat_times": music.beat_times[:3]})
    assert [s.label for s in analyse_form(three).sections] == ["A"]
    bars, alike = music_self_similarity(three, 4)
    assert len(bars) == 0 and alike.shape == (0, 0)
