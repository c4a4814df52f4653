"""Tests of choreo.formats.json_arrays.

Markers say where a test came from: hardening (pyproject.toml, tests/README.md)."""

from __future__ import annotations

import json

import pytest

from choreo.formats import json_arrays, write_motion
from tests.formats.hostile import hostile_dance, peak_bytes


@pytest.mark.hardening
@pytest.mark.parametrize("text", ['{"a": [[1, 2], [3, 4.5e1]], "b": "x: [1, 2]"}', '{"a": [[1], [2, 3]]}',
                                  '{"a": [], "b": [[[-0.5]]]}', '{"a": [1, [2]], "c": {"a": [7]}}',
                                  '{"a": [1 2]}', '{"a": [1,,2]}', '{"a": [1e5e5]}', '{"a": [[]]}'])
def test_number_arrays_read_as_json_reads_them(text):
    try:
        expected = json.loads(text)
    except ValueError:
        with pytest.raises(ValueError):
            json_arrays.loads(text, arrays_at={"a", "b"})
        return
    got = json_arrays.loads(text, arrays_at={"a", "b"})
    assert json.loads(json.dumps(got, default=lambda a: a.tolist())) == expected


@pytest.mark.hardening
def test_a_motion_json_reads_its_arrays_without_a_python_float_per_number(tmp_path):
    write_motion(hostile_dance(2000), tmp_path / "dance.json")
    text = (tmp_path / "dance.json").read_text()
    assert peak_bytes(json_arrays.loads, text, ("rotations", "root_positions", "joint_positions")) < 3 * len(text)
