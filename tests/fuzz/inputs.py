"""Mutation fuzzing of every input format choreo reads (issue 18): no input may be an internal error.

Valid seed files are made with choreo's own writers, mutated (byte flips, truncation, splices,
number replacement, duplication, and field-level edits of NPZ/pickle/checkpoint/JSON contents and
of a glb's accessors and buffer views) and fed
to the same reader the CLI calls, in-process, inside long-lived forked workers that run under a
memory cap and a per-input time limit. Each input is classified:

  accepted  the reader returned
  refused   a choreo error (exit 2 or 3) with a one-line message: the CLI's clean refusal
  INTERNAL  any other exception: the CLI's exit 70 (also a choreo error with another exit code
            or an empty or multi-line message)
  HANG      over the time limit (the worker is killed and replaced)
  MEMORY    MemoryError or a failed allocation under the cap
  CRASH     the worker died (a signal from C code)
  ROUNDTRIP a motion accepted, written as BVH and NPZ by choreo, and then refused by choreo
  WRONG     accepted what must be refused (a beat file of one beat, of `nan`, `0_5` or fullwidth
            numbers), a cache entry refused instead of recomputed or trusted with the wrong
            contents, or a link planted in the cache written through

A refusal that only came after a failed allocation under the cap (a checkpoint whose deflated
record torch inflated first) is MEMORY, and one longer than 1,000 characters is INTERNAL. The
formats of issue 48: ``trainstate`` (`train --resume` and `--init-from` on the tiny preset),
``features`` and ``m2dfit`` (cache entries, planted as the entry itself, as a link to a file
outside the cache, or with the cache root a file), ``beats`` with a 28 MB file, and a checkpoint
(``sgmd``, ``trainstate``) whose largest record is 1.25 GiB of deflated zeros.

Every non-clean input's bytes go to the findings folder, with a .txt saying what happened.

    nice -n 10 .venv/bin/python -m tests.fuzz.inputs --seconds 600
    nice -n 10 .venv/bin/python -m tests.fuzz.inputs --inputs 100000 --workers 2
    .venv/bin/python -m tests.fuzz.inputs --formats bvh,csv --inputs 2000 --seed 3
"""

from __future__ import annotations

import argparse
import hashlib
import io
import json
import multiprocessing
import multiprocessing.connection
import os
import pickle
import random
import re
import resource
import shutil
import struct
import sys
import tempfile
import time
import traceback
import warnings
import zipfile
import zlib
from contextlib import contextmanager
from collections import Counter, defaultdict
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[2]
EXTENSIONS = {"bvh": ".bvh", "npz": ".npz", "npy": ".npy", "pkl": ".pkl", "glb": ".glb", "json": ".json",
              "wav": ".wav", "csv": ".csv", "beats": ".csv", "m2d": ".json", "m2dcfg": ".json", "sgmd": ".pt",
              "repertoire": ".npz", "trainstate": ".pt", "features": ".npz", "m2dfit": ".npz"}  # fmt: skip
FORMATS = tuple(EXTENSIONS)
ZIP_FORMATS = {"npz", "sgmd", "repertoire", "trainstate", "features", "m2dfit"}
CACHE_FORMATS = {"features", "m2dfit"}  # cache entries: never refused, a bad one is recomputed
CLEAN = ("accepted", "refused")
CLASSES = ("accepted", "refused", "INTERNAL", "HANG", "MEMORY", "CRASH", "ROUNDTRIP", "WRONG")
LONGEST_REFUSAL = 1000  # characters: a refusal that echoes a whole cell or file is not one line to read
DEFAULT_FINDINGS = Path(tempfile.gettempdir()) / "choreo-fuzz-findings"


# -- seeds -------------------------------------------------------------------------------------
def _small_motion(frames: int = 6, seed: int = 0):
    from choreo.motion import Motion

    rng = np.random.default_rng(seed)
    root = np.zeros((frames, 3)) + [0.0, 0.9, 0.0] + rng.normal(scale=0.05, size=(frames, 3))
    return Motion.from_axis_angle(root, rng.normal(scale=0.2, size=(frames, 24, 3)), fps=30.0)


def _write(motion, writer, **kwargs) -> bytes:
    buffer = io.BytesIO()
    writer(motion, buffer, **kwargs)
    return buffer.getvalue()


def motion_seeds() -> dict[str, list[bytes]]:
    """BVH, NPZ, NPY, AIST++ pkl and glTF seeds from choreo's own writers (pickles in several protocols;
    BVH and glb also under a root bone, the BVH also on Mixamo's rig)."""
    from choreo.formats.aistpp import write_aistpp_pkl
    from choreo.formats.bvh import write_bvh
    from choreo.formats.gltf import write_glb
    from choreo.formats.json_format import write_json
    from choreo.formats.npy import write_npy
    from choreo.formats.npz import write_npz
    from choreo.formats.rigs import write_bvh_rig
    from choreo.formats.smpl_params import motion_to_smpl_params

    motion = _small_motion()
    params = {k: v.astype(np.float64) for k, v in motion_to_smpl_params(motion, 95.0).items()}
    params["smpl_loss"] = 0.0
    pickles = [pickle.dumps(params, protocol=p) for p in (0, 2, 5)]
    return {"bvh": [_write(motion, write_bvh), _write(_small_motion(3, 1), write_bvh, units="cm"),
                    _write(motion, write_bvh, root_motion=True), _write(motion, write_bvh_rig, root_motion=True)],
            "npz": [_write(motion, write_npz)], "npy": [_write(motion, write_npy)],
            "pkl": [_write(motion, write_aistpp_pkl)] + pickles,
            "glb": [_write(_small_motion(3, 2), write_glb), _write(_small_motion(3, 2), write_glb, root_motion=True)],
            "json": [_write(_small_motion(3, 3), write_json)]}


def wav_seeds() -> list[bytes]:
    """Short WAVs (just over choreo's 0.5 s minimum) in the sample types soundfile writes most."""
    import soundfile as sf

    seeds = []
    for rate, channels, subtype in ((16000, 1, "PCM_16"), (22050, 2, "FLOAT"), (8000, 1, "PCM_U8")):
        t = np.arange(int(0.6 * rate)) / rate
        tone = 0.3 * np.sin(2 * np.pi * 330 * t) * (1 + (t * 8 % 1 < 0.1))
        buffer = io.BytesIO()
        sf.write(buffer, np.repeat(tone[:, None], channels, axis=1), rate, subtype=subtype, format="WAV")
        seeds.append(buffer.getvalue())
    return seeds


