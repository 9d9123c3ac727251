"""SB3 training helpers: the validated training config and the PPO training loop.

``scripts/train.py`` and ``scripts/evaluate.py`` are thin entry points over these. A config is YAML read
with ``yaml.safe_load`` and validated into dataclasses (unknown keys, wrong types and out-of-range values
are :class:`~cnc_gym.errors.ConfigError` naming the file and key). See ``configs/train/ppo.yaml``.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from cnc_gym.config import check_keys, read_yaml
from cnc_gym.errors import ConfigError


@dataclass
class EnvSettings:
    """Keyword arguments of ``cnc_gym/Feedrate-v0`` used for training (and, by default, evaluation)."""

    programs: list[str] = field(default_factory=lambda: ["star", "pocket", "freeform"])
    dialect: str = "gsk25i"
    machine: str = "vmc-small"
    action_mode: str = "override"
    control_period_s: float = 0.01
    reward: dict[str, float] | None = None
    max_episode_steps: int | None = None

    def make_kwargs(self) -> dict[str, Any]:
        kwargs: dict[str, Any] = {"programs": list(self.programs), "dialect": self.dialect,
                                  "machine": self.machine, "action_mode": self.action_mode,
                                  "control_period_s": self.control_period_s}  # fmt: skip
        if self.reward is not None:
            kwargs["reward"] = dict(self.reward)
        if self.max_episode_steps is not None:
            kwargs["max_episode_steps"] = self.max_episode_steps
        return kwargs


@dataclass
class PPOSettings:
    """Subset of ``stable_baselines3.PPO`` arguments (same names)."""

    learning_rate: float = 3e-4
    n_steps: int = 512
    batch_size: int = 128
    n_epochs: int = 10
    gamma: float = 0.99
    gae_lambda: float = 0.95
    clip_range: float = 0.2
    ent_coef: float = 0.0
    vf_coef: float = 0.5
    max_grad_norm: float = 0.5
    log_std_init: float = 0.0
    net_arch: list[int] = field(default_factory=lambda: [64, 64])


@dataclass
class TrainConfig:
    """A training run: env, vectorisation, algorithm settings and where to write."""

    env: EnvSettings = field(default_factory=EnvSettings)
    ppo: PPOSettings = field(default_factory=PPOSettings)
    total_timesteps: int = 100_000
    n_envs: int = 4
    #: Scale rewards by a running estimate of the return's spread (VecNormalize with norm_obs=False):
    #: training only, so the saved model needs no extra statistics to run.
    normalize_reward: bool = False
    seed: int = 0
    torch_threads: int = 1
    output_dir: str = "runs"
    run_name: str = "ppo"
    progress_bar: bool = True
    source: str = "<dict>"


def _check_value(value: Any, default: Any, where: str, source: str) -> Any:
    if isinstance(default, bool):
        if not isinstance(value, bool):
            raise ConfigError(f"{source}: {where} must be true or false, got {value!r}")
        return value
    if isinstance(default, float | int) and not isinstance(default, bool):
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise ConfigError(f"{source}: {where} must be a number, got {value!r}")
        if isinstance(default, int) and not float(value).is_integer():
            raise ConfigError(f"{source}: {where} must be an integer, got {value!r}")
        return type(default)(value)
    if isinstance(default, str):
        if not isinstance(value, str):
            raise ConfigError(f"{source}: {where} must be a string, got {value!r}")
        return value
    return value


def _build(cls: type, data: Any, source: str, where: str) -> Any:
    if data is None:
        data = {}
    if not isinstance(data, dict):
        raise ConfigError(f"{source}: {where or 'the config'} must be a mapping")
    check_keys(data, {f.name for f in dataclasses.fields(cls)} - {"source"}, source, where)
    default = cls()
    values: dict[str, Any] = {}
    for key, raw in data.items():
        path = f"{where}.{key}" if where else key
        current = getattr(default, key)
        if dataclasses.is_dataclass(current):
            values[key] = _build(type(current), raw, source, path)
        elif key in ("programs", "net_arch"):
            if not isinstance(raw, list) or not raw:
                raise ConfigError(f"{source}: {path} must be a non-empty list")
            kind = str if key == "programs" else int
            if not all(isinstance(x, kind) and not isinstance(x, bool) for x in raw):
                raise ConfigError(f"{source}: {path} must be a list of {kind.__name__}s, got {raw!r}")
            values[key] = list(raw)
        elif key == "reward":
            if raw is not None and (
                not isinstance(raw, dict)
                or not all(isinstance(v, int | float) and not isinstance(v, bool) for v in raw.values())
            ):
                raise ConfigError(f"{source}: {path} must be a mapping of weight names to numbers")
            values[key] = None if raw is None else {str(k): float(v) for k, v in raw.items()}
        elif key == "max_episode_steps":
            if raw is not None and (isinstance(raw, bool) or not isinstance(raw, int) or raw <= 0):
                raise ConfigError(f"{source}: {path} must be a positive integer or null")
            values[key] = raw
        else:
            values[key] = _check_value(raw, current, path, source)
    return cls(**values)


def load_config(path: str | Path) -> TrainConfig:
    """Read and validate a training config (YAML via ``yaml.safe_load``)."""
    path = Path(path)
    data = read_yaml(path, "training config")
    config = _build(TrainConfig, data, str(path), "")
    config.source = str(path)
    positive = {"total_timesteps": config.total_timesteps, "n_envs": config.n_envs,
                "torch_threads": config.torch_threads, "ppo.n_steps": config.ppo.n_steps,
                "ppo.batch_size": config.ppo.batch_size, "ppo.n_epochs": config.ppo.n_epochs,
                "ppo.learning_rate": config.ppo.learning_rate}  # fmt: skip
    for key, value in positive.items():
        if value <= 0:
            raise ConfigError(f"{path}: {key} must be positive, got {value}")
    if not 0 < config.ppo.gamma <= 1 or not 0 < config.ppo.gae_lambda <= 1:
        raise ConfigError(f"{path}: ppo.gamma and ppo.gae_lambda must be within (0, 1]")
    if any(n <= 0 for n in config.ppo.net_arch):
        raise ConfigError(f"{path}: ppo.net_arch layer sizes must be positive")
    return config


def config_to_dict(config: TrainConfig) -> dict[str, Any]:
    data = dataclasses.asdict(config)
    data.pop("source", None)
    return data


def train(config: TrainConfig, *, timesteps: int | None = None, out: str | None = None,
          progress_bar: bool | None = None) -> Path:  # fmt: skip
    """Train PPO as configured; returns the path of the saved ``model.zip``."""
    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.vec_env import DummyVecEnv

    import cnc_gym  # noqa: F401  (registers the env)
    from cnc_gym.programs import load_program

    torch.set_num_threads(config.torch_threads)  # small MLPs: more threads only add overhead
    for program in config.env.programs:  # interpret up front: program errors are one clear line
        load_program(program, config.env.dialect)
    run_dir = Path(out or config.output_dir) / config.run_name
    run_dir.mkdir(parents=True, exist_ok=True)
    vec_env = make_vec_env(
        "cnc_gym/Feedrate-v0",
        n_envs=config.n_envs,
        seed=config.seed,
        env_kwargs=config.env.make_kwargs(),
        vec_env_cls=DummyVecEnv,
    )
    if config.normalize_reward:
        from stable_baselines3.common.vec_env import VecNormalize

        vec_env = VecNormalize(vec_env, norm_obs=False, norm_reward=True, gamma=config.ppo.gamma)
    p = config.ppo
    model = PPO(
        "MlpPolicy", vec_env, learning_rate=p.learning_rate, n_steps=p.n_steps, batch_size=p.batch_size,
        n_epochs=p.n_epochs, gamma=p.gamma, gae_lambda=p.gae_lambda, clip_range=p.clip_range,
        ent_coef=p.ent_coef, vf_coef=p.vf_coef, max_grad_norm=p.max_grad_norm, seed=config.seed,
        policy_kwargs={"net_arch": list(p.net_arch), "log_std_init": p.log_std_init},
        tensorboard_log=str(Path(out or config.output_dir) / "tensorboard"), device="cpu", verbose=0,
    )  # fmt: skip
    total = int(timesteps or config.total_timesteps)
    show_bar = config.progress_bar if progress_bar is None else progress_bar
    started = time.perf_counter()
    model.learn(total_timesteps=total, progress_bar=show_bar, tb_log_name=config.run_name)
    elapsed = time.perf_counter() - started
    model_path = run_dir / "model.zip"
    model.save(model_path)
    saved = config_to_dict(config)
    saved["total_timesteps"] = total
    (run_dir / "config.yaml").write_text(yaml.safe_dump(saved, sort_keys=False))
    vec_env.close()
    print(f"trained {total} steps in {elapsed:.0f} s ({total / max(elapsed, 1e-9):.0f} steps/s)")
    print(f"model:       {model_path}")
    print(f"config:      {run_dir / 'config.yaml'}")
    print(f"tensorboard: {Path(out or config.output_dir) / 'tensorboard'}")
    return model_path
