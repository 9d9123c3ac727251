"""Exact NURBS segments (GSK 25i G06.2) against closed forms, brute force and the G06.2 rules."""

import itertools
import math
import pickle
import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cnc_gym.toolpath import SegmentKind, Toolpath, ToolpathBuilder
from cnc_gym.toolpath.nurbs import NurbsCurve

SQRT_HALF = math.sqrt(0.5)


def quarter_circle(radius: float) -> NurbsCurve:
    """The textbook rational quadratic quarter circle: the middle weight is cos(45°) = √2/2."""
    return NurbsCurve([[radius, 0, 0], [radius, radius, 0], [0, radius, 0]], [1, SQRT_HALF, 1],
                      [0, 0, 0, 1, 1, 1], order=3)  # fmt: skip


def full_circle(radius: float, z: float = 0.0) -> NurbsCurve:
    """Nine control points on the square around the circle, double interior knots (four quarters)."""
    r = radius
    points = [[r, 0], [r, r], [0, r], [-r, r], [-r, 0], [-r, -r], [0, -r], [r, -r], [r, 0]]
    weights = [1, SQRT_HALF] * 4 + [1]
    knots = [0, 0, 0, 0.25, 0.25, 0.5, 0.5, 0.75, 0.75, 1, 1, 1]
    return NurbsCurve([[x, y, z] for x, y in points], weights, knots, order=3)


def _one_nurbs(curve: NurbsCurve, feed: float = 800.0) -> Toolpath:
    b = ToolpathBuilder()
    b.nurbs(curve, feed, line=7)
    return b.build()


# ---------------------------------------------------------------------------------------------- geometry


def test_degree_one_nurbs_is_its_polyline():
    # Rank 2: on each span the curve is a (rational) linear blend of two consecutive control points, so
    # whatever the weights and knots, the point set is the polyline and the length its leg sum (the
    # weights only change the speed along each leg, which the arc-length evaluation must undo).
    points = np.array([[0, 0, 0], [3, 4, 0], [3, 4, 12], [0, 0, 12]], dtype=float)
    legs = [5.0, 12.0, 5.0]
    curve = NurbsCurve(points, [1.0, 3.0, 0.5, 2.0], [0, 0, 0.2, 0.9, 1, 1], order=2)
    assert curve.length == pytest.approx(sum(legs), rel=1e-12)

    reference = ToolpathBuilder()
    for a, b in itertools.pairwise(points):
        reference.line(tuple(a), tuple(b), feed=100, line=1)
    polyline = reference.build()
    tp = _one_nurbs(curve)
    s = np.linspace(0, sum(legs), 45)
    got, tangent, curvature = tp.evaluate(s)
    expected, expected_tangent, _ = polyline.evaluate(s)
    np.testing.assert_allclose(got, expected, atol=1e-9)
    inner = np.abs(s[:, None] - np.cumsum(legs)[None, :-1]).min(axis=1) > 1e-6  # away from the corners
    np.testing.assert_allclose(tangent[inner], expected_tangent[inner], atol=1e-9)
    np.testing.assert_allclose(curvature, 0.0, atol=1e-9)


@pytest.mark.parametrize("radius", [0.5, 10.0, 250.0])
def test_rational_quadratic_quarter_circle_is_exact(radius):
    curve = quarter_circle(radius)
    # Length πR/2; every point on the circle; curvature 1/R; tangent ⟂ radius.
    assert curve.length == pytest.approx(math.pi * radius / 2, rel=1e-12)
    t = np.linspace(0, 1, 101)
    point, tangent, curvature = curve.tangent_curvature(t)
    np.testing.assert_allclose(np.linalg.norm(point, axis=1), radius, rtol=1e-13)
    np.testing.assert_allclose(curvature, 1 / radius, rtol=1e-10)
    np.testing.assert_allclose(np.einsum("ij,ij->i", tangent, point), 0, atol=1e-10 * radius)
    # By arc length: the point at s sits at polar angle s/R (exact arc-length parametrisation).
    s = np.linspace(0, curve.length, 37)
    point_s, tangent_s, _ = curve.at_length(s)
    np.testing.assert_allclose(np.arctan2(point_s[:, 1], point_s[:, 0]), s / radius, atol=1e-12)
    np.testing.assert_allclose(tangent_s, np.column_stack((-np.sin(s / radius), np.cos(s / radius),
                                                           np.zeros_like(s))), atol=1e-12)  # fmt: skip


