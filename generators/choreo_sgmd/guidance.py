"""Classifier-free guidance on music (paper eq. 6) over a set of windows, conditions encoded once.

x0 = w x(c, s) + (1 - w) x(null, s): w = 1 is the plain conditional prediction (one network
evaluation per window and step); otherwise the conditional and music-free predictions run as one
batch of twice the size. Music and style enter the network only through `Denoiser.condition`,
which does not depend on the diffusion step, so it is computed once per window and reused by
every step, for the first ``cache_windows`` windows; windows past that budget are re-encoded each
step, which keeps memory bounded for songs of any length.
"""

from __future__ import annotations

import torch

CACHE_WINDOWS = 96  # about 1.4 MB of cached keys and values per window for the cpu model


class GuidedDenoiser:
    def __init__(self, model, music: torch.Tensor, styles: torch.Tensor, keep_style: torch.Tensor, guidance: float,
                 chunk_windows: int = 32, cache_windows: int = CACHE_WINDOWS):
        self.model, self.music, self.styles, self.keep_style, self.guidance = model, music, styles, keep_style, guidance
        self.chunks = [slice(i, min(i + chunk_windows, len(music))) for i in range(0, len(music), chunk_windows)]
        self.cached = {i: self.condition(part) for i, part in enumerate(self.chunks) if part.stop <= cache_windows}

    @property
    def evaluations_per_step(self) -> int:
        return 1 if self.guidance == 1.0 else 2

    def condition(self, part: slice):
        music, styles, keep_style = self.music[part], self.styles[part], self.keep_style[part]
        if self.guidance == 1.0:
            return self.model.condition(music, styles, keep_style=keep_style)
        count = len(music)
        keep_music = torch.cat([torch.ones(count, dtype=torch.bool), torch.zeros(count, dtype=torch.bool)])
        return self.model.condition(torch.cat([music, music]), torch.cat([styles, styles]), keep_music,
                                    torch.cat([keep_style, keep_style]))

    @torch.no_grad()
    def __call__(self, x_t: torch.Tensor, t: int) -> torch.Tensor:
        """Guided x0 predictions (N, W, D) for noisy windows (N, W, D) at diffusion step t."""
        predictions = []
        for index, part in enumerate(self.chunks):
            conditioning = self.cached.get(index) or self.condition(part)
            x = x_t[part]
            steps = torch.full((len(x),), t, dtype=torch.long)
            if self.guidance == 1.0:
                predictions.append(self.model.denoise(x, steps, conditioning))
                continue
            conditional, unconditional = self.model.denoise(torch.cat([x, x]), torch.cat([steps, steps]), conditioning).chunk(2)
            predictions.append(self.guidance * conditional + (1 - self.guidance) * unconditional)
        return torch.cat(predictions)
