"""Music guidance on some channels only (the rest from the conditional prediction): does keeping
the root (and contacts) unguided keep the feet planted while the limbs get guidance's energy?

    python scripts/experiments/guidance_channels.py root root+contacts
"""
import sys
import torch
from choreo.datasets import TEST, TRAIN, load_dataset
from choreo.metrics.protocol import score, scoring_windows, table_row, windows_as_dances, window_dance
from choreo.motion.vector import CONTACT_SLICE, ROOT_SLICE, ROTATION_SLICE
import choreo_sgmd.sampling as sampling  # the sampler's guidance class is replaced for the experiment: no public route
from choreo import load_backend
from choreo.metrics.protocol import generate_window_motions
from pathlib import Path

DATA = Path(__file__).resolve().parents[3] / "shared" / "data" / "m2d"
CHECKPOINT = Path(__file__).resolve().parents[2] / "generators" / "choreo_sgmd" / "weights" / "sgmd-cpu-m2d.pt"
torch.set_num_threads(1)
GuidedDenoiser = sampling.GuidedDenoiser  # the shipped class, kept before the loop below replaces it
KEEP = {"root": [ROOT_SLICE], "root+contacts": [ROOT_SLICE, CONTACT_SLICE], "rotations": [ROTATION_SLICE]}

def channel_guided(unguided):
    class Channel(GuidedDenoiser):
        def __call__(self, x_t, t):
            guided = super().__call__(x_t, t)
            w = self.guidance
            self.guidance = 1.0
            plain = super().__call__(x_t, t)
            self.guidance = w
            for part in unguided:
                guided[..., part] = plain[..., part]
            return guided
    return Channel

clips = load_dataset(DATA)
windows = scoring_windows([c for c in clips if c.split == TEST])
train = windows_as_dances([c for c in clips if c.split == TRAIN])
generator = load_backend("sgmd", CHECKPOINT)
for name in sys.argv[1:]:
    sampling.GuidedDenoiser = channel_guided(KEEP[name])
    motions = generate_window_motions(generator, windows, options={"steps": 10, "guidance": 4.0})
    dances = [window_dance(w, m) for w, m in zip(windows, motions)]
    print(table_row(f"w=4, unguided {name}", score(dances, train)), flush=True)
