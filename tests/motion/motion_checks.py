"""Shared helpers for the controller tests: random programs and an independent limit checker.

The checker recomputes what it needs from the toolpath and the machine (direction components, curvature,
corner steps) instead of reading the controller's tables, so a wrong table is caught too. Only the
``cap`` lookup per tick uses the controller's own segment list, and that list is checked separately in
test_motion_limits.py against closed forms.
"""

from __future__ import annotations

import math

import numpy as np

from cnc_gym.machine import MachineConfig
from cnc_gym.motion import Controller, MotionChunk
from cnc_gym.motion import kernel as K
from cnc_gym.motion.limits import NURBS_MAX_SAMPLES
from cnc_gym.toolpath import PLANE_AXES, Plane, SegmentKind, SegmentMode, Toolpath, ToolpathBuilder

REL_TOL = 1e-6


def random_program(rng: np.random.Generator, n_blocks: int, *, arcs: bool = True,
                   exact_stop_p: float = 0.1, dwell_p: float = 0.05, rapid_p: float = 0.05,
                   step_mm: float = 3.0, nurbs_p: float = 0.0) -> Toolpath:  # fmt: skip
    """A random 3-D program: lines of random length and direction, arcs and helices in all three planes
    (some full circles), exact stops, dwells, rapids."""
    b = ToolpathBuilder()
    p = np.zeros(3)
    for line in range(1, n_blocks + 1):
        r = rng.random()
        modes = SegmentMode.EXACT_STOP if rng.random() < exact_stop_p else SegmentMode.NONE
        feed = float(rng.uniform(300.0, 12000.0))
        if r < dwell_p:
            b.dwell(tuple(p), float(rng.uniform(0.0, 0.02)), line=line)
            continue
        if nurbs_p and r > 1.0 - nurbs_p:
            from cnc_gym.toolpath.nurbs import NurbsCurve

            n_ctrl = int(rng.integers(4, 7))
            ctrl = p + np.cumsum(rng.normal(size=(n_ctrl, 3)) * np.array([1.0, 1.0, 0.2]) * step_mm, axis=0)
            ctrl[0] = p
            inner = np.sort(rng.uniform(0.0, 1.0, size=n_ctrl - 4))
            knots = np.concatenate((np.zeros(4), inner, np.ones(4)))
            curve = NurbsCurve(ctrl, rng.uniform(0.5, 2.0, size=n_ctrl), knots, order=4)
            b.nurbs(curve, feed=feed, line=line, modes=modes)
            p = ctrl[-1].copy()
            continue
        if r < dwell_p + rapid_p:
            q = p + rng.normal(size=3) * step_mm * 3
            b.rapid(tuple(p), tuple(q), line=line)
        elif arcs and r < 0.45:
            plane = Plane(int(rng.integers(0, 3))) if rng.random() < 0.4 else Plane.XY
            u, v, w = PLANE_AXES[plane]
            radius = float(rng.uniform(0.2, 3.0) * step_mm)
            phi = rng.uniform(-np.pi, np.pi)
            center = p.copy()
            center[u] -= radius * np.cos(phi)
            center[v] -= radius * np.sin(phi)
            sweep = float(rng.uniform(0.1, 1.5 * np.pi) * rng.choice([-1.0, 1.0]))
            if rng.random() < 0.05:
                sweep = float(np.sign(sweep) * 2 * np.pi)  # full circle
            rise = float(rng.normal() * 0.3 * step_mm) if rng.random() < 0.3 else 0.0
            q = p.copy()
            q[u] = center[u] + radius * np.cos(phi + sweep)
            q[v] = center[v] + radius * np.sin(phi + sweep)
            q[w] = p[w] + rise
            b.arc(tuple(p), tuple(q), tuple(center), plane, sweep, feed=feed, line=line, modes=modes)
        else:
            length = float(rng.exponential(step_mm)) + 1e-3
            d = rng.normal(size=3)
            if rng.random() < 0.5:
                d[2] = 0.0
            d /= np.linalg.norm(d)
            q = p + d * length
            b.line(tuple(p), tuple(q), feed=feed, line=line, modes=modes)
        p = q
    return b.build()


