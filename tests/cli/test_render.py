"""Previews and plots: files of the right kind and size, audio muxed in, one-line errors."""

import subprocess

import numpy as np
import pytest
from PIL import Image

from choreo.cli import main
from choreo.formats import write_motion
from choreo.motion import Motion
from choreo.render import CameraConfig, FollowCamera

SONG = __import__("pathlib").Path(__file__).resolve().parents[2] / "examples" / "drum_and_bass_174bpm.wav"


def dance(frames=45, fps=30.0):
    rng = np.random.default_rng(0)
    axis_angle = np.cumsum(rng.normal(scale=0.03, size=(frames, 24, 3)), axis=0)
    root = np.cumsum(rng.normal(scale=0.02, size=(frames, 3)), axis=0) + [0, 0.95, 0]
    return Motion.from_axis_angle(root, axis_angle, fps=fps)


def run(capsys, *args):
    code = main(list(map(str, args)))
    return code, capsys.readouterr().err


def test_camera_keeps_the_dancer_in_frame_and_upright():
    motion = dance(60)
    motion.root_positions[:, 0] += np.linspace(0, 6, 60)  # walks 6 m to the side
    camera = FollowCamera(motion.root_positions, 30, 320, 240, CameraConfig())
    positions = motion.joint_positions()
    for frame in (0, 30, 59):
        pixels, depth = camera.project(positions[frame], frame)
        assert (depth > 1).all() and (pixels[:, 0] > 0).all() and (pixels[:, 0] < 320).all()
        head, pelvis = pixels[15], pixels[0]
        assert head[1] < pelvis[1]  # Y up in the world is up on screen


def test_strip_gif_and_video_with_music(tmp_path, capsys):
    write_motion(dance(), tmp_path / "d.bvh")
    code, err = run(capsys, "render", tmp_path / "d.bvh", "-o", tmp_path / "s.png", "--strip", "3", "--size", "100x120")
    assert code == 0, err
    assert Image.open(tmp_path / "s.png").size == (300, 120)
    code, err = run(capsys, "render", tmp_path / "d.bvh", "-o", tmp_path / "a.gif", "--size", "64x64")
    assert code == 0, err
    assert Image.open(tmp_path / "a.gif").n_frames == dance().resample(15).num_frames  # GIF: at most 15 fps
    code, err = run(capsys, "render", tmp_path / "d.bvh", "--music", SONG, "-o", tmp_path / "v.mp4", "--size", "96x64")
    assert code == 0, err
    from choreo.render.video import ffmpeg_executable

    probe = subprocess.run([ffmpeg_executable(), "-i", str(tmp_path / "v.mp4")], capture_output=True, text=True).stderr
    assert "Video: h264" in probe and "96x64" in probe and "Audio: aac" in probe
    assert "Duration: 00:00:01.5" in probe  # -shortest: the 1.5 s dance, not the 11 s song


def test_plots(tmp_path, capsys):
    write_motion(dance(90), tmp_path / "d.npz")
    for plot in ("beats", "path"):
        code, err = run(capsys, "render", tmp_path / "d.npz", "--music", SONG, "--plot", plot, "-o", tmp_path / f"{plot}.png")
        assert code == 0, err
        assert Image.open(tmp_path / f"{plot}.png").size[0] > 400


@pytest.mark.parametrize("extra, message, exit_code", [
    (["-o", "{dir}/x.txt"], "use .mp4", 3), (["--plot", "beats", "-o", "{dir}/x.mp4"], "use .png", 3),
    (["--size", "big", "-o", "{dir}/x.png"], "must look like", 2),
    (["--size", "100000x100000", "-o", "{dir}/x.png"], "--size must be 16 to 7680", 2),  # issue 48: 30 GB asked for
    (["--size", "\uff16\uff14x48", "-o", "{dir}/x.png"], "must look like", 2),
    (["--size", "9" * 5000 + "x2", "-o", "{dir}/x.png"], "must look like", 2),
    (["--fps", "inf", "-o", "{dir}/x.gif"], "--fps takes a finite number", 2),
    (["--strip", "100000", "-o", "{dir}/x.png"], "--strip must be 1 to 64", 2),
    (["--plot", "speed", "-o", "{dir}/x.png"], "unknown plot", 2), (["-o", "{dir}/missing/x.png"], "does not exist", 3),
])  # fmt: skip
def test_bad_render_requests_are_one_line(tmp_path, capsys, extra, message, exit_code):
    write_motion(dance(), tmp_path / "d.bvh")
    code, err = run(capsys, "render", tmp_path / "d.bvh", *[e.format(dir=tmp_path) for e in extra])
    assert code == exit_code and message in err and len(err.strip().splitlines()) == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d.bvh"]


def test_render_config_bounds_frames_before_they_are_allocated():
    """Issue 48, item 10: 100000 x 100000 asked for 30 GB."""
    from choreo.errors import ParameterError
    from choreo.render import RenderConfig

    for sizes in ({"width": 100_000, "height": 100_000}, {"width": 8, "height": 480}, {"strip_frames": 0}):
        with pytest.raises(ParameterError):
            RenderConfig(**sizes)
