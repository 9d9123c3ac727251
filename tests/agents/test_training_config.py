"""The training config loader: the shipped config is valid; mistakes are one ConfigError naming the key."""

from __future__ import annotations

from pathlib import Path

import pytest

from cnc_gym.errors import ConfigError
from cnc_gym_agents.training import load_config

REPO = Path(__file__).resolve().parents[2]


def test_shipped_ppo_config_loads():
    config = load_config(REPO / "configs/train/ppo.yaml")
    assert config.ppo.net_arch == [64, 64]
    assert config.n_envs >= 1 and config.total_timesteps > 0
    kwargs = config.env.make_kwargs()
    assert kwargs["action_mode"] == "override" and kwargs["programs"] == config.env.programs


def test_shipped_v1_configs_load_and_name_the_train_split():
    from cnc_gym.benchmark import load_suite

    train = {str(p) for p in load_suite().paths("train")}
    for name in ("ppo-residual", "ppo-lagrangian-residual"):
        config = load_config(REPO / f"configs/train/{name}.yaml")
        kwargs = config.env.make_kwargs()
        assert config.env.id == "cnc_gym/Feedrate-v1" and kwargs["action_mode"] == "residual"
        assert set(kwargs["programs"]) == train and kwargs["randomize"]["enabled"]
        assert config.env.policy_env() == {"id": "cnc_gym/Feedrate-v1", "kwargs": {
            "action_mode": "residual", "control_period_s": 0.01, "residual_range": 2.0}}
    assert load_config(REPO / "configs/train/ppo-lagrangian-residual.yaml").algorithm == "ppo_lagrangian"


def test_a_shipped_config_loads_by_name_and_an_unknown_name_is_one_line():
    assert load_config("ppo") == load_config(REPO / "configs/train/ppo.yaml")
    with pytest.raises(ConfigError, match=r"unknown training config 'nope'; shipped: .*ppo-residual"):
        load_config("nope")


V1 = "env: {id: cnc_gym/Feedrate-v1, programs: [circle]"


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("total_timestep: 10\n", "unknown key total_timestep"),
        ("env: {action_mode: residual}\n", r"action_mode residual needs id: cnc_gym/Feedrate-v6 \(or -v1"),
        ("env: {randomize: {enabled: true}}\n", "env.randomize belongs to cnc_gym/Feedrate-v1"),
        ("env: {reward_v1: {time: 2}}\n", "env.reward_v1 belongs to cnc_gym/Feedrate-v1"),
        (V1 + ", reward: {time: 2}}\n", "env.reward holds Feedrate-v0's weights"),
        (V1 + ", reward_v1: {finish: 0}}\n", r"env.reward_v1.finish must be in \(0, 1e6\]"),
        (V1 + ", reward_v6: {time: 2}}\n", "env.reward_v6 holds Feedrate-v6.s weights; those of cnc_gym"),
        ("env: {id: cnc_gym/Feedrate-v6, reward_v1: {time: 2}}\n", r"env.reward_v1 holds Feedrate-v1 to -v5"),
        ("env: {id: cnc_gym/Feedrate-v6, reward_v6: {finish: 1}}\n", "unknown key env.reward_v6.finish"),
        (V1 + ", randomize: {kv_scale: [2, 1]}}\n", "env.randomize.kv_scale must be"),
        (V1 + ", randomize: {feed_scale: [0.5, 20]}}\n", r"env.randomize.feed_scale ends must be in"),
        ("env: {id: cnc_gym/Feedrate-v9}\n", "env.id must be one of"),
        ("env: {programs: ['suite:cnc-bench-v1/test']}\n", "the test split is for the reported result"),
        ("env: {programs: ['suite:nope/train']}\n", "unknown suite 'nope'"),
        ("env: {programs: ['suite:cnc-bench-v1']}\n", "suite:<name>/<split>"),
        ("algorithm: ppo_lagrangian\n", "ppo_lagrangian needs env.id: cnc_gym/Feedrate-v6"),
        ("algorithm: sac\n", "algorithm must be one of ppo, ppo_lagrangian"),
        ("lagrangian: {lambda_lr: -1}\n", r"lagrangian.lambda_lr must be in \[0, 1e6\]"),
        ("ppo: {learning_rat: 0.1}\n", "unknown key ppo.learning_rat"),
        ("env: {programs: []}\n", "env.programs must name at least one program"),
        ("ppo: {learning_rate: '3e-4'}\n", "ppo.learning_rate must be a number"),
        ("n_envs: 2.5\n", "n_envs must be an integer"),
        ("n_envs: 0\n", r"n_envs must be an integer in \[1, 256\], got 0"),
        ("ppo: {gamma: 1.5}\n", "gamma"),
        ("progress_bar: yes please\n", "progress_bar must be true or false"),
        ("- a\n- b\n", "must be a mapping"),
        ("ppo: [1\n", "invalid YAML"),
        # Every training reproducer of issue 17 (item 3).
        ("ppo: {learning_rate: .nan}\n", "ppo.learning_rate must be finite, got nan"),
        ("ppo: {gamma: .inf}\n", "ppo.gamma must be finite"),
        ("ppo: {clip_range: .nan}\n", "ppo.clip_range must be finite, got nan"),
        ("ppo: {clip_range: 0}\n", r"ppo.clip_range must be in \(0, 1\]"),
        ("ppo: {ent_coef: -.inf}\n", "ppo.ent_coef must be finite"),
        ("seed: -1\n", r"seed must be an integer in \[0, 4294967295\], got -1"),
        ("seed: 4294967296\n", "seed must be an integer in"),
        ("ppo: {batch_size: 1}\n", r"ppo.batch_size must be an integer in \[2, "),
        ("n_envs: 100000000\n", r"n_envs must be an integer in \[1, 256\]"),
        ("ppo: {net_arch: [100000000]}\n", r"ppo.net_arch entry 1 must be an integer in \[1, 1024\]"),
        ("ppo: {net_arch: [64, 64, 64, 64, 64, 64, 64, 64, 64]}\n", "ppo.net_arch must name at most 8"),
        ("torch_threads: 100000000\n", r"torch_threads must be an integer in \[1, 256\]"),
        ("run_name: /tmp/elsewhere\n", "run_name must be a plain name"),
        ("run_name: ../../elsewhere\n", "run_name must be a plain name"),
        ("run_name: ..\n", "run_name must be a plain name"),
        ("total_timesteps: 0\n", "total_timesteps must be an integer in"),
        ("ppo: {n_steps: 64, batch_size: 256}\nn_envs: 2\n", "ppo.batch_size must not exceed the rollout"),
        ("ppo: {n_steps: 1}\nn_envs: 1\n", "the rollout, 1"),
        ("env: {control_period_s: 1.0e6}\n", r"env.control_period_s must be in \(0, 1\] s"),
        ("env: {reward: {violation: -1}}\n", "env.reward.violation must be in"),
        ("env: {max_episode_steps: 0}\n", "env.max_episode_steps must be an integer in"),
        ("env: 5\n", "'env' must be a mapping"),
    ],
)
def test_config_errors(tmp_path, text, message):
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(ConfigError, match=message) as err:
        load_config(path)
    assert str(err.value).startswith(f"{path}:") and "\n" not in str(err.value)


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