def csv_seeds() -> list[bytes]:
    return [b"t,x,z\n0,0,0\n0.5,1,0.2\n1.0,1.5,-0.5\n2,0,0\n", b"0,0\n1,0.5\n2,2\n",
            b"time,x,y,z\n0,0,0.9,0\n1,1,0.95,1\n2,2,0.9,0\n", b"0,0,0\n1,1,1\n"]


def beats_seeds() -> list[bytes]:
    """The layouts `choreo generate --beats` reads: one time a line, CSV with a downbeat flag or a beat number."""
    return [b"0.5\n1.0\n1.5\n2.0\n", b"beat_time,downbeat\n0.5,1\n1.0,0\n1.5,0\n2.0,0\n2.5,1\n",
            b"time\tbeat\n0.48\t1\n0.98\t2\n1.5\t3\n2.0\t4\n", b"time;flag\n0.5;true\n1.1;false\n1.6;no\n"]


M2D_FRAMES = 12  # read_recording wants at least 10


def m2d_skeletons_seed() -> bytes:
    """An M2D skeletons.json: 23 scattered markers (cm) about a centre 90 cm up, as the dataset lays it out."""
    rng = np.random.default_rng(0)
    markers = np.round(rng.normal(scale=30.0, size=(M2D_FRAMES, 23, 3)), 2).tolist()
    return json.dumps({"length": M2D_FRAMES, "center": [[0.0, 90.0, 0.0]] * M2D_FRAMES,
                       "skeletons": markers}).encode()


def m2d_config_seeds() -> list[bytes]:
    return [json.dumps({"start_position": 0, "end_position": M2D_FRAMES}).encode(),
            b'{"start_position": 250, "end_position": 1210, "music": "x.mp3"}']


def sgmd_seed(checkpoint: str | os.PathLike | None = None) -> bytes:
    """A tiny inference checkpoint: from ``checkpoint`` if given, else one training step of the
    tiny preset on synthetic windows (a few seconds); never the 23 MB training state."""
    from choreo_sgmd import export_for_inference

    with tempfile.TemporaryDirectory() as folder:
        if checkpoint is None:
            checkpoint = _train_tiny(Path(folder))
        out = Path(folder) / "seed.pt"
        export_for_inference(checkpoint, out)
        return out.read_bytes()


def _train_tiny(folder: Path) -> Path:
    from choreo_sgmd import train

    model, config, data = _tiny_training()
    return train(model, config, data, None, folder / "tiny")


def _tiny_training():
    """(model config, train config, windows) of one step of the tiny preset on synthetic windows."""
    import torch
    from choreo.music import FEATURE_DIM
    from choreo_sgmd import TrainConfig, WindowTensors, model_config

    t = torch.arange(150) / 30.0
    motion = torch.zeros(4, 150, 151)
    motion[..., 4:7] = torch.stack([torch.sin(t), 0.9 + 0.05 * torch.sin(4 * t), torch.cos(t)], -1)
    motion[..., 7:] = torch.tensor([1.0, 0, 0, 0, 1, 0]).repeat(24) + 0.1 * torch.sin(3 * t)[:, None]
    g = torch.Generator().manual_seed(0)
    data = WindowTensors(motion, torch.randn(4, 150, FEATURE_DIM, generator=g), torch.eye(14)[:4],  # the 35-d default
                         torch.ones(4, dtype=torch.bool))
    config = TrainConfig(batch_size=4, max_steps=1, validation_every=1, checkpoint_every=1, prompt_kind="onehot")
    return model_config("tiny", style_dim=14), config, data


def trainstate_seed() -> bytes:
    """A tiny training state, what `train --resume` (OUT/last.pt) and `--init-from` read."""
    with tempfile.TemporaryDirectory() as folder:
        return _train_tiny(Path(folder)).read_bytes()


@contextmanager
def cache_at(folder: Path):
    """choreo's cache (CHOREO_CACHE_DIR) in ``folder`` while the block runs."""
    before = os.environ.get("CHOREO_CACHE_DIR")
    os.environ["CHOREO_CACHE_DIR"] = str(folder)
    try:
        yield folder
    finally:
        if before is None:
            os.environ.pop("CHOREO_CACHE_DIR", None)
        else:
            os.environ["CHOREO_CACHE_DIR"] = before


def features_seed() -> bytes:
    """A feature-cache entry (``features/<key>.npz``) as `prepare` and `train` write it, of the first WAV seed."""
    from choreo.datasets.cache import cached_music

    with tempfile.TemporaryDirectory() as folder:
        song = Path(folder) / "song.wav"
        song.write_bytes(wav_seeds()[0])
        with cache_at(Path(folder) / "cache") as cache:
            cached_music(song)
        return next((cache / "features").glob("*.npz")).read_bytes()


def m2d_folder(folder: Path) -> Path:
    """An M2D clip folder of the seed skeletons.json and config.json."""
    clip = folder / "DANCE_C_1"
    clip.mkdir(exist_ok=True)
    (clip / "skeletons.json").write_bytes(m2d_skeletons_seed())
    (clip / "config.json").write_bytes(m2d_config_seeds()[0])
    return clip


def m2dfit_seed() -> bytes:
    """An M2D fit cache entry (``m2d/<clip>_<hash>.npz``) of the seed clip, as `prepare` writes it."""
    from choreo.datasets.m2d import load_fit, read_recording

    with tempfile.TemporaryDirectory() as folder:
        clip = m2d_folder(Path(folder))
        with cache_at(Path(folder) / "cache") as cache:
            load_fit(clip, read_recording(clip))
        return next((cache / "m2d").glob("*.npz")).read_bytes()


def repertoire_seed() -> bytes:
    """A two-clip ChoreoGraph repertoire written by Repertoire.save (smooth values: it compresses)."""
    from choreo.skeleton import SMPL24
    from choreo_graph import CLIP_FRAMES, Repertoire

    n, frames = 2, CLIP_FRAMES
    rotations = np.zeros((n, frames, 24, 4), np.float32)
    rotations[..., 0] = 1.0
    root = np.zeros((n, frames, 3), np.float32) + [0.0, 0.9, 0.0]
    root[..., 0] = np.linspace(0, 1, frames)
    repertoire = Repertoire(
        names=np.array(["song@0", "song@120"]), genres=np.array(["waltz", ""]), root_positions=root,
        rotations=rotations, offsets=SMPL24.offsets.astype(np.float32),
        poses=np.zeros((n, frames, 24, 3), np.float16), style=np.ones((n, 32), np.float32),
        beat_counts=np.array([4.0, 5.0], np.float32), tempo=np.ones((n, frames), np.float32), source=np.array("fuzz"))
    with tempfile.TemporaryDirectory() as folder:
        repertoire.save(Path(folder) / "r.npz")
        return (Path(folder) / "r.npz").read_bytes()


