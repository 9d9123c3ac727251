"""Contour-error meter: exact distances against hand-computed values, the rapid/dwell rule, the window."""

from __future__ import annotations

import math

import numpy as np
import pytest

from cnc_gym.plant import ContourErrorMeter
from cnc_gym.toolpath import Plane, ToolpathBuilder


def build(*segments):
    """segments: ("rapid"|"line", start, end) | ("arc", start, end, center, plane, sweep) | ("dwell", p)."""
    builder = ToolpathBuilder()
    for number, seg in enumerate(segments, start=1):
        if seg[0] == "rapid":
            builder.rapid(seg[1], seg[2], line=number)
        elif seg[0] == "line":
            builder.line(seg[1], seg[2], feed=1000.0, line=number)
        elif seg[0] == "arc":
            builder.arc(seg[1], seg[2], seg[3], seg[4], seg[5], feed=1000.0, line=number)
        else:
            builder.dwell(seg[1], 1.0, line=number)
    return builder.build()


def test_line_distances_by_hand():
    tp = build(("line", (0, 0, 0), (10, 0, 0)))
    meter = ContourErrorMeter(tp)
    points = np.array([
        [5.0, 3.0, 4.0],   # beside the middle: √(3² + 4²) = 5
        [13.0, 4.0, 0.0],  # past the end: distance to (10, 0, 0) = √(9 + 16) = 5
        [-1.0, 0.0, 0.0],  # before the start: 1
        [7.5, 0.0, 0.0],   # on the line: 0
    ])  # fmt: skip
    np.testing.assert_allclose(meter.measure(points, 0), [5.0, 5.0, 1.0, 0.0], atol=1e-12)


def test_arc_distances_by_hand():
    # Quarter arc CCW (G03) about the origin, R 10, from (10, 0) to (0, 10) in XY.
    tp = build(("arc", (10, 0, 0), (0, 10, 0), (0, 0, 0), Plane.XY, math.pi / 2))
    meter = ContourErrorMeter(tp)
    points = np.array([
        [3.0, 4.0, 0.0],    # angle inside the sweep, radius 5: 10 − 5 = 5
        [6.0, 8.0, 5.0],    # on the cylinder, 5 above: 5
        [0.0, -10.0, 0.0],  # angle −90° outside the sweep: nearest end (10, 0): √(100 + 100)
        [12.0, 16.0, 0.0],  # radius 20 inside the sweep: 10
        [0.0, 0.0, 0.0],    # the centre: every arc point is R away
    ])  # fmt: skip
    expected = [5.0, 5.0, math.sqrt(200.0), 10.0, 10.0]
    np.testing.assert_allclose(meter.measure(points, 0), expected, atol=1e-12)


def test_large_clockwise_arc_by_hand():
    # G02 through 270°: from (10, 0) clockwise to (0, 10), passing (0, −10) and (−10, 0). The gap is the
    # open first quadrant (0° … 90°).
    tp = build(("arc", (10, 0, 0), (0, 10, 0), (0, 0, 0), Plane.XY, -1.5 * math.pi))
    meter = ContourErrorMeter(tp)
    gap_point = 10.0 * np.array([math.cos(math.pi / 4), math.sin(math.pi / 4), 0.0])
    points = np.array([[0.0, -7.0, 0.0], [-13.0, 0.0, 0.0], gap_point])
    # In the gap at 45° on the circle, both ends are a chord of 45° away: 2·10·sin(22.5°) = 7.6537.
    expected = [3.0, 3.0, 20.0 * math.sin(math.pi / 8)]
    np.testing.assert_allclose(meter.measure(points, 0), expected, atol=1e-12)


