"""Constraints for controllable generation: masks, user syntax, and SGMD's masked sampling."""

import numpy as np
import torch
import pytest

from choreo.constraints import (Constraints, parse_frame_range, parse_joints, parse_style_schedule, path_to_frames,
                                read_pose, read_root_path)
from choreo.errors import ChoreoError, InputError, ParameterError
from choreo.formats import write_motion
from choreo.motion import Motion
from choreo.motion.vector import ROOT_SLICE, ROTATION_SLICE
from choreo.skeleton import LOWER_BODY_JOINTS, UPPER_BODY_JOINTS


def dance(frames=90, fps=30.0, seed=0):
    rng = np.random.default_rng(seed)
    axis_angle = np.cumsum(rng.normal(scale=0.03, size=(frames, 24, 3)), axis=0)
    root = np.cumsum(rng.normal(scale=0.01, size=(frames, 3)), axis=0) + [0, 0.95, 0]
    return Motion.from_axis_angle(root, axis_angle, fps=fps)


def test_fixed_frames_and_joints_become_a_frame_vector_mask():
    motion = dance(60)
    constraints = Constraints.none(100, 30).fix_motion(motion.slice_frames(0, 10), at=20)
    constraints.fix_motion(motion, at=40, joints=UPPER_BODY_JOINTS, root=False)
    values, mask = constraints.frame_vectors()
    assert mask[20:30].all() and not mask[:20].any() and not mask[30:40].any()
    rotation_mask = mask[:, ROTATION_SLICE].reshape(100, 24, 6)
    assert rotation_mask[40:100][:, UPPER_BODY_JOINTS].all() and not rotation_mask[40:][:, LOWER_BODY_JOINTS].any()
    assert not mask[40:, ROOT_SLICE].any() and not mask[40:, :4].any()  # contacts: only on fully known frames
    np.testing.assert_allclose(values[20:30, ROOT_SLICE], motion.root_positions[:10], atol=1e-6)
    constraints.free(slice(22, 25))
    assert not constraints.frame_vectors()[1][22:25].any()
    assert 0 < constraints.known_fraction() < 1


def test_bad_constraints_are_refused():
    with pytest.raises(ParameterError, match="outside"):
        Constraints.none(50, 30).fix_motion(dance(10), at=45)
    with pytest.raises(ParameterError, match="finite"):
        Constraints.none(3, 30).fix_root_path(np.array([[0, 0], [np.nan, 1], [2, 2]]))
    with pytest.raises(ParameterError, match="outside"):
        parse_frame_range("60:200", 100)
    with pytest.raises(ParameterError):
        parse_frame_range("a:b", 100)
    with pytest.raises(ParameterError, match="unknown joint"):
        parse_joints("l_wing")
    assert parse_joints("upper") == UPPER_BODY_JOINTS and parse_joints("l_wrist, 21") == (20, 21)
    assert parse_frame_range("60:", 100) == slice(60, 100)


def test_other_skeletons_are_refused():
    from choreo.skeleton import Skeleton

    small = Skeleton(("a", "b"), (-1, 0), np.array([[0, 0, 0], [0, 1, 0.0]]))
    motion = Motion(np.zeros((4, 3)), np.tile([1.0, 0, 0, 0], (4, 2, 1)), skeleton=small)
    with pytest.raises(ParameterError, match="SMPL-24"):
        Constraints.none(10, 30).fix_motion(motion)


def test_style_schedule_syntax():
    assert parse_style_schedule("0:30=waltz,30:=cha-cha", 60) == [(0, 30, "waltz"), (30, None, "cha-cha")]
    assert parse_style_schedule("slow, romantic, hips leading", 60) is None
    for bad in ("0:30=waltz,20:=rumba", "0:30=waltz,tango", "70:=waltz", "10:5=waltz"):
        with pytest.raises(ParameterError):
            parse_style_schedule(bad, 60)