def test_full_circle_with_double_knots_in_a_toolpath():
    # Four rational quarters joined by double knots (C¹ geometry; the parametrisation speed jumps).
    radius = 7.0
    b = ToolpathBuilder()
    b.line((0, 0, 2), (radius, 0, 2), feed=500, line=1)
    b.nurbs(full_circle(radius, z=2.0), 500, line=2)
    tp = b.build()
    assert tp.length[1] == pytest.approx(2 * math.pi * radius, rel=1e-12)
    assert tp.total_length == pytest.approx(radius + 2 * math.pi * radius, rel=1e-12)
    s = radius + np.linspace(0, 2 * math.pi * radius, 64)
    point, _, curvature = tp.evaluate(s)
    angle = np.mod(np.arctan2(point[:, 1], point[:, 0]), 2 * math.pi)
    expected = np.mod((s - radius) / radius, 2 * math.pi)
    wrapped = np.minimum(np.abs(angle - expected), 2 * math.pi - np.abs(angle - expected))
    np.testing.assert_allclose(wrapped, 0, atol=1e-11)
    np.testing.assert_allclose(point[:, 2], 2.0)
    np.testing.assert_allclose(curvature, 1 / radius, rtol=1e-9)


def test_parabola_length_and_curvature_closed_form():
    # Non-rational quadratic Bézier P0=(0,0), P1=(a/2,0), P2=(a,a²) is y = x² with x = a·t. Its length is
    # ∫₀^a √(1+4x²) dx = a√(1+4a²)/2 + asinh(2a)/4 and its curvature 2/(1+4x²)^{3/2}.
    a = 3.0
    curve = NurbsCurve([[0, 0, 0], [a / 2, 0, 0], [a, a * a, 0]], [1, 1, 1], [0, 0, 0, 1, 1, 1], order=3)
    exact = a * math.sqrt(1 + 4 * a * a) / 2 + math.asinh(2 * a) / 4
    assert curve.length == pytest.approx(exact, rel=1e-12)
    x = np.linspace(0, a, 13)
    point, _, curvature = curve.tangent_curvature(x / a)
    np.testing.assert_allclose(point[:, 1], x**2, atol=1e-12)
    np.testing.assert_allclose(curvature, 2 / (1 + 4 * x**2) ** 1.5, rtol=1e-10)
    # Arc length to x = 1: (√5)/2 + asinh(2)/4.
    assert curve.length_at(1 / a)[0] == pytest.approx(math.sqrt(5) / 2 + math.asinh(2) / 4, rel=1e-12)


def test_clamped_cubic_ends_and_end_tangents():
    # A clamped curve interpolates its end control points, and there P'(x₀) = p·(w₁/w₀)/(x_{p+1} - x₁)·
    # (P₁ - P₀) (p = degree), P'(x_m) = p·(w_{n-2}/w_{n-1})/(x_{m-p-1}... ) along the last leg.
    points = np.array([[0, 0, 0], [2, 1, 0], [4, -1, 1], [6, 3, 2], [9, 3, 2]], dtype=float)
    weights = np.array([1.0, 2.0, 0.7, 1.5, 1.2])
    knots = np.array([0, 0, 0, 0, 0.4, 1, 1, 1, 1])
    curve = NurbsCurve(points, weights, knots, order=4)
    point, d1, _ = curve.derivatives([0.0, 1.0])
    np.testing.assert_allclose(point[0], points[0], atol=1e-13)
    np.testing.assert_allclose(point[1], points[-1], atol=1e-13)
    # Start: x_{p+1} - x_1 = x_4 - x_1 = 0.4 - 0; end: x_{m-1} - x_{m-p-1} = x_7 - x_4 = 1 - 0.4 = 0.6.
    np.testing.assert_allclose(d1[0], 3 * (weights[1] / weights[0]) / 0.4 * (points[1] - points[0]),
                               rtol=1e-12, atol=1e-12)  # fmt: skip
    np.testing.assert_allclose(d1[1], 3 * (weights[-2] / weights[-1]) / 0.6 * (points[-1] - points[-2]),
                               rtol=1e-12, atol=1e-12)  # fmt: skip
    _, tangent, _ = curve.at_length([0.0, curve.length])
    leg_start = (points[1] - points[0]) / np.linalg.norm(points[1] - points[0])
    leg_end = (points[-1] - points[-2]) / np.linalg.norm(points[-1] - points[-2])
    np.testing.assert_allclose(tangent[0], leg_start, atol=1e-12)
    np.testing.assert_allclose(tangent[1], leg_end, atol=1e-12)


