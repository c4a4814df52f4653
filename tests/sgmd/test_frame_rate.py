"""A model that dances at 15 fps: music and constraints brought down to its rate, its frames
brought back up to 30 fps, and a whole generation through it."""

import numpy as np
import torch

from choreo.music import BEAT_COLUMN, FEATURE_DIM, PEAK_COLUMN, Music
from choreo.generator import GenerationRequest
from choreo_sgmd.frame_rate import frames_at_full_rate, known_at_model_rate, model_frames, music_at_model_rate


def test_music_keeps_every_beat_at_the_nearest_model_frame():
    music = np.arange(7 * FEATURE_DIM, dtype=np.float32).reshape(7, FEATURE_DIM)
    music[:, [PEAK_COLUMN, BEAT_COLUMN]] = 0
    music[[1, 4], BEAT_COLUMN] = 1  # 30 fps frames 1 and 4 -> model frames 1 (0.5 rounds up) and 2
    music[6, PEAK_COLUMN] = 1  # the last frame -> the last model frame, 3
    pooled = music_at_model_rate(music, 2)
    assert pooled.shape == (4, FEATURE_DIM) == (model_frames(7, 2), FEATURE_DIM)
    assert np.flatnonzero(pooled[:, BEAT_COLUMN]).tolist() == [1, 2]
    assert np.flatnonzero(pooled[:, PEAK_COLUMN]).tolist() == [3]
    np.testing.assert_array_equal(pooled[:, 0], music[::2, 0])  # continuous columns: read at frames 0, 2, 4, 6
    assert music_at_model_rate(music, 1) is music
    stacked = music_at_model_rate(np.stack([music, music]), 2)  # windows stacked: the same per window
    np.testing.assert_array_equal(stacked[1], pooled)


def test_a_key_on_an_odd_frame_still_reaches_the_model():
    values, mask = np.zeros((6, 3)), np.zeros((6, 3), bool)
    values[3, 0], mask[3, 0] = 7.0, True  # frame 3: model frame 1 (frames 2 and 3), nothing at frame 2
    values[2, 1], mask[2, 1] = 5.0, True  # frame 2 beats frame 3 for the same model frame's dimension 1
    values[3, 1], mask[3, 1] = 9.0, True
    model_values, model_mask = known_at_model_rate(values, mask, 2)
    assert model_mask.tolist() == [[False] * 3, [True, True, False], [False] * 3]
    assert model_values[1, 0] == 7.0 and model_values[1, 1] == 5.0


def test_frames_come_back_at_30_fps_by_linear_interpolation():
    vectors = np.array([[0.0], [2.0], [4.0]])
    np.testing.assert_allclose(frames_at_full_rate(vectors, 2, 6)[:, 0], [0, 1, 2, 3, 4, 4])  # the last holds
    np.testing.assert_allclose(frames_at_full_rate(vectors, 1, 2), vectors[:2])


def test_a_15_fps_model_trains_and_dances_a_30_fps_song(tmp_path):
    from choreo_sgmd.config import TrainConfig, model_config
    from choreo_sgmd.generator import SGMDGenerator
    from choreo_sgmd.training import train
    from tests.conftest import synthetic_windows

    config = model_config("tiny", style_dim=14, window_frames=75, frame_stride=2)
    data = synthetic_windows(frames=75)
    data.style = torch.eye(14)[:4]
    checkpoint = train(config, TrainConfig(batch_size=4, max_steps=3, checkpoint_every=3, validation_every=3,
                                           prompt_kind="onehot"), data, None, tmp_path)
    generator = SGMDGenerator(checkpoint)
    t = np.arange(int(7 * 22050)) / 22050
    music = Music.from_array((0.3 * np.sin(2 * np.pi * 220 * t) * (np.sin(2 * np.pi * 2 * t) > 0)).astype(np.float32), 22050)
    motion = generator.generate(GenerationRequest(music, style="waltz", seed=1, options={"steps": 3}))
    assert motion.num_frames == music.num_frames == 210 and motion.fps == 30
    # odd frames are interpolated between their even neighbours (rotations as 6D, then re-orthonormalised)
    root = motion.root_positions
    np.testing.assert_allclose(root[1:-2:2], (root[:-3:2] + root[2:-1:2]) / 2, atol=1e-5)
    # a key pose on an odd frame comes out exactly, and the frames beside it lead into it
    from choreo.constraints import Constraints

    key = motion.slice_frames(0, 1)
    key.root_positions[:] += [0.5, 0.0, 0.0]
    constraints = Constraints.none(210, 30.0).fix_motion(key, at=101)
    keyed = generator.generate(GenerationRequest(music, style="waltz", seed=1, options={"steps": 3}, constraints=constraints))
    np.testing.assert_allclose(keyed.root_positions[101], key.root_positions[0], atol=1e-6)
    assert abs(keyed.root_positions[100, 0] - key.root_positions[0, 0]) < abs(root[100, 0] - key.root_positions[0, 0])
