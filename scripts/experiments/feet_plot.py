"""Horizontal speed of the ankles and the root over one rumba and one waltz test window: real, and
the bundled model at guidance 2 and 4 (do the feet step, or glide with the body?).

    python scripts/experiments/feet_plot.py OUT.png [CHECKPOINT]
"""
import sys
import numpy as np, torch, matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
from choreo.datasets import TEST, load_dataset
from choreo.metrics.protocol import scoring_windows
from choreo import load_backend
from choreo.metrics.protocol import generate_window_motions
from pathlib import Path

DATA = Path(__file__).resolve().parents[3] / "shared" / "data" / "m2d"
CHECKPOINT = Path(__file__).resolve().parents[2] / "generators" / "choreo_sgmd" / "weights" / "sgmd-cpu-m2d.pt"
torch.set_num_threads(1)
clips = load_dataset(DATA)
windows = scoring_windows([c for c in clips if c.split == TEST])
pick = [i for i, w in enumerate(windows) if w.genre == "rumba"][5:6] + [i for i, w in enumerate(windows) if w.genre == "waltz"][10:11]
sel = [windows[i] for i in pick]
g = load_backend("sgmd", sys.argv[2] if len(sys.argv) > 2 else CHECKPOINT)
rows = {"real": [w.motion.joint_positions() for w in sel]}
for w in (2.0, 4.0):
    rows[f"w={w:g}"] = [m.joint_positions() for m in generate_window_motions(g, sel, options={"steps": 10, "guidance": w})]
fig, axes = plt.subplots(len(sel), 3, figsize=(15, 3.2 * len(sel)), sharey=False)
for c, (name, dances) in enumerate(rows.items()):
    for r, p in enumerate(dances):
        ax = axes[r, c]
        for joint, label in ((7, "left ankle"), (8, "right ankle"), (0, "root")):
            speed = np.linalg.norm(np.diff(p[:, joint, [0, 2]], axis=0), axis=-1) * 30
            ax.plot(speed, label=label)
        ax.set_title(f"{name} [{sel[r].genre}]: horizontal speed (m/s)")
        ax.set_ylim(0, 3)
axes[0, 0].legend()
plt.tight_layout(); plt.savefig(sys.argv[1] if len(sys.argv) > 1 else "feet.png", dpi=60)
