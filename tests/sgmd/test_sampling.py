"""SGMD's schedule and samplers pinned against literal formulas, and the long-form pieces (window
starts, padding, blocks, per-window styles, root alignment, RePaint resampling) against hand-made
cases with known answers. Each value here comes from an independent computation, not from the
code under test."""

import math

import pytest
import torch

from choreo_sgmd.config import DiffusionConfig
from choreo_sgmd.sampling import (Inpainting, _block_constraints, block_ranges, window_starts, window_styles,
                                  windowed)
from choreo_sgmd.schedule import DDIMSampler, DDPMSampler, NoiseSchedule, cosine_alphas_cumprod, make_sampler
from choreo.motion.vector import ROOT_SLICE


def literal_cosine_alpha_bars(T, s=0.008, cap=0.999):
    """Nichol & Dhariwal's f(t) = cos^2(((t/T + s) / (1 + s)) pi/2), betas 1 - f(t+1)/f(t) capped."""
    f = [math.cos(((t / T) + s) / (1 + s) * math.pi / 2) ** 2 for t in range(T + 1)]
    product, out = 1.0, []
    for t in range(T):
        product *= 1 - min(1 - f[t + 1] / f[t], cap)
        out.append(product)
    return out


@pytest.mark.parametrize("T,offset,cap", [(1000, 0.008, 0.999), (50, 0.02, 0.5)])
def test_cosine_schedule_matches_the_closed_form(T, offset, cap):
    got = cosine_alphas_cumprod(T, offset, cap)
    assert got.dtype == torch.float64 and got.shape == (T,)
    torch.testing.assert_close(got, torch.tensor(literal_cosine_alpha_bars(T, offset, cap), dtype=torch.float64),
                               rtol=1e-12, atol=1e-15)
    if cap == 0.5:  # the cap binds at the end of a short schedule: no step removes more than half
        assert float(got[-1] / got[-2]) == pytest.approx(0.5)


def test_schedule_reads_its_config_and_noises_by_the_closed_form():
    config = DiffusionConfig(timesteps=40, cosine_offset=0.02, max_beta=0.5)
    schedule = NoiseSchedule(config)
    assert schedule.timesteps == 40
    torch.testing.assert_close(schedule.alphas_cumprod, torch.tensor(literal_cosine_alpha_bars(40, 0.02, 0.5),
                                                                     dtype=torch.float64))
    x0 = torch.tensor([[1.0, -2.0], [0.5, 3.0]])
    noise = torch.tensor([[0.3, 0.1], [-1.0, 2.0]])
    t = torch.tensor([3, 31])
    out = schedule.q_sample(x0, t, noise)
    for row in range(2):
        a = float(schedule.alphas_cumprod[t[row]])
        torch.testing.assert_close(out[row], math.sqrt(a) * x0[row] + math.sqrt(1 - a) * noise[row])
    torch.testing.assert_close(schedule.alpha_bar(t), schedule.alphas_cumprod[t])


def test_ddim_timesteps_are_the_rounded_even_stride_from_the_last_step():
    sampler = make_sampler("ddim", NoiseSchedule(), 10)
    assert sampler.timesteps.tolist() == [999, 888, 777, 666, 555, 444, 333, 222, 111, 0]
    assert [sampler.previous(t) for t in (999, 555, 111, 0)] == [888, 444, 0, -1]
    assert make_sampler("ddim", NoiseSchedule(), 4).timesteps.tolist() == [999, 666, 333, 0]
    assert make_sampler("ddim", NoiseSchedule(), 1).timesteps.tolist() == [999]
    assert len(make_sampler("ddim", NoiseSchedule(), 1000).timesteps) == 1000
    for bad in (0, 1001):
        with pytest.raises(ValueError, match=r"steps must be in 1\.\.1000, got " + str(bad)):
            make_sampler("ddim", NoiseSchedule(), bad)
    with pytest.raises(ValueError, match="unknown sampler 'euler'"):
        make_sampler("euler", NoiseSchedule(), 10)
    assert make_sampler("ddim", NoiseSchedule(), 10, eta=0.25).eta == 0.25
    assert isinstance(make_sampler("ddpm", NoiseSchedule(), 1000), DDPMSampler)


