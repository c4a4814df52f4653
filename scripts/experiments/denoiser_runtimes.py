"""Would another runtime make SGMD's sampling cheaper on this CPU? One network evaluation, three ways.

    python scripts/experiments/denoiser_runtimes.py [--windows 23] [--repeats 5]
    pip install onnxruntime onnx   # optional: adds the ONNX Runtime row

The batch is what one guided step of a 60 s song sends through the bundled model: 23 windows of
150 frames, conditional and music-free, so 46 rows. Rows: torch as choreo runs it; a plain numpy
forward pass written here from the same weights (what a torch-free `choreo generate` would run);
and the model exported to ONNX and run by ONNX Runtime (rotary embeddings and RMSNorm rewritten
in real arithmetic for the export). Each prints seconds per evaluation (median of ``--repeats``)
and its largest difference from torch's output. A runtime is worth its import savings (about a
second for torch) only if its evaluations are not slower by more than that over a song's steps.
"""

from __future__ import annotations

import argparse
import math
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np
import torch

from choreo import load_backend
from choreo_sgmd import model as network  # the network's own layers: re-implemented in numpy, patched for the ONNX export


def timed(call, repeats: int) -> tuple[float, np.ndarray]:
    output = call()
    seconds = []
    for _ in range(repeats):
        started = time.perf_counter()
        call()
        seconds.append(time.perf_counter() - started)
    return statistics.median(seconds), np.asarray(output)


class NumpyDenoiser:
    """The decoder side of `choreo_sgmd.model.Denoiser` (x0 prediction) in numpy, for timing."""

    def __init__(self, model: network.Denoiser):
        self.weights = {name: value.numpy() for name, value in model.state_dict().items()}
        self.heads, self.layers = model.config.num_heads, model.config.num_layers
        head_dim = model.config.latent_dim // self.heads
        angles = np.arange(model.config.window_frames)[:, None] / 10_000.0 ** (np.arange(0, head_dim, 2) / head_dim)
        self.cos, self.sin = np.cos(angles).astype(np.float32), np.sin(angles).astype(np.float32)
        self.latent_dim = model.config.latent_dim

    def linear(self, x, name):
        return x @ self.weights[name + ".weight"].T + self.weights[name + ".bias"]

    def layer_norm(self, x, name=None):
        centred = x - x.mean(-1, keepdims=True)
        normed = centred / np.sqrt((centred**2).mean(-1, keepdims=True) + 1e-5)
        return normed if name is None else normed * self.weights[name + ".weight"] + self.weights[name + ".bias"]

    def rotate(self, x):
        even, odd = x[..., 0::2], x[..., 1::2]
        out = np.empty_like(x)
        out[..., 0::2], out[..., 1::2] = even * self.cos - odd * self.sin, even * self.sin + odd * self.cos
        return out

    def split_heads(self, x):
        return x.reshape(*x.shape[:2], self.heads, -1).transpose(0, 2, 1, 3)

    @staticmethod
    def attend(q, k, v):
        scores = q @ k.transpose(0, 1, 3, 2) * q.shape[-1] ** -0.5
        weights = np.exp(scores - scores.max(-1, keepdims=True))
        weights /= weights.sum(-1, keepdims=True)
        out = weights @ v
        return out.transpose(0, 2, 1, 3).reshape(out.shape[0], out.shape[2], -1)

    def film(self, h, condition, name):
        scale, shift = np.split(self.linear(condition / (1 + np.exp(-condition)), name + ".project.1")[:, None], 2, -1)
        return (1 + scale) * h + shift

    def __call__(self, x, t, conditioning: network.Conditioning):
        from scipy.special import erf

        half = self.latent_dim // 2
        angles = t[:, None] * np.exp(-math.log(10_000.0) * np.arange(half) / half)[None]
        step = np.concatenate([np.cos(angles), np.sin(angles)], -1).astype(np.float32)
        hidden = self.linear(step, "time_mlp.0")
        condition = self.linear(hidden / (1 + np.exp(-hidden)), "time_mlp.2") + conditioning.pooled_music.numpy()
        h = self.linear(x, "motion_in")
        for i, (keys, values) in enumerate(conditioning.keys_values):
            p = f"layers.{i}."
            y = self.layer_norm(h, p + "norms.0")
            q = self.rotate(self.split_heads(self.linear(y, p + "self_attention.query")))
            kv = self.linear(y, p + "self_attention.key_value").reshape(*y.shape[:2], 2, self.heads, -1).transpose(2, 0, 3, 1, 4)
            h = h + self.film(self.linear(self.attend(q, self.rotate(kv[0]), kv[1]), p + "self_attention.out"), condition, p + "films.0")
            q = self.rotate(self.split_heads(self.linear(self.layer_norm(h, p + "norms.1"), p + "cross_attention.query")))
            h = h + self.film(self.linear(self.attend(q, keys.numpy(), values.numpy()), p + "cross_attention.out"), condition, p + "films.1")
            if conditioning.style_scale is not None:
                rms = np.sqrt((h * h).mean(-1, keepdims=True) + np.finfo(np.float32).eps)
                h = h + h / rms * conditioning.style_scale.numpy()[:, None]
            hidden = self.linear(self.layer_norm(h, p + "norms.2"), p + "feed_forward.0")
            h = h + self.film(self.linear(0.5 * hidden * (1 + erf(hidden / math.sqrt(2))), p + "feed_forward.3"), condition, p + "films.2")
        return self.linear(self.layer_norm(h, "final_norm"), "motion_out")