def test_zx_plane_arc_and_full_circle():
    # ZX plane (normal +Y): u = Z, v = X. Half circle about (0, 0, 0) from Z = 10 … centre on Y = 2.
    tp = build(
        ("arc", (0, 2, 10), (0, 2, -10), (0, 2, 0), Plane.ZX, math.pi),  # through X = +10 (CCW about +Y)
        ("arc", (0, 2, -10), (0, 2, -10), (0, 2, 0), Plane.ZX, 2 * math.pi),  # full circle
    )
    meter = ContourErrorMeter(tp, window_back=0, window_ahead=0)
    # CCW about +Y from +Z: angle in (u = Z, v = X) grows towards +X, so the half circle covers X ≥ 0.
    points = np.array([[6.0, 2.0, 0.0], [-6.0, 2.0, 0.0], [0.0, 5.0, 0.0]])
    # (6, 2, 0): radial 10 − 6 = 4. (−6, 2, 0) is on the missing half: nearest end is (0, 2, ±10):
    # √(36 + 100). (0, 5, 0) is the centre lifted 3 along the normal: √(100 + 9).
    np.testing.assert_allclose(meter.measure(points, 0), [4.0, math.sqrt(136.0), math.sqrt(109.0)],
                               atol=1e-12)  # fmt: skip
    # The full circle has no missing half: (−6, 2, 0) is 4 from it.
    np.testing.assert_allclose(meter.measure(points, 1), [4.0, 4.0, math.sqrt(109.0)], atol=1e-12)


@pytest.mark.parametrize("rapids_behind", [False, True])
def test_samples_on_rapids_and_dwells_do_not_count(rapids_behind):
    tp = build(
        ("rapid", (0, 0, 10), (0, 0, 0)),
        ("line", (0, 0, 0), (10, 0, 0)),
        ("dwell", (10, 0, 0)),
        ("rapid", (10, 0, 0), (10, 0, 10)),
    )
    meter = ContourErrorMeter(tp, rapids_behind=rapids_behind)
    far = np.array([[50.0, 50.0, 50.0], [0.0, 0.0, 5.0]])
    # Reference on a rapid or a dwell: no contour error, whatever the actual point.
    np.testing.assert_array_equal(meter.measure(far, 0), [0.0, 0.0])
    np.testing.assert_array_equal(meter.measure(far, 2), [0.0, 0.0])
    np.testing.assert_array_equal(meter.measure(far, 3), [0.0, 0.0])
    # Reference on the cut: a point on the approach rapid (behind the reference) is on the programmed path
    # under the path rule; under the cuts rule it is measured to the line's start.
    on_rapid = 0.0 if rapids_behind else 5.0
    np.testing.assert_allclose(meter.measure(far[1:], 1), [on_rapid], atol=1e-12)
    # The retract rapid after the cut is ahead of the reference: never a candidate.
    np.testing.assert_allclose(meter.measure(np.array([[10.0, 0.0, 4.0]]), 1), [4.0], atol=1e-12)
    # Per-point hints: only the points whose own reference is cutting count.
    np.testing.assert_allclose(meter.measure(far, np.array([0, 1])), [0.0, on_rapid], atol=1e-12)
    # Out-of-range hints count as not cutting (no exception, no NaN).
    np.testing.assert_array_equal(meter.measure(far, 99), [0.0, 0.0])
    np.testing.assert_allclose(meter.measure(far, np.array([-1, 1])), [0.0, on_rapid], atol=1e-12)
    np.testing.assert_array_equal(meter.measure(far, np.array([3, 99])), [0.0, 0.0])
    # All points on the cut: the same as one int hint.
    np.testing.assert_allclose(meter.measure(far, np.array([1, 1])), meter.measure(far, 1), atol=0)


def test_window_moves_with_the_hint():
    # A zig-zag pocket: pass A at y = 0, a 1 mm step-over, pass B back at y = 1, then far along.
    tp = build(
        ("line", (0, 0, 0), (100, 0, 0)),  # 0: pass A
        ("line", (100, 0, 0), (100, 1, 0)),  # 1: step-over
        ("line", (100, 1, 0), (0, 1, 0)),  # 2: pass B
    )
    point = np.array([[50.0, 0.9, 0.0]])  # 0.9 mm off pass A, 0.1 mm off pass B
    narrow = ContourErrorMeter(tp, window_back=0, window_ahead=0)
    assert narrow.window(0) == (0, 1)
    assert narrow.measure(point, 0)[0] == pytest.approx(0.9)  # pass B is outside the window
    assert narrow.measure(point, 2)[0] == pytest.approx(0.1)
    wide = ContourErrorMeter(tp, window_back=2, window_ahead=8)
    assert wide.window(0) == (0, 3)
    assert wide.measure(point, 0)[0] == pytest.approx(0.1)  # a wide window sees the neighbour pass


