"""scripts/train.py and scripts/evaluate.py end to end on a tiny budget (the CI smoke test).

A ~2k-step PPO run is far too short to learn anything; the test checks the plumbing: the model is saved
where the script says, the config copy is written, evaluate.py runs it beside the baselines, and SB3's
own loader reads the model back.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

REPO = Path(__file__).resolve().parents[1]

TINY = {
    "env": {"programs": ["star"], "machine": "vmc-small"},
    "total_timesteps": 2048,
    "n_envs": 2,
    "seed": 0,
    "run_name": "tiny",
    "progress_bar": False,
    "ppo": {"n_steps": 256, "batch_size": 128, "n_epochs": 2, "net_arch": [16, 16]},
}


def _run(args: list[str]) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, *args], cwd=REPO, capture_output=True, text=True, timeout=120)


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    out = tmp_path_factory.mktemp("runs")
    config = out / "tiny.yaml"
    config.write_text(yaml.safe_dump(TINY))
    result = _run(["scripts/train.py", "--config", str(config), "--out", str(out), "--no-progress"])
    assert result.returncode == 0, result.stderr
    return out, result


def test_train_saves_model_config_and_tensorboard_logs(trained):
    out, result = trained
    model = out / "tiny" / "model.zip"
    assert f"model:       {model}" in result.stdout
    assert model.is_file()
    saved = yaml.safe_load((out / "tiny" / "config.yaml").read_text())
    assert saved["total_timesteps"] == 2048 and saved["env"]["programs"] == ["star"]
    assert any((out / "tensorboard").rglob("events.out.tfevents.*"))


def test_model_loads_with_sb3_loader_and_acts_in_the_box(trained):
    import gymnasium
    from stable_baselines3 import PPO

    import cnc_gym  # noqa: F401

    out, _ = trained
    model = PPO.load(out / "tiny" / "model.zip", device="cpu")
    env = gymnasium.make("cnc_gym/Feedrate-v0", programs=["star"])
    observation, _ = env.reset(seed=0)
    action, _ = model.predict(observation, deterministic=True)
    assert env.action_space.contains(np.asarray(action, dtype=np.float32))


def test_evaluate_compares_model_with_baselines(trained):
    out, _ = trained
    model = out / "tiny" / "model.zip"
    result = _run(["scripts/evaluate.py", "--model", str(model), "--overrides", "1.0,2.0", "--json"])
    assert result.returncode == 0, result.stderr
    data = json.loads(result.stdout)
    policies = {row["policy"] for row in data["rows"]}
    assert policies == {"constant:1", "constant:2", "classical", "model.zip"}
    assert all(row["program"] == "star" and row["steps"] > 0 for row in data["rows"])
    assert data["totals"]["model.zip"]["cycle_time_s"] > 0


def test_bad_config_is_one_line(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("total_timestep: 5\n")
    result = _run(["scripts/train.py", "--config", str(bad), "--no-progress"])
    assert result.returncode == 2
    assert "unknown key total_timestep" in result.stderr and "Traceback" not in result.stderr


# ------------------------------------------------------------------------------ Feedrate-v1 (residual)
TINY_V1 = {
    "env": {"id": "cnc_gym/Feedrate-v1", "programs": ["circle", "star"], "action_mode": "residual",
            "randomize": {"enabled": True, "machines": 2}},
    "algorithm": "ppo_lagrangian",
    "lagrangian": {"cost_limit": 0.01, "lambda_init": 1.0, "lambda_lr": 5.0},
    "total_timesteps": 2048,
    "n_envs": 2,
    "normalize_reward": True,
    "run_name": "tiny-v1",
    "progress_bar": False,
    "ppo": {"n_steps": 256, "batch_size": 128, "n_epochs": 2, "net_arch": [16, 16], "log_std_init": -1.5},
}  # fmt: skip


@pytest.fixture(scope="module")
def trained_v1(tmp_path_factory):
    out = tmp_path_factory.mktemp("runs_v1")
    config = out / "tiny_v1.yaml"
    config.write_text(yaml.safe_dump(TINY_V1))
    result = _run(["scripts/train.py", "--config", str(config), "--out", str(out), "--seed", "3",
                   "--no-progress"])  # fmt: skip
    assert result.returncode == 0, result.stderr
    return out


def test_v1_lagrangian_run_logs_lambda_and_records_its_env(trained_v1):
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    from cnc_gym.policies.model import load_sb3_model

    model = load_sb3_model(trained_v1 / "tiny-v1" / "model.zip")
    assert model.env_id == "cnc_gym/Feedrate-v1"
    assert model.env_kwargs == {"action_mode": "residual", "control_period_s": 0.01, "residual_range": 2.0}
    assert model.observation_space.shape == (46,)
    saved = yaml.safe_load((trained_v1 / "tiny-v1" / "config.yaml").read_text())
    assert saved["seed"] == 3 and saved["algorithm"] == "ppo_lagrangian"
    events = EventAccumulator(str(next((trained_v1 / "tensorboard").glob("tiny-v1_*"))))
    events.Reload()
    assert "lagrangian/lambda" in events.Tags()["scalars"]


def test_v1_model_runs_in_evaluate_and_in_the_bench_per_training_seed(trained_v1):
    import shutil

    from cnc_gym.benchmark.runner import BenchConfig, BenchProgram, run_bench
    from cnc_gym.programs import resolve_program

    model = trained_v1 / "tiny-v1" / "model.zip"
    result = _run(["scripts/evaluate.py", "--model", str(model), "--overrides", "1.0", "--programs", "circle",
                   "--json"])  # fmt: skip
    assert result.returncode == 0, result.stderr
    rows = json.loads(result.stdout)["rows"]
    assert {row["policy"] for row in rows} == {"constant:1", "classical", "model.zip"}
    # Two "training seeds" (copies of one model): one policy spec, one record per seed.
    for seed in (0, 1):
        shutil.copy(model, trained_v1 / f"m-s{seed}.zip")
    spec = str(trained_v1 / "m-s{seed}.zip")
    text = resolve_program("circle").path.read_text()
    records = run_bench(BenchConfig(programs=[BenchProgram("circle", text)], policies=[spec, "classical"],
                                    seeds=[0, 1]))  # fmt: skip
    mine = [r for r in records if r["policy"] == spec]
    assert [r["seed"] for r in mine] == [0, 1] and mine[0]["cycle_time_s"] == mine[1]["cycle_time_s"] > 0