def make_seeds(formats=FORMATS, sgmd_checkpoint=None) -> dict[str, list[bytes]]:
    """Valid seed files for each requested format, made by choreo's own writers."""
    seeds = motion_seeds()
    seeds.update(wav=wav_seeds(), csv=csv_seeds(), beats=beats_seeds(), m2d=[m2d_skeletons_seed()],
                 m2dcfg=m2d_config_seeds())
    if "sgmd" in formats:
        seeds["sgmd"] = [sgmd_seed(sgmd_checkpoint)]
    if "repertoire" in formats:
        seeds["repertoire"] = [repertoire_seed()]
    if "trainstate" in formats:
        seeds["trainstate"] = [trainstate_seed()]
    if "features" in formats:
        seeds["features"] = [features_seed()]
    if "m2dfit" in formats:
        seeds["m2dfit"] = [m2dfit_seed()]
    return {name: seeds[name] for name in formats}


# -- byte-level mutations ----------------------------------------------------------------------
NUMBER = re.compile(rb"-?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?")
TEXT_NUMBERS = [b"0", b"-1", b"-3", b"1", b"7", b"255", b"65536", b"2147483648", b"99999999999999999999",
                b"1e308", b"1e-320", b"1e-9", b"-1e308", b"nan", b"inf", b"-inf", b"", b"0.0", b"1e5", b"3e9",
                b"0_5", "\uff11\uff12".encode(), b"9" * 5000, b"9223372036854775808", b"NaN", b"Infinity"]
BINARY_INTS = [0, 1, 2, 0x7F, 0x80, 0xFF, 0x7FFF, 0xFFFF, 0x7FFFFFFF, 0x80000000, 0xFFFFFFFF, 1 << 40,
               (1 << 63) - 1, (1 << 64) - 1]
BINARY_FLOATS = [float("nan"), float("inf"), -float("inf"), 1e308, -1e308, 5e-324, 0.0, -0.0, 1e20]


def _position(rng: random.Random, size: int) -> int:
    """Half the time near the start, where the headers are."""
    if size <= 1:
        return 0
    if rng.random() < 0.5:
        return min(size - 1, int(rng.expovariate(1 / 64)))
    return rng.randrange(size)


def _chunk(rng: random.Random, data: bytes) -> tuple[int, int]:
    start = _position(rng, len(data))
    return start, min(len(data), start + rng.choice((1, 2, 4, 8, 16, 64, 256, 4096)))


def flip_bits(rng, data, others):
    data = bytearray(data)
    for _ in range(rng.randint(1, 8)):
        if data:
            data[_position(rng, len(data))] ^= 1 << rng.randrange(8)
    return bytes(data)


def set_bytes(rng, data, others):
    data = bytearray(data)
    for _ in range(rng.randint(1, 4)):
        if data:
            data[_position(rng, len(data))] = rng.choice((0, 0xFF, 0x7F, 0x80, 0x20, 0x0A, 0x2D))
    return bytes(data)


def truncate(rng, data, others):
    return data[:_position(rng, len(data) + 1)] if rng.random() < 0.5 else data[:rng.randrange(len(data) + 1)]


def delete_chunk(rng, data, others):
    start, stop = _chunk(rng, data)
    return data[:start] + data[stop:]


def duplicate_chunk(rng, data, others):
    start, stop = _chunk(rng, data)
    times = rng.choice((1, 2, 16, 256))
    return data[:stop] + data[start:stop] * times + data[stop:]


def splice(rng, data, others):
    """A piece of another seed of the same format (or of this one) put in at a random place."""
    donor = rng.choice(others) if others else data
    start, stop = _chunk(rng, donor)
    at = rng.randrange(len(data) + 1)
    cut = at + rng.choice((0, stop - start))
    return data[:at] + donor[start:stop] + data[cut:]


def replace_text_number(rng, data, others):
    """One ASCII number (BVH counts, CSV values, an .npy header's shape) replaced by an odd one."""
    matches = list(NUMBER.finditer(data[:1 << 16]))
    if not matches:
        return flip_bits(rng, data, others)
    match = rng.choice(matches)
    return data[:match.start()] + rng.choice(TEXT_NUMBERS) + data[match.end():]


def replace_binary_number(rng, data, others):
    """A little- or big-endian integer or float64 written over the bytes at some offset."""
    if rng.random() < 0.6:
        width = rng.choice((1, 2, 4, 8))
        value = rng.choice(BINARY_INTS) % (1 << (8 * width))
        raw = value.to_bytes(width, rng.choice(("little", "big")))
    else:
        with np.errstate(over="ignore"):
            raw = np.array(rng.choice(BINARY_FLOATS), rng.choice(("<f8", "<f4"))).tobytes()
    at = _position(rng, len(data))
    return data[:at] + raw + data[at + len(raw):]


BYTE_MUTATIONS = (flip_bits, set_bytes, truncate, delete_chunk, duplicate_chunk, splice, replace_text_number,
                  replace_binary_number)


def mutate_bytes(rng: random.Random, data: bytes, others: list[bytes]) -> bytes:
    for _ in range(rng.choice((1, 1, 1, 2, 3))):
        data = rng.choice(BYTE_MUTATIONS)(rng, data, others)
    return data


# -- structure-aware mutations -----------------------------------------------------------------
def mutate_zip_member(rng: random.Random, data: bytes, others: list[bytes]) -> bytes:
    """Byte mutations of one member, the zip rewritten with good CRCs (or a member added/dropped),
    so the mutation reaches the array or pickle reader instead of the CRC check."""
    with zipfile.ZipFile(io.BytesIO(data)) as archive:
        members = [(info, archive.read(info)) for info in archive.infolist()]
    index = rng.randrange(len(members))
    choice = rng.random()
    if choice < 0.08:
        members.pop(index)
    elif choice < 0.14:
        info, content = members[index]
        members.append((zipfile.ZipInfo(info.filename.replace(".npy", "") + "_x.npy"), content))
    else:
        info, content = members[index]
        members[index] = (info, mutate_bytes(rng, content, [c for _, c in members]))
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w") as archive:
        for info, content in members:
            archive.writestr(info, content)
    return out.getvalue()


def odd_array(rng: random.Random, array: np.ndarray) -> object:
    """A value of the wrong kind, shape or range in place of ``array``."""
    array = np.asarray(array)
    kind = rng.randrange(12)
    if kind == 0:
        return array.astype(str) if array.size < 5000 else np.array("text")
    if kind == 1:
        return array[:0]
    if kind == 2:
        return array.reshape(-1)
    if kind == 3:
        return array[..., None] if array.ndim < 6 else array
    if kind == 4:
        return array.T
    if kind == 5:
        return np.array(rng.choice(BINARY_FLOATS))
    if kind == 6:
        return np.array([], np.float64)
    if kind == 7:
        bad = array.astype(np.float64) if array.dtype.kind in "fiub" else np.zeros(3)
        bad.reshape(-1)[rng.randrange(max(1, bad.size))] = rng.choice(BINARY_FLOATS) if bad.size else 0
        return bad
    if kind == 8:
        return array.astype(rng.choice((np.int8, np.uint8, np.bool_, np.complex64, np.float16)))\
            if array.dtype.kind in "fiub" else np.zeros(2)
    if kind == 9:
        return np.concatenate([array, array]) if array.ndim else np.array([array, array])
    if kind == 10:
        return array[:1] if array.ndim else np.array([[1.0]])
    return np.array(None, dtype=object)


