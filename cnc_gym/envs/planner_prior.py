"""The deployable planner as a part of ``cnc_gym/Feedrate-v1``, ``-v2`` and ``-v3``: its override as an
observation entry and, in the ``residual`` action mode, the knob the agent scales. Each env id names its
planner version (v1 and v2 planner version 1, frozen; v3 the live planner, version 2).

The planner is the motion stage's service (:mod:`cnc_gym.motion.planner`), the one the ``classical``
baseline policy follows: it reads the program, the machine parameters and the controller's static
tables, never the env's dynamics, so it is what a real controller could run in its look-ahead, and giving
its answer to a policy gives the policy nothing a machine would not have. This module is the env's one
seam to it: :class:`PlannerPrior` plans a program once per (tool path, machine), when the program is
packed for the compiled step, and hands the step its schedule as a table
(:class:`~cnc_gym.envs.engine.bank.Planner`); the step answers "what would the planner command now" every
control period with the planner's one knob rule (:func:`cnc_gym.motion.planner.planner_override`, with
the same reaction lead), and the residual action rounds the knob as the policy does
(:func:`~cnc_gym.envs.options.knob_of_override`), so the residual action 0 reproduces the ``classical``
baseline's episode exactly (``tests/envs/test_feedrate_v1.py``).
"""

from __future__ import annotations

import numpy as np

from cnc_gym.envs.options import knob_of_override
from cnc_gym.machine import MachineConfig
from cnc_gym.motion.limits import PathLimits
from cnc_gym.motion.planner import Schedule, SchedulePlanner, reaction_lead_s
from cnc_gym.toolpath import Toolpath

#: Schedules kept (by tool path and machine); a randomised machine makes a new one every episode.
_CACHE_SIZE = 64


class PlannerPrior:
    """The planner's schedules, for the compiled step (:class:`~cnc_gym.envs.engine.bank.Planner`)."""

    def __init__(self, control_period_s: float, max_override: float, version: int) -> None:
        self.max_override = float(max_override)
        self.lead_s = reaction_lead_s(control_period_s)
        self._planner = SchedulePlanner(cache_size=_CACHE_SIZE, version=version)
        #: The planner version (:data:`cnc_gym.motion.planner.PLANNERS`) and its margin.
        self.version = self._planner.version
        self.margin = self._planner.margin
        #: How far beyond the reaction lead the version's knob rule looks, mm.
        self.reach_mm = self._planner.reach_mm
        #: The machine the planner plans with in place of the env's (None: the env's): the benchmark's
        #: tracks whose plant differs from the parameter table give the nominal machine.
        self.nominal_machine: MachineConfig | None = None

    def schedule(self, toolpath: Toolpath, machine: MachineConfig, limits: PathLimits | None) -> Schedule:
        """The planner's schedule of ``toolpath`` on ``machine`` (or on :attr:`nominal_machine` when
        set), planned or recalled."""
        return self._planner.schedule(toolpath, self.nominal_machine or machine, limits)

    def schedule_table(self, toolpath: Toolpath, machine: MachineConfig,
                       limits: PathLimits | None) -> np.ndarray:  # fmt: skip
        """The schedule as the compiled step reads it: (n, 2) rows of path position and override."""
        return self.schedule(toolpath, machine, limits).table

    def knob(self, override: float) -> float:
        """The knob value of ``override`` as the classical policy rounds it (float32, clipped)."""
        return knob_of_override(override, self.max_override)
