"""The braking closed forms of the kernel against textbook S-curve formulas and against each other."""

from __future__ import annotations

import math

import numpy as np
import pytest

from cnc_gym.motion.kernel import brake, brake_step, reach_speed

A, J = 3000.0, 30000.0  # A²/J = 300 mm/s


@pytest.mark.parametrize("v", [10.0, 100.0, 299.0])
def test_stop_from_cruise_triangular(v):
    # v < A²/J: the deceleration is a triangle of height √(vJ) lasting 2√(v/J); distance = mean speed v/2
    # times the duration.
    dist, time = brake(v, 0.0, 0.0, A, J)
    assert time == pytest.approx(2 * math.sqrt(v / J), rel=1e-12)
    assert dist == pytest.approx(v * math.sqrt(v / J), rel=1e-12)


@pytest.mark.parametrize("v", [301.0, 500.0, 2000.0])
def test_stop_from_cruise_trapezoidal(v):
    # v ≥ A²/J: ramps of A/J at each end, hold A; duration v/A + A/J, distance v/2 times that.
    dist, time = brake(v, 0.0, 0.0, A, J)
    assert time == pytest.approx(v / A + A / J, rel=1e-12)
    assert dist == pytest.approx(v / 2 * (v / A + A / J), rel=1e-12)


def test_slow_down_to_a_speed():
    # From 200 to 50 mm/s: Δv = 150 < A²/J, triangle of duration 2√(150/J), mean speed 125.
    dist, time = brake(200.0, 0.0, 50.0, A, J)
    assert time == pytest.approx(2 * math.sqrt(150 / J))
    assert dist == pytest.approx(125 * 2 * math.sqrt(150 / J))


def test_nothing_to_brake_for():
    assert brake(50.0, 0.0, 50.0, A, J) == (0.0, 0.0)
    # accelerating at 300 mm/s² from 40: ramping the acceleration away still gains a²/2J = 1.5 mm/s
    assert brake(40.0, 300.0, 41.5, A, J) == (0.0, 0.0)
    assert brake(40.0, 300.0, 41.4, A, J)[0] > 0.0


def test_braking_while_accelerating_costs_more_than_from_cruise():
    d_cruise, _ = brake(100.0, 0.0, 0.0, A, J)
    d_acc, _ = brake(100.0, 1000.0, 0.0, A, J)
    d_dec, _ = brake(100.0, -1000.0, 0.0, A, J)
    assert d_dec < d_cruise < d_acc


@pytest.mark.parametrize(("v0", "dist"), [(0.0, 1.0), (0.0, 50.0), (20.0, 0.3), (100.0, 10.0), (5.0, 500.0)])
def test_reach_speed_inverts_brake(v0, dist):
    # (v − v0)(v + v0)² = J·L² in the triangular regime, the trapezoid beyond: slowing from the reachable
    # speed back to v0 (a = 0 at both ends) takes exactly the distance.
    v = reach_speed(v0, dist, A, J)
    assert v > v0
    assert brake(v, 0.0, v0, A, J)[0] == pytest.approx(dist, rel=1e-9)
    if v - v0 <= A * A / J:
        assert (v - v0) * (v + v0) ** 2 == pytest.approx(J * dist**2, rel=1e-9)


@pytest.mark.parametrize(("v", "a", "w"), [(100.0, 0.0, 0.0), (150.0, 800.0, 20.0), (80.0, -1500.0, 10.0),
                                           (400.0, 2000.0, 0.0), (150.0, -2900.0, 0.0)])  # fmt: skip
def test_following_the_manoeuvre_period_by_period_reproduces_it(v, a, w):
    # brake_step integrates the manoeuvre's phases; chained over small periods it must cover exactly the
    # closed-form distance, end at (w, 0), never reverse, and keep |a| ≤ A.
    dist, time = brake(v, a, w, A, J)
    s, vv, aa, t = 0.0, v, a, 0.0
    dt = 1e-4
    while t < time + 5 * dt:
        ds, vv, aa = brake_step(vv, aa, w, A, J, dt)
        assert ds >= -1e-15 and vv >= min(w, v) - 1e-9 and abs(aa) <= max(A, abs(a)) + 1e-9
        s += ds
        t += dt
    assert vv == pytest.approx(w, abs=1e-9) and aa == pytest.approx(0.0, abs=1e-9)
    assert s == pytest.approx(dist + w * (t - time), rel=1e-9, abs=1e-9)


def test_brake_is_monotone_in_speed_and_acceleration():
    rng = np.random.default_rng(0)
    for _ in range(500):
        v = rng.uniform(0, 500)
        a = rng.uniform(-A, A)
        w = rng.uniform(0, v)
        if a < 0 and v - a * a / (2 * J) < 0:
            continue  # no non-reversing continuation exists from there
        d0, _ = brake(v, a, w, A, J)
        assert brake(v + 1.0, a, w, A, J)[0] >= d0 - 1e-12
        assert brake(v, min(a + 50.0, A), w, A, J)[0] >= d0 - 1e-12
