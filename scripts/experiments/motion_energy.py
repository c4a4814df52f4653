"""Where generated kinetic energy lives (per genre): mean joint speed, acceleration and the share of
power above 5 Hz, generated (per guidance setting) against real test windows.

    python scripts/experiments/motion_energy.py [CHECKPOINT.pt] 1 2 4 4@0:0.3   # guidance weights [@ interval]
"""
import sys
import numpy as np
from choreo.datasets import TEST, load_dataset
from choreo.metrics.protocol import scoring_windows
from choreo import load_backend
from choreo.metrics.protocol import generate_window_motions
import torch
from pathlib import Path

DATA = Path(__file__).resolve().parents[3] / "shared" / "data" / "m2d"
CHECKPOINT = Path(__file__).resolve().parents[2] / "generators" / "choreo_sgmd" / "weights" / "sgmd-cpu-m2d.pt"
torch.set_num_threads(1)

def stats(positions_list, fps=30.0):
    speed, acc, high = [], [], []
    for p in positions_list:
        v = np.diff(p, axis=0) * fps
        a = np.diff(v, axis=0) * fps
        speed.append(np.linalg.norm(v, axis=-1).mean())
        acc.append(np.linalg.norm(a, axis=-1).mean())
        spec = np.abs(np.fft.rfft(v - v.mean(0), axis=0)) ** 2
        freqs = np.fft.rfftfreq(len(v), 1 / fps)
        high.append(spec[freqs > 5].sum() / spec.sum())
    return f"speed {np.mean(speed):.3f} m/s, |acc| {np.mean(acc):.2f} m/s^2, power above 5 Hz {100*np.mean(high):.1f} %"

clips = load_dataset(DATA)
windows = scoring_windows([c for c in clips if c.split == TEST])
by_genre = lambda ws, ps, g: [p for w, p in zip(ws, ps) if w.genre == g]
real = [w.motion.joint_positions() for w in windows]
genres = sorted({w.genre for w in windows})
print("real:", stats(real), flush=True)
for g in genres:
    print(f"  real [{g}]:", stats(by_genre(windows, real, g)), flush=True)
specs = sys.argv[1:]
checkpoint = specs.pop(0) if specs and specs[0].endswith(".pt") else CHECKPOINT
generator = load_backend("sgmd", checkpoint)
for spec in specs:
    w, interval = spec.split("@") if "@" in spec else (spec, "0:1")
    options = {"steps": 10, "guidance": float(w), "guidance_interval": tuple(float(b) for b in interval.split(":"))}
    gen = [m.joint_positions() for m in generate_window_motions(generator, windows, options=options)]
    print(f"w={w} on {interval}:", stats(gen), flush=True)
    for g in genres:
        print(f"  [{g}]:", stats(by_genre(windows, gen, g)), flush=True)
