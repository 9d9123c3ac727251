"""Corner smoothing (GSK P1401#1 EFL / P1473 / P1495, Syntec G05.1 Q1 E): the reference leaves the programmed
path by at most the tolerance, keeps speed through small corners, and is off where it must be."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from cnc_gym.machine import machine_from_dict
from cnc_gym.motion import Controller
from cnc_gym.motion import kernel as K
from cnc_gym.toolpath import SegmentKind, SegmentMode, ToolpathBuilder
from cnc_gym.toolpath.smoothing import SmoothingRules, smooth_corners


def machine(tolerance: float, **controller):
    """Slow, corner-limited limits (KIRL-like: 10 mm/s, 100 mm/s², 10 000 mm/s³) with a corner step small
    enough to keep them, so that corners cost time unless they are smoothed."""
    return machine_from_dict({
        "name": "smooth-test",
        "controller": {"max_feed_mm_min": 600, "max_centripetal_accel_mm_s2": 100,
                       "corner_smoothing_tolerance_mm": tolerance, "corner_smoothing_min_angle_deg": 90,
                       **controller},
        "axis_defaults": {"max_feed_mm_min": 600, "max_accel_mm_s2": 100, "max_jerk_mm_s3": 10000,
                          "corner_step_mm_min": 6},
    })  # fmt: skip


def polyline(points: np.ndarray, feed: float = 600.0, **kw):
    b = ToolpathBuilder()
    for i in range(len(points) - 1):
        b.line(tuple(points[i]), tuple(points[i + 1]), feed=feed, line=i + 1, **kw)
    return b.build()


def distance_to_polyline(p: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Distance of each row of p to the polyline through ``points`` (closed form per segment)."""
    a, b = points[:-1], points[1:]
    d = b - a
    length_sq = np.maximum(np.sum(d * d, axis=1), 1e-300)
    rel = p[:, None, :] - a[None, :, :]
    t = np.clip(np.einsum("pnk,nk->pn", rel, d) / length_sq, 0.0, 1.0)
    foot = a[None] + t[:, :, None] * d[None]
    return np.min(np.linalg.norm(p[:, None, :] - foot, axis=2), axis=1)


def organic(n: int = 120, radius: float = 15.0) -> np.ndarray:
    """A closed, wavy planar polyline of n short segments (CAM-style)."""
    th = np.linspace(0.0, 2 * np.pi, n + 1)
    r = radius * (1 + 0.25 * np.sin(3 * th) + 0.1 * np.cos(7 * th))
    return np.column_stack((r * np.cos(th), r * np.sin(th), np.zeros_like(th)))


# ------------------------------------------------------------------------------------------- properties
@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**31 - 1), n=st.integers(2, 25), tolerance=st.floats(1e-4, 0.5),
       step=st.floats(0.05, 3.0), planar=st.booleans())  # fmt: skip
def test_reference_never_leaves_the_programmed_path_by_more_than_the_tolerance(seed, n, tolerance, step,
                                                                            planar):  # fmt: skip
    rng = np.random.default_rng(seed)
    steps = rng.normal(size=(n, 3)) * step
    if planar:
        steps[:, 2] = 0.0
    points = np.vstack((np.zeros(3), np.cumsum(steps, axis=0)))
    keep = np.concatenate(([True], np.linalg.norm(np.diff(points, axis=0), axis=1) > 1e-3))
    points = points[keep]
    if len(points) < 2:
        return
    c = Controller(polyline(points), machine(tolerance, corner_smoothing_min_angle_deg=60),
                   in_position_check=False)  # fmt: skip
    chunk = c.run_to_end()
    assert c.finished
    deviation = distance_to_polyline(chunk.position, points)
    assert np.max(deviation) <= tolerance * (1 + 1e-9) + 1e-9
    np.testing.assert_allclose(chunk.position[-1], points[-1], atol=1e-9)
    # the reported segment is always a programmed row, in order
    assert np.all(np.diff(chunk.segment) >= 0) and chunk.segment.max() < len(points) - 1
    assert np.all(chunk.speed >= 0) and np.all(np.diff(chunk.path_s) >= -1e-12)