def onnx_row(model: network.Denoiser, inputs: tuple, repeats: int) -> tuple[float, np.ndarray] | None:
    try:
        import onnxruntime
    except ImportError:
        return None

    def rotate(self, x):  # complex numbers do not export
        angles = torch.arange(x.shape[-2], dtype=torch.float32)[:, None] * self.inv_freq[None]
        even, odd = x[..., 0::2], x[..., 1::2]
        return torch.stack([even * angles.cos() - odd * angles.sin(), even * angles.sin() + odd * angles.cos()], -1).flatten(-2)

    def modulate(self, x, scale):  # no ONNX RMSNorm at this opset
        return x + x * torch.rsqrt((x * x).mean(-1, keepdim=True) + torch.finfo(torch.float32).eps) * scale[:, None]

    class Flat(torch.nn.Module):
        def __init__(self):
            super().__init__()
            self.model = model

        def forward(self, x, t, pooled, scale, *keys_values):
            pairs = list(zip(keys_values[0::2], keys_values[1::2]))
            return self.model.denoise(x, t, network.Conditioning(pooled, scale, pairs))

    originals = network.RotaryEmbedding.forward, network.StyleModulation.forward
    network.RotaryEmbedding.forward, network.StyleModulation.forward = rotate, modulate
    try:
        with tempfile.TemporaryDirectory() as folder, torch.no_grad():
            path = Path(folder) / "denoiser.onnx"
            torch.onnx.export(Flat(), inputs, str(path), dynamo=False, opset_version=18)
            options = onnxruntime.SessionOptions()
            options.intra_op_num_threads = torch.get_num_threads()
            options.add_session_config_entry("session.intra_op.allow_spinning", "0")  # idle workers would slow torch's rows
            session = onnxruntime.InferenceSession(str(path), options, providers=["CPUExecutionProvider"])
    finally:
        network.RotaryEmbedding.forward, network.StyleModulation.forward = originals
    feed = {given.name: value.numpy() for given, value in zip(session.get_inputs(), inputs)}
    return timed(lambda: session.run(None, feed)[0], repeats)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--windows", type=int, default=23, help="windows of the song (23: 60 s)")
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    model = load_backend("sgmd").model  # the bundled checkpoint's network
    if model.prediction != "x0":
        raise SystemExit("the numpy row is written for an x0-predicting model")
    rows, config = 2 * args.windows, model.config
    generator = torch.Generator().manual_seed(0)
    x = torch.randn(rows, config.window_frames, config.frame_dim, generator=generator)
    t = torch.full((rows,), 500)
    with torch.no_grad():
        conditioning = model.condition(torch.randn(rows, config.window_frames, config.music_dim, generator=generator),
                                       torch.randn(rows, config.style_dim, generator=generator))
        reference_seconds, reference = timed(lambda: model.denoise(x, t, conditioning), args.repeats)
    print(f"one evaluation of {rows} windows x {config.window_frames} frames, {torch.get_num_threads()} threads\n")
    print("| runtime | s per evaluation | / torch | max difference |")
    print("| --- | ---: | ---: | ---: |")
    print(f"| torch {torch.__version__} | {reference_seconds:.3f} | 1.00 | 0 |")
    numpy_forward = NumpyDenoiser(model)
    seconds, output = timed(lambda: numpy_forward(x.numpy(), t.numpy(), conditioning), args.repeats)
    print(f"| numpy {np.__version__} | {seconds:.3f} | {seconds / reference_seconds:.2f} | {np.abs(output - reference).max():.1e} |")
    flat = (x, t, conditioning.pooled_music, conditioning.style_scale, *[a for pair in conditioning.keys_values for a in pair])
    onnx = onnx_row(model, flat, args.repeats)
    if onnx is None:
        print("| ONNX Runtime | not installed | | |")
    else:
        import onnxruntime

        print(f"| ONNX Runtime {onnxruntime.__version__} | {onnx[0]:.3f} | {onnx[0] / reference_seconds:.2f} | "
              f"{np.abs(onnx[1] - reference).max():.1e} |")


if __name__ == "__main__":
    main()