def crossing_speeds(chunk: MotionChunk, s_points: np.ndarray, s0: float = 0.0, v0: float = 0.0,
                    a0: float = 0.0) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """Exact speed at which the profile crosses each arc length in ``s_points`` (within the run).

    Re-integrates each period's constant jerk (the chunk reports it) from the previous tick's state, so this
    checks the continuous profile between samples. Returns (speeds, mask of points crossed)."""
    s_prev = np.concatenate(([s0], chunk.path_s[:-1]))
    v_prev = np.concatenate(([v0], chunk.speed[:-1]))
    a_prev = np.concatenate(([a0], chunk.accel[:-1]))
    dt = np.diff(np.concatenate(([chunk.time_s[0] - (chunk.time_s[1] - chunk.time_s[0])], chunk.time_s)))
    speeds = np.full(len(s_points), np.nan)
    crossed = np.zeros(len(s_points), dtype=bool)
    tick = np.searchsorted(chunk.path_s, s_points, side="left")
    for i, (s_q, t_i) in enumerate(zip(s_points, tick, strict=True)):
        if t_i >= len(chunk.path_s):
            continue
        crossed[i] = True
        s_a, v_a, a_a, j, h = s_prev[t_i], v_prev[t_i], a_prev[t_i], chunk.jerk[t_i], dt[t_i]
        if s_q <= s_a:
            speeds[i] = v_a
            continue
        if abs(chunk.path_s[t_i] - s_q) <= 1e-12 * max(1.0, abs(s_q)):  # a tick ends on the point
            speeds[i] = chunk.speed[t_i]
            continue
        lo, hi = 0.0, h
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            if s_a + v_a * mid + a_a * mid**2 / 2 + j * mid**3 / 6 < s_q:
                lo = mid
            else:
                hi = mid
        speeds[i] = v_a + a_a * hi + j * hi**2 / 2
    return speeds, crossed


def expected_corner_limit(tp: Toolpath, machine: MachineConfig, s_junction: float,
                          eps: float = 1e-10) -> float:  # fmt: skip
    """GSK corner step at the junction at arc length ``s_junction``: v <= min_k step_k / |u_out,k - u_in,k|
    (mm/s), with the unit tangents evaluated just before and just after it (independent of the controller)."""
    _, tangents, _ = tp.evaluate(np.array([s_junction - eps, s_junction + eps]))
    du = np.abs(tangents[1] - tangents[0])
    step = np.array(machine.axis_array("corner_step_mm_min")) / 60.0
    with np.errstate(divide="ignore"):
        return float(np.min(np.where(du > 1e-7, step / np.maximum(du, 1e-300), np.inf)))


