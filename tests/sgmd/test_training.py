"""Training survives SIGKILL: resuming from the last atomic checkpoint continues exactly."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import torch

from choreo_sgmd.checkpoint import load_checkpoint

FIXTURES = Path(__file__).parents[1] / "fixtures" / "aistpp"
CHOREO = [sys.executable, "-c", "import sys; from choreo.cli import main; sys.exit(main())"]


def train_command(out: Path, *extra: str) -> list[str]:
    return [*CHOREO, "train", "sgmd", "--data", str(FIXTURES), "--out", str(out), "--config", "tiny", "--steps", "60",
            "--batch-size", "2", "--checkpoint-every", "10", "--prompt", "onehot", *extra]


def test_killed_run_resumes_as_if_never_interrupted(tmp_path):
    env = {**os.environ, "OMP_NUM_THREADS": "1"}
    subprocess.run(train_command(tmp_path / "whole"), env=env, check=True, capture_output=True)
    killed = subprocess.Popen(train_command(tmp_path / "killed"), env=env, stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL)
    checkpoint, step = tmp_path / "killed" / "last.pt", 0
    deadline = time.time() + 120
    while step < 20 and killed.poll() is None and time.time() < deadline:  # kill between checkpoints
        time.sleep(0.02)
        if checkpoint.exists():
            step = load_checkpoint(checkpoint)["step"]
    killed.send_signal(signal.SIGKILL)
    killed.wait()
    assert 20 <= load_checkpoint(checkpoint)["step"] < 60, "the run finished before it could be killed"
    subprocess.run(train_command(tmp_path / "killed", "--resume"), env=env, check=True, capture_output=True)
    # a kill during a write leaves a temporary file beside last.pt; the resumed run removes it
    assert not [p for p in (tmp_path / "killed").iterdir() if p.name != "last.pt"]
    whole, resumed = load_checkpoint(tmp_path / "whole" / "last.pt"), load_checkpoint(checkpoint)
    assert resumed["step"] == whole["step"] == 60
    assert resumed["history"] == whole["history"]  # the loss curve goes on as if uninterrupted
    for key, value in whole["state_dict"].items():
        assert torch.equal(value, resumed["state_dict"][key]), key


def test_two_processes_train_like_one(tmp_path):
    """torchrun with two CPU processes (gloo): each takes half of every batch; the result matches a
    single process on the whole batch, loads, and generates."""
    env = {**os.environ, "OMP_NUM_THREADS": "1"}
    steps = ["--steps", "20"]
    subprocess.run(train_command(tmp_path / "one", *steps), env=env, check=True, capture_output=True)
    torchrun = [sys.executable, "-m", "torch.distributed.run", "--nproc_per_node=2", "--master_port=29531", "-m", "choreo"]
    result = subprocess.run([*torchrun, *train_command(tmp_path / "two", *steps)[len(CHOREO):]], env=env,
                            capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr[-2000:]
    one, two = load_checkpoint(tmp_path / "one" / "last.pt"), load_checkpoint(tmp_path / "two" / "last.pt")
    assert two["step"] == 20
    for key, value in one["state_dict"].items():
        torch.testing.assert_close(two["state_dict"][key], value, atol=2e-5, rtol=1e-4)
    song = Path(__file__).parents[2] / "examples" / "drum_and_bass_174bpm.wav"
    generated = subprocess.run([*CHOREO, "generate", str(song), "-o", str(tmp_path / "d.npz"), "--checkpoint",
                                str(tmp_path / "two" / "last.pt"), "--steps", "2"], env=env, capture_output=True, text=True)
    assert generated.returncode == 0, generated.stderr
    assert (tmp_path / "d.npz").stat().st_size > 0


def test_every_training_flag_reaches_the_checkpoint(tmp_path):
    """`choreo train sgmd` flags land in the configurations the checkpoint records (each one
    differs from its default, so a flag dropped on the way shows)."""
    out = tmp_path / "run"
    flags = ["--steps", "1", "--batch-size", "2", "--checkpoint-every", "1", "--prompt", "onehot", "--seed", "3",
             "--style-mode", "concat", "--style-init", "zero", "--style-dropout", "0.2", "--mirror", "--stretch", "1,1.1",
             "--turns", "0,90", "--genre-balance", "0.25", "--rhythm", "--prediction", "v", "--sigma-data", "0.5",
             "--snr-gamma", "5", "--reconstruction-weight", "6"]
    command = [*CHOREO, "train", "sgmd", "--data", str(FIXTURES), "--out", str(out), "--config", "tiny", *flags]
    subprocess.run(command, check=True, capture_output=True, timeout=300)
    state = load_checkpoint(out / "last.pt")
    model, diffusion, train = state["model_config"], state["diffusion_config"], state["train_config"]
    assert (model["style_mode"], model["style_init"], model["music_dim"], model["latent_dim"]) == ("concat", "zero", 38, 32)
    assert (diffusion["style_dropout"], diffusion["prediction"], diffusion["sigma_data"], diffusion["snr_gamma"],
            diffusion["reconstruction_weight"]) == (0.2, "v", 0.5, 5.0, 6.0)
    assert (train["max_steps"], train["batch_size"], train["checkpoint_every"], train["validation_every"],
            train["seed"], train["prompt_kind"], train["mirror"], list(train["stretch"]), list(train["turns"]),
            train["genre_balance"]) == (1, 2, 1, 1, 3, "onehot", True, [1.0, 1.1], [0.0, 90.0], 0.25)
    # the rhythm channels (a 38-d music input) are fed at generation too
    song = Path(__file__).parents[2] / "examples" / "drum_and_bass_174bpm.wav"
    generated = subprocess.run([*CHOREO, "generate", str(song), "-o", str(tmp_path / "rhythm.npz"), "--checkpoint",
                                str(out / "last.pt"), "--steps", "2"], capture_output=True, text=True)
    assert generated.returncode == 0, generated.stderr


BASE_CHECKPOINT = Path(__file__).resolve().parents[2] / "generators/choreo_sgmd/weights/sgmd-cpu-m2d-base.pt"


def test_training_defaults_are_the_bundled_models_base_recipe():
    """`choreo train sgmd` with no flags trains the run the bundled model was fine-tuned from
    (docs/sgmd.md, "The bundled model"), read from that run's checkpoint itself: every setting but
    the run's length and logging."""
    from choreo_sgmd.config import DiffusionConfig, ModelConfig, TrainConfig, model_config, to_dict
    from choreo_sgmd.style import style_dim

    base = load_checkpoint(BASE_CHECKPOINT)
    # settings added since (the pace condition) default to what it was trained with
    assert to_dict(model_config("cpu", style_dim=style_dim("description"))) == to_dict(ModelConfig(**base["model_config"]))
    assert set(base["model_config"]) <= set(to_dict(ModelConfig()))
    # settings added since (contact source, stepping, leg weights) default to what it was trained with
    assert to_dict(DiffusionConfig()) == to_dict(DiffusionConfig(**base["diffusion_config"]))
    assert set(base["diffusion_config"]) <= set(to_dict(DiffusionConfig()))
    free = {"max_steps", "validation_every", "checkpoint_every"}
    defaults = {k: v for k, v in to_dict(TrainConfig()).items() if k not in free}
    assert defaults == {k: v for k, v in to_dict(TrainConfig(**base["train_config"])).items() if k not in free}
    assert set(base["train_config"]) <= set(to_dict(TrainConfig()))


