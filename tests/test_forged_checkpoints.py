"""Checkpoints in the right format with wrong contents: refused in one line, before any allocation."""

import copy

import pytest
import torch
from test_cli import EXAMPLE_SONG, run_cli

from choreo_sgmd.checkpoint import load_checkpoint, save_checkpoint


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