def literal_ddim_step(x0, t, t_prev, sample, eta, alpha_bars, noise):
    """Song et al. 2021, eq. 12, written out."""
    a, a_prev = alpha_bars[t], alpha_bars[t_prev]
    eps = (sample - math.sqrt(a) * x0) / math.sqrt(1 - a)
    sigma = eta * math.sqrt((1 - a_prev) / (1 - a)) * math.sqrt(1 - a / a_prev)
    return math.sqrt(a_prev) * x0 + math.sqrt(1 - a_prev - sigma**2) * eps + sigma * noise


@pytest.mark.parametrize("eta", [0.0, 0.5, 1.0])
@pytest.mark.parametrize("t", [999, 444, 111])
def test_ddim_step_is_song_et_al_eq_12(eta, t):
    schedule = NoiseSchedule()
    sampler = DDIMSampler(schedule, eta=eta)
    sampler.set_timesteps(10)
    alpha_bars = schedule.alphas_cumprod.tolist()
    x0 = torch.linspace(-1.4, 1.4, 15, dtype=torch.float64).reshape(3, 5)  # partly outside [-1, 1]
    sample = torch.linspace(1.0, -2.0, 15, dtype=torch.float64).reshape(3, 5)
    out = sampler.step(x0, t, sample, generator=torch.Generator().manual_seed(3))
    noise = torch.randn(sample.shape, generator=torch.Generator().manual_seed(3), dtype=torch.float64)
    expected = literal_ddim_step(x0.clamp(-1, 1), t, sampler.previous(t), sample, eta, alpha_bars, noise)
    torch.testing.assert_close(out.prev_sample, expected, rtol=1e-9, atol=1e-9)
    torch.testing.assert_close(out.pred_original_sample, x0.clamp(-1, 1))


def test_ddim_without_clipping_keeps_x0_and_its_last_step_returns_it():
    schedule = NoiseSchedule()
    sampler = DDIMSampler(schedule, eta=0.0, clip_x0=False)
    sampler.set_timesteps(10)
    x0 = torch.tensor([[2.0, -3.0]], dtype=torch.float64)
    sample = torch.tensor([[0.5, 0.5]], dtype=torch.float64)
    out = sampler.step(x0, 444, sample)
    expected = literal_ddim_step(x0, 444, 333, sample, 0.0, schedule.alphas_cumprod.tolist(), torch.zeros_like(x0))
    torch.testing.assert_close(out.prev_sample, expected)
    last = sampler.step(x0, 0, sample)
    torch.testing.assert_close(last.prev_sample, x0)
    torch.testing.assert_close(DDIMSampler(schedule, eta=0.0).step(x0, 0, sample).prev_sample, x0.clamp(-1, 1))


def test_ddim_eta_zero_draws_no_noise_and_eta_one_does():
    schedule = NoiseSchedule()
    x0, sample = torch.zeros(2, 3), torch.ones(2, 3)
    for eta, differs in ((0.0, False), (1.0, True)):
        sampler = make_sampler("ddim", schedule, 10, eta=eta)
        a = sampler.step(x0, 555, sample, torch.Generator().manual_seed(0)).prev_sample
        b = sampler.step(x0, 555, sample, torch.Generator().manual_seed(1)).prev_sample
        assert bool((a - b).abs().max() > 1e-3) == differs


def test_window_starts_hop_half_a_window_until_the_song_is_covered():
    assert window_starts(10, 10) == [0]
    assert window_starts(11, 10) == [0, 5]
    assert window_starts(15, 10) == [0, 5]
    assert window_starts(16, 10) == [0, 5, 10]
    assert window_starts(3, 10) == [0]
    assert window_starts(20, 9) == [0, 4, 8, 12]  # an odd window hops by its floor half


