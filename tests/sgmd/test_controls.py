"""The SGMD generator obeys its controls: seed, guidance and style each change the dance, and the
same settings give the same dance. (Same-seed determinism alone cannot catch a control that is
silently ignored.)"""

import numpy as np
import pytest

from choreo.generator import GenerationRequest
from choreo.music import SAMPLE_RATE, Music
from tests.music.helpers import click_track


@pytest.fixture(scope="module")
def music():
    return Music.from_array(click_track(120.0, 6.0, SAMPLE_RATE), SAMPLE_RATE)


def dance(generator, music, **settings):
    options = {"steps": 3, "guidance": settings.pop("guidance", 2.0)}
    request = GenerationRequest(music, style=settings.pop("style", "waltz"), seed=settings.pop("seed", 0), options=options)
    return generator.generate(request).joint_positions()


def test_same_settings_same_dance(tiny_generator, music):
    np.testing.assert_array_equal(dance(tiny_generator, music), dance(tiny_generator, music))


@pytest.mark.parametrize("change", [{"seed": 1}, {"guidance": 1.0}, {"guidance": 4.0}, {"style": "rumba"}, {"style": None}])
def test_each_control_changes_the_dance(tiny_generator, music, change):
    base, changed = dance(tiny_generator, music), dance(tiny_generator, music, **change)
    assert np.abs(base - changed).max() > 1e-4, f"{change} did not change the dance"


def test_stitch_cross_fades_each_overlap_with_a_linear_ramp():
    import torch

    from choreo_sgmd.sampling import stitch

    # two half-overlapping windows of 4 frames holding constants 0 and 1: the overlap is a ramp
    windows = torch.stack([torch.zeros(4, 1), torch.ones(4, 1)])
    out = stitch(windows, 6)[:, 0]
    torch.testing.assert_close(out, torch.tensor([0.0, 0.0, 0.25, 0.75, 1.0, 1.0]))
    # a hard cut (no blend) would jump by the whole difference at one frame
    assert (out[1:] - out[:-1]).abs().max() <= 0.5


def test_the_sampler_itself_honours_constraints_before_any_overwrite(tiny_generator):
    """sample_long's own output, not the generator's final copy of the given values: a sampler
    that ignored the mask would leave the known frames wherever the network put them."""
    import torch

    from choreo_sgmd.sampling import Inpainting, SamplingOptions, sample_long

    g = tiny_generator
    frames, dim = 300, g.model_config.frame_dim
    music = torch.randn(frames, g.model_config.music_dim, generator=torch.Generator().manual_seed(0))
    values = torch.zeros(frames, dim)
    values[:, 4:7] = torch.linspace(-1, 1, frames)[:, None]  # a root path, normalised units
    mask = torch.zeros(frames, dim, dtype=torch.bool)
    mask[:60] = True  # a seed motion: the first 2 s, every channel
    mask[:, 4] = mask[:, 6] = True  # and the root's x and z on every frame (a path)
    style, keep = torch.zeros(1, g.model_config.style_dim), False
    free, _ = sample_long(g.model, g.schedule, music, style, keep, dim, g.model_config.window_frames,
                          SamplingOptions(steps=3))
    x0, _ = sample_long(g.model, g.schedule, music, style, keep, dim, g.model_config.window_frames,
                        SamplingOptions(steps=3), inpainting=Inpainting(values, mask))
    torch.testing.assert_close(x0[mask], values[mask], atol=1e-5, rtol=0)
    assert (free[mask] - values[mask]).abs().max() > 0.1  # without the mask the sampler lands elsewhere
    assert not torch.allclose(x0[~mask], free[~mask])  # and the free channels respond to the given ones
