"""The planner's schedule: the jerk-limited reach and scan against closed forms and a simulated S-curve,
and the schedule of a plain line."""

from __future__ import annotations

import math

import numpy as np
import pytest

from cnc_gym.machine import load_machine
from cnc_gym.motion.kernel import reach_speed
from cnc_gym.motion.planner import bidirectional_scan, plan_schedule
from cnc_gym.motion.planner.record import Schedule
from cnc_gym.programs import load_program


def _s_curve_distance(v0: float, v1: float, accel: float, jerk: float) -> float:
    """Distance of a jerk-limited ramp v0 → v1, integrated numerically (phases +J, 0, −J)."""
    dv = v1 - v0
    t_jerk = min(accel / jerk, math.sqrt(dv / jerk))
    t_const = max(0.0, dv / accel - accel / jerk) if t_jerk == accel / jerk else 0.0
    dt = 1e-6
    t_total = 2 * t_jerk + t_const
    t = np.arange(0.0, t_total, dt) + dt / 2
    j = np.where(t < t_jerk, jerk, np.where(t < t_jerk + t_const, 0.0, -jerk))
    a = np.cumsum(j) * dt
    v = v0 + np.cumsum(a) * dt
    return float(np.sum(v) * dt)


@pytest.mark.parametrize(("v0", "v1"), [(0.0, 5.0), (10.0, 40.0), (20.0, 150.0)])
def test_the_scans_reach_inverts_a_simulated_s_curve(v0, v1):
    # The scan solves the S-curve reach with the controller's own solver (kernel.reach_speed).
    accel, jerk = 3000.0, 30000.0  # A²/J = 300 mm/s: the first two cases never reach A, the third does
    distance = _s_curve_distance(v0, v1, accel, jerk)
    assert reach_speed(v0, distance, accel, jerk) == pytest.approx(v1, rel=2e-3)


def test_scan_with_huge_jerk_is_the_constant_acceleration_profile():
    # With J → ∞ the reach is v = √(v_c² + 2·A·d) on both sides of a single slow point.
    s = np.linspace(0.0, 100.0, 1001)
    cap = np.full_like(s, 300.0)
    cap[500] = 5.0
    accel = 2000.0
    out = bidirectional_scan(s, cap, accel, 1e12)
    expected = np.minimum(cap, np.sqrt(5.0**2 + 2 * accel * np.abs(s - 50.0)))
    np.testing.assert_allclose(out, expected, rtol=1e-3)
    # Finite jerk: slower ramps, never above the cap, the cap kept far from the dip.
    limited = bidirectional_scan(s, cap, accel, 20000.0)
    assert np.all(limited <= expected + 1e-9)
    assert limited[500] == 5.0 and limited[0] == 300.0 and limited[-1] == 300.0
    assert np.all(np.diff(limited[:501]) <= 1e-12) and np.all(np.diff(limited[500:]) >= -1e-12)


def test_schedule_of_a_line_runs_at_the_knobs_top_away_from_its_ends():
    machine = load_machine("vmc-small")
    _, toolpath = load_program("G90 G21\nG01 X100 F3000\nM30\n", "gsk25i", machine)
    schedule = plan_schedule(toolpath, machine)
    middle = (schedule.s > 20) & (schedule.s < 80)
    assert np.all(schedule.override[middle] == pytest.approx(2.0))
    assert math.isclose(schedule.s[-1], 100.0)


def test_the_sliding_window_maximum_is_the_maximum_over_the_window():
    """_window_max (the net-turn windows' sharpest junction) against a brute-force max, for windows
    whose ends only move forward, empty windows included."""
    from cnc_gym.motion.planner.schedule import _window_max

    rng = np.random.default_rng()
    for _ in range(20):
        n = int(rng.integers(1, 60))
        values = rng.random(n + 1) * (rng.random(n + 1) < 0.7)
        queue = np.empty((1, n + 1), dtype=np.int64)
        head, tail, pushed = (np.zeros(1, dtype=np.int64) for _ in range(3))
        pushed[:] = 1
        lo, hi = 1, 0
        for _ in range(3 * n):
            hi = min(n, hi + int(rng.integers(0, 3)))
            lo = min(hi + 1, lo + int(rng.integers(0, 2)), n)
            want = values[lo : hi + 1].max() if lo <= hi else 0.0
            assert _window_max(values, queue[0], head, tail, pushed, 0, lo, hi) == want


# ----------------------------------------------------------------------------------- the schedule's time
def _schedule(s, speed):
    s, speed = np.asarray(s, dtype=float), np.asarray(speed, dtype=float)
    return Schedule(s=s, cap_mm_s=speed, speed_mm_s=speed, override=np.ones_like(s))


def test_schedule_time_is_the_closed_form_of_its_speed():
    # Constant speed: length / speed.
    assert _schedule([0.0, 10.0, 30.0], [20.0, 20.0, 20.0]).time_s == pytest.approx(1.5, rel=1e-12)
    # A ramp from rest at constant acceleration: 2 L / v (L = v² / 2a, t = v / a).
    assert _schedule([0.0, 25.0], [0.0, 10.0]).time_s == pytest.approx(5.0, rel=1e-12)
    # A stop (zero speed at both ends of a grid step, e.g. a repeated point) takes no time; one point: 0.
    assert _schedule([0.0, 4.0, 4.0, 8.0], [4.0, 0.0, 0.0, 4.0]).time_s == pytest.approx(4.0, rel=1e-12)
    assert _schedule([3.0], [5.0]).time_s == 0.0