def test_windowed_cuts_and_zero_pads_past_the_end():
    features = torch.arange(1.0, 8.0)[:, None] * torch.tensor([[1.0, -1.0]])  # (7, 2)
    out = windowed(features, [0, 2, 4], 4)
    assert out.shape == (3, 4, 2)
    assert out[0, :, 0].tolist() == [1, 2, 3, 4]
    assert out[1, :, 0].tolist() == [3, 4, 5, 6]
    assert out[2, :, 0].tolist() == [5, 6, 7, 0]
    assert out[2, :, 1].tolist() == [-5, -6, -7, 0]


def test_block_ranges_share_one_window_between_neighbours():
    assert block_ranges(3, 48) == [(0, 3)]
    assert block_ranges(48, 48) == [(0, 48)]
    assert block_ranges(5, 2) == [(0, 2), (1, 3), (2, 4), (3, 5)]
    assert block_ranges(10, 4) == [(0, 4), (3, 7), (6, 10)]
    assert block_ranges(11, 4) == [(0, 4), (3, 7), (6, 10), (9, 11)]


def test_window_styles_average_a_per_frame_schedule_over_each_window():
    one = torch.tensor([[1.0, 2.0]])
    styles, keep = window_styles(one, True, [0, 2, 4], 4, 8)
    assert styles.tolist() == [[1.0, 2.0]] * 3 and keep.tolist() == [True] * 3
    _, keep = window_styles(one, False, [0, 2], 4, 6)
    assert keep.tolist() == [False, False]
    # frames 0-3 style A = (1, 0), frames 4-7 style B = (0, 1); frames 6-7 have no style
    per_frame = torch.tensor([[1.0, 0.0]] * 4 + [[0.0, 1.0]] * 4)
    given = torch.tensor([True] * 6 + [False] * 2)
    styles, keep = window_styles(per_frame, given, [0, 2, 4], 4, 8)
    torch.testing.assert_close(styles, torch.tensor([[1.0, 0.0], [0.5, 0.5], [0.0, 1.0]]))
    assert keep.tolist() == [True, True, True]
    _, keep = window_styles(per_frame, torch.tensor([True] * 4 + [False] * 4), [0, 4], 4, 8)
    assert keep.tolist() == [True, False]  # a window with no styled frame is style-free


def test_align_root_moves_only_the_root_by_the_mean_offset_of_known_frames():
    frames, dim = 6, 151
    x0 = torch.zeros(1, frames, dim)
    x0[..., ROOT_SLICE] = torch.tensor([1.0, 2.0, 3.0])
    x0[0, :, 10] = 7.0
    values, mask = torch.zeros(1, frames, dim), torch.zeros(1, frames, dim, dtype=torch.bool)
    root = list(range(dim))[ROOT_SLICE]
    values[0, 1, root] = torch.tensor([2.0, 2.0, 3.0])  # offsets +1 and +3 on x: mean +2
    values[0, 4, root] = torch.tensor([4.0, 2.0, 3.0])
    mask[0, [1, 4], root[0]] = True
    mask[0, 1, root[2]] = True  # z known and already right: offset 0
    out = Inpainting(values, mask).align_root(x0)
    torch.testing.assert_close(out[0, :, root[0]], torch.full((frames,), 3.0))
    torch.testing.assert_close(out[0, :, root[1]], torch.full((frames,), 2.0))  # y unknown: untouched
    torch.testing.assert_close(out[0, :, root[2]], torch.full((frames,), 3.0))
    torch.testing.assert_close(out[0, :, 10], torch.full((frames,), 7.0))
    assert x0[0, 0, root[0]] == 1.0  # the input is not modified
    no_root = torch.zeros_like(mask)
    no_root[0, :, 10] = True
    assert Inpainting(values, no_root).align_root(x0) is x0


