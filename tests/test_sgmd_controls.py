"""The SGMD generator obeys its controls: seed, guidance and style each change the dance, and the
same settings give the same dance. (Same-seed determinism alone cannot catch a control that is
silently ignored.)"""

import numpy as np
import pytest

from choreo.generator import GenerationRequest
from choreo.music import SAMPLE_RATE, Music
from tests.test_music import click_track


@pytest.fixture(scope="module")
def music():
    return Music.from_array(click_track(120.0, 6.0, SAMPLE_RATE), SAMPLE_RATE)


def dance(generator, music, **settings):
    options = {"steps": 3, "guidance": settings.pop("guidance", 2.0)}
    request = GenerationRequest(music, style=settings.pop("style", "waltz"), seed=settings.pop("seed", 0), options=options)
    return generator.generate(request).joint_positions()


def test_same_settings_same_dance(tiny_generator, music):
    np.testing.assert_array_equal(dance(tiny_generator, music), dance(tiny_generator, music))


@pytest.mark.parametrize("change", [{"seed": 1}, {"guidance": 1.0}, {"guidance": 4.0}, {"style": "rumba"}, {"style": None}])
def test_each_control_changes_the_dance(tiny_generator, music, change):
    base, changed = dance(tiny_generator, music), dance(tiny_generator, music, **change)
    assert np.abs(base - changed).max() > 1e-4, f"{change} did not change the dance"
