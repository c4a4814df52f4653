"""Checkpoints in the right format with wrong contents: refused in one line, before any allocation."""

import copy
import struct
import zipfile
from pathlib import Path

import pytest
import torch

from choreo.errors import InputError
from choreo.generator.archive import check_checkpoint_archive
from choreo_sgmd.checkpoint import load_checkpoint, save_checkpoint
from tests.helpers import EXAMPLE_SONG, run_cli


def first_weight(state):
    return next(iter(state["ema_state_dict"]))


FORGERIES = {
    "2^16-wide layers": lambda s: s["model_config"].update(latent_dim=1 << 16),
    "a weight of the wrong shape": lambda s: s["ema_state_dict"].update({first_weight(s): torch.zeros(3)}),
    "a missing weight": lambda s: s["ema_state_dict"].pop(first_weight(s)),
    "zero heads": lambda s: s["model_config"].update(num_heads=0),
    "a negative window": lambda s: s["model_config"].update(window_frames=-5),
    "no normaliser": lambda s: s.pop("normalizer"),
}


@pytest.mark.parametrize("forgery", list(FORGERIES))
def test_forged_checkpoint_is_bad_input(tiny_checkpoint, tmp_path, capsys, forgery):
    state = copy.deepcopy(load_checkpoint(tiny_checkpoint))
    FORGERIES[forgery](state)
    forged = tmp_path / "forged.pt"
    save_checkpoint(state, forged)
    code, _, err = run_cli(capsys, "generate", EXAMPLE_SONG, "-o", tmp_path / "d.bvh", "--checkpoint", forged)
    assert code == 2, err
    assert len(err.strip().splitlines()) == 1 and str(forged) in err
    assert not (tmp_path / "d.bvh").exists()


# Issue 48, item 2: checkpoint archives whose reading would allocate more than the file holds ------

FIXTURES = Path(__file__).parents[1] / "fixtures" / "aistpp"


def rezip(source, target, change=lambda name, data: data, deflate=lambda name: False):
    """``source``'s records written again to ``target``, each through ``change``; stored, as torch
    writes them, but those ``deflate`` names."""
    with zipfile.ZipFile(source) as original, zipfile.ZipFile(target, "w") as copy_:
        for info in original.infolist():
            method = zipfile.ZIP_DEFLATED if deflate(info.filename) else zipfile.ZIP_STORED
            copy_.writestr(info.filename, change(info.filename, original.read(info)), compress_type=method)
    return target


def zip_bomb(source, target):
    """The first tensor record swapped for 64 MB of deflated zeros (about 64 kB on disk)."""
    bomb = lambda name: name.endswith("/data/0")  # noqa: E731
    return rezip(source, target, lambda name, data: bytes(1 << 26) if bomb(name) else data, deflate=bomb)


def with_declared_size(data: bytes, record: str, size: int) -> bytes:
    """The zip's central directory made to say ``record`` holds ``size`` bytes (both sizes)."""
    start = 0
    while True:
        start = data.index(b"PK\x01\x02", start)
        length = struct.unpack_from("<H", data, start + 28)[0]
        if data[start + 46:start + 46 + length].decode() == record:
            return data[:start + 20] + struct.pack("<II", size, size) + data[start + 28:]
        start += 4


def test_a_deflated_record_is_refused_before_torch_inflates_it(tiny_checkpoint, tmp_path):
    bomb = zip_bomb(tiny_checkpoint, tmp_path / "bomb.pt")
    assert bomb.stat().st_size < 2 << 20  # 64 MB of zeros in about 64 kB
    with pytest.raises(InputError, match="data/0 is compressed"):
        check_checkpoint_archive(bomb)


def test_a_record_shorter_than_its_pickle_claims_is_refused(tiny_checkpoint, tmp_path):
    short = rezip(tiny_checkpoint, tmp_path / "short.pt", lambda name, data: data[:8] if name.endswith("/data/0") else data)
    with pytest.raises(InputError, match="storage 0 claims"):
        check_checkpoint_archive(short)


def test_a_pickle_claiming_a_record_that_is_absent_is_refused(tiny_checkpoint, tmp_path):
    with zipfile.ZipFile(tiny_checkpoint) as original:
        names = [info.filename for info in original.infolist()]
    last = max((n for n in names if "/data/" in n), key=lambda n: int(n.rsplit("/", 1)[1]))
    with zipfile.ZipFile(tiny_checkpoint) as original, zipfile.ZipFile(tmp_path / "gap.pt", "w") as copy_:
        for name in names:
            if name != last:
                copy_.writestr(name, original.read(name))
    with pytest.raises(InputError, match="its record holds none"):
        check_checkpoint_archive(tmp_path / "gap.pt")