def check_run(controller: Controller, chunk: MotionChunk, overrides: np.ndarray | None = None) -> None:
    """Assert every limit on a run from reset: speed caps, tangential accel/jerk, per-axis speed,
    corner speeds, exact stops, path following and the final stop. ``overrides``: the knob per tick
    (None = constant 1.0); the feed target is only checked where the knob was constant."""
    tp = controller.toolpath
    machine = controller.machine
    lim = controller.segment_limits()
    junctions = controller.junction_limits()
    tol_v = 1e-6 + REL_TOL * np.max(lim["cap_mm_s"], initial=1.0)
    # --- speed, acceleration and jerk against the segment the reference is on
    moving = np.isin(tp.kind[chunk.segment],
                     (SegmentKind.LINE, SegmentKind.ARC, SegmentKind.RAPID, SegmentKind.NURBS))  # fmt: skip
    # the controller's piece (segment row) under each tick, by arc length (NURBS rows have several pieces)
    rows = np.searchsorted(lim["s_start"], chunk.path_s, side="right") - 1
    on = moving & (rows >= 0) & (len(lim["index"]) > 0)
    rows = np.clip(rows, 0, max(len(lim["index"]) - 1, 0))
    on &= lim["index"][rows] == chunk.segment if len(lim["index"]) else on
    r = rows[on]
    assert np.all(chunk.speed >= -1e-12), "reverse motion"
    assert np.all(chunk.speed[on] <= lim["cap_mm_s"][r] + tol_v), "speed above the segment cap"
    acc = np.maximum(lim["accel_mm_s2"][r], 0)
    assert np.all(np.abs(chunk.accel[on]) <= acc * (1 + REL_TOL) + 1e-6), "acceleration above the limit"
    # a period's jerk acts from where the period started (it may end on the next piece)
    s_before = np.concatenate(([chunk.path_s[0]], chunk.path_s[:-1]))
    r_start = np.clip(np.searchsorted(lim["s_start"], s_before, side="right") - 1, 0, None)[on]
    jerk_lim = lim["jerk_mm_s3"][r_start]
    jerk_ok = np.abs(chunk.jerk[on]) <= jerk_lim * (1 + REL_TOL) + 1e-6
    assert np.all(jerk_ok), "jerk above the limit"
    # --- kinematic consistency: each period's speed change is the integral of its acceleration (exact for a
    # constant jerk; within J·T²/4 where a braking switch falls inside the period) — no speed teleports,
    # e.g. a stop reached too fast and then snapped to rest.
    dt_ = controller.dt
    dv = np.diff(chunk.speed)
    dv_expected = 0.5 * (chunk.accel[1:] + chunk.accel[:-1]) * dt_
    jerk_top = np.max(lim["jerk_mm_s3"], initial=0.0)
    slack = jerk_top * dt_**2 / 4 + 1e-9 + 1e-9 * np.abs(chunk.speed[1:])
    assert np.all(np.abs(dv - dv_expected) <= slack), "speed jumped"
    # --- per-axis speed from the positions (finite differences bound the mean axis speed per tick)
    dt = controller.dt
    axis_v = np.abs(np.diff(chunk.position, axis=0)) / dt
    cutting_next = chunk.cutting[1:]
    vmax_cut = np.array(machine.axis_array("max_feed_mm_min")) / 60.0
    vmax_rapid = np.array(machine.axis_array("rapid_mm_min")) / 60.0
    assert np.all(axis_v[cutting_next] <= vmax_cut * (1 + 1e-6) + 1e-6), "cutting axis speed above P1225"
    assert np.all(axis_v[~cutting_next] <= vmax_rapid * (1 + 1e-6) + 1e-6), "axis speed above the rapid rate"
    # --- the reference stays on the programmed path
    point, _, _ = tp.evaluate(chunk.path_s)
    on_path = chunk.segment >= 0
    off_path = np.linalg.norm(point - chunk.position, axis=1)
    # Lines and arcs: the kernel and Toolpath.evaluate compute the same point in different float operations;
    # each rounds to a few ulp of the largest magnitude involved (arc length or coordinate), measured ≤ 2.5
    # ulp over random 3-D programs; 16 ulp of that scale (3.6e-12 mm on a 1000 mm path) is float noise, not
    # geometry.
    scale = np.maximum(1.0, np.maximum(np.abs(chunk.path_s), np.abs(chunk.position).max(axis=1)))
    tol_path = 16 * np.finfo(float).eps * scale
    # NURBS pieces: the kernel interpolates a cubic Hermite table (points and unit tangents by arc length),
    # refined until it is within NURBS_TABLE_TOL_MM (1e-10 mm) of the curve at every interval midpoint:
    # 1e-9 allows for the error between midpoints. Where the refinement stopped at NURBS_MAX_SAMPLES (a
    # near-cusp: radius of curvature below the sample spacing h), only the table's own bound holds: the
    # Hermite point is within h·(1 + |h10| + |h11|) ≤ 1.3 h of the first sample, the curve within h of it,
    # so 2.3 h (h = piece / 1024 ≤ 0.49 µm for 0.5 mm pieces). Measured: 0.32 µm off at a radius of 17 nm.
    if len(lim["index"]):
        nurbs_rows = controller.limits.seg_i[rows, K.I_TABLE] >= 0
        n_samples = controller.limits.seg_i[rows, K.I_NSAMP]
        spacing = lim["length"][rows] / np.maximum(n_samples - 1, 1)
        capped = n_samples >= NURBS_MAX_SAMPLES
        tol_path = np.where(nurbs_rows, np.where(capped, 2.3 * spacing, 1e-9), tol_path)
        # Blocks shorter than MIN_LENGTH_MM are dropped as geometry: at a stop after one the reference rests
        # at the end of the block it reports while the arc length already counts the dropped length.
        last_row = np.clip(np.searchsorted(lim["index"], chunk.segment, side="right") - 1, 0, None)
        reported = lim["index"][last_row] == chunk.segment
        seg_end = lim["s_start"][last_row] + lim["length"][last_row]
        tol_path = tol_path + np.where(reported, np.maximum(chunk.path_s - seg_end, 0.0), 0.0)
    assert np.all(off_path[on_path] <= tol_path[on_path]), "reference off the path"
    assert np.all(np.diff(chunk.path_s) >= -1e-12), "path position went backwards"
    # no jumps: a chord is never longer than the arc travelled (dropped sub-nm blocks aside), give or take how
    # far each of its two ends may be off the path (the triangle inequality: a capped NURBS table, above,
    # allows 2.3 h at each end; hypothesis found a 0.12 mm near-cusp piece 2.009 µm over a flat 2 µm)
    step = np.linalg.norm(np.diff(chunk.position, axis=0), axis=1)
    off_allowed = np.where(on_path, tol_path, 0.0)
    chord_slack = 2e-6 + off_allowed[1:] + off_allowed[:-1]
    assert np.all(step <= np.diff(chunk.path_s) + chord_slack), "the reference jumped"
    # --- speed through each junction (exact crossing speed) against the corner limit, and stops
    s_pts = junctions["s"][1:-1]
    if len(s_pts):
        speeds, crossed = crossing_speeds(chunk, s_pts)
        limits = junctions["limit_mm_s"][1:-1]
        # Where the braking switches inside a period the chunk reports the period's mean jerk, so the
        # re-integrated crossing speed can be off by at most J·T²/4 (the exact profile is not).
        tol_cross = tol_v + np.max(lim["jerk_mm_s3"], initial=0.0) * dt**2 / 4
        assert np.all(speeds[crossed] <= limits[crossed] + tol_cross), "junction crossed above its limit"
        stops = junctions["stop"][1:-1] & crossed
        # At rest to rounding: a stop reached within ε = 1e-12·s of its point (float resolution of s) may
        # carry the speed of a jerk-limited ramp that still has ε to go, v = J^(1/3)·(6ε)^(2/3)/2.
        eps = 1e-12 * np.maximum(1.0, np.abs(s_pts))
        tol_stop = 1e-6 + 0.5 * np.cbrt(np.max(lim["jerk_mm_s3"], initial=0.0)) * (6 * eps) ** (2 / 3)
        assert np.all(np.abs(speeds[stops]) <= tol_stop[stops]), "no stop at a mandatory stop"
        # the corner limit itself, recomputed independently for cutting junctions
        for q in np.flatnonzero(crossed & ~junctions["stop"][1:-1])[:50]:
            expected = min(expected_corner_limit(tp, machine, float(s_pts[q])), lim["cap_mm_s"][q],
                           lim["cap_mm_s"][q + 1])  # fmt: skip
            if machine.controller.corner_rule == "jerk":  # the jerk rule only lowers it (tested on its own)
                assert limits[q] <= expected * (1 + 1e-4) + 1e-9
            else:
                assert math.isclose(limits[q], expected, rel_tol=1e-4, abs_tol=1e-9)
            assert speeds[q] <= expected + tol_cross
    # --- feed target at constant override
    if overrides is None:
        base = lim["base_mm_s"][r]
        assert np.all(chunk.speed[on] <= np.minimum(base, lim["cap_mm_s"][r]) + tol_v), "speed above F"
    # --- end of program
    if controller.finished:
        assert chunk.speed[-1] == 0.0 and chunk.accel[-1] == 0.0
        if len(lim["index"]):
            last = int(lim["index"][-1])
            assert np.allclose(chunk.position[-1], tp.end[last], atol=1e-9)