def test_window_back_mm_covers_lag_over_short_segments():
    # 100 segments of 0.1 mm along X. A lag of 2.5 mm is 25 segments: 2 segments back miss it.
    builder = ToolpathBuilder()
    for i in range(100):
        builder.line((0.1 * i, 0, 0), (0.1 * (i + 1), 0, 0), feed=1000.0, line=i + 1)
    tp = builder.build()
    actual = np.array([[5.0, 0.02, 0.0]])  # truly 0.02 mm off the path
    short = ContourErrorMeter(tp, window_back=2, window_ahead=8)
    assert short.measure(actual, 75)[0] == pytest.approx(np.hypot(7.3 - 5.0, 0.02))  # overestimates
    reach = ContourErrorMeter(tp, window_back=2, window_ahead=8, window_back_mm=3.0)
    assert reach.window(75)[0] <= 45
    assert reach.measure(actual, 75)[0] == pytest.approx(0.02)


def test_agrees_with_the_toolpath_nearest_service():
    # Lines, flat arcs of every size and direction, a helix and a multi-turn helix; random points and hints.
    tp = build(
        ("rapid", (0, 0, 10), (0, 0, 0)),
        ("line", (0, 0, 0), (10, 0, 0)),
        ("arc", (10, 0, 0), (20, 0, 0), (15, 0, 0), Plane.XY, -math.pi),
        ("line", (20, 0, 0), (20, -10, 0)),
        ("arc", (20, -10, 0), (20, -10, 0), (15, -10, 0), Plane.XY, 2 * math.pi),
        ("arc", (20, -10, 0), (20, -10, -3), (15, -10, 0), Plane.ZX, 1.5),
        ("arc", (20, -10, -3), (10, -10, -6), (15, -10, -3), Plane.XY, -3 * math.pi),
        ("dwell", (10, -10, -6)),
        ("arc", (10, -10, -6), (10, -6, -6), (10, -8, -6), Plane.YZ, -math.pi),
        ("line", (10, -6, -6), (0, 0, 0)),
    )
    meter = ContourErrorMeter(tp, window_back=2, window_ahead=3, rapids_behind=False)
    rng = np.random.default_rng(3)
    checked = 0
    for _ in range(300):
        points = rng.uniform(-5.0, 25.0, (6, 3))
        hint = int(rng.integers(0, len(tp)))
        measured = meter.measure(points, hint)
        assert np.all(np.isfinite(measured))
        if tp.kind[hint] in (0, 3):
            continue
        first, last = meter.window(hint)
        reference, _, _ = tp.nearest(points, first, last, cutting_only=True)
        np.testing.assert_allclose(measured, reference, rtol=1e-9, atol=1e-9)
        checked += 1
    assert checked > 150


def test_bad_hint_shape_and_window_sizes():
    tp = build(("line", (0, 0, 0), (10, 0, 0)))
    meter = ContourErrorMeter(tp)
    with pytest.raises(ValueError, match="segment_hint"):
        meter.measure(np.zeros((3, 3)), np.array([0, 0]))
    with pytest.raises(ValueError):
        ContourErrorMeter(tp, window_back=-1)
    assert meter.measure(np.zeros((0, 3)), 0).shape == (0,)