def test_impose_noises_known_values_to_the_next_level_and_ends_exact():
    schedule = NoiseSchedule()
    x = torch.full((1, 4, 2), 5.0)
    values = torch.tensor([[[1.0, -1.0]] * 4])
    mask = torch.tensor([[[True, False]] * 4])
    known = Inpainting(values, mask)
    out = known.impose(x, schedule, 300, torch.Generator().manual_seed(2))
    noise = torch.randn(x.shape, generator=torch.Generator().manual_seed(2))
    a = float(schedule.alphas_cumprod[300])
    torch.testing.assert_close(out[..., 0], (math.sqrt(a) * values + math.sqrt(1 - a) * noise)[..., 0])
    torch.testing.assert_close(out[..., 1], x[..., 1])
    end = known.impose(x, schedule, -1, torch.Generator().manual_seed(2))
    torch.testing.assert_close(end[..., 0], values[..., 0])


def test_resampling_runs_the_step_again_from_the_renoised_result():
    """RePaint: with resample = 2 the denoiser sees x, then the first result noised back to level t."""
    schedule = NoiseSchedule()
    sampler = make_sampler("ddim", schedule, 10, eta=0.0)
    seen = []

    def denoise(sample):
        seen.append(sample.clone())
        return torch.zeros_like(sample)

    values, mask = torch.zeros(1, 3, 2), torch.zeros(1, 3, 2, dtype=torch.bool)
    mask[..., 0] = True
    x = torch.ones(1, 3, 2)
    generator = torch.Generator().manual_seed(4)
    out = Inpainting(values, mask).step(denoise, sampler, schedule, x, 555, generator, resample=2)
    assert len(seen) == 2
    torch.testing.assert_close(seen[0], x)
    # replay by hand: step, impose at 444 (one noise draw), then re-noise to 555 (a second draw)
    g = torch.Generator().manual_seed(4)
    a, a_prev = (float(schedule.alphas_cumprod[t]) for t in (555, 444))
    first = math.sqrt(1 - a_prev) * (x - 0) / math.sqrt(1 - a)  # DDIM eta 0 with x0 = 0
    imposed = torch.where(mask, math.sqrt(1 - a_prev) * torch.randn(x.shape, generator=g), first)
    keep = a / a_prev
    renoised = math.sqrt(keep) * imposed + math.sqrt(1 - keep) * torch.randn(x.shape, generator=g)
    torch.testing.assert_close(seen[1], renoised)
    second = math.sqrt(1 - a_prev) * renoised / math.sqrt(1 - a)
    torch.testing.assert_close(out[..., 1], second[..., 1])
    assert len(Inpainting(values, mask).step(denoise, sampler, schedule, x, 555, generator, resample=1)) == 1
    assert len(seen) == 3  # resample = 1: one evaluation


def test_block_constraints_carry_the_sampled_frames_and_keep_the_users():
    done = torch.arange(20.0)[:, None].repeat(1, 2)
    assert _block_constraints(None, done, 5, 15, 0) is None
    carried = _block_constraints(None, done, 5, 15, 3)
    assert carried.mask[:3].all() and not carried.mask[3:].any()
    assert carried.values[:3, 0].tolist() == [5.0, 6.0, 7.0]
    user = Inpainting(torch.full((20, 2), -1.0), torch.zeros(20, 2, dtype=torch.bool))
    user.mask[12, 1] = True
    both = _block_constraints(user, done, 5, 15, 2)
    assert both.mask.shape == (10, 2) and both.mask[7, 1] and float(both.values[7, 1]) == -1.0
    assert both.values[:2, 0].tolist() == [5.0, 6.0] and both.mask[:2].all()
    assert int(both.mask.sum()) == 5
    assert not user.mask[5:7].any()  # the user's constraints are not modified