def mutate_npz_fields(rng: random.Random, data: bytes, others: list[bytes]) -> bytes:
    """An NPZ with one array dropped, replaced by an odd one, or swapped with another's."""
    with np.load(io.BytesIO(data), allow_pickle=False) as archive:
        arrays = {key: archive[key] for key in archive.files}
    compressed = any(i.compress_type != zipfile.ZIP_STORED for i in zipfile.ZipFile(io.BytesIO(data)).infolist())
    for _ in range(rng.choice((1, 1, 2))):
        key = rng.choice(sorted(arrays))
        if rng.random() < 0.15:
            del arrays[key]
        elif rng.random() < 0.15 and len(arrays) > 1:
            arrays[key] = arrays[rng.choice(sorted(arrays))]
        else:
            arrays[key] = odd_array(rng, arrays[key])
        if not arrays:
            break
    out = io.BytesIO()
    (np.savez_compressed if compressed else np.savez)(out, **arrays)
    return out.getvalue()


def odd_value(rng: random.Random, value: object) -> object:
    """A replacement for one leaf of a pickled dict or checkpoint: odd numbers, types, shapes."""
    import torch

    if isinstance(value, bool) or rng.random() < 0.1:
        return rng.choice((None, "text", [], {}, -1, 0, 1.5, [1, 2], float("nan")))
    if isinstance(value, int):
        return rng.choice((0, -1, -5, 1 << 16, 1 << 20, 1 << 31, (1 << 63) - 1, value + 1, value * 2, 3))
    if isinstance(value, float):
        return rng.choice(BINARY_FLOATS + [-1.0, 0.5, 1e6])
    if isinstance(value, str):
        return rng.choice(("", "other", value * 2, "\x00", "nan"))
    if isinstance(value, torch.Tensor):
        odd = odd_array(rng, value.detach().numpy())
        return torch.from_numpy(np.ascontiguousarray(odd)) if isinstance(odd, np.ndarray) and odd.dtype.kind in "fiub"\
            else rng.choice((torch.zeros(0), torch.zeros(3), "text"))
    if isinstance(value, np.ndarray):
        return odd_array(rng, value)
    if isinstance(value, (list, tuple)):
        return rng.choice(([], list(value)[:1], list(value) * 2, list(value)[::-1], None))
    return None


def _leaves(value, path=()):
    """(path, value) of every dict/list entry, containers included."""
    items = value.items() if isinstance(value, dict) else enumerate(value) if isinstance(value, list) else ()
    for key, item in items:
        yield path + (key,), item
        yield from _leaves(item, path + (key,))


def mutate_tree(rng: random.Random, tree: dict, odd=odd_value, shallow: float = 0.0) -> dict:
    """Drop or replace (by ``odd``) one or two entries anywhere in a nested dict of values; with
    probability ``shallow`` among the top two levels only (names, counts, flags rather than array cells)."""
    for _ in range(rng.choice((1, 1, 2))):
        leaves = list(_leaves(tree))
        top = [leaf for leaf in leaves if len(leaf[0]) <= 2]
        if not leaves:
            break
        path, value = rng.choice(top if top and rng.random() < shallow else leaves)
        parent = tree
        for key in path[:-1]:
            parent = parent[key]
        if isinstance(parent, dict) and rng.random() < 0.2:
            del parent[path[-1]]
        else:
            parent[path[-1]] = odd(rng, value)
    return tree


def mutate_pickle_fields(rng: random.Random, data: bytes, others: list[bytes]) -> bytes:
    """The seed's dict with an entry dropped or replaced, pickled again in a random protocol."""
    tree = pickle.loads(data)  # our own seed, never a mutated input
    tree = {key: (value.tolist() if isinstance(value, np.ndarray) and rng.random() < 0.1 else value)
            for key, value in tree.items()}
    return pickle.dumps(mutate_tree(rng, tree), protocol=rng.choice((0, 2, 4, 5)))


def mutate_checkpoint_fields(rng: random.Random, data: bytes, others: list[bytes]) -> bytes:
    """The checkpoint with a config number, a weight or a statistic dropped or replaced, saved again."""
    import torch

    state = torch.load(io.BytesIO(data), weights_only=True)
    out = io.BytesIO()
    torch.save(mutate_tree(rng, state), out)
    return out.getvalue()


DEEP = "\x00deep\x00"  # stands for nesting too deep to build as Python objects; spliced in as text
HOSTILE_STRINGS = ("", "\x00", "a\nb", "<script>alert(1)</script>", "../../etc/passwd", "pelvis", "x" * 100_000,
                   "\u202eevil", "%s%n{}", "\ud800", "é" * 50)


def odd_json_value(rng: random.Random, value: object) -> object:
    """A hostile JSON value: a joint-name-style string, deep nesting, or an odd number, type or shape."""
    choice = rng.random()
    if choice < 0.25:
        return rng.choice(HOSTILE_STRINGS)
    if choice < 0.4:
        return DEEP
    if choice < 0.5:
        return rng.choice(([value] * 3, {"a": value}, 10**30, -(10**30), 1e308))
    odd = odd_value(rng, value)
    return odd.tolist() if isinstance(odd, np.ndarray) and odd.dtype.kind in "fiub" else \
        None if isinstance(odd, np.ndarray) else odd


def dump_json(rng: random.Random, tree: object) -> bytes:
    """JSON text of ``tree``, each DEEP placeholder replaced by arrays nested 10 to 100,000 deep."""
    text = json.dumps(tree, ensure_ascii=rng.random() < 0.5)
    while json.dumps(DEEP) in text:
        depth = rng.choice((10, 33, 1000, 100_000))
        text = text.replace(json.dumps(DEEP), "[" * depth + "1" + "]" * depth, 1)
    return text.encode("utf-8", "surrogatepass")


def mutate_json_fields(rng: random.Random, data: bytes, others: list[bytes]) -> bytes:
    """A JSON seed with entries dropped or replaced by hostile values (joint names, counts, nesting)."""
    return dump_json(rng, mutate_tree(rng, json.loads(data), odd_json_value, shallow=0.5))


