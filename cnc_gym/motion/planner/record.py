"""The planner's output record: the override to command at each path position (every planner version)."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np


@dataclass
class Schedule:
    """The planner's result for one program: override to command at each path position."""

    s: np.ndarray  # grid of path positions, mm
    cap_mm_s: np.ndarray  # tolerance speed cap (after refinement)
    speed_mm_s: np.ndarray  # scheduled (reachable) speed
    override: np.ndarray  # speed / programmed feed, clipped to [0, max_override]
    iterations: int = 0
    predicted_violations: int = 0

    @cached_property
    def time_s(self) -> float:
        """The schedule's own time over the path: ``Σ 2 Δs / (v_i + v_{i+1})`` of the scheduled speed on
        the grid (constant acceleration between grid points; dwells not counted). An estimate of the
        deployable planner's cycle time, not a simulation of it."""
        s = np.asarray(self.s, dtype=np.float64)
        v = np.asarray(self.speed_mm_s, dtype=np.float64)
        if s.size < 2:
            return 0.0
        mean = 0.5 * (v[1:] + v[:-1])
        moving = mean > 0.0
        return float(np.sum(np.diff(s)[moving] / mean[moving]))

    @cached_property
    def table(self) -> np.ndarray:
        """(n, 2) rows of path position and override: the table the compiled rule reads
        (:func:`~cnc_gym.motion.planner.rule.planner_override`)."""
        return np.column_stack((np.asarray(self.s, dtype=np.float64),
                                np.asarray(self.override, dtype=np.float64)))  # fmt: skip