def test_random_lines_and_flat_arcs_agree_with_toolpath_nearest():
    # Random chains of lines (some of zero length) and flat arcs in all planes with sweeps across
    # (−2π, 2π] (half turns, near-full and full circles), with points scattered close to the path
    # (where inside/outside-the-sweep decisions matter) and far from it, at machine-sized coordinates.
    rng = np.random.default_rng(11)
    builder = ToolpathBuilder()
    here = np.array([400.0, -250.0, 80.0])
    sweeps = [math.pi, -math.pi, 2 * math.pi, -2 * math.pi, 1.999 * math.pi, 0.001, 1.0001 * math.pi]
    for number in range(60):
        if number % 3 == 0:
            there = here + (0.0 if number % 9 == 0 else 1.0) * rng.normal(0, 5, 3)
            builder.line(tuple(here), tuple(there), feed=1000.0, line=number + 1)
        else:
            plane = Plane(int(rng.integers(0, 3)))
            u, v, _ = {Plane.XY: (0, 1, 2), Plane.ZX: (2, 0, 1), Plane.YZ: (1, 2, 0)}[plane]
            center = here.copy()
            center[u] += rng.normal(0, 4)
            center[v] += rng.normal(0, 4)
            sweep = sweeps[number % len(sweeps)] if number % 2 else rng.uniform(-2 * math.pi, 2 * math.pi)
            radius = math.hypot(here[u] - center[u], here[v] - center[v])
            angle = math.atan2(here[v] - center[v], here[u] - center[u]) + sweep
            there = here.copy()
            there[u] = center[u] + radius * math.cos(angle)
            there[v] = center[v] + radius * math.sin(angle)
            builder.arc(tuple(here), tuple(there), tuple(center), plane, sweep, feed=1000.0, line=number + 1)
        here = there
    tp = builder.build()
    meter = ContourErrorMeter(tp, window_back=3, window_ahead=3)
    _, on_path = tp.sample(0.7)
    for hint in range(len(tp)):
        first, last = meter.window(hint)
        near = on_path[rng.integers(0, len(on_path), 8)] + rng.normal(0, 0.05, (8, 3))
        far = here + rng.normal(0, 20, (4, 3))
        points = np.concatenate((near, far))
        reference, _, _ = tp.nearest(points, first, last, cutting_only=True)
        np.testing.assert_allclose(meter.measure(points, hint), reference, rtol=1e-9, atol=1e-9)


def test_points_on_the_path_measure_zero_far_from_the_origin():
    # Exactness at machine coordinates: points on a line and on an arc 500 mm from the origin are 0 to
    # rounding (no |p|² − 2p·q + |q|² cancellation, which would leave ~1e−5 mm here).
    tp = build(
        ("line", (500, 500, -300), (600, 510, -300)),
        ("arc", (600, 510, -300), (610, 520, -300), (610, 510, -300), Plane.XY, -math.pi / 2),
    )
    meter = ContourErrorMeter(tp)
    on_line = np.array([500.0, 500.0, -300.0]) + np.linspace(0, 1, 7)[:, None] * np.array([100.0, 10.0, 0.0])
    theta = math.pi - np.linspace(0, math.pi / 2, 7)
    on_arc = np.stack((610 + 10 * np.cos(theta), 510 + 10 * np.sin(theta), np.full(7, -300.0)), axis=1)
    assert meter.measure(on_line, 0).max() < 1e-12
    assert meter.measure(on_arc, 1).max() < 1e-12


