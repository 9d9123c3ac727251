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
