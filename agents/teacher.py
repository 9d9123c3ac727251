"""The teacher: the oracle held to the student's action range, planning on the episode's true plant.

:class:`ResidualOracle` is :class:`cnc_gym.policies.oracle.OraclePlanner` (simulate-and-correct on copies
of the exact env) acting in the ``residual`` action mode: at every step it asks for the oracle's override,
held within ``[ov_plan / ρ, ov_plan · ρ]`` of the deployable planner's override ``ov_plan`` (the range a
residual policy with ``residual_range = ρ`` can reach), as the residual action

    a* = clip(log(ov_oracle / ov_plan) / log ρ, −1, 1).

It plans with that restriction in force: the oracle's simulations run this very policy (the oracle runs
``self.act`` in its copies of the env), so its corrections see the clipped knob, and the schedule it
converges to is the best one it finds *within the student's reach*. It plans on ``env.unwrapped``, the
episode the student is in: the machine drawn for it by the env's domain randomisation, its feed scale and
its plant, so every randomised machine gets a teacher of its own. Nothing here edits the oracle: this
class only changes how its knob is spoken (residual instead of override) and drops the override-mode
check of :func:`~cnc_gym.policies.classical.knob_setup`.

With ``planner_floor`` the teacher is never slower than the deployable planner where the planner's run of
the episode keeps within the teacher's target. The oracle plans against the contour error, not against
time: it starts from the servo model's speed cap and raises only a little, so on some programs it stays
below a planner that was already clean (docs/training.md, the loop). The teacher then runs the planner
(the residual action 0) on a copy of the episode, marks the stretches of path behind each step where the
planner's contour error exceeds the teacher's target (``margin`` × tolerance, what the oracle aims at; the
stretch is the oracle's own correction window), and elsewhere acts at ``max(a*, 0)``: at the planner's
override, or the oracle's where it is faster. It simulates that combined schedule and, for a few rounds,
hands every stretch where its error exceeded the target back to the oracle, until a round adds none; if
none is found within the rounds, or the last run cuts more steps over tolerance than the oracle's own
schedule, the episode keeps the oracle alone.

What the teacher knows that the student does not: the whole program (not a 24 mm preview), and the exact
plant of the episode, which it simulates to the end before the first step. The student only sees the
env's observation (docs/env.md).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from cnc_gym.errors import CncGymError
from cnc_gym.motion.planner import ServoErrorModel, reaction_lead_s
from cnc_gym.policies.oracle import OraclePlanner


def residual_label(oracle_override: float, planner_override: float, residual_range: float,
                   limit: float = 1.0) -> float:  # fmt: skip
    """The residual action that asks for ``oracle_override`` given the planner's ``planner_override``:
    ``log(oracle / planner) / log(residual_range)``, clipped to [-limit, limit] (the action box is
    ``limit`` 1; a larger limit keeps how far beyond the box the oracle would go, a regression target
    that saturates the student's action firmly where the oracle is far past the range). Where the
    planner commands nothing (0: a stop, or no planner) any action gives the same override; the label
    is then 0."""
    if not planner_override > 1e-9 or not math.isfinite(planner_override):
        return 0.0
    if not oracle_override > 0.0:
        return -limit
    if not math.isfinite(oracle_override):
        return limit
    a = math.log(oracle_override / planner_override) / math.log(residual_range)
    return min(max(a, -limit), limit)


class ResidualOracle(OraclePlanner):
    """The oracle restricted to the residual range ``ρ``, as a ``residual``-mode policy (module docstring).

    ``margin``, ``refine_iterations`` and ``raise_rounds`` are the oracle's (the fraction of the contour
    tolerance it aims at, its simulate-and-correct rounds and its raising rounds); ``planner_floor``: never
    below the planner where the planner keeps within the target (module docstring). An **oracle**: it runs
    copies of the exact env, so it labels training data; it is never deployed.
    """

    deterministic = True
    #: Simulated rounds that hand stretches where the combined schedule's error went over the target back
    #: to the oracle (``planner_floor``).
    FLOOR_ROUNDS = 3

    def __init__(self, residual_range: float, margin: float = 0.85, refine_iterations: int = 12,
                 raise_rounds: int = 3, planner_floor: bool = False) -> None:  # fmt: skip
        super().__init__(margin=margin, refine_iterations=refine_iterations, raise_rounds=raise_rounds,
                         progress=False)  # fmt: skip
        if not residual_range > 1.0:
            raise CncGymError(f"residual oracle: residual_range must be above 1, got {residual_range}")
        self.name = "residual-oracle"
        self.residual_range = float(residual_range)
        self.planner_floor = bool(planner_floor)
        #: Per point of the schedule's grid: the planner keeps within the target there, so the teacher acts
        #: at ``max(a*, 0)`` (None: the oracle alone).
        self.floor: np.ndarray | None = None
        self._as_planner = False  # simulating the planner (the residual action 0)

    def reset(self, env: Any) -> None:
        """Plan the episode ``env`` was just reset to (its machine, feed scale and plant)."""
        base = self.attach(env)
        self._cache.clear()  # one schedule per episode: a randomised episode has a machine of its own
        self.floor = None
        self.schedule = self.plan(base.toolpath, base.machine, env=base)
        if self.planner_floor:
            self.floor = self._planner_floor(base)

    def _planner_floor(self, base: Any) -> np.ndarray | None:
        """Where the teacher acts at least at the planner's override (module docstring); None: nowhere."""
        schedule = self.schedule
        assert schedule is not None
        tolerance = float(base.machine.controller.contour_tolerance_mm)
        target = self.margin * tolerance
        lag_s = float(np.max(1.0 / ServoErrorModel(base.machine).kv))
        s = schedule.s

        def clear_behind(mask: np.ndarray, run: tuple[np.ndarray, np.ndarray, np.ndarray]) -> int:
            """Clear ``mask`` behind every step of ``run`` over the target; the steps over tolerance."""
            path_s, error, speed = run
            for k in np.flatnonzero(error > target):  # the oracle's correction window: the error builds
                back = max(2.0, 4.0 * float(speed[k]) * lag_s)  # up over the servo's settling distance
                mask[(s >= path_s[k] - back) & (s <= path_s[k] + 1.0)] = False
            return int(np.sum(error > tolerance))

        self._as_planner = True
        try:
            planner_run = self._simulate(base)
        finally:
            self._as_planner = False
        if planner_run is None:
            return None
        floor = np.ones(len(s), dtype=bool)
        clear_behind(floor, planner_run)
        for _ in range(self.FLOOR_ROUNDS):
            if not floor.any():
                return None
            self.floor = floor
            run = self._simulate(base)
            self.floor = None
            if run is None:
                return None
            simulated = floor.copy()
            over_tolerance = clear_behind(floor, run)
            if np.array_equal(floor, simulated):  # every step over the target lies in the oracle's stretches
                return simulated if over_tolerance <= schedule.predicted_violations else None
        return None

    def attach(self, env: Any) -> Any:
        """Drive ``env`` (just reset) with the schedule planned already, without planning again: for
        another env reset to the same episode (the same program, seed and settings). Returns the
        unwrapped env."""
        base = env.unwrapped
        mode = getattr(base, "action_mode", "override")
        if mode != "residual":
            raise CncGymError(f"{self.name} speaks the residual action; the env is in {mode!r} mode")
        have = float(base.residual_range)
        if not math.isclose(have, self.residual_range, rel_tol=1e-12):
            raise CncGymError(f"{self.name}: planned for residual_range {self.residual_range:g}, the env has "
                              f"{have:g}")  # fmt: skip
        # As knob_setup does for the override-mode oracle (whose mode check this skips).
        self._max_override = float(base.machine.controller.max_override)
        lead = self.reaction_time_s
        self._lead_s = lead if lead is not None else reaction_lead_s(float(base.control_period_s))
        return base

    def label(self, info: dict[str, Any], limit: float = 1.0) -> float:
        """The residual action the teacher takes at the state ``info`` describes (path position, speed and
        the planner's override for the next step); with ``limit`` > 1, how far beyond the action box the
        oracle would go, up to ``limit`` (:func:`residual_label`)."""
        if self._as_planner:
            return 0.0
        path_s = float(info.get("path_s", 0.0))
        oracle = self.override_at(path_s, info)
        label = residual_label(oracle, float(info.get("planner_override", 0.0)), self.residual_range, limit)
        if self.floor is not None and self.schedule is not None:
            index = min(max(int(np.searchsorted(self.schedule.s, path_s, side="right")) - 1, 0),
                        len(self.floor) - 1)  # fmt: skip
            if self.floor[index]:
                return max(label, 0.0)
        return label

    def act(self, observation: Any, info: dict[str, Any]) -> np.ndarray:
        return np.array([self.label(info)], dtype=np.float32)
