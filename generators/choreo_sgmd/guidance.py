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

from choreo.motion.vector import ROOT_SLICE
from choreo.threads import in_parallel

FLOOR_CHANNELS = [ROOT_SLICE.start, ROOT_SLICE.start + 2]  # the root's x and z: where on the floor the dancer is
CACHE_WINDOWS = 96  # about 1.4 MB of cached keys and values per window for the cpu model


class GuidedDenoiser:
    """Guided x0 predictions for a set of windows.

    x0 = x(c, s) + (w - 1) (x(c, s) - x(null, s)) + (w_s - 1) (x(c, s) - x(c, null)): guidance
    on music (weight w, paper eq. 6) and, when ``style_guidance`` is not 1, on style too (the model
    learns the style-free prediction from its style dropout). Each term's extra prediction is a
    block of the same batch; a step outside the music guidance's interval leaves its block out.
    """

    def __init__(self, model, music: torch.Tensor, styles: torch.Tensor, keep_style: torch.Tensor, guidance: float,
                 chunk_windows: int = 4, cache_windows: int = CACHE_WINDOWS,
                 interval: tuple[int, int] | None = None, style_guidance: float = 1.0,
                 style_interval: tuple[int, int] | None = None, pace: float | None = None,
                 travel_guidance: float = 1.0):
        """``interval`` / ``style_interval`` (first, last): the diffusion steps t, inclusive, at which
        music / style guidance applies (None: all). ``pace``: m/s every window is asked to travel at,
        in every block alike (a condition, not a guided term), for a network with a pace condition.
        ``travel_guidance``: the share of both guidance terms the root's floor position gets (0: the
        dancer travels as the conditional prediction alone; the guidance terms are what rush it)."""
        self.model, self.music, self.styles, self.keep_style, self.guidance = model, music, styles, keep_style, guidance
        self.pace = float("nan") if pace is None else float(pace)
        self.travel_guidance = travel_guidance
        self.interval, self.style_guidance, self.style_interval = interval, style_guidance, style_interval
        styled = guides_style(style_guidance, keep_style)
        self.blocks = ["conditional"] + (["no music"] if guidance != 1.0 else []) + (["no style"] if styled else [])
        self.chunks = [slice(i, min(i + chunk_windows, len(music))) for i in range(0, len(music), chunk_windows)]
        cached = [i for i, part in enumerate(self.chunks) if part.stop <= cache_windows]
        self.cached = dict(zip(cached, in_parallel(lambda i: self.condition(self.chunks[i]), cached)))

    def guided_at(self, t: int) -> bool:
        return self.guidance != 1.0 and _inside(self.interval, t)

    def style_guided_at(self, t: int) -> bool:
        return "no style" in self.blocks and _inside(self.style_interval, t)

    def blocks_at(self, t: int) -> list[str]:
        active = {"conditional": True, "no music": self.guided_at(t), "no style": self.style_guided_at(t)}
        return [b for b in self.blocks if active[b]]

    def evaluations_at(self, t: int) -> int:
        """Network evaluations per window at step t: the cost unit of diffusion samplers."""
        return len(self.blocks_at(t))

    def condition(self, part: slice):
        """The conditioning of every block, stacked block after block."""
        music, styles, keep_style = self.music[part], self.styles[part], self.keep_style[part]
        count = len(music)
        keep_music = {"conditional": True, "no music": False, "no style": True}
        return self.model.condition(torch.cat([music] * len(self.blocks)), torch.cat([styles] * len(self.blocks)),
                                    torch.cat([torch.full((count,), keep_music[b]) for b in self.blocks]),
                                    torch.cat([keep_style & (b != "no style") for b in self.blocks]),
                                    torch.full((count * len(self.blocks),), self.pace))

    @torch.no_grad()
    def __call__(self, x_t: torch.Tensor, t: int) -> torch.Tensor:
        """Guided x0 predictions (N, W, D) for noisy windows (N, W, D) at diffusion step t: the
        chunks side by side on the chosen threads (choreo.threads)."""
        return torch.cat(in_parallel(lambda index: self.guided_chunk(x_t, t, index), range(len(self.chunks))))

    def guided_chunk(self, x_t: torch.Tensor, t: int, index: int) -> torch.Tensor:
        active, part = self.blocks_at(t), self.chunks[index]
        conditioning = self.cached.get(index) or self.condition(part)
        x = x_t[part]
        count = len(x)
        rows = torch.cat([torch.arange(count) + self.blocks.index(b) * count for b in active])
        steps = torch.full((count * len(active),), t, dtype=torch.long)
        outputs = dict(zip(active, self.model.denoise(x.repeat(len(active), 1, 1), steps,
                                                      conditioning.rows(rows)).chunk(len(active))))
        guided = torch.zeros_like(outputs["conditional"])
        if "no music" in outputs:
            guided += (self.guidance - 1) * (outputs["conditional"] - outputs["no music"])
        if "no style" in outputs:
            guided += (self.style_guidance - 1) * (outputs["conditional"] - outputs["no style"])
        guided[..., FLOOR_CHANNELS] *= self.travel_guidance
        return outputs["conditional"] + guided


def guides_style(style_guidance: float, keep_style) -> bool:
    """Whether style guidance has anything to do: a weight other than 1 and a window with a style
    (with no style anywhere its term is zero, and its evaluation is skipped)."""
    return style_guidance != 1.0 and bool(torch.as_tensor(keep_style).any())


def _inside(interval: tuple[int, int] | None, t: int) -> bool:
    return interval is None or interval[0] <= t <= interval[1]
