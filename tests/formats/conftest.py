"""Fixtures shared by the format tests."""

import pytest

from tests.conftest import wandering_dance


@pytest.fixture(scope="module")
def dance():
    return wandering_dance(3, 6, 30.0)