def test_the_bundled_model_is_its_base_fine_tuned_without_dropout_and_with_the_legs_speed():
    """The bundled model differs from its base run in exactly `--dropout 0 --legs-speed-weight 1`,
    and names the base file and step it started from: the recipe is the two documented commands."""
    from choreo_sgmd import DEFAULT_CHECKPOINT
    from choreo_sgmd.config import DiffusionConfig, ModelConfig, TrainConfig, to_dict

    base, bundled = load_checkpoint(BASE_CHECKPOINT), load_checkpoint(DEFAULT_CHECKPOINT)
    assert bundled["started_from"] == {"checkpoint": BASE_CHECKPOINT.name, "step": base["step"]}
    # settings added after the base was trained take their defaults, which are what it was trained with
    assert to_dict(ModelConfig(**bundled["model_config"])) == to_dict(ModelConfig(**{**base["model_config"], "dropout": 0.0}))
    assert to_dict(DiffusionConfig(**bundled["diffusion_config"])) == \
        to_dict(DiffusionConfig(**{**base["diffusion_config"], "legs_speed_weight": 1.0}))
    free = {"max_steps", "validation_every", "checkpoint_every", "num_threads"}
    assert {k: v for k, v in to_dict(TrainConfig(**bundled["train_config"])).items() if k not in free} == \
        {k: v for k, v in to_dict(TrainConfig(**base["train_config"])).items() if k not in free}
    assert bundled["step"] > base["step"]


