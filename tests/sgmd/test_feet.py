"""SGMD's foot terms (contacts from the data, the feet's speeds, the legs' weight) and fine-tuning
from another run's state: the training levers of docs/sgmd.md, "Feet"."""

import numpy as np
import pytest
import torch
from tests.conftest import synthetic_windows

from choreo.motion import Motion, motion_to_vector
from choreo.motion.vector import CONTACT_SLICE, ROOT_SLICE, ROTATION_SLICE
from choreo.skeleton import LOWER_BODY_JOINTS
from choreo_sgmd.config import DiffusionConfig, TrainConfig, model_config
from choreo_sgmd.losses import diffusion_losses, leg_channels
from choreo_sgmd.normalizer import Normalizer
from choreo_sgmd.training import Trainer


def skating_and_standing():
    """(normalised prediction, normalised target, normaliser): the target stands still with both
    feet marked planted; the prediction glides 1 m/s along x and marks no contact."""
    frames = 30
    standing = Motion.from_axis_angle(np.zeros((frames, 3)) + [0, 0.9, 0], np.zeros((frames, 24, 3)))
    gliding = standing.replace(root_positions=standing.root_positions + np.arange(frames)[:, None] / 30 * [1.0, 0, 0])
    target, predicted = (torch.from_numpy(motion_to_vector(m))[None].float() for m in (standing, gliding))
    assert float(target[..., CONTACT_SLICE].min()) == 1 and float(predicted[..., CONTACT_SLICE].max()) == 0
    normalizer = Normalizer.fit(torch.cat([target[0], predicted[0]]))
    return normalizer.normalize(predicted), normalizer.normalize(target), normalizer


def test_target_contacts_pin_feet_the_model_does_not_mark():
    predicted, target, normalizer = skating_and_standing()
    own = diffusion_losses(predicted, target, normalizer, contact_source="predicted")
    data = diffusion_losses(predicted, target, normalizer, contact_source="target")
    assert float(own.foot) == 0.0  # the model marks no contact, so EDGE's term is silent
    assert float(data.foot) == pytest.approx((1 / 30) ** 2, rel=1e-3)  # 1 m/s = 1/30 m per frame, every foot joint
    with pytest.raises(ValueError, match="contact_source"):
        diffusion_losses(predicted, target, normalizer, contact_source="both")


def test_stepping_term_compares_the_feet_speeds_in_metres_per_second():
    predicted, target, normalizer = skating_and_standing()
    assert float(diffusion_losses(target, target, normalizer).stepping) == 0.0
    assert float(diffusion_losses(predicted, target, normalizer).stepping) == pytest.approx(1.0, rel=1e-3)  # (1 m/s)^2
    config = DiffusionConfig(stepping_weight=2.0)
    terms = diffusion_losses(predicted, target, normalizer)
    without = DiffusionConfig()
    assert float(terms.total(config) - terms.total(without)) == pytest.approx(2.0 * float(terms.stepping), rel=1e-5)


def test_root_speed_term_compares_pace_whatever_the_direction():
    predicted, target, normalizer = skating_and_standing()  # the prediction glides 1 m/s, the target stands
    assert float(diffusion_losses(predicted, target, normalizer).root_speed) == pytest.approx(1.0, rel=1e-3)
    backwards_motion = normalizer.denormalize(predicted)
    backwards_motion[..., ROOT_SLICE.start] *= -1  # the root's x: the same glide the other way
    backwards = normalizer.normalize(backwards_motion)
    assert float(diffusion_losses(backwards, predicted, normalizer).root_speed) == pytest.approx(0.0, abs=1e-6)
    assert float(diffusion_losses(backwards, predicted, normalizer).joints) > 0  # which the other terms do see
    terms = diffusion_losses(predicted, target, normalizer)
    added = terms.total(DiffusionConfig(root_speed_weight=3.0)) - terms.total(DiffusionConfig())
    assert float(added) == pytest.approx(3.0 * float(terms.root_speed), rel=1e-5)
    with pytest.raises(ValueError, match="root_speed_weight"):
        DiffusionConfig(root_speed_weight=-1.0)


