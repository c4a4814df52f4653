"""The corpus of bad inputs (tests/bad_inputs, made by make_corpus.py): each gets its one-line
error and non-zero exit code, no traceback, and no output file."""

import os
import shutil
from pathlib import Path

import numpy as np
import pytest

from choreo.cli import main

CORPUS = Path(__file__).parents[1] / "bad_inputs"
SONG = Path(__file__).parents[2] / "examples" / "drum_and_bass_174bpm.wav"

# (name, command with {c} = corpus folder, {s} = a good song, {m} = a good motion, {k} = a good checkpoint,
#  {o} = the output path, expected exit code, expected words)
CASES = [
    ("not audio", "generate {c}/not_audio.mp3 -o {o}.bvh --checkpoint {k}", 2, "not a readable audio file"),
    ("empty file", "generate {c}/empty.wav -o {o}.bvh --checkpoint {k}", 2, "is empty"),
    ("silence", "generate {c}/silence.wav -o {o}.bvh --checkpoint {k}", 2, "is silent"),
    ("float WAV with a NaN sample", "generate {c}/nan_sample.wav -o {o}.bvh --checkpoint {k}", 2, "NaN or infinite"),
    ("0.2 s of audio", "generate {c}/short.wav -o {o}.bvh --checkpoint {k}", 2, "too short"),
    ("truncated mp3", "generate {c}/truncated.mp3 -o {o}.bvh --checkpoint {k}", 2, "not a readable audio file"),
    ("corrupt mp3", "generate {c}/corrupt.mp3 -o {o}.bvh --checkpoint {k}", 2, "not a readable audio file"),
    ("unknown extension", "generate {c}/song.xyz -o {o}.bvh --checkpoint {k}", 2, "unsupported audio type"),
    ("unknown output extension", "generate {s} -o {o}.abc --checkpoint {k}", 3, "abc"),
    ("BVH with another skeleton", "inpaint {s} --motion {c}/other_skeleton.bvh -o {o}.bvh --checkpoint {k}", 2, "not SMPL-24"),
    ("truncated BVH", "convert {c}/truncated.bvh {o}.npz", 2, "no MOTION section"),
    ("AIST++ pickle of shared lists (2^40 when unfolded)", "convert {c}/shared_lists_bomb.pkl {o}.npz", 2, "unfolds"),
    ("pickle nested 2,000 deep", "convert {c}/deeply_nested.pkl {o}.npz", 2, "nests"),
    ("BVH Frame Time 1e-320", "convert {c}/tiny_frame_time.bvh {o}.npz", 2, "Frame Time"),
    ("BVH with a negative channel count", "convert {c}/negative_channels.bvh {o}.npz", 2, "CHANNELS -3"),
    ("NaN in a motion", "inpaint {s} --motion {m}.nan.bvh -o {o}.bvh --checkpoint {k}", 2, "NaN"),
    ("infinite values in a motion", "convert {m}.inf.bvh {o}.npz", 2, "NaN or infinite"),
    ("path file of the wrong shape", "trajectory {s} --path {c}/wrong_shape_path.csv -o {o}.bvh --checkpoint {k}", 2, "columns"),
    ("missing checkpoint", "generate {s} -o {o}.bvh --checkpoint {c}/nothing_here.pt", 2, "does not exist"),
    ("corrupt checkpoint", "generate {s} -o {o}.bvh --checkpoint {c}/corrupt_checkpoint.pt", 2, "not a readable checkpoint"),
    ("checkpoint of the other generator", "generate {s} -o {o}.bvh --checkpoint {c}/graph_checkpoint.pt", 2, "not an SGMD checkpoint"),
    ("SGMD checkpoint given to graph", "graph {s} -o {o}.bvh --checkpoint {k}", 2, "not a ChoreoGraph checkpoint"),
    ("missing repertoire", "graph {s} -o {o}.bvh --repertoire {c}/nothing_here.npz", 2, "does not exist"),
    ("corrupt repertoire", "graph {s} -o {o}.bvh --repertoire {c}/corrupt_checkpoint.pt", 2, "not a readable repertoire"),
    ("output in a missing folder", "generate {s} -o {o}/missing/d.bvh --checkpoint {k}", 3, "does not exist"),
    ("output in a read-only folder", "generate {s} -o {o}.readonly/d.bvh --checkpoint {k}", 3, "not writable"),
]


@pytest.fixture(scope="module")
def good_files(tmp_path_factory):
    from choreo.formats import write_motion
    from choreo.motion import Motion

    folder = tmp_path_factory.mktemp("good")
    rng = np.random.default_rng(0)
    motion = Motion.from_axis_angle(np.zeros((30, 3)) + [0, 0.9, 0], rng.normal(scale=0.1, size=(30, 24, 3)))
    write_motion(motion, folder / "m.bvh")
    text = (folder / "m.bvh").read_text().splitlines()
    frame_start = text.index(next(line for line in text if line.startswith("Frame Time"))) + 1
    for bad, name in (("nan", "nan"), ("inf", "inf")):
        lines = list(text)
        values = lines[frame_start + 3].split()
        values[5] = bad
        lines[frame_start + 3] = " ".join(values)
        (folder / f"m.{name}.bvh").write_text("\n".join(lines) + "\n")
    return folder


@pytest.mark.parametrize("name, command, code, words", CASES, ids=[case[0] for case in CASES])
def test_bad_input_gives_one_line_and_no_output(name, command, code, words, good_files, tiny_checkpoint, tmp_path, capsys,
                                                monkeypatch):
    out = tmp_path / "out"
    readonly = Path(f"{out}.readonly")
    readonly.mkdir()
    readonly.chmod(0o555)
    try:
        if os.access(readonly, os.W_OK) and "read-only" in name:
            # root may write anywhere: the folder is made read-only the way choreo asks about it
            real_access = os.access
            denied = lambda path, mode, **kw: (False if Path(path).resolve() == readonly.resolve() and mode & os.W_OK  # noqa: E731
                                               else real_access(path, mode, **kw))
            monkeypatch.setattr("choreo.fileio.os.access", denied)
        args = command.format(c=CORPUS, s=SONG, m=good_files / "m", k=tiny_checkpoint, o=out).split()
        exit_code = main(args)
        err = capsys.readouterr().err
        lines = [line for line in err.splitlines() if line.strip()]
        assert exit_code == code, err
        assert len(lines) == 1 and lines[0].startswith("choreo: error: ") and words in lines[0], err
        assert "Traceback" not in err
        assert sorted(p.name for p in tmp_path.iterdir()) == ["out.readonly"]
        assert not any(readonly.iterdir())
    finally:
        readonly.chmod(0o755)
        shutil.rmtree(readonly)
