"""Shared helpers of the YAML configs (machines, tasks, training): one way to read and to check keys.

Every config is read with ``yaml.safe_load`` (never a loader that can build Python objects) and every
problem is a :class:`~cnc_gym.errors.ConfigError` that names the file and the key.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import yaml

from cnc_gym.errors import ConfigError


def configs_dir() -> Path:
    """The repository's ``configs/`` folder (set ``CNC_GYM_CONFIGS`` to use another)."""
    env = os.environ.get("CNC_GYM_CONFIGS")
    return Path(env) if env else Path(__file__).resolve().parent.parent / "configs"


def read_yaml(path: Path, what: str) -> Any:
    """The data of a YAML file, or ConfigError (``what`` names the kind of config in the message)."""
    try:
        return yaml.safe_load(Path(path).read_text())
    except OSError as exc:
        raise ConfigError(f"{path}: cannot read {what}: {exc.strerror}") from None
    except yaml.YAMLError as exc:
        raise ConfigError(f"{path}: invalid YAML: {exc}") from None


def check_keys(data: dict, allowed: Iterable[str], source: str, where: str = "") -> None:
    """ConfigError naming the first key of ``data`` that is not in ``allowed`` (``where`` = its parent)."""
    allowed = set(allowed)
    unknown = sorted(set(map(str, data)) - allowed)
    if unknown:
        prefix = f"{where}." if where else ""
        names = ", ".join(sorted(allowed))
        raise ConfigError(f"{source}: unknown key {prefix}{unknown[0]} (allowed: {names})")
