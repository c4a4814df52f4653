"""choreo.lazy: packages whose names load their module when first asked for."""

import subprocess
import sys

import pytest


def test_every_listed_name_resolves_to_its_modules_object():
    import choreo.motion
    import choreo.music
    from choreo.motion.motion import Motion
    from choreo.music.beat_source import BeatSource

    assert choreo.motion.Motion is Motion and choreo.music.BeatSource is BeatSource
    for package in (choreo.motion, choreo.music):
        for name in package.__all__:
            assert getattr(package, name) is not None, (package.__name__, name)


def test_an_unknown_name_is_an_attribute_error_naming_the_package():
    import choreo.music

    with pytest.raises(AttributeError, match="'choreo.music' has no attribute 'Beat'"):
        choreo.music.Beat  # noqa: B018


def test_the_beat_and_delivery_flags_load_without_numpy():
    code = ("import sys; from choreo.music import BeatOptions; from choreo.motion.delivery_options import Delivery; "
            "Delivery(fps=60); BeatOptions(bpm=120); print('numpy' in sys.modules)")
    assert subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip() == "False"
