"""Horizontal speed of the ankles and the root over one rumba and one waltz test window: real, and
the bundled model's dance finished without and with footsteps (do the feet step, or glide with
the body?).

    python -m experiments.feet_plot OUT.png [CHECKPOINT]
"""
import sys
from pathlib import Path

import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from choreo import load_backend  # noqa: E402
from choreo.datasets import TEST, load_dataset  # noqa: E402
from choreo.finishing import finish  # noqa: E402
from choreo.pipeline import Finishing  # noqa: E402
from choreo.metrics.protocol import generate_window_motions, music_beats, scoring_windows  # noqa: E402

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "m2d"
CHECKPOINT = Path(__file__).resolve().parents[1] / "generators" / "choreo_sgmd" / "weights" / "sgmd-cpu-m2d.pt"
clips = load_dataset(DATA)
windows = scoring_windows([c for c in clips if c.split == TEST])
pick = [i for i, w in enumerate(windows) if w.genre == "rumba"][5:6] + [i for i, w in enumerate(windows) if w.genre == "waltz"][10:11]
chosen = [windows[i] for i in pick]
motions = generate_window_motions(load_backend("sgmd", sys.argv[2] if len(sys.argv) > 2 else CHECKPOINT), chosen,
                                  options={"steps": 10})
rows = {"real": [w.motion.joint_positions() for w in chosen]}
for label, footsteps in (("SGMD, without footsteps", False), ("SGMD, as written (footsteps)", True)):
    rows[label] = [finish(m, music_beats(w.features), Finishing(footsteps=footsteps)).joint_positions() for w, m in zip(chosen, motions)]
fig, axes = plt.subplots(len(chosen), 3, figsize=(15, 3.2 * len(chosen)), sharey=False)
for c, (name, dances) in enumerate(rows.items()):
    for r, p in enumerate(dances):
        ax = axes[r, c]
        for joint, label in ((7, "left ankle"), (8, "right ankle"), (0, "root")):
            speed = np.linalg.norm(np.diff(p[:, joint, [0, 2]], axis=0), axis=-1) * 30
            ax.plot(speed, label=label)
        ax.set_title(f"{name} [{chosen[r].genre}]: horizontal speed (m/s)")
        ax.set_ylim(0, 3)
axes[0, 0].legend()
plt.tight_layout()
plt.savefig(sys.argv[1] if len(sys.argv) > 1 else "feet.png", dpi=60)