def test_plant_and_meter_together_give_the_circle_closed_form():
    # End to end: a programmed full circle R 50 (G03) after a 1 mm lead-in line, a constant F5000
    # reference sampled from the tool path by arc length, the p-loop-30 plant, then the meter with the
    # reference's own segment index as hint. After the transient (e^(−30 t)) the contour error on the
    # circle is the radial shrink R(1 − 1/√(1 + (v/(R Kv))²)) = 0.07698 mm ≈ v²/(2 R Kv²) = 0.0772 mm.
    from cnc_gym.machine import load_machine
    from cnc_gym.plant import ServoPlant

    radius, speed, period = 50.0, 5000.0 / 60.0, 0.002
    tp = build(
        ("rapid", (-1.0, -radius, 5.0), (-1.0, -radius, 0.0)),
        ("line", (-1.0, -radius, 0.0), (0.0, -radius, 0.0)),
        ("arc", (0.0, -radius, 0.0), (0.0, -radius, 0.0), (0.0, 0.0, 0.0), Plane.XY, 2 * math.pi),
    )
    s = tp.s_start[1] + speed * period * np.arange(1, round((1.0 + 2 * math.pi * radius) / speed / period))
    reference, _, _ = tp.evaluate(s)
    hints = tp.segment_at(s)
    plant = ServoPlant(load_machine("p-loop-30"))
    plant.reset(tp.start[1])
    meter = ContourErrorMeter(tp)
    # The env steps in chunks of a few ticks; the meter gets one hint per chunk (the chunk's last).
    errors = [
        meter.measure(plant.step(reference[k : k + 5]), int(hints[k : k + 5][-1]))
        for k in range(0, len(s), 5)
    ]
    error = np.concatenate(errors)
    assert np.all(np.isfinite(error))
    steady = (hints == 2) & (s - tp.s_start[2] > 1.0 * speed)  # on the circle, after 1 s
    exact = radius * (1 - 1 / math.sqrt(1 + (speed / (radius * 30.0)) ** 2))
    np.testing.assert_allclose(error[steady], exact, atol=5e-4)
    assert error[steady].mean() == pytest.approx(speed**2 / (2 * radius * 30.0**2), rel=0.10)


def test_compiled_meter_equals_toolpath_nearest_on_random_paths_and_hints():
    # The numba kernel against the reference service (cnc_gym/toolpath/nearest.py, plain numpy) on random
    # paths mixing rapids, dwells, lines (some of zero length), flat arcs in all planes and helices,
    # with per-point hints that straddle rapids. Expected values: a point whose own hint is not a cutting
    # segment measures 0; the others measure Toolpath.nearest over the window [lo − back, hi + ahead + 1)
    # of the counted hints' range [lo, hi], written out here from the documented rule.
    rng = np.random.default_rng(2026)
    back, ahead = 2, 4
    for trial in range(6):
        builder = ToolpathBuilder()
        here = rng.uniform(-200.0, 200.0, 3)
        for number in range(40):
            choice = rng.integers(0, 10)
            there = here + (0.0 if choice == 0 else 1.0) * rng.normal(0, 3, 3)
            if choice <= 3:
                builder.line(tuple(here), tuple(there), feed=1000.0, line=number + 1)
            elif choice == 4:
                builder.rapid(tuple(here), tuple(there), line=number + 1)
            elif choice == 5:
                builder.dwell(tuple(here), 0.5, line=number + 1)
                there = here
            else:
                plane = Plane(int(rng.integers(0, 3)))
                u, v, w = {Plane.XY: (0, 1, 2), Plane.ZX: (2, 0, 1), Plane.YZ: (1, 2, 0)}[plane]
                center = here.copy()
                center[u] += rng.normal(0, 4)
                center[v] += rng.normal(0, 4)
                sweep = rng.uniform(-2 * math.pi, 2 * math.pi)
                radius = math.hypot(here[u] - center[u], here[v] - center[v])
                angle = math.atan2(here[v] - center[v], here[u] - center[u]) + sweep
                there = here.copy()
                there[u] = center[u] + radius * math.cos(angle)
                there[v] = center[v] + radius * math.sin(angle)
                if choice == 9 and trial % 2:  # a helix: rises along the plane's normal
                    there[w] += rng.normal(0, 2)
                builder.arc(tuple(here), tuple(there), tuple(center), plane, sweep, feed=1000.0,
                            line=number + 1)  # fmt: skip
            here = there
        tp = builder.build()
        cuts = ContourErrorMeter(tp, window_back=back, window_ahead=ahead, rapids_behind=False)
        path = ContourErrorMeter(tp, window_back=back, window_ahead=ahead)
        cutting = np.isin(tp.kind, [1, 2, 4])  # line, arc, NURBS (rapid 0 and dwell 3 are not)
        _, on_path = tp.sample(0.5)

        def behind(points, first, own, tp=tp):
            """Per point: the nearest of every segment, rapids included, in [first, own[i])."""
            return np.array([tp.nearest(p, first, o, cutting_only=False)[0][0] if o > first else np.inf
                             for p, o in zip(points, own, strict=True)])  # fmt: skip

        for _ in range(40):
            start = int(rng.integers(0, len(tp)))
            hints = np.sort(np.minimum(start + rng.integers(0, 3, 5), len(tp) - 1))
            points = on_path[rng.integers(0, len(on_path), 5)] + rng.normal(0, 0.3, (5, 3))
            counted = cutting[hints]
            expected = expected_path = np.zeros(5)
            if counted.any():
                lo, hi = hints[counted].min(), hints[counted].max()
                first = max(0, lo - back)
                reference, _, _ = tp.nearest(points, first, min(len(tp), hi + ahead + 1))
                expected = np.where(counted, reference, 0.0)
                expected_path = np.where(counted, np.minimum(reference, behind(points, first, hints)), 0.0)
            np.testing.assert_allclose(cuts.measure(points, hints), expected, rtol=1e-9, atol=1e-9)
            np.testing.assert_allclose(path.measure(points, hints), expected_path, rtol=1e-9, atol=1e-9)
            # One common hint: every point counts where that segment cuts.
            own = int(hints[0])
            single, single_path = cuts.measure(points, own), path.measure(points, own)
            if cutting[own]:
                first, last = max(0, own - back), min(len(tp), own + ahead + 1)
                reference = tp.nearest(points, first, last)[0]
                np.testing.assert_allclose(single, reference, rtol=1e-9, atol=1e-9)
                expected_path = np.minimum(reference, behind(points, first, np.full(5, own)))
                np.testing.assert_allclose(single_path, expected_path, rtol=1e-9, atol=1e-9)
            else:
                np.testing.assert_array_equal(single, 0.0)
                np.testing.assert_array_equal(single_path, 0.0)