def test_pace_term_compares_travel_along_the_smoothed_path_not_its_wobble():
    predicted, target, normalizer = skating_and_standing()  # 1 s: the prediction glides 1 m/s, the target stands
    assert float(diffusion_losses(predicted, target, normalizer).pace) == pytest.approx(1.0, rel=1e-2)
    motion = normalizer.denormalize(target).repeat(1, 4, 1)  # 4 s standing still
    wobbling = motion.clone()
    wobbling[..., ROOT_SLICE.start] += 0.05 * torch.sin(torch.arange(120) * 2 * np.pi * 3 / 30)  # 3 Hz, 5 cm
    travelling = motion.clone()
    travelling[..., ROOT_SLICE.start + 2] += torch.arange(120) / 30 * 0.5  # 0.5 m/s along z
    terms = {name: diffusion_losses(normalizer.normalize(m), normalizer.normalize(motion), normalizer)
             for name, m in (("wobbling", wobbling), ("travelling", travelling))}
    assert float(terms["wobbling"].root_speed) > 0.3  # the frame-by-frame speed counts the wobble as travel
    assert float(terms["wobbling"].pace) < 0.01 * float(terms["wobbling"].root_speed)  # the pace does not
    assert float(terms["travelling"].pace) == pytest.approx(0.25, rel=2e-2)  # (0.5 m/s)^2
    skating = diffusion_losses(predicted, target, normalizer)
    added = skating.total(DiffusionConfig(pace_weight=2.0)) - skating.total(DiffusionConfig())
    assert float(added) == pytest.approx(2.0 * float(skating.pace), rel=1e-5)
    with pytest.raises(ValueError, match="pace_weight"):
        DiffusionConfig(pace_weight=-1.0)


def test_leg_weight_scales_only_the_legs_rotation_channels():
    legs = leg_channels(151)
    assert int(legs.sum()) == 6 * (len(LOWER_BODY_JOINTS) - 1)
    assert not legs[:ROTATION_SLICE.start + 6].any()  # contacts, root and the pelvis' own rotation are not legs
    normalizer = Normalizer.fit(torch.randn(100, 151))
    target = torch.zeros(1, 5, 151)
    leg, arm = target.clone(), target.clone()
    leg[..., ROTATION_SLICE.start + 6 * 4] = 0.5  # the left knee
    arm[..., ROTATION_SLICE.start + 6 * 18] = 0.5  # the left elbow
    for moved, factor in ((leg, 3.0), (arm, 1.0)):
        plain = diffusion_losses(moved, target, normalizer).reconstruction
        weighted = diffusion_losses(moved, target, normalizer, leg_weight=3.0).reconstruction
        assert float(weighted) == pytest.approx(factor * float(plain))


def test_legs_term_sees_steps_around_the_pelvis_not_the_travel_or_the_facing():
    from choreo_sgmd.losses import legs_error

    frames = 30
    t = np.arange(frames)[:, None] / 30
    still = np.zeros((frames, 24, 3))
    stepping = still.copy()
    stepping[:, 1, 0] = 0.4 * np.sin(2 * np.pi * t[:, 0])  # the left hip swings the leg forward and back
    root = np.zeros((frames, 3)) + [0, 0.9, 0]

    def vectors(axis_angle, root_positions, yaw=0.0):
        axis_angle = axis_angle.copy()
        axis_angle[:, 0, 1] += yaw
        motion = Motion.from_axis_angle(root_positions, axis_angle)
        return torch.from_numpy(motion_to_vector(motion))[None].float()

    def term(a, b):
        from choreo_sgmd.losses import joint_positions, legs_around_pelvis

        return float(legs_error(legs_around_pelvis(a, joint_positions(a)), legs_around_pelvis(b, joint_positions(b)))[0])

    target = vectors(stepping, root)
    assert term(target, target) == pytest.approx(0.0, abs=1e-9)
    travelling = root + t * [1.0, 0, 0]  # the whole dancer glides 1 m/s: the legs around the pelvis are the same
    assert term(vectors(stepping, travelling, yaw=1.0), target) == pytest.approx(0.0, abs=1e-6)
    assert term(vectors(still, root), target) > 0.05  # a leg that stays put while the data's steps