GLB_MAGIC, GLB_JSON, GLB_BIN = b"glTF", 0x4E4F534A, 0x004E4942
GLB_FIELDS = ("count", "byteOffset", "byteLength", "byteStride", "componentType", "type", "bufferView", "buffer",
              "input", "output", "sampler", "node")
GLB_NUMBERS = (0, 1, 3, -1, 4, 7, 5126, 5121, 5123, 1 << 31, 1 << 62, 10**30, 2.5, 1e308, "4", None, "VEC4", "SCALAR",
               "MAT4", [1])


def glb_parts(data: bytes) -> tuple[dict, bytes]:
    """The JSON document and BIN chunk of a glb written by choreo (a seed, never a mutated input)."""
    json_length = struct.unpack_from("<I", data, 12)[0]
    document = json.loads(data[20:20 + json_length])
    return document, data[28 + json_length:]


def pack_glb(text: bytes, blob: bytes) -> bytes:
    """A glb with consistent chunk lengths, so a forged field reaches the accessor reader."""
    text += b" " * (-len(text) % 4)
    blob += b"\0" * (-len(blob) % 4)
    chunks = struct.pack("<II", len(text), GLB_JSON) + text + struct.pack("<II", len(blob), GLB_BIN) + blob
    return GLB_MAGIC + struct.pack("<II", 2, 12 + len(chunks)) + chunks


def forge_glb_entry(rng: random.Random, document: dict) -> None:
    """One accessor, buffer view or animation channel/sampler given a forged count, offset, stride,
    type or index, or an accessor made sparse."""
    lists = [key for key in ("accessors", "bufferViews", "buffers") if document.get(key)]
    entry = rng.choice(document[rng.choice(lists)])
    if "componentType" in entry and rng.random() < 0.2:
        count = rng.choice((1, 2, entry.get("count", 1), 1 << 31))
        entry["sparse"] = {"count": count, "indices": {"bufferView": 0, "componentType": 5125},
                           "values": {"bufferView": rng.choice((0, 1, 99))}}
        return
    entry[rng.choice([key for key in GLB_FIELDS if key in entry] or list(GLB_FIELDS))] = rng.choice(GLB_NUMBERS)


def mutate_glb_fields(rng: random.Random, data: bytes, others: list[bytes]) -> bytes:
    """The seed's glb with forged accessor/buffer-view fields (or any JSON entry made hostile), repacked."""
    document, blob = glb_parts(data)
    for _ in range(rng.choice((1, 1, 2))):
        if rng.random() < 0.7:
            forge_glb_entry(rng, document)
        else:
            mutate_tree(rng, document, odd_json_value, shallow=0.5)
    return pack_glb(dump_json(rng, document), blob)


BOMB_BYTES = 5 << 28  # 1.25 GiB of zeros, deflated to about 1.2 MB: past the workers' 1 GiB cap
_BOMB: list[tuple[bytes, int]] = []


def _deflated_zeros() -> tuple[bytes, int]:
    """(raw deflate stream, CRC-32) of BOMB_BYTES zero bytes, made once, 16 MiB at a time."""
    if not _BOMB:
        packer, chunk, crc, parts = zlib.compressobj(9, zlib.DEFLATED, -15), bytes(1 << 24), 0, []
        for _ in range(BOMB_BYTES >> 24):
            parts.append(packer.compress(chunk))
            crc = zlib.crc32(chunk, crc)
        _BOMB.append((b"".join(parts) + packer.flush(), crc))
    return _BOMB[0]


def pack_zip(members: list[tuple[str, bytes, int, int, int]]) -> bytes:
    """A zip of (name, bytes as stored, method, CRC-32, size unpacked) records, written by hand:
    zipfile cannot take bytes already deflated."""
    out, central = bytearray(), bytearray()
    for name, data, method, crc, size in members:
        raw = name.encode()
        central += struct.pack("<4s6H3L5H2L", b"PK\1\2", 20, 20, 0, method, 0, 0x21, crc, len(data), size, len(raw),
                               0, 0, 0, 0, 0, len(out)) + raw
        out += struct.pack("<4s5H3L2H", b"PK\3\4", 20, 0, method, 0, 0x21, crc, len(data), size, len(raw), 0) + raw
        out += data
    end = struct.pack("<4s4H2LH", b"PK\5\6", 0, 0, len(members), len(members), len(central), len(out), 0)
    return bytes(out + central + end)


def checkpoint_bomb(rng: random.Random, data: bytes, others: list[bytes]) -> bytes:
    """A checkpoint whose largest tensor record is 1.25 GiB of deflated zeros (the probe's 1.5 MB
    file that took 1.8 GB): torch writes records stored, so a deflated one is forged."""
    with zipfile.ZipFile(io.BytesIO(data)) as archive:
        members = [(i.filename, archive.read(i)) for i in archive.infolist()]
    records = [i for i, (name, _) in enumerate(members) if "/data/" in name]
    bomb = max(records or range(len(members)), key=lambda i: len(members[i][1]))
    packed, crc = _deflated_zeros()
    return pack_zip([(name, packed, zipfile.ZIP_DEFLATED, crc, BOMB_BYTES) if i == bomb else
                     (name, content, zipfile.ZIP_STORED, zlib.crc32(content), len(content))
                     for i, (name, content) in enumerate(members)])


_HUGE_BEATS: list[bytes] = []


def huge_beats(rng: random.Random, data: bytes, others: list[bytes]) -> bytes:
    """A beat file of 28 MB (the probe's: it took 1.38 GB), a beat every 0.2 s; a 10-hour song at
    300 bpm needs about 2 MB."""
    if not _HUGE_BEATS:
        _HUGE_BEATS.append("".join(map("{:.3f}\n".format, np.arange(2_900_000) * 0.2)).encode())
    return _HUGE_BEATS[0]


FIELD_MUTATORS = {"npz": mutate_npz_fields, "repertoire": mutate_npz_fields, "pkl": mutate_pickle_fields,
                  "sgmd": mutate_checkpoint_fields, "json": mutate_json_fields, "m2d": mutate_json_fields,
                  "m2dcfg": mutate_json_fields, "glb": mutate_glb_fields, "trainstate": mutate_checkpoint_fields,
                  "features": mutate_npz_fields, "m2dfit": mutate_npz_fields}
RARE_MUTATORS = {"sgmd": checkpoint_bomb, "trainstate": checkpoint_bomb, "beats": huge_beats}  # big: 5 % of inputs