def test_nurbs_and_helices_agree_with_toolpath_nearest():
    # Rows of every cutting kind with NURBS curves among them (the meter's compiled search against the
    # curve's own numpy search, through Toolpath.nearest), points near the path and far from it.
    from cnc_gym.toolpath.nurbs import NurbsCurve

    rng = np.random.default_rng(77)
    builder = ToolpathBuilder()
    here = np.zeros(3)
    for number in range(30):
        choice = number % 3
        if choice == 0:
            ctrl = here + np.cumsum(rng.normal(size=(6, 3)) * np.array([3.0, 3.0, 0.5]), axis=0)
            ctrl[0] = here
            knots = np.concatenate((np.zeros(4), np.sort(rng.uniform(0, 1, 2)), np.ones(4)))
            builder.nurbs(NurbsCurve(ctrl, rng.uniform(0.5, 2.0, 6), knots, order=4), feed=1000.0,
                          line=number + 1)  # fmt: skip
            there = ctrl[-1].copy()
        elif choice == 1:
            center = here + np.array([rng.normal(0, 3), rng.normal(0, 3), 0.0])
            sweep = rng.uniform(-9.0, 9.0)
            radius = math.hypot(*(here - center)[:2])
            angle = math.atan2(here[1] - center[1], here[0] - center[0]) + sweep
            there = np.array([center[0] + radius * math.cos(angle), center[1] + radius * math.sin(angle),
                              here[2] + rng.normal(0, 2)])  # fmt: skip
            builder.arc(tuple(here), tuple(there), tuple(center), Plane.XY, sweep, feed=1000.0,
                        line=number + 1)  # fmt: skip
        else:
            there = here + rng.normal(0, 3, 3)
            builder.line(tuple(here), tuple(there), feed=1000.0, line=number + 1)
        here = there
    tp = builder.build()
    meter = ContourErrorMeter(tp, window_back=2, window_ahead=4)
    _, on_path = tp.sample(0.3)
    for _ in range(150):
        hint = int(rng.integers(0, len(tp)))
        points = on_path[rng.integers(0, len(on_path), 5)] + rng.normal(0, rng.choice([0.01, 1.0]), (5, 3))
        first, last = meter.window(hint)
        expected, _, _ = tp.nearest(points, first, last)
        np.testing.assert_allclose(meter.measure(points, hint), expected, rtol=0, atol=1e-9)