def test_repeated_end_control_point_has_a_tangent():
    # P₀ = P₁: P'(x₀) = 0, but the curve leaves P₀ toward P₂ (P''(x₀) ∝ P₂ - P₀ there).
    points = [[0, 0, 0], [0, 0, 0], [4, 0, 0], [4, 4, 0]]
    curve = NurbsCurve(points, [1, 1, 1, 1], [0, 0, 0, 0, 1, 1, 1, 1], order=4)
    _, tangent, curvature = curve.at_length([0.0, 1e-9])
    np.testing.assert_allclose(tangent[0], [1, 0, 0], atol=1e-6)
    assert np.all(np.isfinite(curvature))
    # A hair further on (s = 1 nm, t ≈ 1e-5) the tangent is still the leg's to about t/2.
    np.testing.assert_allclose(tangent[1], [1, 0, 0], atol=1e-4)


def test_length_parameter_round_trip():
    rng = np.random.default_rng(3)
    curve = NurbsCurve(rng.uniform(-10, 10, (12, 3)), rng.uniform(0.3, 3, 12),
                       np.r_[[0] * 4, np.sort(rng.uniform(0, 5, 8)), [5] * 4], order=4)  # fmt: skip
    t = np.linspace(0, 5, 301)
    s = curve.length_at(t)
    assert np.all(np.diff(s) > 0) and s[0] == 0 and s[-1] == pytest.approx(curve.length, rel=1e-13)
    np.testing.assert_allclose(curve.parameter_at_length(s), t, atol=1e-11)
    # Length against a fine polyline of the curve (chord sums converge from below as O(h²)).
    dense = curve.evaluate(np.linspace(0, 5, 400_001))
    chords = np.sum(np.linalg.norm(np.diff(dense, axis=0), axis=1))
    assert chords <= curve.length and curve.length == pytest.approx(chords, rel=1e-8)


# ----------------------------------------------------------------------------------------- nearest point


def test_nearest_on_quarter_circle_closed_form():
    # Distance to a circle arc: |‖p_xy‖ - R| in the plane (with z), when the polar angle is inside the
    # arc; otherwise the nearer end point.
    radius = 10.0
    tp = _one_nurbs(quarter_circle(radius))
    queries = np.array([[3, 4, 0], [20, 20, 1], [0.0, 0.0, 0.0], [15, -5, 0], [-1, 12, 0]])
    dist, seg, s = tp.nearest(queries)
    expected = [5.0, math.hypot(20 * math.sqrt(2) - 10, 1), 10.0, math.hypot(5, 5), math.hypot(1, 2)]
    np.testing.assert_allclose(dist, expected, atol=1e-12)
    assert np.all(seg == 0)
    # Arc length of the foot point: R·(polar angle of the query), clamped to [0, πR/2].
    np.testing.assert_allclose(s[[0, 1, 3, 4]], [radius * math.atan2(4, 3), radius * math.pi / 4, 0,
                                                 radius * math.pi / 2], atol=1e-9)  # fmt: skip


def test_nearest_mixed_toolpath_picks_the_nurbs():
    b = ToolpathBuilder()
    b.rapid((0, 0, 5), (10, 0, 0), line=1)
    b.nurbs(quarter_circle(10.0), 600, line=2)
    b.line((0, 10, 0), (-10, 10, 0), feed=600, line=3)
    tp = b.build()
    dist, seg, s = tp.nearest([[7, 7, 0], [-5, 11, 0], [10, 0, 4]])
    assert list(seg) == [1, 2, 1]
    np.testing.assert_allclose(dist, [10 - 7 * math.sqrt(2), 1, 4], atol=1e-12)
    assert s[0] == pytest.approx(tp.s_start[1] + 10 * math.pi / 4)


def _random_curve(rng_data) -> NurbsCurve:
    order, n, points, weights, inner = rng_data
    knots = np.r_[[0.0] * order, np.sort(inner[: n - order]), [1.0] * order]
    return NurbsCurve(points[:n], weights[:n], knots, order)