def test_holding_out_validation_needs_m2d_and_leaves_its_clips_out():
    """--hold-out-validation: a dataset without M2D's validation clips is a one-line error; on M2D
    clips, the validation clips leave training and become its validation set."""
    from types import SimpleNamespace

    from choreo.datasets.m2d import validation_clips
    from choreo_sgmd import _without_validation

    refused = subprocess.run([*CHOREO, "train", "sgmd", "--data", str(FIXTURES), "--out", "runs-never", "--config", "tiny",
                              "--steps", "1", "--hold-out-validation"], capture_output=True, text=True, timeout=300)
    assert refused.returncode == 2 and "validation clips" in refused.stderr and "Traceback" not in refused.stderr
    clips = [SimpleNamespace(name=n) for n in ("DANCE_C_6", *validation_clips(), "DANCE_W_1")]
    train, held = _without_validation(clips)
    assert [c.name for c in train] == ["DANCE_C_6", "DANCE_W_1"]
    assert [c.name for c in held] == list(validation_clips())


def test_a_generation_checkpoint_is_fine_tuned_from_its_ema_weights(tmp_path):
    """`--init-from` a bundled-style checkpoint (EMA weights, float16, no optimiser): the run starts
    from those weights as raw and average weights alike, the step count carries on, the optimiser is new."""
    from choreo_sgmd.checkpoint import export_for_inference

    env = {**os.environ, "OMP_NUM_THREADS": "1"}
    subprocess.run(train_command(tmp_path / "first", "--steps", "10"), env=env, check=True, capture_output=True)
    export_for_inference(tmp_path / "first" / "last.pt", tmp_path / "bundled.pt", half=True)
    tuned = subprocess.run(train_command(tmp_path / "tuned", "--steps", "12", "--init-from", str(tmp_path / "bundled.pt")),
                           env=env, capture_output=True, text=True)
    assert tuned.returncode == 0, tuned.stderr[-2000:]
    state = load_checkpoint(tmp_path / "tuned" / "last.pt")
    assert state["step"] == 12 and state["started_from"] == {"checkpoint": "bundled.pt", "step": 10}
    assert all(len(moments) == 0 or moments["step"] == 2 for moments in state["optimizer"]["state"].values())
    start = load_checkpoint(tmp_path / "bundled.pt")["ema_state_dict"]
    moved = max(float((state["state_dict"][key] - start[key].float()).abs().max()) for key in start)
    assert 0 < moved < 0.05  # two steps of AdamW from the bundled weights, not from a fresh network
    exported = export_for_inference(tmp_path / "tuned" / "last.pt", tmp_path / "tuned.pt", half=True)
    assert exported["started_from"] == {"checkpoint": "bundled.pt", "step": 10}  # the recipe's first run, named