def test_turning_junction_lateness_is_not_error_offset_is():
    # A rapid along X to the corner (10, 0), then a cut along Y (the reference is on the cut, hint 1).
    tp = build(("rapid", (0, 0, 0), (10, 0, 0)), ("line", (10, 0, 0), (10, 5, 0)))
    path, cuts = ContourErrorMeter(tp), ContourErrorMeter(tp, rapids_behind=False)
    late = np.array([[9.996, 0.0, 0.0]])  # 4 µm short of the corner, on the rapid's line
    np.testing.assert_allclose(path.measure(late, 1), [0.0], atol=1e-12)
    np.testing.assert_allclose(cuts.measure(late, 1), [0.004], atol=1e-12)  # the old rule's spike
    # Past the corner and 3 µm beside the cut: a genuine offset, the same under both rules.
    beside = np.array([[10.003, 1.0, 0.0], [9.997, 2.0, 0.0]])
    np.testing.assert_allclose(path.measure(beside, 1), [0.003, 0.003], atol=1e-12)
    np.testing.assert_allclose(cuts.measure(beside, 1), [0.003, 0.003], atol=1e-12)
    # Inside the corner, short of it: the nearer of the two lines (closed form min(dy, dx)).
    inside = np.array([[9.995, 0.002, 0.0]])
    np.testing.assert_allclose(path.measure(inside, 1), [0.002], atol=1e-12)
    np.testing.assert_allclose(cuts.measure(inside, 1), [0.005], atol=1e-12)
    # Outside the corner (overshoot in X): the corner is the nearest point under both rules.
    over = np.array([[10.003, -0.004, 0.0]])
    np.testing.assert_allclose(path.measure(over, 1), [0.005], atol=1e-12)
    np.testing.assert_allclose(cuts.measure(over, 1), [0.005], atol=1e-12)


def test_rapids_behind_only_within_the_window():
    # A rapid, then many 1 mm cuts: once the window (2 segments back) has left the rapid it is no candidate.
    segments = [("rapid", (0, 0, 5), (0, 0, 0))]
    segments += [("line", (k, 0, 0), (k + 1, 0, 0)) for k in range(6)]
    tp = build(*segments)
    meter = ContourErrorMeter(tp, window_back=2)
    on_rapid = np.array([[0.0, 0.0, 1.0]])
    np.testing.assert_allclose(meter.measure(on_rapid, 2), [0.0], atol=1e-12)  # window [0, ...]
    np.testing.assert_allclose(meter.measure(on_rapid, 4), [math.sqrt(2.0)], atol=1e-12)  # from (1, 0, 0)


def test_the_env_meter_rule_removes_the_rapid_to_cut_spike_and_nothing_else():
    # circle: a rapid to Z4, then a plunge; the controller releases the plunge with the tool still 4.6 µm
    # above Z4 on the rapid (in-position width 10 µm). The cuts rule measured ~4.1 µm there.
    from cnc_gym.envs.feedrate import FeedrateEnv

    errors = {}
    for rule in ("cuts", "path"):
        env = FeedrateEnv(programs=["circle"], contour_rule=rule)
        env.reset(seed=0)
        steps = []
        while True:
            *_, terminated, truncated, info = env.step(np.zeros(1, dtype=np.float32))
            steps.append((info["cycle_time_s"], info["contour_error_mm"]))
            if terminated or truncated:
                break
        errors[rule] = np.array(steps)
    cuts, path = errors["cuts"], errors["path"]
    np.testing.assert_array_equal(cuts[:, 0], path[:, 0])  # the same motion
    spike = int(np.argmax(np.abs(cuts[:, 1] - path[:, 1])))
    assert cuts[spike, 0] == pytest.approx(0.59) and cuts[spike, 1] == pytest.approx(0.0041, abs=2e-4)
    assert path[spike, 1] < 1e-4
    others = np.arange(len(cuts)) != spike
    np.testing.assert_allclose(path[others, 1], cuts[others, 1], atol=1e-6)