@pytest.mark.parametrize("text, message", [
    ("", "empty"), ("x,z\n1,2\n", "at least two"), ("x,z\n1,2\n3,oops\n", "number"),
    ("a,b\n1,2\n3,4\n", "header"), ("1,2,3,4\n5,6,7,8\n", "2 columns"), ("t,x,z\n0,0,0\n0,1,1\n", "increase"),
    ("x,z\n1,2\nnan,3\n", "finite"), ("t,x,z\n-1e308,0,0\n1e308,1,1\n", "not a dance floor"),
])  # fmt: skip
def test_bad_path_files_are_one_clear_error(tmp_path, text, message):
    (tmp_path / "p.csv").write_text(text)
    with pytest.raises(InputError, match=message):
        read_root_path(tmp_path / "p.csv")


def test_paths_from_csv_and_motion_files_stretch_over_the_song(tmp_path):
    (tmp_path / "p.csv").write_text("t,x,z\n0,0,0\n1,1,0\n3,1,2\n")
    times, xz, heights = read_root_path(tmp_path / "p.csv")
    frames, _ = path_to_frames(times, xz, heights, 301)
    assert frames.shape == (301, 2) and np.allclose(frames[0], [0, 0]) and np.allclose(frames[-1], [1, 2])
    assert np.allclose(frames[100], [1, 0])  # t = 1 of 3 -> a third of the way through the song
    (tmp_path / "q.txt").write_text("0,0\n2,0\n")  # no header, no times: evenly spread
    frames, _ = path_to_frames(*read_root_path(tmp_path / "q.txt"), 5)
    assert np.allclose(frames[:, 0], [0, 0.5, 1, 1.5, 2])
    motion = dance(30)
    write_motion(motion, tmp_path / "m.bvh")
    times, xz, heights = read_root_path(tmp_path / "m.bvh")
    assert len(xz) == 30 and np.allclose(heights, motion.root_positions[:, 1], atol=1e-4)


def test_poses_come_from_any_frame_of_a_motion_file(tmp_path):
    motion = dance(20)
    write_motion(motion, tmp_path / "m.npz")
    last = read_pose(f"{tmp_path / 'm.npz'}@-1")
    assert last.num_frames == 1 and np.allclose(last.root_positions[0], motion.root_positions[-1])
    with pytest.raises(ChoreoError):
        read_pose(f"{tmp_path / 'm.npz'}@20")


def song(seconds=12.0, rate=22050):
    from choreo.music import Music

    t = np.arange(int(seconds * rate)) / rate
    return Music.from_array((0.3 * np.sin(2 * np.pi * 220 * t) * (np.sin(2 * np.pi * 2 * t) > 0)).astype(np.float32), rate)


@pytest.mark.parametrize("sampler, steps", [("ddim", 4), ("ddpm", 1000)])
def test_masked_sampling_reproduces_constrained_frames_exactly(tiny_generator, sampler, steps):
    from choreo.generator import GenerationRequest

    music = song(6.0)  # two windows, overlapping on frames 75..150
    given = dance(music.num_frames, seed=3)
    constraints = Constraints.none(music.num_frames, music.fps)
    constraints.fix_motion(given.slice_frames(0, 20))  # seed motion
    constraints.fix_motion(given.slice_frames(100, 160), at=100, joints=LOWER_BODY_JOINTS)  # across a window's end
    out = tiny_generator.generate(GenerationRequest(music, style="waltz", seed=1, constraints=constraints,
                                                    options={"steps": steps, "sampler": sampler}))
    positions, target = out.joint_positions(), given.joint_positions()
    assert np.abs(positions[:20] - target[:20]).max() < 1e-5
    lower = np.array(LOWER_BODY_JOINTS)
    np.testing.assert_allclose(out.rotations[100:160][:, lower], given.rotations[100:160][:, lower], atol=1e-6)
    np.testing.assert_allclose(out.root_positions[100:160], given.root_positions[100:160], atol=1e-6)
    assert np.abs(positions[20:100] - target[20:100]).max() > 0.05  # the rest was generated, not copied


def test_root_path_is_followed_and_style_schedules_work(tiny_generator):
    from choreo.generator import GenerationRequest

    music = song()
    angle = np.linspace(0, np.pi, music.num_frames)
    path = np.stack([np.cos(angle), np.sin(angle)], axis=1)
    constraints = Constraints.none(music.num_frames, music.fps).fix_root_path(path)
    out = tiny_generator.generate(GenerationRequest(music, style="0:6=waltz,6:=tango", seed=0, constraints=constraints,
                                                    options={"steps": 3}))
    assert np.abs(out.root_positions[:, [0, 2]] - path).max() < 1e-6
    assert out.metadata["genre"] == "waltz,tango"