def test_sampler_defaults_are_the_cosine_schedule_and_edge_stochastic_ddim():
    """The defaults callers rely on: cosine offset 0.008 and cap 0.999, DDIM with eta = 1 (as EDGE
    samples) over every step until set_timesteps, and each step's clipped x0 reported."""
    defaults = cosine_alphas_cumprod(1000)
    torch.testing.assert_close(defaults, torch.tensor(literal_cosine_alpha_bars(1000), dtype=torch.float64), rtol=1e-12, atol=0)
    assert float(defaults[-1] / defaults[-2]) == pytest.approx(0.001)  # the last beta is the 0.999 cap
    schedule = NoiseSchedule()
    sampler = DDIMSampler(schedule)
    assert sampler.eta == 1.0 and sampler.clip_x0
    assert sampler.timesteps.tolist() == list(range(999, -1, -1))
    assert make_sampler("ddim", schedule, 10).eta == 1.0
    x0 = torch.tensor([[2.0, -0.5]])
    for last in (make_sampler("ddim", schedule, 10).step(x0, 0, torch.zeros(1, 2)),
                 make_sampler("ddpm", schedule, 1000).step(x0, 0, torch.zeros(1, 2))):
        torch.testing.assert_close(last.pred_original_sample, x0.clamp(-1, 1))
    with pytest.raises(ValueError, match="DDPM runs all 1000 steps; use DDIM for fewer"):
        make_sampler("ddpm", schedule, 10)


def counting(calls):
    def denoise(sample):
        calls.append(sample.clone())
        return torch.zeros_like(sample)
    return denoise


def test_resampling_repeats_every_step_but_the_last_and_draws_from_the_callers_generator():
    schedule = NoiseSchedule()
    values, mask = torch.zeros(1, 3, 2), torch.zeros(1, 3, 2, dtype=torch.bool)
    mask[..., 0] = True
    known = Inpainting(values, mask)
    ddim = make_sampler("ddim", schedule, 10)  # eta = 1: the step itself draws noise
    for t, expected_calls in ((111, 3), (0, 1)):  # 111 steps to 0 (still a step); 0 is the end
        calls = []
        known.step(counting(calls), ddim, schedule, torch.ones(1, 3, 2), t, torch.Generator().manual_seed(0), resample=3)
        assert len(calls) == expected_calls, t
    runs = [known.step(counting([]), ddim, schedule, torch.ones(1, 3, 2), 555, torch.Generator().manual_seed(7), resample=2)
            for _ in range(2)]
    torch.testing.assert_close(runs[0], runs[1])  # same generator seed, same result: no global RNG
    # the generator is left exactly where five draws leave it: step, impose, re-noise, step, impose
    generator = torch.Generator().manual_seed(7)
    known.step(counting([]), ddim, schedule, torch.ones(1, 3, 2), 555, generator, resample=2)
    replay = torch.Generator().manual_seed(7)
    for _ in range(5):
        torch.randn((1, 3, 2), generator=replay)
    torch.testing.assert_close(torch.randn(4, generator=generator), torch.randn(4, generator=replay))


def test_impose_at_level_zero_still_noises_and_only_the_end_is_exact():
    schedule = NoiseSchedule()
    values = torch.full((1, 2, 1), 0.5)
    known = Inpainting(values, torch.ones(1, 2, 1, dtype=torch.bool))
    out = known.impose(torch.zeros(1, 2, 1), schedule, 0, torch.Generator().manual_seed(1))
    a = float(schedule.alphas_cumprod[0])
    noise = torch.randn((1, 2, 1), generator=torch.Generator().manual_seed(1))
    torch.testing.assert_close(out, math.sqrt(a) * values + math.sqrt(1 - a) * noise)
    assert not torch.equal(out, values)


def test_window_styles_with_one_styled_frame_and_with_a_plain_bool():
    per_frame = torch.tensor([[float(i), 0.0] for i in range(8)])
    given = torch.tensor([False] * 3 + [True] + [False] * 4)  # only frame 3 has a style
    styles, keep = window_styles(per_frame, given, [0, 4], 4, 8)
    torch.testing.assert_close(styles[0], torch.tensor([3.0, 0.0]))
    assert keep.tolist() == [True, False]
    wide = torch.cat([per_frame, torch.ones(8, 1)], dim=1)  # 3 columns: no accidental broadcasting
    styles, keep = window_styles(wide, True, [0, 4], 4, 8)  # a style everywhere, given as a bool
    torch.testing.assert_close(styles, torch.tensor([[1.5, 0.0, 1.0], [5.5, 0.0, 1.0]]))
    assert keep.tolist() == [True, True]