curves = st.integers(2, 4).flatmap(lambda order: st.tuples(
    st.just(order),
    st.integers(order, 8),
    st.lists(st.tuples(*[st.floats(-20, 20)] * 3), min_size=8, max_size=8).map(np.array),
    st.lists(st.floats(0.3, 4.0), min_size=8, max_size=8).map(np.array),
    st.lists(st.floats(0.05, 0.95), min_size=6, max_size=6).map(np.array),
))  # fmt: skip


@settings(max_examples=40, deadline=None)
@given(data=curves, query=st.lists(st.tuples(*[st.floats(-30, 30)] * 3), min_size=3, max_size=3))
def test_nearest_matches_dense_brute_force(data, query):
    """The exact search is never worse than a dense sampling and never beats it by more than its gap."""
    try:
        curve = _random_curve(data)
    except ValueError:  # e.g. a random knot repeated rank times: rejected, covered by the tests below
        return
    query = np.array(query)
    dist, t, s = curve.nearest(query)
    dense = curve.evaluate(np.linspace(0, 1, 40_001))
    brute = np.min(np.linalg.norm(dense[None, :, :] - query[:, None, :], axis=2), axis=1)
    gap = np.max(np.linalg.norm(np.diff(dense, axis=0), axis=1))
    assert np.all(dist <= brute + 1e-9)
    assert np.all(dist >= brute - gap)
    # The returned parameter and arc length name the same foot point at that distance.
    np.testing.assert_allclose(np.linalg.norm(curve.evaluate(t) - query, axis=1), dist, atol=1e-9)
    point_at_s, _, _ = curve.at_length(s)
    np.testing.assert_allclose(np.linalg.norm(point_at_s - query, axis=1), dist, atol=1e-7)


def test_nearest_at_a_kink_knot():
    # Rank 4 with a triple interior knot: a C⁰ corner at P₃ = (4, 0, 0). The query sits on the corner's
    # bisector outside, so the nearest point is the corner itself.
    points = [[0, 0, 0], [1, 1, 0], [3, 1, 0], [4, 0, 0], [5, 1, 0], [7, 1, 0], [8, 0, 0]]
    curve = NurbsCurve(points, [1] * 7, [0, 0, 0, 0, 0.5, 0.5, 0.5, 1, 1, 1, 1], order=4)
    dist, t, _ = curve.nearest([[4, -3, 0]])
    assert dist[0] == pytest.approx(3.0, abs=1e-12) and t[0] == pytest.approx(0.5)


# ------------------------------------------------------------------------------------ validation, records


@pytest.mark.parametrize(
    ("points", "weights", "knots", "order", "message"),
    [
        ([[0, 0, 0]] * 4, [1] * 4, [0] * 4 + [1] * 4, 5, "rank must be 2, 3 or 4"),
        ([[0, 0, 0]] * 4, [1] * 4, [0] * 4 + [1] * 4, 2.5, "rank must be 2, 3 or 4"),
        ([[0, 0, 0]] * 3, [1] * 3, [0] * 3 + [1] * 4, 4, "at least 4 control points"),
        ([[0, 0]] * 4, [1] * 4, [0] * 4 + [1] * 4, 4, r"\(n, 3\) array"),
        ([[0, 0, 0]] * 4, [1] * 3, [0] * 4 + [1] * 4, 4, "one weight per control point"),
        ([[0, 0, 0]] * 4, [1, 0, 1, 1], [0] * 4 + [1] * 4, 4, "weight 2 is 0"),
        ([[0, 0, 0]] * 4, [1, 1, -2, 1], [0] * 4 + [1] * 4, 4, "weights must be positive"),
        ([[0, 0, 0]] * 4, [1] * 4, [0] * 4 + [1] * 3, 4, r"knot count must be .* = 4 \+ 4"),
        ([[0, 0, 0]] * 5, [1] * 5, [0, 0, 0, 0, 0.6, 0.4, 1, 1, 1], 4, "non-decreasing"),
        ([[0, 0, 0]] * 4, [1] * 4, [0, 0, 0, 0.1, 1, 1, 1, 1], 4, "the first 4 knots"),
        ([[0, 0, 0]] * 4, [1] * 4, [0, 0, 0, 0, 0.9, 1, 1, 1], 4, "the last 4 knots"),
        ([[0, 0, 0]] * 4, [1] * 4, [2] * 8, 4, "no parameter range"),
        ([[0, 0, 0]] * 5, [1] * 5, [0, 0, 0, 0, 0, 1, 1, 1, 1], 4, "repeat exactly 4 times"),
        ([[0, 0, 0]] * 6, [1] * 6, [0, 0, 0, 0.5, 0.5, 0.5, 1, 1, 1], 3, "repeats 3 times"),
        ([[0, 0, float("nan")]] * 4, [1] * 4, [0] * 4 + [1] * 4, 4, "finite"),
        ([[1, 2, 3]] * 4, [1] * 4, [0] * 4 + [1] * 4, 4, "all coincide"),
        ([[0, 0, 0]] * 4, [1e-4, 1e3, 1e-4, 1e3], [0] * 4 + [1] * 4, 4, "differ by more than a factor of 1e"),
    ],
)
def test_validation_errors(points, weights, knots, order, message):
    if message != "all coincide":  # distinct points, so that only the rule under test is broken
        points = [[i, p[1], p[2]] if len(p) == 3 else [i, p[1]] for i, p in enumerate(points)]
    with pytest.raises(ValueError, match=message):
        NurbsCurve(points, weights, knots, order)


