"""Task configs (``configs/tasks/*.yaml``): what :class:`~cnc_gym.envs.FeedrateEnv` runs and how it is
rewarded.

A task file names a program set, a dialect, a machine, the action mode, the control period and the
reward weights. It is read with the bounded safe loader of :mod:`cnc_gym.config`; its keys are declared
below with the same specs as the env's arguments (:mod:`cnc_gym.envs.options`), so unknown keys, wrong
types and out-of-range values are one :class:`~cnc_gym.errors.ConfigError` line naming the file and the
key (docs/configs.md lists them).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from cnc_gym.config import check_object, configs_dir, declared, from_mapping, read_yaml, section, shown, text
from cnc_gym.envs.options import (
    ACTION_MODE,
    ACTION_MODES,
    CONTROL_PERIOD,
    DEFAULT_ACTION_MODE,
    DEFAULT_CONTROL_PERIOD_S,
    DIALECT,
    MACHINE_NAME,
    PROGRAM_NAMES,
    SOURCE,
    RewardWeights,
)
from cnc_gym.errors import ConfigError
from cnc_gym.machine import DEFAULT_MACHINE
from cnc_gym.programs import DEFAULT_DIALECT

__all__ = ["ACTION_MODES", "RewardWeights", "TaskConfig", "load_task", "resolve_reward", "reward_from_dict",
           "task_from_dict", "task_path"]  # fmt: skip


@dataclass(frozen=True)
class TaskConfig:
    """One task: what the env runs and how it is rewarded."""

    name: str = text("default", doc="the task's name")
    description: str = text("", max_length=4096, doc="one paragraph for people")
    programs: tuple[str, ...] = declared(PROGRAM_NAMES, default_factory=lambda: ("circle", "star", "freeform",
                                                                                  "pocket"))  # fmt: skip
    dialect: str = declared(DIALECT, DEFAULT_DIALECT)
    machine: str = declared(MACHINE_NAME, DEFAULT_MACHINE)
    action_mode: str = declared(ACTION_MODE, DEFAULT_ACTION_MODE)
    control_period_s: float = declared(CONTROL_PERIOD, DEFAULT_CONTROL_PERIOD_S)
    reward: RewardWeights = section(RewardWeights, doc="reward weights (docs/env.md, Reward)")  # noqa: RUF009
    source: str = "<defaults>"


def task_path(name_or_path: str | Path) -> Path:
    """A task by name (``default`` → ``configs/tasks/default.yaml``) or a YAML path."""
    path = Path(name_or_path)
    if path.suffix in (".yaml", ".yml"):
        return path
    path = configs_dir() / "tasks" / f"{name_or_path}.yaml"
    if not str(name_or_path) or not path.is_file():
        names = sorted(p.stem for p in (configs_dir() / "tasks").glob("*.yaml"))
        raise ConfigError(f"unknown task {shown(str(name_or_path))}; tasks: {', '.join(names)}")
    return path


def load_task(name_or_path: str | Path = "default") -> TaskConfig:
    """Load and validate a task file (by name under ``configs/tasks/`` or by path)."""
    path = task_path(name_or_path)
    data = read_yaml(path, "task config")
    return task_from_dict(data, source=str(path))


def task_from_dict(data: Any, source: str = "<dict>") -> TaskConfig:
    """Build and check a task from the data of a task file."""
    return from_mapping(TaskConfig, data, source, "", {"source": source})


def reward_from_dict(data: Any, source: str = "<dict>") -> RewardWeights:
    """Validate a mapping of reward weights (all optional; unknown keys are errors)."""
    return from_mapping(RewardWeights, data, source, "reward")


def resolve_reward(reward: str | os.PathLike | dict | RewardWeights | None) -> RewardWeights:
    """The env's ``reward`` argument: None (the default task's weights), a task file, a dict or weights."""
    if reward is None:
        return load_task("default").reward
    if isinstance(reward, RewardWeights):
        check_object(reward, SOURCE, "reward")
        return reward
    if isinstance(reward, dict):
        return reward_from_dict(reward, SOURCE)
    if isinstance(reward, str | os.PathLike):
        return load_task(reward if isinstance(reward, str) else Path(reward)).reward
    raise ConfigError(f"{SOURCE}: reward must be None, a task YAML path or a dict of weights, "
                      f"got {type(reward).__name__}")  # fmt: skip
