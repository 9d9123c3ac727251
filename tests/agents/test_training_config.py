"""The training config loader: the shipped config is valid; mistakes are one ConfigError naming the key."""

from __future__ import annotations

from pathlib import Path

import pytest

from agents.training import load_config
from cnc_gym.errors import ConfigError

REPO = Path(__file__).resolve().parents[2]


def test_shipped_ppo_config_loads():
    config = load_config(REPO / "configs/train/ppo.yaml")
    assert config.ppo.net_arch == [64, 64]
    assert config.n_envs >= 1 and config.total_timesteps > 0
    kwargs = config.env.make_kwargs()
    assert kwargs["action_mode"] == "override" and kwargs["programs"] == config.env.programs


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("total_timestep: 10\n", "unknown key total_timestep"),
        ("ppo: {learning_rat: 0.1}\n", "unknown key ppo.learning_rat"),
        ("env: {programs: []}\n", "env.programs must name at least one program"),
        ("ppo: {learning_rate: '3e-4'}\n", "ppo.learning_rate must be a number"),
        ("n_envs: 2.5\n", "n_envs must be an integer"),
        ("n_envs: 0\n", r"n_envs must be an integer in \[1, 256\], got 0"),
        ("ppo: {gamma: 1.5}\n", "gamma"),
        ("progress_bar: yes please\n", "progress_bar must be true or false"),
        ("- a\n- b\n", "must be a mapping"),
        ("ppo: [1\n", "invalid YAML"),
    ],
)
def test_config_errors(tmp_path, text, message):
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(ConfigError, match=message) as err:
        load_config(path)
    assert str(path) in str(err.value)


def test_missing_config_file(tmp_path):
    with pytest.raises(ConfigError, match="cannot read"):
        load_config(tmp_path / "nope.yaml")


def test_progress_bonus_is_no_longer_a_training_key(tmp_path):
    # The progress term moved into the env's reward (configs/tasks/default.yaml: progress); a training
    # config that still asks for the old wrapper must fail loudly rather than be silently ignored.
    path = tmp_path / "old.yaml"
    path.write_text("progress_bonus: 10.0\n")
    with pytest.raises(ConfigError, match="progress_bonus"):
        load_config(path)