def run_cli(capsys, *args):
    from choreo.cli import main

    code = main(list(map(str, args)))
    return code, capsys.readouterr().err


@pytest.fixture(scope="module")
def song_file(tmp_path_factory):
    import soundfile as sf

    path = tmp_path_factory.mktemp("song") / "song.wav"
    t = np.arange(int(6 * 22050)) / 22050
    sf.write(path, (0.3 * np.sin(2 * np.pi * 220 * t) * (np.sin(2 * np.pi * 2 * t) > 0)).astype(np.float32), 22050)
    return path


def test_controllable_commands_keep_what_they_are_given(tiny_generator, song_file, tmp_path, capsys):
    from choreo.formats import read_motion

    common = ["--checkpoint", tiny_generator.checkpoint, "--steps", "2", "--style", "waltz"]
    given = dance(180, seed=4)
    write_motion(given, tmp_path / "given.bvh")
    write_motion(dance(10, seed=5), tmp_path / "pose.npz")

    code, err = run_cli(capsys, "inpaint", song_file, "--motion", tmp_path / "given.bvh", "--frames", "60:120",
                        "--joints", "upper", "-o", tmp_path / "inpainted.npz", *common)
    assert code == 0, err
    out = read_motion(tmp_path / "inpainted.npz")
    keep = np.ones(180, bool)
    keep[60:120] = False
    assert np.abs(out.joint_positions()[keep] - given.joint_positions()[keep]).max() < 1e-3  # BVH text: 1e-4 m
    lower = np.array(LOWER_BODY_JOINTS)
    assert np.abs(out.joint_positions()[60:120][:, lower] - given.joint_positions()[60:120][:, lower]).max() < 1e-3

    code, err = run_cli(capsys, "inbetween", song_file, "--start", tmp_path / "given.bvh", "--end",
                        f"{tmp_path / 'pose.npz'}@-1", "--key", f"3.0={tmp_path / 'pose.npz'}@2", "-o", tmp_path / "ib.npz",
                        *common)
    assert code == 0, err
    out, pose = read_motion(tmp_path / "ib.npz"), read_motion(tmp_path / "pose.npz")
    assert np.abs(out.joint_positions()[0] - given.joint_positions()[0]).max() < 1e-3
    assert np.abs(out.joint_positions()[90] - pose.joint_positions()[2]).max() < 1e-5
    assert np.abs(out.joint_positions()[-1] - pose.joint_positions()[-1]).max() < 1e-5

    (tmp_path / "path.csv").write_text("x,z\n0,0\n1,0\n1,1\n")
    code, err = run_cli(capsys, "trajectory", song_file, "--path", tmp_path / "path.csv", "-o", tmp_path / "tr.npz", *common)
    assert code == 0, err
    root = read_motion(tmp_path / "tr.npz").root_positions
    assert np.allclose(root[0, [0, 2]], [0, 0], atol=1e-6) and np.allclose(root[-1, [0, 2]], [1, 1], atol=1e-6)

    code, err = run_cli(capsys, "generate", song_file, "--seed-motion", tmp_path / "given.bvh", "-o", tmp_path / "g.npz",
                        *common)
    assert code == 0, err
    assert np.abs(read_motion(tmp_path / "g.npz").joint_positions() - given.joint_positions()).max() < 1e-3


def smooth_dance(seconds=6.0, fps=60.0):
    """A dance slow enough that a resample round trip changes it by well under a centimetre."""
    t = np.arange(round(seconds * fps))[:, None, None] / fps
    axis_angle = 0.3 * np.sin(2 * np.pi * 0.5 * t + np.arange(24)[None, :, None] + np.arange(3)) * np.ones((1, 24, 3))
    root = np.concatenate([0.2 * np.sin(t[:, 0]), 0.95 + 0 * t[:, 0], 0.1 * t[:, 0]], axis=1)
    return Motion.from_axis_angle(root, axis_angle, fps=fps)