def test_a_directory_declaring_bytes_the_file_lacks_is_refused(tiny_checkpoint, tmp_path):
    stored = rezip(tiny_checkpoint, tmp_path / "stored.pt")
    name = next(n for n in zipfile.ZipFile(stored).namelist() if n.endswith("/data/0"))
    forged = tmp_path / "forged.pt"
    forged.write_bytes(with_declared_size(stored.read_bytes(), name, (1 << 31) - 1))
    with pytest.raises(InputError, match="does not hold|more than"):
        check_checkpoint_archive(forged)


def test_a_checkpoint_torch_wrote_passes_the_archive_check(tiny_checkpoint):
    from choreo_sgmd import DEFAULT_CHECKPOINT

    check_checkpoint_archive(tiny_checkpoint)  # a training state: weights, EMA and AdamW moments
    check_checkpoint_archive(DEFAULT_CHECKPOINT)


@pytest.mark.parametrize("where", ["generate --checkpoint", "train --init-from", "train --resume"])
def test_a_zip_bomb_is_exit_2_on_every_command_that_loads_a_checkpoint(tiny_checkpoint, tmp_path, capsys, where):
    out = tmp_path / "run"
    out.mkdir()
    bomb = zip_bomb(tiny_checkpoint, out / "last.pt")
    train = ["train", "sgmd", "--data", FIXTURES, "--out", out, "--config", "tiny", "--steps", "1", "--batch-size", "2",
             "--prompt", "onehot"]
    args = {"generate --checkpoint": ["generate", EXAMPLE_SONG, "-o", tmp_path / "d.bvh", "--checkpoint", bomb],
            "train --init-from": [*train, "--init-from", bomb], "train --resume": [*train, "--resume"]}[where]
    before = sorted(p.name for p in out.iterdir())
    code, _, err = run_cli(capsys, *args)
    assert code == 2, err
    assert len(err.strip().splitlines()) == 1 and "compressed" in err
    assert not (tmp_path / "d.bvh").exists() and sorted(p.name for p in out.iterdir()) == before


# -- SGMD checkpoints whose schedule or layer counts hang or divide by zero ------------------------
@pytest.mark.fuzz_finding
@pytest.mark.parametrize("section, key, value, words", [
    ("diffusion_config", "timesteps", 1 << 31, "timesteps"),          # a schedule built step by step: a hang
    ("diffusion_config", "cosine_offset", -1, "cosine_offset"),       # ZeroDivisionError before
    ("diffusion_config", "max_beta", float("nan"), "max_beta"),
    ("model_config", "num_layers", 1 << 16, "num_layers"),            # minutes to lay out, even on meta
    ("model_config", "music_layers", 128, "layers"),                  # more layers than weights in the file
])  # fmt: skip
def test_checkpoint_schedule_and_layer_counts_are_checked_first(tmp_path, tiny_checkpoint, section, key, value, words):
    from choreo_sgmd.checkpoint import load_checkpoint, save_checkpoint
    from choreo_sgmd.generator import SGMDGenerator

    state = load_checkpoint(tiny_checkpoint)
    state[section] = {**state[section], key: value}
    forged = tmp_path / "forged.pt"
    save_checkpoint(state, forged)
    with pytest.raises(InputError, match=words):
        SGMDGenerator(forged)


@pytest.mark.fuzz_finding
def test_a_checkpoint_config_key_with_a_newline_gives_one_line(tmp_path, tiny_checkpoint):
    # Found by the 100,000-input run: the refusal quoted the key, newline and all, on two lines.
    from choreo_sgmd.checkpoint import load_checkpoint, save_checkpoint
    from choreo_sgmd.generator import SGMDGenerator

    state = load_checkpoint(tiny_checkpoint)
    state["model_config"] = {**state["model_config"], "\nstyle_mode": "none"}
    forged = tmp_path / "forged.pt"
    save_checkpoint(state, forged)
    with pytest.raises(InputError, match="damaged SGMD checkpoint") as refused:
        SGMDGenerator(forged)
    assert "\n" not in str(refused.value)
