"""The braking closed forms of the kernel against textbook S-curve formulas and against each other; the
kernel's entry (typed records in, rows out) against the Controller built on it."""

from __future__ import annotations

import math

import numpy as np
import pytest

from cnc_gym.motion import kernel
from cnc_gym.motion.kernel import brake, brake_step, reach, reach_speed

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


def _simulated_reach(v, a, w, level, acc, jerk, dt=2e-6):
    """Distance after which the speed stays ≤ level, by following brake_step in tiny periods (the manoeuvre
    itself is checked against the closed forms above): the arc length at the last period that ended above
    the level, interpolated inside that period."""
    _, time = brake(v, a, w, acc, jerk)
    s, last = 0.0, 0.0 if v <= level else None
    t = 0.0
    while t < time + 10 * dt or a != 0.0:  # (where the ramp crosses w, brake's time ends at the crossing)
        ds, v_next, a = brake_step(v, a, w, acc, jerk, dt)
        if v > level >= v_next:  # crossed down inside this period: linear interpolation is within ds
            last = s + ds * (v - level) / (v - v_next)
        elif v_next > level:
            last = None
        s += ds
        v = v_next
        t += dt
    return math.inf if last is None else last


@pytest.mark.parametrize(("v", "a", "w", "level"), [
    (100.0, 0.0, 0.0, 50.0), (100.0, 0.0, 0.0, 0.0), (100.0, 0.0, 20.0, 60.0), (100.0, 0.0, 20.0, 20.0),
    (150.0, 800.0, 0.0, 151.0), (150.0, 800.0, 0.0, 140.0), (400.0, 2000.0, 0.0, 30.0),
    (80.0, -1500.0, 10.0, 50.0), (150.0, -2900.0, 0.0, 5.0), (60.0, -1800.0, 20.0, 10.0),
    (100.0, 0.0, 20.0, 10.0),
])  # fmt: skip
def test_reach_matches_the_manoeuvre_followed_period_by_period(v, a, w, level):
    # reach(v, a, w, level): arc length along brake(v, a, w) after which the speed stays ≤ level. Checked
    # against the manoeuvre integrated in 2 µs periods (the crossing interpolated inside its period).
    got = reach(v, a, w, level, A, J)
    if level == w:  # the speed lands on w tangentially: the whole manoeuvre's distance
        assert got == pytest.approx(brake(v, a, w, A, J)[0], rel=1e-12)
        return
    expected = _simulated_reach(v, a, w, level, A, J)
    if math.isinf(expected):  # the manoeuvre ends above the level: never reached (kernel.INF)
        assert got >= 1e299
    else:
        assert got == pytest.approx(expected, rel=1e-8, abs=1e-9)


def test_the_braking_certificate_is_not_monotone_but_the_stop_envelope_is():
    # Why the controller needs the viability test (kernel._rescue): the certificate brake(v, a, w) ≤ d is
    # not monotone in the target nor in the jerk, so a state can lose it when the look-ahead window slides
    # (the window-end stop w = 0 becomes the point's own limit) or when the braking jerk grows.
    # From 100 mm/s (a = 0, triangular): stopping takes 100·√(100/J); slowing to 5 takes 105·√(95/J), more.
    assert brake(100.0, 0.0, 5.0, A, J)[0] == pytest.approx(105 * math.sqrt(95 / J))
    assert brake(100.0, 0.0, 5.0, A, J)[0] > brake(100.0, 0.0, 0.0, A, J)[0]
    # Decelerating, just too fast to land on w by ramping the acceleration back at J: with J the speed
    # crosses w early (and ends below it); a larger jerk lands exactly on w, later (hypothesis found this).
    v, a, w = 8.22410562873622, -62.67835610993302, 8.163760203385865
    assert brake(v, a, w, 3000.0, 32521.16)[0] < 0.01530 < brake(v, a, w, 3000.0, 33617.74)[0]
    # The time-optimal stop is the lowest speed profile of all, so the distance after which it stays below
    # any level falls when A or J grow and lies below every other manoeuvre's.
    rng = np.random.default_rng(1)
    for _ in range(2000):
        v = rng.uniform(0, 500)
        a = rng.uniform(-A, A)
        if a < 0 and v - a * a / (2 * J) < 0:
            continue
        level = rng.uniform(0, v + 50)
        w = rng.uniform(0, level)
        d0 = reach(v, a, 0.0, level, A, J)
        assert d0 <= reach(v, a, w, level, A, J) * (1 + 1e-12) + 1e-12
        assert reach(v, a, 0.0, level, A, J * rng.uniform(1, 3)) <= d0 * (1 + 1e-12) + 1e-12
        assert reach(v, a, 0.0, level, A * rng.uniform(1, 3), J) <= d0 * (1 + 1e-12) + 1e-12


def test_the_entry_takes_records_and_runs_as_the_controller():
    from cnc_gym.machine import load_machine
    from cnc_gym.motion import Controller
    from cnc_gym.motion.controller import kernel_config
    from cnc_gym.programs import load_program

    machine = load_machine("vmc-small")
    _, toolpath = load_program("star")
    controller = Controller(toolpath, machine)
    controller.reset()
    lim = controller.limits
    path = kernel.PathTables(lim.seg_f, lim.seg_i, lim.pt_f, lim.pt_i, lim.dwell_f, lim.curve_f,
                             kernel_config(machine, lim))  # fmt: skip
    state = kernel.ControllerState(np.zeros(kernel.N_STATE_F), np.zeros(kernel.N_STATE_I, dtype=np.int64))
    kernel.reset_state(lim.pt_i, lim.pt_f, lim.dwell_f, lim.seg_f.shape[0], state.f, state.i)
    scratch = np.zeros((int(path.cfg[1]) + 2, 3))
    # The same periods as the controller's, row for row: at an override, then at a commanded feed.
    out = np.zeros((400, kernel.N_OUT))
    command = kernel.Command(kernel.MODE_OVERRIDE, 1.5, 1.0, 0.0, True, False)
    assert kernel.advance_into(path, state, command, out, scratch) == 400
    np.testing.assert_array_equal(out, controller.advance_rows(400, override=1.5))
    feed = kernel.Command(kernel.MODE_FEED, 1.0, 1.0, 1200.0 / 60.0, True, False)
    assert kernel.advance_into(path, state, feed, out, scratch) == 400
    np.testing.assert_array_equal(out, controller.advance_rows(400, feed_mm_min=1200.0))
    np.testing.assert_array_equal(state.f, controller._st_f)
    # stop_when_done: from the start, the run ends on the period that finishes the program (no in-position
    # waits)
    kernel.reset_state(lim.pt_i, lim.pt_f, lim.dwell_f, lim.seg_f.shape[0], state.f, state.i)
    to_the_end = kernel.Command(kernel.MODE_OVERRIDE, 2.0, 1.0, 0.0, False, True)
    rows = kernel.advance_kernel(path, state, to_the_end, 200_000, scratch)
    assert 0 < len(rows) < 200_000
    assert rows[-1, kernel.O_DONE] == 1.0 and not rows[:-1, kernel.O_DONE].any()
    assert state.i[kernel.K_PHASE] == kernel.PHASE_DONE
