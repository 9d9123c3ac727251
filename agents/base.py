"""The policy protocol shared by the baselines, trained models and the runner.

A policy drives ``cnc_gym/Feedrate-v0`` exactly as an RL agent would: :meth:`Policy.reset` is called once
per episode, after ``env.reset()``, with the env (wrapped or not); :meth:`Policy.act` maps the latest
observation and ``info`` to the env action. Baselines and trained models therefore run through the same
code path (``cnc_gym.runner.simulate`` and ``scripts/evaluate.py``).
"""

from __future__ import annotations

from typing import Any, Protocol, runtime_checkable

import numpy as np

from cnc_gym.errors import CncGymError


@runtime_checkable
class Policy(Protocol):
    """Anything that can turn the feed-override knob of a Feedrate env."""

    #: Short human-readable name used in tables and plots (``constant:1.0``, ``classical``, a model file).
    name: str

    def reset(self, env: Any) -> None:
        """Prepare for a new episode; ``env`` has just been reset (``env.unwrapped`` gives the toolpath,
        machine and controller)."""

    def act(self, observation: np.ndarray, info: dict[str, Any]) -> np.ndarray:
        """The env action for this control step."""


def override_action(override: float, max_override: float = 2.0) -> np.ndarray:
    """Override-mode action for a knob value.

    The env maps a ∈ [-1, 1] to override ``(a + 1)/2 · max_override`` (0 %..200 % on the presets, where
    that is simply a + 1), so a = 2·override/max_override − 1, clipped to the action box.
    """
    return np.array([np.clip(2.0 * override / max_override - 1.0, -1.0, 1.0)], dtype=np.float32)


def require_override_mode(env: Any, policy_name: str) -> None:
    """Baselines speak the override knob; refuse an env in another action mode with one clear error."""
    mode = getattr(env.unwrapped, "action_mode", "override")
    if mode != "override":
        raise CncGymError(
            f"policy {policy_name!r} drives the feed-override knob; the env is in {mode!r} mode"
        )