def test_align_root_on_a_single_known_frame_moves_by_its_whole_offset():
    x0 = torch.zeros(1, 4, 151)
    values, mask = torch.zeros(1, 4, 151), torch.zeros(1, 4, 151, dtype=torch.bool)
    root = list(range(151))[ROOT_SLICE]
    values[0, 2, root[0]] = 0.8
    mask[0, 2, root[0]] = True
    out = Inpainting(values, mask).align_root(x0)
    torch.testing.assert_close(out[0, :, root[0]], torch.full((4,), 0.8))


def test_block_constraints_mask_is_boolean_and_frame_by_channel():
    carried = _block_constraints(None, torch.zeros(20, 3), 5, 15, 2)
    assert carried.mask.dtype == torch.bool and carried.mask.shape == (10, 3) and carried.values.shape == (10, 3)


@pytest.mark.parametrize("field, value, words", [
    ("guidance", math.nan, "guidance must be 0 to 20"), ("guidance", math.inf, "guidance must be 0 to 20"),
    ("guidance", 1e308, "guidance must be 0 to 20"), ("style_guidance", math.nan, "style_guidance must be 0 to 20"),
    ("seed", 2**64, "seed must be"), ("seed", -(2**40), "seed must be"),
])
def test_sampling_options_refuse_what_the_sampler_cannot_use(field, value, words):
    """Issue 48, items 10 and 12: NaN guidance sampled a whole dance of NaN; 1e308 overflowed to it; a
    seed past 64 bits overflowed torch's generator (exit 70)."""
    from choreo_sgmd.options import SamplingOptions

    from choreo.errors import ParameterError
    from choreo.options import parse_options

    with pytest.raises(ParameterError, match=words):
        parse_options("sgmd", SamplingOptions, {field: value})


def test_a_request_seed_is_bounded_for_every_backend():
    from choreo.errors import ParameterError
    from choreo.generator import GenerationRequest

    assert GenerationRequest(music=None, seed=-1).seed == -1  # generate takes -1, and so does graph
    with pytest.raises(ParameterError, match="seed must be"):
        GenerationRequest(music=None, seed=10**30)


@pytest.mark.parametrize("options, timesteps, given, words", [
    ({"sampler": "ddpm", "steps": 50}, 1000, True, "ddpm runs all 1000 steps"),
    ({"steps": 1001}, 1000, True, "steps must be 1 to 1000"),
    ({"steps": 40}, 30, True, "steps must be 1 to 30"),
])
def test_steps_a_chain_cannot_take_are_refused(options, timesteps, given, words):
    """Issue 48, item 8: the sampler found these only after the song was analysed (exit 70)."""
    from choreo_sgmd.options import SamplingOptions

    with pytest.raises(ValueError, match=words):
        SamplingOptions(**options).on_chain(timesteps, given)


def test_ddpm_without_steps_walks_the_whole_chain_and_steps_are_bounded():
    from choreo_sgmd.options import MAX_STEPS, SamplingOptions

    from choreo.errors import ParameterError
    from choreo.options import parse_options

    assert SamplingOptions(sampler="ddpm").on_chain(700, steps_given=False).steps == 700
    assert SamplingOptions(sampler="ddpm", steps=700).on_chain(700).steps == 700
    for steps in (2**63, MAX_STEPS + 1, 0, True):
        with pytest.raises(ParameterError, match="steps must be 1 to 100,000"):
            parse_options("sgmd", SamplingOptions, {"steps": steps})


def test_the_chain_the_cli_checks_steps_on_is_the_bundled_checkpoints():
    """--steps is checked before the bundled checkpoint loads, on SamplingOptions.bundled_timesteps:
    that number must be the bundled checkpoint's own chain."""
    from choreo_sgmd import DEFAULT_CHECKPOINT
    from choreo_sgmd.checkpoint import load_checkpoint
    from choreo_sgmd.options import SamplingOptions

    assert SamplingOptions.bundled_timesteps == load_checkpoint(DEFAULT_CHECKPOINT)["diffusion_config"]["timesteps"]
