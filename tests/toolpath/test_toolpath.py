"""Tool path geometry against closed forms and a brute-force reference."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cnc_gym.toolpath import Plane, SegmentKind, ToolpathBuilder


def _one_arc(start, end, center, plane, sweep, feed=1000.0):
    b = ToolpathBuilder()
    b.arc(start, end, center, plane, sweep, feed, line=1)
    return b.build()


def test_lengths_of_line_arc_helix_and_dwell():
    b = ToolpathBuilder()
    b.rapid((0, 0, 0), (3, 4, 0), line=1)  # 3-4-5 triangle
    b.line((3, 4, 0), (3, 4, 12), feed=500, line=2)
    b.arc((10, 0, 0), (-10, 0, 0), (0, 0, 0), Plane.XY, math.pi, 1000, line=3)  # half circle R10
    # Helix: one full turn of R 10 rising 5 mm. Length = sqrt((2πR)² + h²).
    b.arc((10, 0, 0), (10, 0, 5), (0, 0, 0), Plane.XY, 2 * math.pi, 1000, line=4)
    b.dwell((10, 0, 5), 2.0, line=5)
    tp = b.build()
    assert tp.length == pytest.approx([5, 12, 10 * math.pi, math.hypot(20 * math.pi, 5), 0])
    assert tp.s_start[-1] == pytest.approx(tp.total_length)
    # GSK: F is the speed of the projected arc, so the 3-D path speed on the helix is larger.
    assert tp.path_feed[3] == pytest.approx(1000 * math.hypot(20 * math.pi, 5) / (20 * math.pi))
    assert tp.path_feed[2] == pytest.approx(1000)


@pytest.mark.parametrize(
    ("plane", "start", "center", "quarter_ccw"),
    [
        # XY, normal +Z: CCW from +X goes to +Y.
        (Plane.XY, (5, 0, 0), (0, 0, 0), (0, 5, 0)),
        # ZX, normal +Y: u = Z, v = X, so CCW from +Z goes to +X.
        (Plane.ZX, (0, 0, 5), (0, 0, 0), (5, 0, 0)),
        # YZ, normal +X: u = Y, v = Z, so CCW from +Y goes to +Z.
        (Plane.YZ, (0, 5, 0), (0, 0, 0), (0, 0, 5)),
    ],
)
@pytest.mark.parametrize("direction", [1, -1])
def test_arc_quarter_points_in_every_plane(plane, start, center, quarter_ccw, direction):
    sweep = direction * math.pi / 2
    quarter = np.array(quarter_ccw, dtype=float) if direction > 0 else -np.array(quarter_ccw, dtype=float)
    tp = _one_arc(start, tuple(quarter), center, plane, sweep)
    point, tangent, curvature = tp.evaluate([0.0, tp.total_length / 2, tp.total_length])
    np.testing.assert_allclose(point[2], quarter, atol=1e-12)
    mid = (np.array(start, dtype=float) + quarter) / np.sqrt(2)  # 45° point on the R5 circle
    np.testing.assert_allclose(point[1], mid, atol=1e-12)
    # The tangent at the start points toward the quarter point.
    np.testing.assert_allclose(tangent[0], quarter / 5, atol=1e-12)
    np.testing.assert_allclose(curvature, 1 / 5)


def test_helix_curvature_closed_form():
    # Helix r = 10, rise c per radian = 5/(2π): curvature r/(r²+c²).
    tp = _one_arc((10, 0, 0), (10, 0, 5), (0, 0, 0), Plane.XY, 2 * math.pi)
    c = 5 / (2 * math.pi)
    _, tangent, curvature = tp.evaluate(tp.total_length / 3)
    assert curvature[0] == pytest.approx(10 / (100 + c * c))
    assert np.linalg.norm(tangent[0]) == pytest.approx(1.0)


def test_sampling_spacing_and_segment_ends():
    b = ToolpathBuilder()
    b.line((0, 0, 0), (10, 0, 0), feed=100, line=1)
    b.line((10, 0, 0), (10, 2.5, 0), feed=100, line=2)
    tp = b.build()
    s, points = tp.sample(1.0)
    assert s[0] == 0 and s[-1] == pytest.approx(12.5)
    assert np.all(np.diff(s) <= 1.0 + 1e-12)
    np.testing.assert_allclose(points[-1], (10, 2.5, 0))
    assert 10.0 in s  # the corner itself is sampled


def test_nearest_line_arc_and_rapid_exclusion():
    b = ToolpathBuilder()
    b.rapid((0, 0, 0), (0, 10, 0), line=1)
    b.line((0, 10, 0), (10, 10, 0), feed=100, line=2)
    b.arc((10, 10, 0), (10, -10, 0), (10, 0, 0), Plane.XY, -math.pi, 100, line=3)  # CW half circle x ≥ 10
    tp = b.build()
    queries = np.array([[5, 11, 0], [21, 0, 0], [10, 0, 0], [0, 5, 0], [5, 10, 3]])
    dist, seg, s = tp.nearest(queries)
    # (5,11): 1 above the line. (21,0): 1 outside the R10 arc at its mid point. (10,0): the arc centre,
    # 10 from every arc point and from the line's end. (0,5): on the rapid, but rapids don't count, so the
    # nearest cutting point is the line's start (0,10): distance 5. (5,10,3): 3 above the line.
    np.testing.assert_allclose(dist, [1, 1, 10, 5, 3], atol=1e-12)
    assert seg[0] == 1 and seg[1] == 2 and seg[3] == 1
    assert s[1] == pytest.approx(10 + 10 + 5 * math.pi)
    dist_all, seg_all, _ = tp.nearest(queries[3:4], cutting_only=False)
    assert dist_all[0] == pytest.approx(0) and seg_all[0] == 0


def test_nearest_empty_window_is_inf():
    b = ToolpathBuilder()
    b.rapid((0, 0, 0), (1, 0, 0), line=1)
    dist, seg, _ = b.build().nearest([[0, 0, 0]])
    assert np.isinf(dist[0]) and seg[0] == -1


def test_toolpath_is_immutable():
    b = ToolpathBuilder()
    b.line((0, 0, 0), (1, 0, 0), feed=1, line=1)
    tp = b.build()
    with pytest.raises(ValueError):
        tp.end[0, 0] = 5.0
    assert tp.kind[0] == SegmentKind.LINE


def test_records_follow_trace_contract():
    tp = _one_arc((10, 0, 0), (0, 10, 0), (0, 0, 0), Plane.XY, math.pi / 2, feed=600)
    (rec,) = tp.to_records()
    assert rec["kind"] == "arc" and rec["plane"] == "XY" and rec["line"] == 1
    assert rec["end"] == [0.0, 10.0, 0.0] and rec["center"] == [0.0, 0.0, 0.0]
    assert rec["sweep_deg"] == pytest.approx(90.0) and rec["feed"] == 600.0


coords = st.floats(-50, 50, allow_nan=False)


@settings(max_examples=150, deadline=None)
@given(
    cx=coords, cy=coords, radius=st.floats(1, 30), theta0=st.floats(-math.pi, math.pi),
    sweep=st.floats(-4 * math.pi, 4 * math.pi).filter(lambda x: abs(x) > 0.05),
    rise=st.sampled_from([0.0, 3.0, -7.0]), plane=st.sampled_from(list(Plane)),
    query=st.tuples(coords, coords, coords),
)  # fmt: skip
def test_nearest_matches_dense_sampling(cx, cy, radius, theta0, sweep, rise, plane, query):
    """The nearest-point distance equals the minimum over a dense sampling (to the sampling error)."""
    from cnc_gym.toolpath import PLANE_AXES

    u, v, w = PLANE_AXES[plane]
    start = np.zeros(3)
    start[u], start[v], start[w] = cx + radius * math.cos(theta0), cy + radius * math.sin(theta0), 1.0
    center = np.zeros(3)
    center[u], center[v], center[w] = cx, cy, 1.0
    end = np.zeros(3)
    end[u] = cx + radius * math.cos(theta0 + sweep)
    end[v] = cy + radius * math.sin(theta0 + sweep)
    end[w] = 1.0 + rise
    tp = _one_arc(tuple(start), tuple(end), tuple(center), plane, sweep)
    dist, _, s = tp.nearest([query])
    s_dense = np.linspace(0, tp.total_length, 20001)
    points, _, _ = tp.evaluate(s_dense)
    brute = np.min(np.linalg.norm(points - np.array(query), axis=1))
    spacing = tp.total_length / 20000
    assert dist[0] <= brute + 1e-9
    assert dist[0] >= brute - spacing  # cannot beat the true minimum by more than the sampling error
    point_at_s, _, _ = tp.evaluate(s[0])
    assert np.linalg.norm(point_at_s[0] - np.array(query)) == pytest.approx(dist[0], abs=1e-6)


def test_an_empty_tool_path_has_no_segment_at_any_length():
    tp = ToolpathBuilder().build()
    with pytest.raises(ValueError, match="empty"):
        tp.segment_at(0.0)
