"""Task configs (``configs/tasks/*.yaml``) and the reward weights of :class:`~cnc_gym.envs.FeedrateEnv`.

A task file names a program set, a dialect, a machine, the action mode, the control period and the
reward weights. It is read with ``yaml.safe_load``; unknown keys, wrong types and out-of-range values
are :class:`~cnc_gym.errors.ConfigError` naming the file and the key.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from cnc_gym.config import check_keys, configs_dir, read_yaml
from cnc_gym.errors import ConfigError

ACTION_MODES = ("override", "feed")


@dataclass(frozen=True)
class RewardWeights:
    """Reward weights, per control step:
    ``r = -time·dt/T + progress·Δp - contour_error·min(e/tol, cap)² - violation·[e > tol]``
    (Δp: path progress in the step as a fraction of the program's length; see FeedrateEnv's docstring).
    """

    time: float = 10.0  # whole-episode time cost at nominal (100 %) speed
    contour_error: float = 0.05  # per step, per (e_max / tol)²
    violation: float = 1.0  # per control step whose contour error exceeds the tolerance
    error_ratio_cap: float = 10.0  # e_max / tol is capped here so one bad step cannot dominate a return
    # Paid per unit of path progress; sums to exactly this over a finished episode whatever the policy,
    # so it leaves the undiscounted ranking of finishing policies unchanged but pays for progress when it
    # happens, which a discounted (γ < 1) learner needs to see that slow costs (see docs/env.md).
    progress: float = 10.0


@dataclass(frozen=True)
class TaskConfig:
    """One task: what the env runs and how it is rewarded."""

    name: str = "default"
    description: str = ""
    programs: tuple[str, ...] = ("circle", "star", "freeform", "pocket")
    dialect: str = "gsk25i"
    machine: str = "vmc-small"
    action_mode: str = "override"
    control_period_s: float = 0.01
    reward: RewardWeights = field(default_factory=RewardWeights)
    source: str = "<defaults>"


def task_path(name_or_path: str | Path) -> Path:
    """A task by name (``default`` → ``configs/tasks/default.yaml``) or a YAML path."""
    path = Path(name_or_path)
    if path.suffix in (".yaml", ".yml"):
        return path
    path = configs_dir() / "tasks" / f"{name_or_path}.yaml"
    if not path.exists():
        names = sorted(p.stem for p in (configs_dir() / "tasks").glob("*.yaml"))
        raise ConfigError(f"unknown task {name_or_path!r}; tasks: {', '.join(names)}")
    return path


def load_task(name_or_path: str | Path = "default") -> TaskConfig:
    """Load and validate a task file (by name under ``configs/tasks/`` or by path)."""
    path = task_path(name_or_path)
    data = read_yaml(path, "task config")
    return task_from_dict(data, source=str(path))


def task_from_dict(data: Any, source: str = "<dict>") -> TaskConfig:
    if not isinstance(data, dict):
        raise ConfigError(f"{source}: a task config must be a mapping")
    allowed = {"name", "description", "programs", "dialect", "machine", "action_mode", "control_period_s",
               "reward"}  # fmt: skip
    check_keys(data, allowed, source, "")
    values: dict[str, Any] = {"source": source}
    for key in ("name", "description", "dialect", "machine", "action_mode"):
        if key in data:
            if not isinstance(data[key], str):
                raise ConfigError(f"{source}: {key} must be a string, got {data[key]!r}")
            values[key] = data[key]
    if values.get("action_mode", "override") not in ACTION_MODES:
        raise ConfigError(f"{source}: action_mode must be one of {', '.join(ACTION_MODES)}")
    if "programs" in data:
        programs = data["programs"]
        if isinstance(programs, str):
            programs = [programs]
        if not isinstance(programs, list) or not programs or not all(isinstance(p, str) for p in programs):
            raise ConfigError(f"{source}: programs must be a non-empty list of names or paths")
        values["programs"] = tuple(programs)
    if "control_period_s" in data:
        values["control_period_s"] = _positive_number(data["control_period_s"], source, "control_period_s")
    if "reward" in data:
        values["reward"] = reward_from_dict(data["reward"], source)
    return TaskConfig(**values)


def reward_from_dict(data: Any, source: str = "<dict>") -> RewardWeights:
    """Validate a mapping of reward weights (all optional; unknown keys are errors)."""
    if not isinstance(data, dict):
        raise ConfigError(f"{source}: reward must be a mapping of weights")
    names = ("time", "progress", "contour_error", "violation", "error_ratio_cap")
    check_keys(data, set(names), source, "reward")
    values = {}
    for key, raw in data.items():
        if isinstance(raw, bool) or not isinstance(raw, int | float) or not math.isfinite(raw) or raw < 0:
            raise ConfigError(f"{source}: reward.{key} must be a finite number >= 0, got {raw!r}")
        values[key] = float(raw)
    if values.get("error_ratio_cap", 1.0) <= 0:
        raise ConfigError(f"{source}: reward.error_ratio_cap must be positive")
    return RewardWeights(**values)


def resolve_reward(reward: str | Path | dict | RewardWeights | None) -> RewardWeights:
    """The env's ``reward`` argument: None (the default task's weights), a task file, a dict or weights."""
    if reward is None:
        return load_task("default").reward
    if isinstance(reward, RewardWeights):
        return reward
    if isinstance(reward, dict):
        return reward_from_dict(reward, "reward")
    if isinstance(reward, str | Path):
        return load_task(reward).reward
    raise ConfigError(
        f"reward must be None, a task YAML path or a dict of weights, got {type(reward).__name__}"
    )


def _positive_number(raw: Any, source: str, key: str) -> float:
    if isinstance(raw, bool) or not isinstance(raw, int | float) or not math.isfinite(raw) or raw <= 0:
        raise ConfigError(f"{source}: {key} must be a positive number, got {raw!r}")
    return float(raw)