def mutate(fmt: str, rng: random.Random, seeds: list[bytes]) -> bytes:
    """One mutated input of ``fmt``: raw bytes, a zip member's bytes, or a field, at random."""
    data = rng.choice(seeds)
    choice = rng.random()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            if fmt in RARE_MUTATORS and rng.random() < 0.05:
                return RARE_MUTATORS[fmt](rng, data, seeds)
            if fmt in FIELD_MUTATORS and choice < 0.4:
                return FIELD_MUTATORS[fmt](rng, data, seeds)
            if fmt in ZIP_FORMATS and choice < 0.8:
                return mutate_zip_member(rng, data, seeds)
    except Exception:  # a mutation the writer itself cannot save: fall back to raw bytes
        pass
    return mutate_bytes(rng, data, seeds)


# -- the readers, as the CLI calls them --------------------------------------------------------
class RoundTripError(Exception):
    """choreo accepted a file, wrote it, and refused what it wrote."""


class WrongError(Exception):
    """choreo accepted what it must refuse (an odd number in a beat file, a cache entry of the wrong
    shape), refused what it must take (a damaged cache entry is a miss, recomputed), or wrote where
    it must not (through a link planted in the cache)."""


def read_motion_file(path: Path) -> None:
    """`choreo convert` and `info`: read, compute positions, write BVH and NPZ; what choreo
    writes must read back (a refusal there is a ROUNDTRIP finding)."""
    from choreo.errors import ChoreoError
    from choreo.formats import read_joint_positions, read_motion, write_motion

    motion = read_motion(path)
    motion.joint_positions()
    read_joint_positions(path)  # `choreo eval`
    for extension in (".bvh", ".npz"):
        written = path.with_name(f"written{extension}")
        write_motion(motion, written)
        try:
            read_motion(written)
        except ChoreoError as error:
            raise RoundTripError(f"wrote {extension}, then refused it: {error}") from None


def read_npy_file(path: Path) -> None:
    from choreo.formats import read_joint_positions

    read_joint_positions(path)


def read_wav_file(path: Path) -> None:
    """`choreo info` / `generate`: decode and analyse the whole song."""
    from choreo.music import Music

    Music.from_file(path)


def read_csv_file(path: Path) -> None:
    """`choreo trajectory --path`: read the path and stretch it over a dance."""
    from choreo.constraints import path_to_frames, read_root_path

    path_to_frames(*read_root_path(path), 150)


PLAIN_NUMBER = re.compile(r"[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?")


def read_beats_file(path: Path) -> None:
    """`choreo generate --beats`: the beat file's reader and checks. What it accepts must be two or
    more finite increasing beats, and every row of numbers (Python's float reads them) plain ASCII
    decimals: `nan` taken for a header, `0_5` read as 5 or fullwidth digits are WRONG."""
    from choreo.music.beat_file import read_beat_file

    times = np.asarray(read_beat_file(path).times)
    if times.size < 2 or not np.isfinite(times).all() or np.any(np.diff(times) <= 0):
        raise WrongError(f"accepted {times.size} beats: {times[:4]!r}")
    for line in path.read_text("utf-8", "replace").splitlines():
        cells = [c for c in re.split(r"[,;\t ]+", line.strip()) if c]
        try:
            [float(c) for c in cells]
        except (ValueError, OverflowError):
            continue  # a header or a flag column
        odd = [c for c in cells if not PLAIN_NUMBER.fullmatch(c)]
        if odd:
            raise WrongError(f"accepted the number {ascii(odd[0][:24])}")


def read_m2d_clip(path: Path, member: str) -> None:
    """`choreo prepare` on an M2D folder up to the IK fit (which is too slow to fuzz): the clip read
    from ``path`` as ``member`` beside a valid copy of the other JSON file, its IK targets, the
    performer's proportions and the leg length its root path is divided by."""
    from choreo.datasets.clips import leg_length
    from choreo.datasets.ik import performer_skeleton
    from choreo.datasets.m2d import read_recording

    folder = path.parent / "DANCE_C_1"
    folder.mkdir(exist_ok=True)
    (folder / "skeletons.json").write_bytes(m2d_skeletons_seed())
    (folder / "config.json").write_bytes(m2d_config_seeds()[0])
    (folder / member).write_bytes(path.read_bytes())
    recording = read_recording(folder)
    targets, joints = recording.targets()
    leg_length(performer_skeleton(targets, joints), recording.name)


def read_m2d_skeletons(path: Path) -> None:
    read_m2d_clip(path, "skeletons.json")


def read_m2d_config(path: Path) -> None:
    read_m2d_clip(path, "config.json")


def read_sgmd_file(path: Path) -> None:
    """`choreo generate --checkpoint`: the generator built from the file (by the plugin's factory, as
    `choreo.load_backend` builds it, but never from load_backend's cache: every input is a new file)."""
    from choreo_sgmd import plugin

    plugin.factory(path)


def read_repertoire_file(path: Path) -> None:
    """`choreo graph --repertoire`: load, then what the graph reads of every clip."""
    from choreo_graph import Repertoire

    repertoire = Repertoire.load(path)
    repertoire.origins
    repertoire.genre_mask("waltz")
    for index in range(min(len(repertoire), 2)):
        repertoire.clip_motion(index).joint_positions()


def read_training_state(path: Path) -> None:
    """`choreo train sgmd --resume` (``path`` as OUT/last.pt) or `--init-from PATH` (by the file's
    hash), on the tiny preset with one step to go; ValueError is a refusal, as the train command makes it."""
    from choreo.errors import ParameterError
    from choreo_sgmd import train

    out = path.parent / "train"
    shutil.rmtree(out, ignore_errors=True)
    out.mkdir()
    resume = hashlib.sha1(path.read_bytes()).digest()[0] % 2 == 0
    if resume:
        shutil.copy(path, out / "last.pt")
    model, config, data = _tiny_training()
    try:
        train(model, config, data, None, out, resume=resume, init_from=None if resume else path)
    except ValueError as error:
        raise ParameterError(str(error)) from None


def _cache_variant(path: Path) -> int:
    """How the entry is planted, by the input's hash: 0 a link to a file outside the cache, 1 with
    the cache root a file, else the entry itself."""
    return hashlib.sha1(path.read_bytes()).digest()[0] % 8


def _from_cache(path: Path, entry_of, load) -> object:
    """Plant ``path``'s bytes as the cache entry ``entry_of()`` names and run ``load``: whatever is
    there must be a miss (recomputed) or whole, never a refusal or an error; a planted link's
    target is never written; a cache that cannot be written is skipped."""
    from choreo.errors import ChoreoError

    variant, cache, victim = _cache_variant(path), path.parent / "cache", path.parent / "victim.npz"
    shutil.rmtree(cache, ignore_errors=True)
    if variant == 1:
        cache.write_bytes(b"a file, not a folder\n")
    with cache_at(cache):
        if variant != 1:
            entry = entry_of()
            entry.parent.mkdir(parents=True, exist_ok=True)
            if variant == 0:
                victim.write_bytes(path.read_bytes())
                os.symlink(victim, entry)
            else:
                shutil.copy(path, entry)
        try:
            result = load()
        except ChoreoError as error:
            raise WrongError(f"a cache entry was refused, not recomputed: {str(error)[:200]}") from None
        finally:
            if cache.is_file():
                cache.unlink()
    if variant == 0 and victim.read_bytes() != path.read_bytes():
        raise WrongError("wrote through a link planted in the cache")
    return result


