"""Self-describing checkpoints: configs as dicts, weights and statistics as tensors.

Everything in the file is a tensor, dict, list, str, int or float, so ``torch.load(...,
weights_only=True)`` reads it without executing code. The model rebuilds from the file alone.
"""

from __future__ import annotations

import os

from choreo.errors import InputError
from choreo.generator.checkpoint import read_checkpoint, write_checkpoint

FORMAT_VERSION = 1
GENERATOR_NAME = "sgmd"
# What generation needs; training checkpoints also hold the raw weights and the optimiser state.
INFERENCE_KEYS = ("model_config", "diffusion_config", "train_config", "genres", "prompt_kind", "ema_state_dict",
                  "normalizer", "music_scaler", "step", "history")


def save_checkpoint(state: dict, path: str | os.PathLike) -> None:
    write_checkpoint(state, path, GENERATOR_NAME, FORMAT_VERSION)


def load_checkpoint(path: str | os.PathLike) -> dict:
    return read_checkpoint(path, GENERATOR_NAME, "an SGMD", FORMAT_VERSION)


def inference_state(state: dict) -> dict:
    """The part of a training checkpoint that generation uses: EMA weights, configs and statistics.

    A quarter of the size of a training checkpoint (no raw weights, no AdamW moments); it cannot be
    resumed from, which is why ``choreo train`` keeps writing full ones.
    """
    missing = [key for key in INFERENCE_KEYS if key not in state]
    if missing:
        raise InputError(f"checkpoint lacks {', '.join(missing)}")
    return {key: state[key] for key in INFERENCE_KEYS}


def export_for_inference(source: str | os.PathLike, destination: str | os.PathLike) -> dict:
    state = inference_state(load_checkpoint(source))
    save_checkpoint(state, destination)
    return state


if __name__ == "__main__":  # python -m choreo_sgmd.checkpoint runs/sgmd-cpu/last.pt generators/choreo_sgmd/weights/x.pt
    import sys

    if len(sys.argv) != 3:
        sys.exit("usage: python -m choreo_sgmd.checkpoint TRAINING_CHECKPOINT INFERENCE_CHECKPOINT")
    exported = export_for_inference(sys.argv[1], sys.argv[2])
    print(f"wrote {sys.argv[2]}: EMA weights after {exported['step']} steps")