def _main(argv):
    import importlib.util

    spec = importlib.util.spec_from_file_location("train_script", REPO / "scripts" / "train.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.main(argv)


@pytest.mark.parametrize("timesteps", ["0", "-1"])
def test_timesteps_zero_or_negative_are_refused_before_training(capsys, timesteps):
    assert _main(["--config", str(REPO / "configs/train/ppo.yaml"), "--timesteps", timesteps]) == 2
    err = capsys.readouterr().err.strip()
    assert err == f"train: --timesteps must be an integer in [1, 10000000000], got {timesteps}"


def test_an_unwritable_output_dir_is_one_line_before_training(tmp_path, capsys):
    # A file where a folder should be: unwritable even for root (chmod would not stop root).
    (tmp_path / "file").write_text("")
    config = tmp_path / "c.yaml"
    config.write_text(f"output_dir: {tmp_path / 'file' / 'runs'}\n")
    assert _main(["--config", str(config), "--no-progress"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"train: {config}: output_dir: cannot write to ") and "\n" not in err
    assert _main(["--config", str(REPO / "configs/train/ppo.yaml"), "--out", str(tmp_path / "file")]) == 2
    assert capsys.readouterr().err.startswith("train: --out: cannot write to ")


def test_a_config_built_in_python_keeps_the_file_rules(tmp_path):
    from cnc_gym_agents.training import TrainConfig, train

    config = TrainConfig(run_name="../outside", output_dir=str(tmp_path))
    with pytest.raises(ConfigError, match="run_name must be a plain name"):
        train(config)
    assert not (tmp_path.parent / "outside").exists()


def test_the_saved_config_of_a_run_loads_again(tmp_path):
    import yaml

    from cnc_gym_agents.training import config_to_dict

    config = load_config(REPO / "configs/train/ppo.yaml")
    path = tmp_path / "config.yaml"
    path.write_text(yaml.safe_dump(config_to_dict(config), sort_keys=False))
    again = load_config(path)
    assert again.env == config.env and again.ppo == config.ppo
