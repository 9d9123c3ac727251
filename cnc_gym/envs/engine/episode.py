"""Whole episodes in compiled code: the knob of a deployable policy turned inside the step loop.

A policy with no Python in its loop (a constant override, the deployable planner's schedule) is a
:class:`KnobRule`: a small record naming a constant knob, or a schedule table with the planner's reaction
lead, reach and knob range. :func:`run_steps` runs env 0 of a batch step after step under such a rule in
one compiled call (:meth:`~cnc_gym.envs.engine.batch.FeedrateBatch.run_rule`), up to a number of steps,
the episode's end or a simulated time, and writes the info values a caller records (a progress bar, a
plot's series) one row per step.

Each step is the batch's own compiled step (:func:`~cnc_gym.envs.engine.step.run_serial`) on the action
the Python loop would have given it: the rule reads the last step's ``path_s`` and ``feed_mm_min`` (the
info values a policy reads), asks the planner's one knob rule
(:func:`~cnc_gym.motion.planner.planner_override`) and rounds the override to the action space's float32
and clips it with :func:`knob_of_override`, as the policy does; the return is
summed in the same order. So an episode run here is the Python loop's, bit for bit
(``tests/envs/engine/test_episode.py``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numba import njit

from cnc_gym.envs.engine.layout import F_OUT, OUTPUT_INFO_KEYS
from cnc_gym.envs.engine.step import run_serial, step_arrays
from cnc_gym.motion.planner.rule import planner_override

#: Why :func:`run_steps` returned: it ran its steps (the episode goes on), the episode ended (terminated or
#: truncated), it reached the simulated time it was given, or the rule asked for a knob that is not a
#: number (the step that would take it is not run: the Python loop raises the env's ``ActionError``).
RAN, ENDED, STOPPED, NOT_FINITE = 0, 1, 2, 3

# Columns of the step's outputs (from F_OUT): reward, terminated, truncated, then the info values.
_OUT_CYCLE = 3 + OUTPUT_INFO_KEYS.index("cycle_time_s")
_OUT_FEED = 3 + OUTPUT_INFO_KEYS.index("feed_mm_min")
_OUT_PATH_S = 3 + OUTPUT_INFO_KEYS.index("path_s")


@dataclass(frozen=True, eq=False)
class KnobRule:
    """How a deployable policy turns the knob, as data: a constant knob value, or a schedule.

    ``schedule``: (n, 2) rows of path position and override (the planner's
    :attr:`Schedule.table <cnc_gym.motion.planner.schedule.Schedule.table>`), read by the planner's knob
    rule with ``lead_s`` and ``reach_mm`` and rounded to the knob of ``max_override``; empty: the knob is
    ``constant`` (an action value in [-1, 1], as the env reads it: float32 precision).
    """

    constant: float = 0.0
    schedule: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    lead_s: float = 0.0
    reach_mm: float = 0.0
    max_override: float = 2.0

    @classmethod
    def hold(cls, knob: float) -> KnobRule:
        """The knob held at ``knob`` for the whole episode."""
        return cls(constant=float(knob))

    @classmethod
    def follow(cls, schedule: np.ndarray, lead_s: float, reach_mm: float, max_override: float) -> KnobRule:
        """The knob of the planner's schedule ``schedule`` (see the class docstring)."""
        table = np.ascontiguousarray(schedule, dtype=np.float64)
        if table.ndim != 2 or table.shape[1] != 2 or not len(table):
            raise ValueError(f"a schedule table has (n >= 1, 2) rows, got shape {table.shape}")
        return cls(schedule=table, lead_s=float(lead_s), reach_mm=float(reach_mm),
                   max_override=float(max_override))  # fmt: skip


@njit(cache=True, nogil=True)
def knob_of_override(override: float, max_override: float) -> float:
    """The knob value in [-1, 1] that asks for ``override``, rounded to the action space's float32 and
    clipped: :func:`cnc_gym.envs.options.knob_of_override`, compiled (the one definition of both)."""
    return float(np.float32(min(max(2.0 * override / max_override - 1.0, -1.0), 1.0)))


@njit(cache=True, nogil=True)
def run_steps(address, constant, schedule, lead_s, reach_mm, max_override, max_steps, stop_time_s, columns,
              rows, total):  # fmt: skip
    """Step env 0 of a batch (its other envs are stepped too: a batch of one is what this is for), whose
    arrays are described at ``address`` (:func:`~cnc_gym.envs.engine.step.describe`), under a knob rule
    (:class:`KnobRule`'s fields) up to ``max_steps`` steps: ``(steps, total, why)``, ``total`` the return so
    far (``total`` plus each step's reward, in order), ``why`` one of :data:`RAN`,
    :data:`ENDED`, :data:`STOPPED`, :data:`NOT_FINITE`. After each step, row ``k`` of ``rows`` gets the
    info values of output columns ``columns`` (indices into ``OUTPUT_INFO_KEYS``). ``stop_time_s``: stop
    after the step whose cycle time reaches it, less 1 ns, unless that step terminated the episode (inf:
    never), as ``cnc-gym run --max-time`` does."""
    _, _, sf, _, _, _, _, _, actions, _, _, _ = step_arrays(address)
    out = sf[0, F_OUT:]
    follow = schedule.shape[0] > 0
    for k in range(max_steps):
        if follow:
            override = planner_override(schedule, out[_OUT_PATH_S], out[_OUT_FEED], lead_s, reach_mm)
            if override != override:
                return k, total, NOT_FINITE
            knob = knob_of_override(override, max_override)  # as the policy rounds it
        else:
            knob = constant
        actions[0] = min(max(knob, -1.0), 1.0)
        # A typed True, not the literal: numba would compile the step (its whole tree of kernels) a second
        # time for Literal[bool](True), beside the (int64, bool) one the batch's own calls use.
        run_serial(address, np.bool_(True))
        total += out[0]
        for j in range(columns.shape[0]):
            rows[k, j] = out[3 + columns[j]]
        terminated = out[1] != 0.0
        if not terminated and out[_OUT_CYCLE] >= stop_time_s - 1e-9:
            return k + 1, total, STOPPED
        if terminated or out[2] != 0.0:
            return k + 1, total, ENDED
    return max_steps, total, RAN


def _dependencies() -> None:
    from cnc_gym.envs.engine import bank, layout, step
    from cnc_gym.motion import kernel
    from cnc_gym.motion.planner import rule
    from cnc_gym.numba_cache import refresh_on_change
    from cnc_gym.plant import contour, servo
    from cnc_gym.toolpath import nearest

    refresh_on_change(__name__, [layout, bank, step, kernel, servo, contour, nearest, rule])


_dependencies()  # the driver links the step, and with it everything the step links: drop it when one of
# them changes
