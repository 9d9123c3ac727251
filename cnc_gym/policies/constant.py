"""The simplest baseline: the operator leaves the override knob at one value for the whole program."""

from __future__ import annotations

from typing import Any

import numpy as np

from cnc_gym.envs.engine import KnobRule
from cnc_gym.errors import CncGymError
from cnc_gym.policies.base import override_action, require_override_mode


class ConstantOverride:
    """Hold the feed override at ``override`` (1.0 = 100 %) for the whole episode."""

    def __init__(self, override: float) -> None:
        override = float(override)
        if not np.isfinite(override) or not 0.0 <= override <= 2.0:
            raise CncGymError(f"constant override must be within 0..2 (0 %..200 %), got {override!r}")
        self.override = override
        self.name = f"constant:{override:g}"
        self._action = override_action(override)

    def reset(self, env: Any) -> None:
        require_override_mode(env, self.name)
        max_override = float(env.unwrapped.machine.controller.max_override)
        if self.override > max_override + 1e-12:
            raise CncGymError(f"{self.name}: above this machine's max override {max_override:g}")
        self._action = override_action(self.override, max_override)

    def act(self, observation: np.ndarray, info: dict[str, Any]) -> np.ndarray:
        return self._action.copy()

    def knob_rule(self) -> KnobRule | None:
        """The knob :meth:`act` gives, held (the rollout runs the episode in compiled code:
        :func:`cnc_gym.rollout.compiled_rule`); None for a subclass with an ``act`` of its own."""
        if type(self).act is not ConstantOverride.act:
            return None
        return KnobRule.hold(float(self._action[0]))
