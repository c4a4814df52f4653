"""scripts/results_tables.py: the generated tables of docs/results.md and the README match their saved runs."""

import importlib
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).parents[2]


def test_every_generated_table_matches_its_runs():
    done = subprocess.run([sys.executable, str(REPO / "scripts" / "results_tables.py"), "--check"],
                          capture_output=True, text=True, cwd=REPO)
    assert done.returncode == 0, done.stdout + done.stderr


def test_a_table_edited_by_hand_is_rebuilt_from_its_runs(monkeypatch):
    monkeypatch.syspath_prepend(str(REPO / "scripts"))
    tables = importlib.import_module("results_tables")
    text = (REPO / "docs" / "results.md").read_text()
    start = text.index("<!-- table: whole-songs-summary")
    row = text.index("\n|", text.index("\n|", start) + 1)  # a row below the header
    edited = text[:row + 2] + "tampered " + text[row + 2:]
    assert tables.regenerated(edited) == text != edited