def test_valid_definition_of_the_same_shape_is_accepted():
    # The baseline of the table above: a line as a clamped cubic (guards against over-strict checks).
    curve = NurbsCurve([[i, 0, 0] for i in range(4)], [1, 2, 2, 1], [0] * 4 + [1] * 4, 4)
    assert curve.length == pytest.approx(3.0, rel=1e-12)


def test_curve_is_immutable_and_owns_its_arrays():
    points = np.array([[10.0, 0, 0], [10, 10, 0], [0, 10, 0]])
    curve = NurbsCurve(points, [1, SQRT_HALF, 1], [0, 0, 0, 1, 1, 1], order=3)
    points[1, 0] = 99.0  # the caller's array is not the curve's
    assert curve.control_points[1, 0] == 10.0
    for name in ("control_points", "weights", "knots"):
        with pytest.raises(ValueError):
            getattr(curve, name)[0] = 1.0
    tp = _one_nurbs(curve)
    with pytest.raises(TypeError):
        tp.nurbs[0] = curve  # read-only mapping


def test_toolpath_rejects_nurbs_rows_without_curves():
    b = ToolpathBuilder()
    b.nurbs(quarter_circle(1.0), 100, line=1)
    tp = b.build()
    fields = {name: getattr(tp, name) for name in (
        "kind", "start", "end", "center", "plane", "radius", "start_angle", "sweep", "feed", "dwell_s",
        "line", "file_index", "modes", "tool", "spindle_rpm")}  # fmt: skip
    with pytest.raises(ValueError, match="NURBS rows"):
        Toolpath(**fields, nurbs={})
    with pytest.raises(TypeError, match="NurbsCurve"):
        b.nurbs("not a curve", 100, line=2)


def test_toolpath_with_nurbs_pickles():
    # Vector-env workers receive the tool path by pickle: the curves (and their tables) must travel.
    b = ToolpathBuilder()
    b.line((20, 0, 0), (10, 0, 0), feed=100, line=1)
    b.nurbs(quarter_circle(10.0), 100, line=2)
    tp = pickle.loads(pickle.dumps(b.build()))
    dist, seg, _ = tp.nearest([[3, 4, 0]])
    assert seg[0] == 1 and dist[0] == pytest.approx(5.0, abs=1e-12)
    with pytest.raises(TypeError):
        tp.nurbs[0] = tp.nurbs[1]


