"""What the baselines share: the policy protocol, the knob as an action, and the override-mode check.

A policy drives a Feedrate env exactly as an RL agent would: :meth:`Policy.reset` is called once per
episode, after ``env.reset()``, with the env (wrapped or not); :meth:`Policy.act` maps the latest
observation and ``info`` to the env action. The protocol is the rollout's (:mod:`cnc_gym.rollout`), the
one loop that runs baselines and trained models alike.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from cnc_gym.envs.options import knob_of_override
from cnc_gym.errors import CncGymError
from cnc_gym.rollout import Policy

__all__ = ["Policy", "override_action", "require_override_mode"]


def override_action(override: float, max_override: float = 2.0) -> np.ndarray:
    """Override-mode action for a knob value.

    The env maps a ∈ [-1, 1] to override ``(a + 1)/2 · max_override`` (0 %..200 % on the presets, where
    that is simply a + 1), so a = 2·override/max_override − 1, clipped to the action box
    (:func:`~cnc_gym.envs.options.knob_of_override`, the env's own rounding of the ``residual`` knob).
    """
    return np.array([knob_of_override(override, max_override)], dtype=np.float32)


def require_override_mode(env: Any, policy_name: str) -> None:
    """Baselines speak the override knob; refuse an env in another action mode with one clear error."""
    mode = getattr(env.unwrapped, "action_mode", "override")
    if mode != "override":
        raise CncGymError(
            f"policy {policy_name!r} drives the feed-override knob; the env is in {mode!r} mode"
        )
