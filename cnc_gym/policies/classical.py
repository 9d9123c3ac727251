"""The classical baseline: the deployable planner (:mod:`cnc_gym.motion.planner`) as an override policy.

The policy plans each program once (the planner's :class:`~cnc_gym.motion.planner.SchedulePlanner`,
from the program, the machine parameters and the controller's static tables: never the env's dynamics)
and turns the knob by the planner's one rule (:func:`~cnc_gym.motion.planner.planner_override`), the rule
the env's planner observation entry and ``residual`` action mode evaluate too.

The simulate-and-correct planner that used to be the baseline refines this kind of schedule by running
copies of the env: it is :class:`cnc_gym.policies.oracle.OraclePlanner`, an oracle, not deployable.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from cnc_gym.envs.engine import KnobRule
from cnc_gym.machine import MachineConfig
from cnc_gym.motion.planner import PLANNER_VERSION, Schedule, SchedulePlanner, override_at, reaction_lead_s
from cnc_gym.policies.base import override_action, require_override_mode
from cnc_gym.toolpath import Toolpath


class ClassicalPlanner:
    """The deployable planner as a feed-override policy, named ``classical``.

    ``margin``: the fraction of the contour tolerance the schedule aims at (None: the planner version's
    own); ``reaction_time_s``: how far ahead (in time) the knob anticipates the schedule (default: the
    planner's reaction lead, two control periods + 10 ms); ``version``: the planner version (default the
    live one; 1 is the frozen planner of Feedrate-v1 and v2, :data:`cnc_gym.motion.planner.PLANNERS`).

    ``nominal_machine``: the machine the planner plans with (None: the env's). The benchmark's tracks
    whose plant differs from the machine's parameter table set it to the nominal machine: a deployed
    planner knows the table, not the true plant.
    """

    deterministic = True

    def __init__(self, margin: float | None = None, reaction_time_s: float | None = None,
                 version: int = PLANNER_VERSION) -> None:  # fmt: skip
        self.name = "classical"
        self.reaction_time_s = reaction_time_s
        self.schedule: Schedule | None = None
        self._planner = SchedulePlanner(margin, version=version)
        self.margin = self._planner.margin
        self.version = self._planner.version
        self._max_override = 2.0
        self._lead_s = reaction_lead_s(0.01)
        self.nominal_machine: MachineConfig | None = None

    def reset(self, env: Any) -> None:
        base, toolpath, machine, _ = knob_setup(self, env)
        # The controller's static tables (what its look-ahead knows); never the env's dynamics.
        limits = getattr(getattr(base, "controller", None), "limits", None)
        self.schedule = self._planner.schedule(toolpath, self.nominal_machine or machine, limits)

    def act(self, observation: np.ndarray, info: dict[str, Any]) -> np.ndarray:
        return override_action(override_at(self.schedule, float(info.get("path_s", 0.0)),
                                           float(info.get("feed_mm_min", 0.0)), self._lead_s,
                                           self._planner.reach_mm),
                               self._max_override)  # fmt: skip

    def knob_rule(self) -> KnobRule | None:
        """The knob :meth:`act` gives, as data: the schedule with the reaction lead, the reach and the knob
        range :meth:`act` reads it with (the rollout runs the episode in compiled code, by the same knob
        rule: :func:`cnc_gym.rollout.compiled_rule`); None before a reset, or for a subclass with an
        ``act`` of its own."""
        if self.schedule is None or type(self).act is not ClassicalPlanner.act:
            return None
        return KnobRule.follow(self.schedule.table, self._lead_s, self._planner.reach_mm, self._max_override)


def knob_setup(planner: Any, env: Any) -> tuple[Any, Toolpath, MachineConfig, float]:
    """What a schedule-following planner reads from a just-reset env (the unwrapped env, its tool path,
    machine and control period); sets the planner's knob range and reaction lead (``reaction_time_s``, or
    the planner's :func:`~cnc_gym.motion.planner.reaction_lead_s`)."""
    require_override_mode(env, planner.name)
    base = env.unwrapped
    period = float(getattr(base, "control_period_s", 0.01))
    planner._max_override = float(base.machine.controller.max_override)
    lead = planner.reaction_time_s
    planner._lead_s = lead if lead is not None else reaction_lead_s(period)
    return base, base.toolpath, base.machine, period
