"""The deployable planner as a part of ``cnc_gym/Feedrate-v1``: its override as an observation entry and,
in the ``residual`` action mode, the knob the agent scales.

The planner is the benchmark's ``classical`` baseline (:mod:`agents.classical`): it reads the program,
the machine parameters and the controller's static tables, never the env's dynamics, so it is what a
real controller could run in its look-ahead, and giving its answer to a policy gives the policy nothing
a machine would not have. This module is the env's one seam to it: :class:`PlannerPrior` plans a
program once per (tool path, machine), when the program is packed for the compiled step, and hands the
step its schedule as a table (:class:`~cnc_gym.envs.fused.Planner`); the step answers "what would the
planner command now" every control period with the ``classical`` policy's rule
(:func:`cnc_gym.envs.fused.planner_override`: same schedule, same reaction lead), and the residual action
rounds the knob as that policy does (:meth:`PlannerPrior.knob`), so the residual action 0 reproduces the
``classical`` baseline's episode exactly (``tests/envs/test_feedrate_v1.py``).

(The planner lives with the other policies under ``agents/``; it is imported on first use, as the
benchmark imports its policies.)
"""

from __future__ import annotations

from typing import Any

import numpy as np

from cnc_gym.machine import MachineConfig
from cnc_gym.toolpath import Toolpath

#: Schedules kept (by tool path and machine); a randomised machine makes a new one every episode.
_CACHE_SIZE = 64


class PlannerPrior:
    """The ``classical`` planner's schedules, for the compiled step (:class:`~cnc_gym.envs.fused.Planner`)."""

    def __init__(self, control_period_s: float, max_override: float) -> None:
        from agents.classical import MARGIN

        self.margin = MARGIN
        self.max_override = float(max_override)
        # The classical policy's reaction lead: two control periods + 10 ms (agents.classical.knob_setup).
        self.lead_s = 2.0 * float(control_period_s) + 0.01
        self._cache: dict[tuple[int, MachineConfig], tuple[Toolpath, Any]] = {}

    def schedule(self, toolpath: Toolpath, machine: MachineConfig, limits: Any) -> Any:
        """The planner's schedule of ``toolpath`` on ``machine`` (planned, or recalled)."""
        from agents.classical import plan_schedule

        key = (id(toolpath), machine)
        cached = self._cache.get(key)
        if cached is not None and cached[0] is toolpath:
            return cached[1]
        schedule = plan_schedule(toolpath, machine, limits=limits, margin=self.margin)
        if len(self._cache) >= _CACHE_SIZE:
            self._cache.pop(next(iter(self._cache)))
        self._cache[key] = (toolpath, schedule)  # keeps the tool path alive so its id stays unique
        return schedule

    def schedule_table(self, toolpath: Toolpath, machine: MachineConfig, limits: Any) -> np.ndarray:
        """The schedule as the compiled step reads it: (n, 2) rows of path position and override."""
        schedule = self.schedule(toolpath, machine, limits)
        return np.column_stack((np.asarray(schedule.s, dtype=np.float64),
                                np.asarray(schedule.override, dtype=np.float64)))  # fmt: skip

    def knob(self, override: float) -> float:
        """The knob value of ``override`` as the classical policy rounds it (float32, clipped)."""
        return float(np.float32(min(max(2.0 * override / self.max_override - 1.0, -1.0), 1.0)))
