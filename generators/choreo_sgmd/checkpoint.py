"""Self-describing checkpoints: configs as dicts, weights and statistics as tensors.

Everything in the file is a tensor, dict, list, str, int or float, so ``torch.load(...,
weights_only=True)`` reads it without executing code. The model rebuilds from the file alone.
"""

from __future__ import annotations

import math
import os

from choreo.errors import InputError
from choreo.generator.checkpoint import read_checkpoint, write_checkpoint

from .options import MAX_STEPS

FORMAT_VERSION = 1
GENERATOR_NAME = "sgmd"
# What generation needs; training checkpoints also hold the raw weights and the optimiser state.
INFERENCE_KEYS = ("model_config", "diffusion_config", "train_config", "genres", "prompt_kind", "ema_state_dict",
                  "normalizer", "music_scaler", "step", "history", "trained_genres")

MAX_LAYERS = 128  # each of decoder and music encoder: sixteen times the paper's 8
# The noise schedule is built step by step from these before anything else looks at them: 2^31 steps
# never finish, and a cosine offset of -1 divides by zero. (low, high, whole numbers only)
DIFFUSION_LIMITS = {"timesteps": (1, MAX_STEPS, True), "cosine_offset": (0.0, 1.0, False),
                    "max_beta": (1e-9, 1.0, False)}


def save_checkpoint(state: dict, path: str | os.PathLike) -> None:
    write_checkpoint(state, path, GENERATOR_NAME, FORMAT_VERSION)


def load_checkpoint(path: str | os.PathLike) -> dict:
    state = read_checkpoint(path, GENERATOR_NAME, "an SGMD", FORMAT_VERSION)
    check_diffusion_config(state.get("diffusion_config"), str(path))
    check_layer_counts(state.get("model_config"), state.get("ema_state_dict"), str(path))
    return state


def check_layer_counts(config, weights, where: str) -> None:
    """Refuse layer counts beyond MAX_LAYERS or beyond the weights present (every layer has several):
    the generator lays the model out before it compares weights, and 65536 layers take minutes even
    on torch's meta device."""
    if not isinstance(config, dict):
        return
    counts = {key: config.get(key) for key in ("num_layers", "music_layers")}
    counts = {key: n for key, n in counts.items() if isinstance(n, int) and not isinstance(n, bool)}
    for key, count in counts.items():
        if count > MAX_LAYERS:
            raise InputError(f"{where}: model_config {key}={count} (choreo builds at most {MAX_LAYERS})")
    if isinstance(weights, dict) and sum(counts.values()) > len(weights):
        raise InputError(f"{where}: model_config asks for {sum(counts.values())} layers but the checkpoint "
                         f"holds {len(weights)} weights")


def check_diffusion_config(config, where: str) -> None:
    """Refuse schedule sizes no training run writes; a missing or odd config is left to the
    generator, which refuses it when it builds the config."""
    if not isinstance(config, dict):
        return
    for key, (low, high, whole) in DIFFUSION_LIMITS.items():
        if key not in config:
            continue
        value = config[key]
        number = isinstance(value, int if whole else (int, float)) and not isinstance(value, bool)
        if not number or not math.isfinite(value) or not low <= value <= high:
            raise InputError(f"{where}: diffusion_config {key}={value!r} is outside {low:g} to {high:g}")


def inference_state(state: dict, half: bool = False) -> dict:
    """The part of a training checkpoint that generation uses: EMA weights, configs and statistics.

    A quarter of the size of a training checkpoint (no raw weights, no AdamW moments); it cannot be
    resumed from, which is why ``choreo train`` keeps writing full ones. ``half`` stores the weights
    in float16 (an eighth; the generator computes in float32 after loading): every committed
    checkpoint stays in the repository's history, so its size is paid for good.
    """
    missing = [key for key in INFERENCE_KEYS if key not in state]
    if missing:
        raise InputError(f"checkpoint lacks {', '.join(missing)}")
    inference = {key: state[key] for key in INFERENCE_KEYS}
    if "started_from" in state:  # a fine-tune names its starting point: the recipe is two runs
        inference["started_from"] = state["started_from"]
    if half:
        inference["ema_state_dict"] = {name: weight.half() if weight.is_floating_point() else weight
                                       for name, weight in inference["ema_state_dict"].items()}
    return inference


def export_for_inference(source: str | os.PathLike, destination: str | os.PathLike, half: bool = False) -> dict:
    state = inference_state(load_checkpoint(source), half)
    save_checkpoint(state, destination)
    return state


if __name__ == "__main__":  # python -m choreo_sgmd.checkpoint runs/sgmd-cpu/last.pt generators/choreo_sgmd/weights/x.pt [--half]
    import sys

    arguments = [a for a in sys.argv[1:] if a != "--half"]
    if len(arguments) != 2:
        sys.exit("usage: python -m choreo_sgmd.checkpoint TRAINING_CHECKPOINT INFERENCE_CHECKPOINT [--half]")
    exported = export_for_inference(*arguments, half="--half" in sys.argv[1:])
    precision = "float16" if "--half" in sys.argv[1:] else "float32"
    print(f"wrote {arguments[1]}: EMA weights after {exported['step']} steps ({precision})")
