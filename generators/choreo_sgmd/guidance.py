"""Classifier-free guidance on music (paper eq. 6) over a set of windows, conditions encoded once.

x0 = w x(c, s) + (1 - w) x(null, s): w = 1 is the plain conditional prediction (one network
evaluation per window and step); otherwise the conditional and music-free predictions run as one
batch of twice the size. Guidance may be limited to an interval of noise levels (Kynkäänniemi et
al., "Applying Guidance in a Limited Interval Improves Sample and Distribution Quality in
Diffusion Models", 2024): outside it the step is the conditional prediction alone, at half the
cost. Music and style enter the network only through `Denoiser.condition`,
which does not depend on the diffusion step, so it is computed once per window and reused by
every step, for the first ``cache_windows`` windows; windows past that budget are re-encoded each
step, which keeps memory bounded for songs of any length.
"""

from __future__ import annotations

import torch

CACHE_WINDOWS = 96  # about 1.4 MB of cached keys and values per window for the cpu model


class GuidedDenoiser:
    def __init__(self, model, music: torch.Tensor, styles: torch.Tensor, keep_style: torch.Tensor, guidance: float,
                 chunk_windows: int = 32, cache_windows: int = CACHE_WINDOWS,
                 interval: tuple[int, int] | None = None):
        """``interval`` (first, last): the diffusion steps t, inclusive, at which guidance applies
        (None: all)."""
        self.model, self.music, self.styles, self.keep_style, self.guidance = model, music, styles, keep_style, guidance
        self.interval = interval
        self.chunks = [slice(i, min(i + chunk_windows, len(music))) for i in range(0, len(music), chunk_windows)]
        self.cached = {i: self.condition(part) for i, part in enumerate(self.chunks) if part.stop <= cache_windows}

    def guided_at(self, t: int) -> bool:
        return self.guidance != 1.0 and (self.interval is None or self.interval[0] <= t <= self.interval[1])

    def evaluations_at(self, t: int) -> int:
        """Network evaluations per window at step t: the cost unit of diffusion samplers."""
        return 2 if self.guided_at(t) else 1

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
            if not self.guided_at(t):
                predictions.append(self.model.denoise(x, steps, conditioning if self.guidance == 1.0
                                                      else conditioning.head(len(x))))
                continue
            conditional, unconditional = self.model.denoise(torch.cat([x, x]), torch.cat([steps, steps]), conditioning).chunk(2)
            predictions.append(self.guidance * conditional + (1 - self.guidance) * unconditional)
        return torch.cat(predictions)