def read_features_entry(path: Path) -> None:
    """`choreo prepare` / `train` / `graph build`: a song's features from the feature cache
    (``features/<key>.npz``), which must come back as FEATURE_DIM-wide finite features."""
    from choreo.datasets.cache import _cache_key, cache_dir, cached_music
    from choreo.music import FEATURE_DIM

    song = path.parent / "song.wav"
    if not song.exists():
        song.write_bytes(wav_seeds()[0])
    music = _from_cache(path, lambda: cache_dir() / "features" / f"{_cache_key(song, None, None)}.npz",
                        lambda: cached_music(song))
    features, beats = np.asarray(music.features), np.asarray(music.beat_times)
    if features.ndim != 2 or features.shape[1] != FEATURE_DIM or not np.isfinite(features).all() \
            or not np.isfinite(beats).all() or not np.isfinite(music.tempo):
        raise WrongError(f"a cache entry of features {features.shape} {features.dtype} was trusted")


def read_m2dfit_entry(path: Path) -> None:
    """`choreo prepare` on M2D: the seed clip's fit from the fit cache (``m2d/<clip>_<hash>.npz``),
    then what load_clip makes of it (the standard motion, on the floor, at 30 fps, its joints)."""
    from choreo.datasets.m2d import _fit_cache_path, load_fit, place_on_floor, read_recording, standard_motion

    clip = m2d_folder(path.parent)
    recording = read_recording(clip)
    fit = _from_cache(path, lambda: _fit_cache_path(clip, recording.fps), lambda: load_fit(clip, recording))
    metadata = {"source": clip.name, "genre": recording.genre, "dataset": "m2d"}
    try:
        motion = place_on_floor(standard_motion(fit, recording.fps, metadata).resample(30.0))
        positions = motion.joint_positions()
    except Exception as error:
        raise WrongError(f"a cache entry was trusted, then failed: {type(error).__name__}: {str(error)[:200]}") from None
    if not np.isfinite(positions).all():
        raise WrongError("a cache entry with non-finite values was trusted")


TARGETS = {"bvh": read_motion_file, "npz": read_motion_file, "pkl": read_motion_file, "glb": read_motion_file,
           "json": read_motion_file, "npy": read_npy_file, "wav": read_wav_file, "csv": read_csv_file,
           "beats": read_beats_file, "m2d": read_m2d_skeletons, "m2dcfg": read_m2d_config, "sgmd": read_sgmd_file,
           "repertoire": read_repertoire_file, "trainstate": read_training_state, "features": read_features_entry,
           "m2dfit": read_m2dfit_entry}


def warm_up(seeds: dict[str, list[bytes]]) -> None:
    """Import and run each reader once in the parent, so forked workers start warm (and with one
    torch thread: a forked child must not inherit a thread pool)."""
    import torch

    torch.set_num_threads(1)
    with tempfile.TemporaryDirectory() as folder:
        for fmt, files in seeds.items():
            classify(fmt, files[0], Path(folder))


def classify(fmt: str, data: bytes, folder: Path) -> tuple[str, str]:
    """(class, detail) of one input, run in the calling process."""
    from choreo.errors import ChoreoError

    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"input{EXTENSIONS[fmt]}"
    path.write_bytes(data)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            TARGETS[fmt](path)
        return "accepted", ""
    except ChoreoError as error:
        message = str(error).strip()
        cause = _failed_allocation(error)
        if cause:  # refused, but only once an allocation under the cap had failed: the memory was asked for
            return "MEMORY", f"refused after a failed allocation: {cause}"
        if error.exit_code in (2, 3) and message and "\n" not in message and len(message) <= LONGEST_REFUSAL:
            return "refused", message
        return "INTERNAL", f"{type(error).__name__} exit {error.exit_code}: {message!r}"
    except RoundTripError as error:
        return "ROUNDTRIP", str(error)
    except WrongError as error:
        return "WRONG", str(error)
    except MemoryError:
        return "MEMORY", "MemoryError"
    except RecursionError:
        return "INTERNAL", "RecursionError"
    except OverflowError as error:
        return "INTERNAL", f"OverflowError: {str(error)[:300]}\n{_where(error)}"
    except Exception as error:
        if "alloc" in str(error).lower() and "memory" in str(error).lower():
            return "MEMORY", f"{type(error).__name__}: {str(error)[:200]}"
        return "INTERNAL", f"{type(error).__name__}: {str(error)[:300]}\n{_where(error)}"


def _failed_allocation(error: BaseException) -> str:
    """The MemoryError or failed allocation among ``error``'s causes and contexts, as text ('' if none)."""
    seen = set()
    while error is not None and id(error) not in seen:
        seen.add(id(error))
        text = str(error)
        if isinstance(error, MemoryError) or ("alloc" in text.lower() and "memory" in text.lower()):
            return f"{type(error).__name__}: {text[:200]}"
        error = error.__cause__ or error.__context__
    return ""


def _where(error: BaseException) -> str:
    frames = traceback.extract_tb(error.__traceback__)[-4:]
    return " <- ".join(f"{Path(f.filename).name}:{f.lineno} {f.name}" for f in reversed(frames))


# -- workers -----------------------------------------------------------------------------------
def _vm_size() -> int:
    with open("/proc/self/status") as status:
        return int(re.search(r"VmSize:\s+(\d+)", status.read()).group(1)) * 1024


def _worker_main(conn, memory_cap: int, folder: Path) -> None:
    """Serve inputs until the pipe closes: classify each under an address-space cap of the
    process's current size plus ``memory_cap``."""
    limit = _vm_size() + memory_cap
    resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 1)  # readers must not print; keep the report readable if one does
    while True:
        try:
            fmt, data = conn.recv()
        except EOFError:
            return
        conn.send(classify(fmt, data, folder))


