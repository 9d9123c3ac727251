"""The classical planner's servo error model and look-ahead scan, against the plant and closed forms."""

from __future__ import annotations

import math

import numpy as np
import pytest

from agents.classical import ServoErrorModel, bidirectional_scan, jerk_limited_reach
from cnc_gym.machine import load_machine
from cnc_gym.plant import ServoPlant


def _simulated_circle_error(machine_name: str, radius: float, speed: float) -> float:
    """Run a circle reference through the real plant; steady radial error over the last revolution."""
    machine = load_machine(machine_name)
    period = machine.controller.interpolation_period_s
    omega = speed / radius
    t = np.arange(0.0, 5 * 2 * np.pi / omega + 2.0, period)
    ref = np.stack([radius * np.cos(omega * t), radius * np.sin(omega * t), np.zeros_like(t)], axis=1)
    plant = ServoPlant(machine)
    plant.reset(ref[0])
    actual = plant.step(ref)
    last = t > t[-1] - 2 * np.pi / omega
    return float(np.max(np.abs(np.hypot(actual[last, 0], actual[last, 1]) - radius)))


def test_p_loop_circle_matches_textbook_closed_form():
    # p-loop-30: Kv = 30 1/s, f = 0: radial error = R(1 − 1/√(1 + (v/(R·Kv))²)) ≈ v²/(2·R·Kv²).
    model = ServoErrorModel(load_machine("p-loop-30"))
    radius, speed = 50.0, 5000.0 / 60.0
    exact = radius * (1.0 - 1.0 / math.sqrt(1.0 + (speed / (radius * 30.0)) ** 2))
    assert model.arc_error(speed, radius, 0)[0] == pytest.approx(exact, rel=1e-9)
    assert exact == pytest.approx(speed**2 / (2 * radius * 30.0**2), rel=0.01)  # 77 µm


@pytest.mark.parametrize("machine_name", ["p-loop-30", "vmc-small", "gsk25i", "h4cm"])
@pytest.mark.parametrize(("radius", "speed"), [(25.0, 4000.0 / 60.0), (10.0, 100.0)])
def test_arc_error_model_matches_the_plant(machine_name, radius, speed):
    # vmc-small has feed-forward 0.7, a 60 Hz velocity loop and Kv 40/38 (mismatch): no textbook form,
    # so the model is checked against the plant simulated sample by sample.
    predicted = ServoErrorModel(load_machine(machine_name)).arc_error(speed, radius, 0)[0]
    simulated = _simulated_circle_error(machine_name, radius, speed)
    assert predicted == pytest.approx(simulated, rel=0.06, abs=2e-4)


def test_ff_reduces_circle_error_by_one_minus_f_squared():
    # Ideal velocity loop, matched Kv, FF fraction f: |G|² = (Kv² + f²ω²)/(Kv² + ω²), so the radial
    # error is ≈ (1 − f²)·v²/(2·R·Kv²) — 0.51 × the plain P loop's at f = 0.7.
    from cnc_gym.machine import machine_from_dict

    base = {"axis_defaults": {"kv_1_s": 30, "velocity_loop_hz": 0}}
    plain = ServoErrorModel(machine_from_dict(base))
    with_ff = ServoErrorModel(
        machine_from_dict({"axis_defaults": {**base["axis_defaults"], "feedforward": 0.7}})
    )
    radius, speed = 50.0, 30.0
    ratio = with_ff.arc_error(speed, radius, 0)[0] / plain.arc_error(speed, radius, 0)[0]
    assert ratio == pytest.approx(1 - 0.7**2, rel=0.01)


def test_line_lateral_error_from_gain_mismatch():
    # Steady lag per axis (1 − f)·v/Kv; on a 45° line with Kv 40 / 38, f = 0.7 the sideways part is
    # (1 − f)·v·(1/38 − 1/40)/2 (the lag vector's component normal to the line).
    model = ServoErrorModel(load_machine("vmc-small"))
    tangent = np.array([[1.0, 1.0, 0.0]]) / math.sqrt(2.0)
    expected_per_speed = 0.3 * (1 / 38 - 1 / 40) / 2
    assert model.line_error_per_speed(tangent)[0] == pytest.approx(expected_per_speed, rel=1e-9)
    # Axis-parallel lines have no sideways error.
    assert model.line_error_per_speed(np.array([[1.0, 0.0, 0.0]]))[0] == pytest.approx(0.0, abs=1e-15)
    # And the plant agrees: ramp along the diagonal at 100 mm/s, lateral offset once settled.
    machine = load_machine("vmc-small")
    t = np.arange(0.0, 3.0, machine.controller.interpolation_period_s)
    ref = 100.0 * t[:, None] * tangent
    plant = ServoPlant(machine)
    plant.reset(ref[0])
    actual = plant.step(ref)[-1]
    lateral = np.linalg.norm(actual - (actual @ tangent[0]) * tangent[0])
    assert lateral == pytest.approx(100.0 * expected_per_speed, rel=0.01)


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
def test_jerk_limited_reach_inverts_a_simulated_s_curve(v0, v1):
    accel, jerk = 3000.0, 30000.0  # A²/J = 300 mm/s: the first two cases never reach A, the third does
    distance = _s_curve_distance(v0, v1, accel, jerk)
    assert jerk_limited_reach(v0, distance, accel, jerk) == pytest.approx(v1, rel=2e-3)


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