def test_blend_is_tangent_and_curvature_continuous_with_the_lines():
    points = np.array([[0, 0, 0], [2, 0, 0], [4, 1, 0], [6, 1, 0.5]], dtype=float)
    smoothed, origin = smooth_corners(polyline(points), SmoothingRules(0.05, min_angle_deg=60))
    blends = np.flatnonzero(smoothed.kind == SegmentKind.NURBS)
    assert len(blends) == 2
    assert origin.tolist() == [0, 0, 1, 1, 2]
    for row in blends:
        curve = smoothed.nurbs[int(row)]
        _, t0, k0 = curve.at_length(np.array([0.0]))
        _, t1, k1 = curve.at_length(np.array([curve.length]))
        u_in = smoothed.end[row - 1] - smoothed.start[row - 1]
        u_out = smoothed.end[row + 1] - smoothed.start[row + 1]
        np.testing.assert_allclose(t0[0], u_in / np.linalg.norm(u_in), atol=1e-9)
        np.testing.assert_allclose(t1[0], u_out / np.linalg.norm(u_out), atol=1e-9)
        assert k0[0] <= 1e-9 and k1[0] <= 1e-9  # the lines have zero curvature: G2 at both ends
        # continuous with the trimmed lines
        np.testing.assert_allclose(smoothed.end[row - 1], smoothed.start[row], atol=1e-12)
        np.testing.assert_allclose(smoothed.end[row], smoothed.start[row + 1], atol=1e-12)
        # the largest deviation is the tolerance (the half-length is not cut by the segment lengths here)
        s = np.linspace(0.0, curve.length, 401)
        p, _, _ = curve.at_length(s)
        assert np.max(distance_to_polyline(p, points)) == pytest.approx(0.05, rel=2e-3)


def test_smoothing_shortens_the_cycle_on_short_segments():
    points = organic()
    tp = polyline(points)
    plain = Controller(tp, machine(0.0), in_position_check=False).run_to_end()
    smooth = Controller(tp, machine(0.05), in_position_check=False).run_to_end()
    length = tp.total_length
    # L / v_max is the lower bound for any planner at 10 mm/s
    assert smooth.time_s[-1] < 0.75 * plain.time_s[-1]
    assert smooth.time_s[-1] >= length / 10.0
    assert np.max(distance_to_polyline(smooth.position, points)) <= 0.05 + 1e-9


# ------------------------------------------------------------------------------------------- where it is off
def test_off_by_default_and_without_lookahead():
    tp = polyline(organic(40))
    for m in (machine(0.0), machine(0.05, lookahead_blocks=1)):
        c = Controller(tp, m, in_position_check=False)
        assert np.all(c.limits.seg_i[:, K.I_TABLE] < 0)  # no curve pieces: nothing blended
        smoothed, _ = smooth_corners(tp, SmoothingRules(m.controller.corner_smoothing_tolerance_mm),
                                     lookahead=m.controller.lookahead_blocks > 1)  # fmt: skip
        assert smoothed is tp
        chunk = c.run_to_end()
        assert np.max(distance_to_polyline(chunk.position, organic(40))) <= 1e-9


def test_off_at_exact_stops_and_rapids_and_sharp_corners():
    b = ToolpathBuilder()
    b.line((0, 0, 0), (1, 0, 0), feed=600, line=1, modes=SegmentMode.EXACT_STOP)  # G09: a stop at (1, 0)
    b.line((1, 0, 0), (2, 0.2, 0), feed=600, line=2)  # blended with line 3
    b.line((2, 0.2, 0), (3, 0.2, 0), feed=600, line=3)
    b.line((3, 0.2, 0), (3, 1.2, 0), feed=600, line=4)  # a 90° corner: below the 150° included angle
    b.rapid((3, 1.2, 0), (4, 1.2, 0), line=5)
    b.rapid((4, 1.2, 0), (4, 2.2, 0), line=6)  # rapid-rapid corner: never blended
    tp = b.build()
    smoothed, origin = smooth_corners(tp, SmoothingRules(0.05))
    assert np.flatnonzero(smoothed.kind == SegmentKind.NURBS).tolist() == [2]
    assert origin[2] == 1  # the blend between lines 2 and 3 belongs to line 2
    c = Controller(tp, machine(0.05, corner_smoothing_min_angle_deg=150), in_position_check=False)
    chunk = c.run_to_end()
    # the reference passes exactly through the unblended corners
    for corner in ((1, 0, 0), (3, 0.2, 0), (4, 1.2, 0)):
        assert np.min(np.linalg.norm(chunk.position - corner, axis=1)) <= 1e-9
    assert np.min(np.linalg.norm(chunk.position - (2, 0.2, 0), axis=1)) > 1e-3