def test_legs_speed_term_asks_for_the_datas_speed_not_its_timing():
    """A leg swinging at the data's speed but half a cycle late costs the legs term a lot and the
    mean-speed term nothing; a leg standing still costs both (why the speed: docs/sgmd.md, "Legs")."""
    from choreo_sgmd.losses import legs_error, mean_speed

    t = torch.arange(60)[None, :, None, None] / 30.0
    swing = lambda phase: torch.cat([0.3 * torch.sin(2 * torch.pi * t + phase), torch.zeros(1, 60, 1, 2)], -1)  # noqa: E731
    data, late, still = swing(0.0), swing(torch.pi), torch.zeros(1, 60, 1, 3)
    assert float(legs_error(late, data)[0]) > 1.0
    assert float((mean_speed(late) - mean_speed(data))[0]) == pytest.approx(0.0, abs=1e-4)
    assert float(mean_speed(data)[0]) == pytest.approx(4 * 0.3, rel=0.02)  # 4 amplitudes a second
    assert float(mean_speed(still)[0]) < 1e-3


@pytest.mark.parametrize("bad", [{"contact_source": "model"}, {"stepping_weight": -1.0}, {"leg_weight": 0.0},
                                 {"legs_weight": -1.0}, {"legs_speed_weight": -1.0}])
def test_bad_foot_settings_are_refused(bad):
    with pytest.raises(ValueError):
        DiffusionConfig(**bad)


def small_trainer(diffusion=DiffusionConfig(), latent=32, **model):
    config = model_config("tiny", latent_dim=latent, style_dim=8, **model)
    return Trainer(config, diffusion, TrainConfig(batch_size=2, max_steps=10), synthetic_windows(), None)


def test_fine_tuning_may_change_the_dropout_but_not_the_network():
    source = small_trainer()
    source.train_step()
    tuned = small_trainer(dropout=0.0)
    tuned.start_from(source.state(), "base.pt")  # the same weights: dropout has none
    assert tuned.model_config.dropout == 0.0 and tuned.step == 1
    with pytest.raises(Exception, match="latent_dim"):
        small_trainer(latent=16).start_from(source.state(), "base.pt")


def test_fine_tuning_starts_from_the_weights_and_step_under_new_losses():
    source = small_trainer()
    for _ in range(3):
        source.train_step()
    state = source.state()
    tuned = small_trainer(DiffusionConfig(contact_source="target", stepping_weight=0.1))
    tuned.start_from(state, "base.pt")
    assert tuned.step == 3 and tuned.started_from == {"checkpoint": "base.pt", "step": 3}
    for name, value in source.model.state_dict().items():
        torch.testing.assert_close(tuned.model.state_dict()[name], value)
    tuned.train_step()
    assert tuned.step == 4 and tuned.state()["started_from"]["step"] == 3  # kept in its own checkpoints
    resumed = small_trainer(DiffusionConfig(contact_source="target", stepping_weight=0.1))
    resumed.load_state(tuned.state())
    assert resumed.started_from == tuned.started_from


def test_fine_tuning_refuses_another_network():
    state = small_trainer().state()
    with pytest.raises(ValueError, match="cannot start from base.pt: its network differs .*latent_dim 32 -> 64"):
        small_trainer(latent=64).start_from(state, "base.pt")


def test_train_command_refuses_a_missing_init_checkpoint(tmp_path, capsys):
    from choreo.cli import main

    code = main(["train", "sgmd", "--data", str(tmp_path), "--out", str(tmp_path / "out"),
                 "--init-from", str(tmp_path / "missing.pt")])
    assert code == 2 and "--init-from" in capsys.readouterr().err