def test_frames_count_in_the_given_motion_and_the_dance_keeps_its_rate(tiny_generator, song_file, tmp_path, capsys):
    """Issue 59, item 14: --frames counted at 30 fps whatever the motion's rate, and a 60 fps motion
    came back at 30 fps."""
    from choreo.formats import read_motion

    common = ["--checkpoint", tiny_generator.checkpoint, "--steps", "2"]
    given = smooth_dance(fps=60.0)
    write_motion(given, tmp_path / "given.npz")
    code, err = run_cli(capsys, "inpaint", song_file, "--motion", tmp_path / "given.npz", "--frames", "120:240",
                        "--joints", "upper", "-o", tmp_path / "out.npz", *common)
    assert code == 0, err
    out = read_motion(tmp_path / "out.npz")
    assert out.fps == 60.0 and abs(out.num_frames - given.num_frames) <= 1
    moved = np.abs(out.joint_positions() - given.joint_positions()[: out.num_frames]).max(axis=(1, 2))
    upper = np.abs(out.joint_positions()[:, UPPER_BODY_JOINTS]
                   - given.joint_positions()[: out.num_frames, UPPER_BODY_JOINTS]).max(axis=(1, 2))
    assert moved[:110].max() < 0.01 and moved[250:].max() < 0.01  # kept: 0-2 s and 4-6 s (frames of the 60 fps file)
    assert upper[130:230].max() > 0.05  # danced afresh: 2-4 s
    lower = np.array(LOWER_BODY_JOINTS)
    assert np.abs(out.joint_positions()[:, lower] - given.joint_positions()[: out.num_frames, lower]).max() < 0.01

    code, err = run_cli(capsys, "inpaint", song_file, "--motion", tmp_path / "given.npz", "--frames", "120:240",
                        "-o", tmp_path / "at30.npz", "--fps", "30", *common)
    assert code == 0, err
    assert read_motion(tmp_path / "at30.npz").fps == 30.0  # --fps wins

    code, err = run_cli(capsys, "generate", song_file, "--seed-motion", tmp_path / "given.npz", "-o",
                        tmp_path / "continued.npz", *common)
    assert code == 0, err
    assert read_motion(tmp_path / "continued.npz").fps == 60.0


def test_inpainting_frames_are_the_motions_own():
    from types import SimpleNamespace

    from choreo.constraints.recipes import in_song_frames

    music = SimpleNamespace(fps=30.0, num_frames=300, duration=10.0)
    assert in_song_frames(slice(120, 240), dance(600, fps=60.0), music) == slice(60, 120)
    assert in_song_frames(slice(120, 240), dance(300, fps=30.0), music) == slice(120, 240)
    assert in_song_frames(slice(1, 2), dance(600, fps=240.0), music) == slice(0, 1)  # never empty
    with pytest.raises(ParameterError, match="past the song's end"):
        in_song_frames(slice(400, 500), dance(600, fps=30.0), music)


@pytest.mark.parametrize("command, extra, message", [
    ("inpaint", ["--motion", "{given}", "--frames", "100:900"], "outside"),
    ("inpaint", ["--motion", "{given}", "--joints", "wings"], "unknown joint"),
    ("inbetween", [], "at least one of"),
    ("inbetween", ["--key", "60={given}"], "past the song's end"),
    ("inbetween", ["--key", "1=missing.bvh"], "missing.bvh"),
    ("trajectory", ["--path", "{empty}"], "empty"),
    ("trajectory", ["--path", "{short}"], "at least two points"),
    ("inpaint", ["--motion", "{nan}"], "NaN"),
])  # fmt: skip
def test_bad_constraints_give_one_line_and_no_output(tiny_generator, song_file, tmp_path, capsys, command, extra, message):
    write_motion(dance(30), tmp_path / "given.bvh")
    (tmp_path / "empty.csv").write_text("")
    (tmp_path / "short.csv").write_text("x,z\n1,1\n")
    (tmp_path / "nan.bvh").write_text((tmp_path / "given.bvh").read_text().replace("0.000000", "nan", 3))
    files = {"given": tmp_path / "given.bvh", "empty": tmp_path / "empty.csv", "short": tmp_path / "short.csv",
             "nan": tmp_path / "nan.bvh"}
    extra = [e.format(**files) for e in extra]
    code, err = run_cli(capsys, command, song_file, *extra, "--checkpoint", tiny_generator.checkpoint, "--steps", "1",
                        "-o", tmp_path / "out.bvh")
    assert code == 2 and message in err, err  # bad input
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert not (tmp_path / "out.bvh").exists()


