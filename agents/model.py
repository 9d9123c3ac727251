"""Trained Stable-Baselines3 models as policies.

Models are loaded with SB3's own loader (``PPO.load``: a zip of JSON + ``torch.load(weights_only=True)``
tensors), never with raw pickle.
"""

from __future__ import annotations

import zipfile
from pathlib import Path
from typing import Any

import numpy as np

from cnc_gym.errors import CncGymError

#: Algorithms a model file may hold, tried in this order (their zips are interchangeable in layout).
_ALGORITHMS = ("PPO", "SAC", "TD3", "A2C")


def load_sb3_model(path: str | Path, device: str = "cpu") -> Any:
    """Load an SB3 model zip with SB3's loader; a missing or unreadable file is a CncGymError."""
    path = Path(path)
    if not path.is_file():
        raise CncGymError(f"{path}: no such model file")
    try:
        import stable_baselines3 as sb3
    except ImportError:  # pragma: no cover - rl extra not installed
        raise CncGymError("loading a trained model needs the rl extra: pip install -e '.[rl]'") from None
    if not zipfile.is_zipfile(path):
        raise CncGymError(f"{path}: not a Stable-Baselines3 model (an SB3 model is a .zip file)")
    errors = []
    for algo in _ALGORITHMS:
        try:
            return getattr(sb3, algo).load(str(path), device=device)
        except (ValueError, KeyError, TypeError, AssertionError) as exc:  # wrong algorithm for this zip
            errors.append(f"{algo}: {exc}")
        except Exception as exc:  # zipfile.BadZipFile, OSError ...
            raise CncGymError(
                f"{path}: not a Stable-Baselines3 model ({type(exc).__name__}: {exc})"
            ) from None
    raise CncGymError(f"{path}: cannot load as an SB3 model ({'; '.join(errors)[:300]})")


class ModelPolicy:
    """A trained SB3 model (deterministic actions) driving the env."""

    def __init__(self, path: str | Path, deterministic: bool = True) -> None:
        self.path = Path(path)
        self.name = self.path.name
        self.deterministic = deterministic
        self.model = load_sb3_model(self.path)

    def reset(self, env: Any) -> None:
        want = self.model.observation_space.shape
        have = env.observation_space.shape
        if want != have:
            raise CncGymError(
                f"{self.name}: model expects observations of shape {want}, the env gives {have}"
            )
        if self.model.action_space.shape != env.action_space.shape:
            raise CncGymError(f"{self.name}: model acts in shape {self.model.action_space.shape}, "
                              f"the env expects {env.action_space.shape}")  # fmt: skip

    def act(self, observation: np.ndarray, info: dict[str, Any]) -> np.ndarray:
        action, _ = self.model.predict(observation, deterministic=self.deterministic)
        return np.asarray(action, dtype=np.float32)
