"""The planner's knob rule: what override a schedule asks for at a path position, compiled once.

The same function answers for the ``classical`` baseline policy, for the env's planner observation entry
and for the ``residual`` action mode (both from inside the env's compiled step), so the three can never
drift apart: :func:`planner_override`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numba import njit

if TYPE_CHECKING:
    from cnc_gym.motion.planner.schedule import Schedule

#: The reaction lead (how far ahead in time the knob anticipates the schedule) is this many control
#: periods ...
REACTION_PERIODS = 2.0
#: ... plus this much, s.
REACTION_MARGIN_S = 0.01
#: How much farther than the reaction lead the knob of planner versions 1 and 2 looks, mm (at a few mm/s
#: that is tenths of a second of crawl before every slow stretch; version 3 bakes its anticipation into
#: the schedule at the scheduled speed and looks no farther: :func:`rule_reach_mm`).
REACH_MM_V1 = 0.5


def reaction_lead_s(control_period_s: float) -> float:
    """The reaction lead at a control period: two control periods + 10 ms (the one default of the
    ``classical`` policy, the env's planner entry and the ``residual`` action mode)."""
    return REACTION_PERIODS * float(control_period_s) + REACTION_MARGIN_S


def rule_reach_mm(version: int) -> float:
    """The knob's look beyond the reaction lead for planner ``version``, mm (:data:`REACH_MM_V1`)."""
    return REACH_MM_V1 if version <= 2 else 0.0


@njit(cache=True, nogil=True)
def planner_override(schedule: np.ndarray, path_s: float, feed_mm_min: float, lead_s: float,
                     reach_mm: float) -> float:  # fmt: skip
    """A schedule's override at path position ``path_s`` moving at ``feed_mm_min``: the smallest scheduled
    override over the stretch covered in ``lead_s`` at the current speed and ``reach_mm`` more
    (:func:`rule_reach_mm`).

    ``schedule``: (n, 2) rows of path position (mm, ascending) and the override scheduled from there on
    (:attr:`Schedule.table <cnc_gym.motion.planner.schedule.Schedule.table>`). A NaN override in the
    stretch is the answer, as ``np.min`` would give it.
    """
    speed = max(feed_mm_min / 60.0, 1.0)
    n = schedule.shape[0]
    lo = _count_at_most(schedule, path_s) - 1
    hi = _count_at_most(schedule, path_s + speed * lead_s + reach_mm)
    lo = min(max(lo, 0), n - 1)
    lowest = schedule[lo, 1]
    for i in range(lo + 1, max(hi, lo + 1)):
        x = schedule[i, 1]
        if x < lowest or x != x:  # (NaN wins, as in np.min)
            lowest = x
            if x != x:
                break
    return lowest


@njit(cache=True, nogil=True, inline="always")
def _count_at_most(schedule: np.ndarray, x: float) -> int:
    """How many positions of ``schedule`` are ≤ x (``np.searchsorted(s, x, side="right")``; NaN: all)."""
    lo, hi = 0, schedule.shape[0]
    while lo < hi:
        mid = (lo + hi) >> 1
        if x < schedule[mid, 0]:
            hi = mid
        else:
            lo = mid + 1
    return lo


def override_at(schedule: Schedule | None, path_s: float, feed_mm_min: float, lead_s: float,
                reach_mm: float) -> float:  # fmt: skip
    """:func:`planner_override` of a :class:`~cnc_gym.motion.planner.schedule.Schedule` (a policy's
    call; an env's compiled step reads the table itself)."""
    if schedule is None:
        raise RuntimeError("the planner's reset(env) must be called before act()")
    return float(planner_override(schedule.table, float(path_s), float(feed_mm_min), float(lead_s),
                                  float(reach_mm)))  # fmt: skip