def test_builder_row_and_records():
    curve = quarter_circle(10.0)
    tp = _one_nurbs(curve, feed=750)
    assert tp.kind[0] == SegmentKind.NURBS and tp.line[0] == 7
    np.testing.assert_array_equal(tp.start[0], [10, 0, 0])
    np.testing.assert_array_equal(tp.end[0], [0, 10, 0])
    assert tp.path_feed[0] == 750  # F is the path speed along a NURBS
    (rec,) = tp.to_records()
    assert rec["kind"] == "nurbs" and rec["line"] == 7 and rec["feed"] == 750.0
    assert rec["start"] == [10.0, 0.0, 0.0] and rec["end"] == [0.0, 10.0, 0.0]
    assert rec["order"] == 3 and rec["knots"] == [0.0, 0.0, 0.0, 1.0, 1.0, 1.0]
    assert rec["control_points"] == [[10.0, 0.0, 0.0], [10.0, 10.0, 0.0], [0.0, 10.0, 0.0]]
    assert rec["weights"] == [1.0, 0.707106781187, 1.0]
    _, points = tp.sample(1.0)
    np.testing.assert_allclose(np.linalg.norm(points, axis=1), 10.0, rtol=1e-13)
    np.testing.assert_allclose(points[-1], [0, 10, 0], atol=1e-12)


# ------------------------------------------------------------------------ arc length: accuracy and work
def _reference_length(curve: NurbsCurve) -> float:
    """∫|P'| by scipy's adaptive quadrature on scipy's de Boor evaluation (not the curve's Taylor table),
    with each knot span cut geometrically towards both ends, where a small weight beside a large one
    packs millimetres of curve into 1e-7 of the parameter."""
    from scipy.integrate import quad
    from scipy.interpolate import BSpline

    homogeneous = np.column_stack((curve.control_points * curve.weights[:, None], curve.weights))
    spline = BSpline(curve.knots, homogeneous, curve.order - 1)
    derivative = spline.derivative()

    def speed(t: float) -> float:
        h, d = spline(t), derivative(t)
        return float(np.linalg.norm((d[:3] - d[3] * h[:3] / h[3]) / h[3]))

    total = 0.0
    breaks = np.unique(curve.knots)
    for lo, hi in itertools.pairwise(breaks):
        steps = (hi - lo) * np.logspace(-15, -1, 15)
        cuts = np.unique(np.concatenate(([lo, hi, 0.5 * (lo + hi)], lo + steps, hi - steps)))
        for a, b in itertools.pairwise(cuts):
            with warnings.catch_warnings():  # quad's round-off warnings at this tolerance
                warnings.simplefilter("ignore")
                total += quad(speed, a, b, epsabs=0.0, epsrel=1e-13, limit=500)[0]
    return total


SQUARE = [[0, 0, 0], [10, 0, 0], [10, 10, 0], [0, 10, 0]]


@pytest.mark.parametrize(
    "weights",
    [
        [1, 0.01, 1, 0.01],  # the R0.01 beside R1: 1 647 leaves and 2.8 s in one program
        [0.01, 1, 1, 0.01],
        [1e-3, 1e3, 1e-3, 1e3],  # the largest ratio allowed: 1e6
        [1e-3, 1e3, 1, 1],  # the curve leaves P0 for P1 within 3e-7 of the parameter: no node sees it
        [1, 1, 1e3, 1e-3],
    ],
)
def test_extreme_weights_keep_the_length_accurate_and_the_work_small(weights):
    curve = NurbsCurve(SQUARE, weights, [0] * 4 + [1] * 4, 4)
    assert curve.length == pytest.approx(_reference_length(curve), rel=1e-10)
    assert len(curve._leaf_t) < 1000  # leaves of the length table (the work)
    # Arc length and parameter stay each other's inverse, and the length is at least the chord sum.
    t = np.linspace(0, 1, 201)
    s = curve.length_at(t)
    assert np.all(np.diff(s) >= 0) and s[-1] == pytest.approx(curve.length, rel=1e-10)
    chords = np.sum(np.linalg.norm(np.diff(curve.evaluate(t), axis=0), axis=1))
    assert chords <= curve.length * (1 + 1e-9)


def test_a_rational_quadratic_with_a_tiny_middle_weight_is_cheap():
    # 8 program lines of the issue: R0.01 beside R1 took 4 s and 900 MB (200 000 leaves at an unreachable
    # 1e-13 tolerance); the speed's round-off now ends the splitting.
    curve = NurbsCurve([[0, 0, 0], [10, 0, 0], [10, 10, 0], [0, 10, 0]], [1, 0.01, 1, 0.01],
                       [0, 0, 0, 0.5, 1, 1, 1], 3)  # fmt: skip
    assert len(curve._leaf_t) < 200
    assert curve.length == pytest.approx(_reference_length(curve), rel=1e-11)
