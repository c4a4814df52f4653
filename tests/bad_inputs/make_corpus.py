"""Write the corpus of bad inputs that tests/cli/test_bad_inputs.py feeds to the CLI.

Small, deterministic files, committed; rerun from the repository root to regenerate them:
    python tests/bad_inputs/make_corpus.py
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import soundfile as sf
import torch

HERE = Path(__file__).parent
RATE = 16000


def tone(seconds: float) -> np.ndarray:
    t = np.arange(int(seconds * RATE)) / RATE
    return (0.3 * np.sin(2 * np.pi * 330 * t)).astype(np.float32)


def _deep_pickle(depth: int) -> bytes:
    """A protocol-2 pickle of one float inside ``depth`` nested lists, written opcode by opcode
    (pickle.dumps itself would recurse that deep)."""
    return b"\x80\x02" + b"]" * depth + b"G?\xf0\x00\x00\x00\x00\x00\x00" + b"a" * depth + b"."


THREE_JOINT_BVH = """HIERARCHY
ROOT Hips
{
  OFFSET 0 10 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT Chest
  {
    OFFSET 0 10 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    JOINT Head
    {
      OFFSET 0 10 0
      CHANNELS 3 Zrotation Xrotation Yrotation
      End Site
      {
        OFFSET 0 5 0
      }
    }
  }
}
MOTION
Frames: 3
Frame Time: 0.0333333
""" + "0 90 0 0 0 0 0 0 0 0 0 0\n" * 3


def main() -> None:
    (HERE / "not_audio.mp3").write_text("this is a text file with an mp3 extension\n")
    (HERE / "empty.wav").write_bytes(b"")
    sf.write(HERE / "silence.wav", np.zeros(2 * RATE, np.float32), RATE)
    sf.write(HERE / "short.wav", tone(0.2), RATE)
    sf.write(HERE / "good.mp3", tone(3.0), RATE, format="MP3")
    good = (HERE / "good.mp3").read_bytes()
    (HERE / "truncated.mp3").write_bytes(good[:400])
    rng = np.random.default_rng(0)
    (HERE / "corrupt.mp3").write_bytes(good[:200] + rng.integers(0, 256, 4000, dtype=np.uint8).tobytes())
    (HERE / "good.mp3").unlink()
    (HERE / "song.xyz").write_bytes(b"RIFF....WAVE")
    (HERE / "other_skeleton.bvh").write_text(THREE_JOINT_BVH)
    (HERE / "truncated.bvh").write_text(THREE_JOINT_BVH[: THREE_JOINT_BVH.index("MOTION") - 20])
    # float WAV with a NaN sample (librosa raised its own error on it: an internal error here)
    nan_song = tone(3.0)
    nan_song[1000] = np.nan
    sf.write(HERE / "nan_sample.wav", nan_song, RATE, subtype="FLOAT")
    # a few hundred bytes of shared lists that unfold into 2^40 items, and lists nested 2,000 deep
    import pickle

    shared = [1.0]
    for _ in range(40):
        shared = [shared, shared]
    (HERE / "shared_lists_bomb.pkl").write_bytes(pickle.dumps({"smpl_poses": shared, "smpl_trans": shared}, protocol=2))
    (HERE / "deeply_nested.pkl").write_bytes(_deep_pickle(2000))
    # a frame time whose inverse overflows (an internal error before)
    (HERE / "tiny_frame_time.bvh").write_text(THREE_JOINT_BVH.replace("Frame Time: 0.0333333", "Frame Time: 1e-320"))
    # 80 bytes that made the parser loop forever: a negative channel count
    (HERE / "negative_channels.bvh").write_text(
        "HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\nCHANNELS -3 Xrotation\n}\nMOTION\nFrames: 1\nFrame Time: 0.03\n0\n")
    (HERE / "wrong_shape_path.csv").write_text("1,2,3,4\n5,6,7,8\n")
    (HERE / "corrupt_checkpoint.pt").write_bytes(b"PK\x03\x04 not really a checkpoint")
    torch.save({"generator": "graph", "format_version": 1}, HERE / "graph_checkpoint.pt")


if __name__ == "__main__":
    main()