@dataclass
class Worker:
    memory_cap: int
    process: multiprocessing.Process | None = None
    conn: object = None
    folder: Path | None = None

    def start(self) -> None:
        """Fork a worker with its own scratch folder (made here, so a killed worker leaves none)."""
        context = multiprocessing.get_context("fork")
        parent, child = context.Pipe()
        self.folder = Path(tempfile.mkdtemp(prefix="choreo-fuzz-"))
        self.process = context.Process(target=_worker_main, args=(child, self.memory_cap, self.folder), daemon=True)
        self.process.start()
        child.close()
        self.conn = parent

    def stop(self, wait: float = 0.0) -> None:
        """End the worker (closing its pipe first, so an idle one exits by itself) and its folder."""
        if self.process is not None:
            self.conn.close()
            self.process.join(wait)
            if self.process.is_alive():
                self.process.kill()
            self.process.join()
            shutil.rmtree(self.folder, ignore_errors=True)
        self.process = None

    def submit(self, fmt: str, data: bytes) -> None:
        if self.process is None or not self.process.is_alive():
            self.start()
        self.conn.send((fmt, data))


@dataclass
class Report:
    counts: dict = field(default_factory=lambda: defaultdict(Counter))
    findings: dict = field(default_factory=dict)  # signature -> (fmt, class, detail, saved path, count)

    def add(self, fmt: str, cls: str, detail: str, data: bytes, folder: Path) -> None:
        self.counts[fmt][cls] += 1
        if cls in CLEAN:
            return
        signature = (fmt, cls, re.sub(r"\d+", "N", detail.splitlines()[0] if detail else "")[:100],
                     detail.splitlines()[1] if "\n" in detail else "")
        path = save_finding(folder, fmt, cls, detail, data)
        previous = self.findings.get(signature)
        self.findings[signature] = (fmt, cls, detail, previous[3] if previous else path,
                                    (previous[4] if previous else 0) + 1)

    def bad(self) -> int:
        return sum(n for c in self.counts.values() for k, n in c.items() if k not in CLEAN)


def save_finding(folder: Path, fmt: str, cls: str, detail: str, data: bytes) -> Path:
    digest = hashlib.sha1(data).hexdigest()[:12]
    path = folder / fmt / f"{cls}-{digest}{EXTENSIONS[fmt]}"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(data)
    path.with_suffix(".txt").write_text(f"{fmt} {cls}\n{detail}\n")
    return path


def run(formats, inputs: int | None, seconds: float | None, seed: int, workers: int = 2, timeout: float = 10.0,
        memory_cap: int = 1 << 30, findings: Path = DEFAULT_FINDINGS, sgmd_checkpoint=None,
        progress=None) -> Report:
    """Fuzz ``formats`` round-robin until ``inputs`` inputs or ``seconds`` have passed."""
    seeds = make_seeds(formats, sgmd_checkpoint)
    warm_up(seeds)
    pool = [Worker(memory_cap) for _ in range(max(1, workers))]
    report, started, index = Report(), time.monotonic(), 0
    busy: dict[int, tuple[str, bytes, float]] = {}
    try:
        while True:
            out_of_time = seconds is not None and time.monotonic() - started > seconds
            for slot, worker in enumerate(pool):
                if slot not in busy and not out_of_time and (inputs is None or index < inputs):
                    fmt = formats[index % len(formats)]
                    data = mutate(fmt, random.Random(f"{seed}:{index}"), seeds[fmt])
                    worker.submit(fmt, data)
                    busy[slot] = (fmt, data, time.monotonic())
                    index += 1
            if not busy:
                break
            _collect(pool, busy, report, timeout, findings)
            if progress:
                progress(report, index, time.monotonic() - started)
    finally:
        for worker in pool:
            worker.stop(wait=2.0)
    return report


def _collect(pool, busy, report: Report, timeout: float, findings: Path) -> None:
    """Wait a little for any busy worker; record its answer, or its death or overrun."""
    multiprocessing.connection.wait([pool[s].conn for s in busy] + [pool[s].process.sentinel for s in busy], 0.05)
    for slot in list(busy):
        worker, (fmt, data, since) = pool[slot], busy[slot]
        if worker.conn.poll():
            try:
                cls, detail = worker.conn.recv()
            except EOFError:
                cls, detail = "CRASH", f"worker died (exit {worker.process.exitcode})"
                worker.stop()
        elif not worker.process.is_alive():
            cls, detail = "CRASH", f"worker died (exit {worker.process.exitcode})"
            worker.stop()
        elif time.monotonic() - since > timeout:
            cls, detail = "HANG", f"over {timeout:g} s"
            worker.stop()
        else:
            continue
        del busy[slot]
        report.add(fmt, cls, detail, data, findings)


def print_report(report: Report, formats, elapsed: float, findings: Path) -> None:
    print(f"\n{'format':<11}" + "".join(f"{c:>10}" for c in CLASSES) + f"{'total':>10}")
    for fmt in formats:
        counts = report.counts[fmt]
        print(f"{fmt:<11}" + "".join(f"{counts[c]:>10}" for c in CLASSES) + f"{sum(counts.values()):>10}")
    total = sum(sum(c.values()) for c in report.counts.values())
    print(f"{total} inputs in {elapsed:.0f} s ({total / max(elapsed, 1e-9):.1f}/s); {report.bad()} not clean")
    for (fmt, cls, _, _), (_, _, detail, path, count) in sorted(report.findings.items()):
        print(f"  {cls} {fmt} x{count}: {detail.splitlines()[0][:160]}\n      {path}")
    if report.findings:
        print(f"findings saved under {findings}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seconds", type=float, default=None, help="stop after this long (60 s without --inputs)")
    parser.add_argument("--inputs", type=int, default=None, help="stop after this many inputs")
    parser.add_argument("--formats", default=",".join(FORMATS), help=f"comma list of {', '.join(FORMATS)}")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--timeout", type=float, default=10.0, help="seconds per input")
    parser.add_argument("--memory", type=float, default=1.0, help="GiB a worker may allocate beyond its start")
    parser.add_argument("--findings", type=Path, default=DEFAULT_FINDINGS)
    parser.add_argument("--checkpoint", default=None, help="an SGMD checkpoint to make the .pt seed from")
    args = parser.parse_args(argv)
    formats = tuple(f.strip() for f in args.formats.split(",") if f.strip())
    unknown = set(formats) - set(FORMATS)
    if unknown:
        parser.error(f"unknown formats {', '.join(sorted(unknown))}")
    seconds = args.seconds if args.seconds is not None or args.inputs is not None else 60.0
    started, last = time.monotonic(), [0.0]

    def progress(report, index, elapsed):
        if elapsed - last[0] >= 30:
            last[0] = elapsed
            print(f"[{elapsed:.0f} s] {index} inputs, {report.bad()} not clean", file=sys.stderr, flush=True)

    report = run(formats, args.inputs, seconds, args.seed, args.workers, args.timeout, int(args.memory * (1 << 30)),
                 args.findings, args.checkpoint, progress)
    print_report(report, formats, time.monotonic() - started, args.findings)
    return 1 if report.bad() else 0


if __name__ == "__main__":
    sys.exit(main())
