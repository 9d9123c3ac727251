"""The planner's one knob rule: the compiled function every user calls, against a numpy statement of it."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cnc_gym.machine import load_machine
from cnc_gym.motion.planner import (
    Schedule,
    override_at,
    plan_schedule,
    planner_override,
    reaction_lead_s,
    rule_reach_mm,
)
from cnc_gym.programs import load_program


def _numpy_rule(s: np.ndarray, override: np.ndarray, path_s: float, feed_mm_min: float,
                lead_s: float, reach_mm: float = 0.5) -> float:  # fmt: skip
    """The rule as written with numpy: the smallest override from the point at or before ``path_s`` to the
    last point within ``speed·lead_s + reach_mm`` ahead."""
    speed = max(feed_mm_min / 60.0, 1.0)
    lo = np.searchsorted(s, path_s, side="right") - 1
    hi = np.searchsorted(s, path_s + speed * lead_s + reach_mm, side="right")
    lo = min(max(lo, 0), len(s) - 1)
    return float(np.min(override[lo : max(hi, lo + 1)]))


positions = st.floats(-5.0, 120.0, allow_nan=False)


@settings(deadline=None)  # (the first call compiles)
@given(st.lists(st.floats(0.0, 2.0, allow_nan=False), min_size=1, max_size=40),
       st.floats(0.1, 5.0), positions, st.floats(0.0, 12000.0), st.floats(0.0, 0.2),
       st.sampled_from([0.0, 0.5, 1.7]))  # fmt: skip
def test_the_compiled_rule_is_the_numpy_rule(overrides, spacing, path_s, feed, lead, reach):
    override = np.array(overrides)
    s = np.cumsum(np.full(len(override), spacing)) - spacing
    table = np.column_stack((s, override))
    assert planner_override(table, path_s, feed, lead, reach) == _numpy_rule(s, override, path_s, feed, lead,
                                                                             reach)  # fmt: skip


def test_a_nan_in_the_stretch_is_the_answer_and_a_nan_position_reads_the_last_point():
    s = np.arange(5.0)
    override = np.array([1.0, np.nan, 0.5, 2.0, 0.7])
    table = np.column_stack((s, override))
    assert math.isnan(planner_override(table, 0.0, 0.0, 0.6, 0.5))
    assert planner_override(table, 2.0, 0.0, 0.0, 0.5) == 0.5
    assert planner_override(table, float("nan"), 0.0, 0.0, 0.5) == _numpy_rule(s, override, float("nan"), 0.0,
                                                                               0.0)  # fmt: skip


def test_a_schedule_of_a_real_program_answers_the_same_through_both_faces():
    machine = load_machine("vmc-small")
    _, toolpath = load_program("star", "gsk25i", machine)
    schedule = plan_schedule(toolpath, machine)
    lead = reaction_lead_s(0.01)
    for path_s in np.linspace(0.0, float(schedule.s[-1]), 97):
        for reach in (0.0, 0.5):
            expected = _numpy_rule(schedule.s, schedule.override, path_s, 3000.0, lead, reach)
            assert override_at(schedule, path_s, 3000.0, lead, reach) == expected


def test_the_reaction_lead_is_two_control_periods_and_ten_milliseconds():
    assert reaction_lead_s(0.01) == pytest.approx(0.03, rel=1e-12)
    assert reaction_lead_s(0.02) == pytest.approx(0.05, rel=1e-12)


def test_override_at_needs_a_schedule():
    with pytest.raises(RuntimeError, match="reset"):
        override_at(None, 0.0, 0.0, 0.03, 0.0)
    one = Schedule(s=np.zeros(1), cap_mm_s=np.ones(1), speed_mm_s=np.ones(1), override=np.ones(1))
    assert override_at(one, 10.0, 600.0, 0.03, 0.5) == 1.0


def test_versions_1_and_2_look_half_a_millimetre_farther_and_version_3_bakes_its_anticipation():
    assert rule_reach_mm(1) == rule_reach_mm(2) == 0.5
    assert rule_reach_mm(3) == 0.0