def test_generate_preview_writes_a_video_beside_the_dance(tiny_generator, song_file, tmp_path, capsys):
    code, err = run_cli(capsys, "generate", song_file, "-o", tmp_path / "d.bvh", "--preview", "--checkpoint",
                        tiny_generator.checkpoint, "--steps", "1")
    assert code == 0, err
    assert (tmp_path / "d.mp4").stat().st_size > 10_000 and "d.mp4" in err


from hypothesis import given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402


@settings(max_examples=150, deadline=None)
@given(text=st.one_of(st.text(max_size=300), st.lists(st.lists(st.sampled_from(
    ["0", "1.5", "-2", "nan", "inf", "x", "z", "t", "y", "", " ", "1e308", "abc"]), max_size=5), max_size=8).map(
    lambda rows: "\n".join(",".join(r) for r in rows))))
def test_fuzzed_path_files_only_raise_our_errors(tmp_path_factory, text):
    path = tmp_path_factory.mktemp("fuzz") / "p.csv"
    path.write_text(text)
    try:
        times, xz, heights = read_root_path(path)
    except ChoreoError:
        return
    assert np.isfinite(xz).all() and len(xz) >= 2
    frames, _ = path_to_frames(times, xz, heights, 50)
    assert frames.shape == (50, 2)


def test_root_alignment_moves_the_prediction_rigidly_onto_the_given_root():
    from choreo_sgmd.sampling import Inpainting

    values = torch.zeros(2, 10, 151)
    values[0, :3, 4:7] = torch.tensor([1.0, 0.5, -2.0])  # window 0: root given on 3 frames
    mask = torch.zeros(2, 10, 151, dtype=torch.bool)
    mask[0, :3, 4:7] = True
    prediction = torch.randn(2, 10, 151)
    aligned = Inpainting(values, mask).align_root(prediction)
    shift = aligned[0, :, 4:7] - prediction[0, :, 4:7]
    assert torch.allclose(shift, shift[:1].expand_as(shift))  # rigid: the same offset on every frame
    assert torch.allclose(aligned[0, :3, 4:7].mean(0), values[0, :3, 4:7].mean(0), atol=1e-6)
    assert torch.equal(aligned[1], prediction[1]) and torch.equal(aligned[..., 7:], prediction[..., 7:])


def test_displacement_map_is_exact_at_given_values_and_smooth_around_them():
    from choreo.constraints.displacement import displace_to_constraints

    frames = np.zeros((1, 100, 3))
    values = np.ones((1, 100, 3))
    mask = np.zeros((1, 100, 3), bool)
    mask[0, 50, 0] = True  # one keyframe: a tent of offsets 15 frames wide on each side
    mask[0, ::3, 2] = True  # dense given frames: bridged at full strength
    mask[0, [10, 80], 1] = True  # far apart: each fades out on its own
    moved = displace_to_constraints(frames, values, mask)
    np.testing.assert_array_equal(moved[mask], 1.0)
    assert np.abs(np.diff(moved[0], axis=0)).max() <= 1 / 15 + 1e-9  # no step anywhere
    assert moved[0, 35, 0] == 0 and moved[0, 65, 0] == 0 and moved[0, 45, 1] == 0
    np.testing.assert_array_equal(moved[0, :98, 2], 1.0)


def test_a_huge_path_file_is_refused_before_it_is_read(tmp_path):
    from choreo.constraints import read_root_path
    from choreo.constraints.parse import MAX_PATH_BYTES
    from choreo.errors import InputError

    huge = tmp_path / "huge.csv"
    with open(huge, "wb") as f:  # sparse: no disk used, but far too long to read
        f.truncate(MAX_PATH_BYTES + 1)
    with pytest.raises(InputError, match="is larger than 32 MiB"):
        read_root_path(huge)