def test_tolerance_carried_by_the_tool_path_is_honoured():
    # Syntec G05.1 Q1 E0.02: the rows carry the tolerance; the machine's own is off.
    points = organic(60)
    b = ToolpathBuilder()
    b.smoothing({SegmentKind.LINE: 0.02})
    for i in range(len(points) - 1):
        b.line(tuple(points[i]), tuple(points[i + 1]), feed=600, line=i + 1)
    tp = b.build()
    c = Controller(tp, machine(0.0), in_position_check=False)
    chunk = c.run_to_end()
    deviation = distance_to_polyline(chunk.position, points)
    assert 0.005 < np.max(deviation) <= 0.02 + 1e-9
    # the tool path's tolerance rules over the machine's
    wide = Controller(tp, machine(0.3), in_position_check=False).run_to_end()
    assert np.max(distance_to_polyline(wide.position, points)) <= 0.02 + 1e-9


def test_blend_length_never_overlaps_its_neighbour():
    # Segments far shorter than the tolerance allows: each line gives half of itself to each blend.
    points = organic(200, radius=5.0)
    smoothed, _ = smooth_corners(polyline(points), SmoothingRules(0.5, min_angle_deg=60))
    lines = smoothed.kind == SegmentKind.LINE
    assert np.all(smoothed.length[lines] >= -1e-12)
    assert smoothed.total_length == pytest.approx(sum(c.length for c in smoothed.nurbs.values())
                                                  + smoothed.length[lines].sum())  # fmt: skip
    assert math.isfinite(smoothed.total_length)


def test_bulk_blend_samples_match_the_exact_curve():
    # The controller samples blends in bulk (blend_tables); the general NURBS evaluation must agree.
    from cnc_gym.toolpath.smoothing import blend_curves, blend_tables

    rng = np.random.default_rng(3)
    u_in = rng.normal(size=(5, 3))
    u_out = rng.normal(size=(5, 3))
    u_in /= np.linalg.norm(u_in, axis=1)[:, None]
    u_out /= np.linalg.norm(u_out, axis=1)[:, None]
    curves = blend_curves(rng.normal(size=(5, 3)), u_in, u_out, rng.uniform(0.01, 2.0, 5))
    tables = blend_tables(curves, [4] * 5, 1e-10, 9, 1025)
    for curve, pieces in zip(curves, tables, strict=True):
        s = np.concatenate([np.linspace(i * curve.length / 4, (i + 1) * curve.length / 4, len(p[0]))
                            for i, p in enumerate(pieces)])  # fmt: skip
        point, tangent, kappa = curve.at_length(s)
        np.testing.assert_allclose(np.concatenate([p[0] for p in pieces]), point, atol=1e-9)
        np.testing.assert_allclose(np.concatenate([p[1] for p in pieces]), tangent, atol=1e-7)
        np.testing.assert_allclose(np.concatenate([p[2] for p in pieces]), kappa, rtol=1e-6, atol=1e-9)


def test_time_optimal_bound_follows_the_smoothed_path():
    from cnc_gym.motion.bound import compute_bound

    tp = polyline(organic())
    smooth, plain = machine(0.05), machine(0.0)
    bound_smooth = compute_bound(tp, smooth).total_s
    assert bound_smooth < compute_bound(tp, plain).total_s
    assert bound_smooth <= Controller(tp, smooth, in_position_check=False).run_to_end().time_s[-1]
