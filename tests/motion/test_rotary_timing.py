"""The controller's timing of rotary-axis moves (manual §3.2.2) against closed forms.

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cnc_gym.errors import ProgramError
from cnc_gym.gcode import interpret
from cnc_gym.machine import load_machine, machine_from_dict
from cnc_gym.motion import Controller
from cnc_gym.motion import kernel as K
from cnc_gym.motion.limits import build_limits, rest_to_rest_position, rest_to_rest_time
from cnc_gym.toolpath import SegmentKind

GSK = load_machine("gsk25i")  # B axis: 4000 deg/min clamp, A = 2777.78 deg/s², J = 347222 deg/s³


def integrate_profile(peak: float, accel: float, jerk: float, dt: float = 1e-6) -> tuple[float, float]:
    """Distance and duration of a symmetric jerk-limited rest-to-rest move that peaks at ``peak`` without
    cruising, by integrating the jerk phases numerically (independent of the closed form)."""
    if peak >= accel * accel / jerk:
        t_jerk, t_hold = accel / jerk, peak / accel - accel / jerk
    else:
        t_jerk, t_hold = math.sqrt(peak / jerk), 0.0
    phases = [jerk, 0.0, -jerk, -jerk, 0.0, jerk]
    durations = [t_jerk, t_hold, t_jerk, t_jerk, t_hold, t_jerk]
    a = v = x = 0.0
    total = 0.0
    for j, duration in zip(phases, durations, strict=True):
        steps = max(round(duration / dt), 1) if duration > 0 else 0
        h = duration / steps if steps else 0.0
        for _ in range(steps):  # exact for piecewise-constant jerk (Taylor series of degree 3)
            x += v * h + a * h * h / 2 + j * h**3 / 6
            v += a * h + j * h * h / 2
            a += j * h
        total += duration
    assert abs(v) < 1e-6 * max(peak, 1.0)
    return x, total


@pytest.mark.parametrize("peak", [0.5, 3.0, 20.0])  # below and above a²/j = 10 for a = 100, j = 1000
def test_rest_to_rest_time_matches_an_integrated_profile(peak):
    accel, jerk = 100.0, 1000.0
    distance, duration = integrate_profile(peak, accel, jerk, dt=1e-4)
    # a speed limit above the peak: the move cannot cruise, so the closed form must find this peak
    assert rest_to_rest_time(distance, peak * 5, accel, jerk) == pytest.approx(duration, rel=1e-9)
    # with the speed limit exactly at the peak plus a cruise of 2 s
    assert rest_to_rest_time(distance + 2 * peak, peak, accel, jerk) == pytest.approx(duration + 2, rel=1e-9)


def test_rest_to_rest_time_is_zero_for_no_distance_and_vectorised():
    out = rest_to_rest_time(np.array([0.0, 90.0]), np.array([5.0, 5.0]), 2777.78, 347222.0)
    assert out[0] == 0.0
    # cruise at 5 deg/s; v = 5 < a²/j = 22.2 deg/s, so the acceleration never reaches a and each ramp
    # takes 2·√(v/j), covering v·√(v/j): T = 90/5 + 2·√(5/j)
    assert out[1] == pytest.approx(18.0 + 2 * math.sqrt(5.0 / 347222.0))


def run_time(text: str, machine=GSK) -> tuple[float, object]:
    tp = interpret(text, machine=machine)
    chunk = Controller(tp, machine, in_position_check=False).run_to_end()
    return float(chunk.time_s[-1]), chunk


def test_x8_rotary_only_move_takes_its_closed_form_time_and_holds_xyz():
    # G91 G01 B90 F300: 5 deg/s over 90°, B's own acceleration and jerk limits.
    t, chunk = run_time("G91 G01 B90.0 F300;\n")
    expected = float(rest_to_rest_time(90.0, 5.0, 2777.78, 347222.0))
    assert expected == pytest.approx(18.0, abs=0.01)
    assert abs(t - expected) <= 2 * GSK.controller.interpolation_period_s
    assert np.all(chunk.position == 0.0)  # the tool tip stays put while the table turns


def test_x8_combined_move_runs_at_the_composite_feed():
    # G91 G01 X20 B40 F300: X at 300·20/√2000 mm/min = 2.2361 mm/s for 8.944 s (0.14907 min), plus the
    # S-curve ramps: total = 20/v + 2·√(v/J_path) (v < A²/J), with J the tighter of X's and B's projected
    # jerk (B turns 2° per mm: J_B/2 = 173611 deg/s³ per mm/s³ < J_X = 347222).
    v = 300 * 20 / math.sqrt(2000) / 60
    t, chunk = run_time("G91 G01 X20.0 B40.0 F300.0;\n")
    expected = 20 / v + 2 * math.sqrt(v / (347222.0 / 2))
    assert abs(t - expected) <= 2 * GSK.controller.interpolation_period_s
    assert np.max(chunk.speed) == pytest.approx(v, rel=1e-9)


def slow_b(**b) -> object:
    return machine_from_dict({"name": "slow-b", "rotary_axes": {"b": b}})


def test_rotary_axis_limits_cap_the_path():
    # B limited to 100 deg/min while it turns 2° per mm of X: X may go at most 50 mm/min, below F300.
    machine = slow_b(max_feed_deg_min=100)
    limits = build_limits(interpret("G91 G01 X20 B40 F300\n", machine=machine), machine)
    assert limits.seg_f[0, K.F_CAP] * 60 == pytest.approx(50.0)
    assert limits.seg_f[0, K.F_BASE] * 60 == pytest.approx(50.0)
    # gsk25i: P1224 = 4000 clamps the composite rate: X20 B40 at F20000 → XYZ cap 4000·20/√2000 =
    # 1789 mm/min, below B's own clamp (P1225 4000 deg/min at 2°/mm: 2000 mm/min).
    limits = build_limits(interpret("G91 G01 X20 B40 F20000\n", machine=GSK), GSK)
    assert limits.seg_f[0, K.F_CAP] * 60 == pytest.approx(4000 * 20 / math.sqrt(2000))
    # acceleration and jerk: B's 100 deg/s² and 1000 deg/s³ at 2°/mm give 50 mm/s² and 500 mm/s³
    machine = slow_b(max_accel_deg_s2=100, max_jerk_deg_s3=1000)
    limits = build_limits(interpret("G91 G01 X20 B40 F300\n", machine=machine), machine)
    assert limits.seg_f[0, K.F_ACC] == pytest.approx(50.0)
    assert limits.seg_f[0, K.F_JERK] == pytest.approx(500.0)


def test_rotary_rapid_and_feed_clamp():
    # G00 B90 at B's rapid rate 10000 deg/min with the rapid acceleration and jerk.
    t, _ = run_time("G00 B90\n")
    expected = float(rest_to_rest_time(90.0, 10000 / 60, 1111.11, 22222.2))
    assert abs(t - expected) <= 2 * GSK.controller.interpolation_period_s
    # G01 B90 F9000: the per-axis clamp P1225 = 4000 deg/min wins.
    t, _ = run_time("G01 B90 F9000\n")
    expected = float(rest_to_rest_time(90.0, 4000 / 60, 2777.78, 347222.0))
    assert abs(t - expected) <= 2 * GSK.controller.interpolation_period_s


def test_junction_into_a_rotary_move_is_limited_by_the_rotary_corner_step():
    # X alone, then X with B turning 2°/mm: B's speed jumps from 0 to 2·v at the junction, so v may be at
    # most step/2 = (1000/60)/2 deg/s per (deg/mm) = 8.33 mm/s there; the X step is 0 (same direction).
    tp = interpret("G91 G01 X20 F3000\nX20 B40\n", machine=GSK)
    limits = build_limits(tp, GSK)
    assert limits.pt_f[1, K.P_HARD] == pytest.approx(1000 / 60 / 2)


def test_a_path_with_a_rotary_axis_the_machine_lacks_is_an_error():
    tp = interpret("G01 B10 F100\n", machine=GSK)
    with pytest.raises(ProgramError) as err:
        build_limits(tp, load_machine("vmc-small"))
    assert err.value.code == "motion.no_rotary_axis"


def test_env_runs_a_rotary_program_and_counts_its_time():
    from cnc_gym.runner import simulate

    result = simulate("G91 G01 B90 F300\nG01 X20 B40\n", machine="gsk25i")
    move1 = float(rest_to_rest_time(90.0, 5.0, 2777.78, 347222.0))
    v = 300 * 20 / math.sqrt(2000) / 60
    move2 = 20 / v + 2 * math.sqrt(v / (347222.0 / 2))
    assert result.cycle_time_s == pytest.approx(move1 + move2, abs=0.05)
    assert result.contour_error_max_mm < 1e-9  # a straight X move: no contour error


word = st.sampled_from(["X", "Y", "Z", "B"])
number = st.integers(-400, 400).map(lambda v: v / 4)


@settings(max_examples=40, deadline=None)
@given(blocks=st.lists(st.tuples(st.sampled_from(["G00", "G01", ""]), st.sampled_from(["G90", "G91", ""]),
                                 st.dictionaries(word, number, min_size=1, max_size=3)),
                       min_size=1, max_size=6))  # fmt: skip
def test_random_rotary_programs_run_to_the_end_within_the_composite_time(blocks):
    """Random G00/G01 programs with B words: interpretation succeeds, the controller finishes, and every
    feed move takes at least its composite length over F (degrees counted as mm), never less."""
    lines = ["F600"]
    for motion, distance, words in blocks:
        axes = " ".join(f"{k}{v:g}" for k, v in words.items())
        lines.append(" ".join(x for x in (motion, distance, axes) if x))
    tp = interpret("\n".join(lines) + "\n", machine=GSK)
    controller = Controller(tp, GSK, in_position_check=False)
    chunk = controller.run_to_end(max_ticks=2_000_000)
    assert controller.finished and np.all(np.isfinite(chunk.position))
    feed_moves = tp.kind == SegmentKind.LINE
    composite = np.hypot(tp.length, tp.rotary_length)[feed_moves]
    lower_bound = float(np.sum(composite / np.minimum(tp.feed[feed_moves], 4000.0))) * 60.0
    elapsed = float(chunk.time_s[-1]) if len(chunk) else 0.0  # a program that never moves has no periods
    assert elapsed >= lower_bound - 1e-9


def sampled_profile(peak: float, accel: float, jerk: float, cruise_s: float, times: np.ndarray,
                    dt: float = 1e-3) -> np.ndarray:  # fmt: skip
    """Position at ``times`` of the jerk-limited rest-to-rest move peaking at ``peak`` with ``cruise_s``
    seconds at that speed, integrated step by step (independent of the closed form; each step stays inside
    one phase, where the cubic step is exact)."""
    if peak >= accel * accel / jerk:
        t_jerk, t_hold = accel / jerk, peak / accel - accel / jerk
    else:
        t_jerk, t_hold = math.sqrt(peak / jerk), 0.0
    phases = [(jerk, t_jerk), (0.0, t_hold), (-jerk, t_jerk), (0.0, cruise_s), (-jerk, t_jerk), (0.0, t_hold),
              (jerk, t_jerk)]  # fmt: skip
    edges = np.cumsum([0.0] + [d for _, d in phases])
    out = np.empty(len(times))
    a = v = x = t = 0.0
    order = np.argsort(times)
    for k, target in enumerate(np.asarray(times)[order]):
        while t < target - 1e-15:
            phase = min(int(np.searchsorted(edges, t, side="right")) - 1, len(phases) - 1)
            j = phases[phase][0]
            h = min(dt, target - t, edges[phase + 1] - t) if phase + 1 < len(edges) else min(dt, target - t)
            h = max(h, 1e-15)
            x += v * h + a * h * h / 2 + j * h**3 / 6
            v += a * h + j * h * h / 2
            a += j * h
            t += h
        out[order[k]] = x
    return out


@pytest.mark.parametrize(("distance", "speed"), [(0.5, 20.0), (2.0, 3.0), (30.0, 20.0)])
def test_rest_to_rest_position_follows_the_integrated_profile(distance, speed):
    # a = 100, j = 1000 (a²/j = 10): a short move that never reaches `speed`, a cruise below a²/j, and a
    # cruise above it; the closed-form position against step-by-step integration of the same jerk phases.
    accel, jerk = 100.0, 1000.0
    total = float(rest_to_rest_time(distance, speed, accel, jerk))
    times = np.linspace(0.0, total, 23)
    got = rest_to_rest_position(times, distance, speed, accel, jerk)
    # the peak and cruise the closed form must have used, found independently by bisection on v·T(v) = d
    def ramp(v):
        return v / accel + accel / jerk if v >= accel * accel / jerk else 2 * math.sqrt(v / jerk)

    if speed * ramp(speed) <= distance:
        peak, cruise = speed, (distance - speed * ramp(speed)) / speed
    else:
        lo, hi = 0.0, speed
        for _ in range(200):
            mid = (lo + hi) / 2
            lo, hi = (mid, hi) if mid * ramp(mid) < distance else (lo, mid)
        peak, cruise = lo, 0.0
    want = sampled_profile(peak, accel, jerk, cruise, times)
    assert np.allclose(got, want, atol=1e-6 * distance)
    assert got[0] == 0.0 and got[-1] == pytest.approx(distance)


def test_controller_outputs_the_rotary_reference():
    # X8 on gsk25i, then a rapid back: B follows the hold's own profile while X, Y, Z rest, then turns 2°
    # per mm of X during the combined move, then rapids by -10°.
    tp = interpret("G91 G01 B90.0 F300;\nG91 G01 X20.0 B40.0 F300.0;\nG00 B-10\n", machine=GSK)
    controller = Controller(tp, GSK, in_position_check=False)
    chunk = controller.run_to_end()
    b = chunk.rotary[:, 0]
    hold = chunk.segment == 0
    periods = np.arange(1, int(hold.sum()) + 1) * GSK.controller.interpolation_period_s
    assert np.allclose(b[hold], rest_to_rest_position(periods, 90.0, 5.0, 2777.78, 347222.0))
    assert np.all(chunk.position[hold] == 0.0) and b[hold][-1] == pytest.approx(90.0)
    combined = chunk.segment == 1
    assert np.allclose(b[combined], 90.0 + 2.0 * chunk.position[combined, 0])
    assert b[-1] == pytest.approx(120.0) and np.all(np.isfinite(b))
    # advancing in small chunks gives the same reference (the hold's progress carries over)
    controller.reset()
    parts = []
    while not controller.finished:
        parts.append(controller.advance(7, override=1.0))
    stepped = np.concatenate([p.rotary[:, 0] for p in parts])
    assert np.allclose(stepped[: len(b)], b[: len(stepped)])
    # a 3-axis tool path has no rotary reference
    plain = Controller(interpret("G01 X1 F100\n"), GSK, in_position_check=False)
    assert plain.advance(5, override=1.0).rotary is None
