"""Tests of choreo.formats.aistpp.

Markers say where a test came from: survivor (pyproject.toml, tests/README.md)."""

import io
import pickle

import numpy as np
import pytest

from choreo.formats import aistpp


@pytest.mark.survivor
def test_aistpp_pickle_keeps_the_scaling_asked(dance):
    buffer = io.BytesIO()
    aistpp.write_aistpp_pkl(dance, buffer, scaling=95.0)
    stored = pickle.loads(buffer.getvalue())
    np.testing.assert_allclose(stored["smpl_trans"], dance.root_positions * 95.0, rtol=1e-6)
    np.testing.assert_array_equal(stored["smpl_scaling"], [95.0])
    assert stored["smpl_trans"].dtype == np.float64
