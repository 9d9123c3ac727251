"""Planner version 1, frozen: the deployable schedule of ``cnc_gym/Feedrate-v1`` and ``-v2``.

Those env ids publish the planner's override (the ``planner_override`` observation entry and info key, and
the knob the ``residual`` action mode scales), so their planner is part of their definition and must not
move, not even in its last bits (``scripts/fingerprint_env.py``). This module keeps that planner as it
was: the servo model's steady caps at half the tolerance (line lag, arc, single-corner transient held
3/Kv of travel after the corner, chain curvature), the jerk-limited scan with its own S-curve solver, the
knob at ``max_override`` on rapids. It is reached through :class:`~cnc_gym.motion.planner.SchedulePlanner`
with ``version=1``; the live planner (version 2, :mod:`.schedule`) is what the ``classical`` baseline, the
benchmark and ``cnc_gym/Feedrate-v3`` use. Do not change this file: a fix here is a new planner version.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from cnc_gym.machine import MachineConfig
from cnc_gym.motion import kernel as K
from cnc_gym.motion.limits import PathLimits, build_limits
from cnc_gym.motion.planner.error_model import (
    SPEED_CEILING_MM_S,
    arc_caps,
    corner_error_per_speed,
    servo_tables,
)
from cnc_gym.motion.planner.record import Schedule
from cnc_gym.toolpath import SegmentKind, Toolpath


@njit(cache=True)
def _ramp_length(v0: float, v: float, accel: float, jerk: float) -> float:
    """Path length of the jerk-limited S-curve from ``v0`` to ``v`` (both at zero acceleration)."""
    dv = v - v0
    if dv <= 0:
        return 0.0
    t = 2.0 * math.sqrt(dv / jerk) if dv <= accel * accel / jerk else dv / accel + accel / jerk
    return 0.5 * (v0 + v) * t


@njit(cache=True)
def jerk_limited_reach(v0: float, distance_mm: float, accel: float, jerk: float) -> float:
    """Highest speed reachable from ``v0`` (at zero acceleration) within ``distance_mm``.

    S-curve with jerk ``jerk`` and acceleration capped at ``accel``: a change Δv ≤ A²/J takes
    T = 2·√(Δv/J) over L = (v0 + v)·√(Δv/J), i.e. ``(v − v0)(v + v0)² = J·L²`` (solved by Newton in
    w = v + v0 from the right, where the cubic is increasing and convex); a larger change takes
    T = Δv/A + A/J over L = (v0 + v)/2·T, a quadratic in v.

    Part of the frozen planner: the controller solves the same reach (:func:`cnc_gym.motion.kernel.
    reach_speed`, another Newton start and stop) and the two agree to the last bit or two, but Feedrate-v1
    and v2's planner observation is this solver's, bit for bit (the live planner uses the controller's).
    """
    if distance_mm <= 0:
        return v0
    dv_full = accel * accel / jerk
    if distance_mm > _ramp_length(v0, v0 + dv_full, accel, jerk):
        b = dv_full  # v² + (A²/J)·v + (v0·A²/J − v0² − 2·A·L) = 0
        c = v0 * dv_full - v0 * v0 - 2.0 * accel * distance_mm
        return 0.5 * (-b + math.sqrt(b * b - 4.0 * c))
    target = jerk * distance_mm * distance_mm
    w = 2.0 * v0 + dv_full
    for _ in range(60):
        f = (w - 2.0 * v0) * w * w - target
        step = f / (w * (3.0 * w - 4.0 * v0))
        w -= step
        if abs(step) < 1e-9 * max(w, 1.0):
            break
    return max(w - v0, v0)


@njit(cache=True)
def _scan(s: np.ndarray, out: np.ndarray, accel_at: np.ndarray, jerk: float) -> None:
    n = len(s)
    for backward in (True, False):
        have = False
        anchor_s = anchor_v = anchor_a = 0.0
        for k in range(n):
            i = n - 1 - k if backward else k
            if have:
                # The ramp from the anchor crosses every point since: the lowest acceleration among them.
                anchor_a = min(anchor_a, accel_at[i])
                distance = abs(anchor_s - s[i])
                # Cheap test first: is the cap itself reachable from the anchor?
                if _ramp_length(anchor_v, out[i], anchor_a, jerk) > distance:
                    out[i] = jerk_limited_reach(anchor_v, distance, anchor_a, jerk)
                    continue
            have = True
            anchor_s, anchor_v, anchor_a = s[i], out[i], accel_at[i]


#: Fraction of the contour tolerance the schedule aims at. Chosen on the val split of cnc-bench-v1 (score
#: 44.5 / 47.0 / 49.5 / 49.2 / 47.0 / 48.7 at 0.4 / 0.45 / 0.5 / 0.55 / 0.6 / 0.7), never on test.
MARGIN_V1 = 0.5
#: Junctions turning at least this much are corners (corner model); smaller turns make chain curvature.
CORNER_DEG = 10.0
#: Longest distance between two schedule points inside a move, mm.
NODE_SPACING_MM = 0.5


#: How long after a corner its cap holds, in loop time constants 1/Kv (the transient's peak comes later).
HOLD_TIME_CONSTANTS = 3.0


@njit(cache=True)
def _piece_tangents(seg_f: np.ndarray, seg_i: np.ndarray,
                    curve_f: np.ndarray) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """Unit tangent at the start and at the end of every motion piece of the controller's tables: chords
    of lines and rapids, arcs and helices from their angles, NURBS pieces from their sample table."""
    n = seg_f.shape[0]
    t0 = np.zeros((n, 3))
    t1 = np.zeros((n, 3))
    for k in range(n):
        if seg_i[k, K.I_TABLE] >= 0:  # NURBS piece: first and last sample of its table
            first = seg_i[k, K.I_TABLE]
            last = first + seg_i[k, K.I_NSAMP] - 1
            for a in range(3):
                t0[k, a] = curve_f[first, 3 + a]
                t1[k, a] = curve_f[last, 3 + a]
        elif seg_i[k, K.I_KIND] == K.KIND_ARC:
            r, sweep, rise = seg_f[k, K.F_RADIUS], seg_f[k, K.F_SWEEP], seg_f[k, K.F_RISE]
            u, v, w = seg_i[k, K.I_PU], seg_i[k, K.I_PV], seg_i[k, K.I_PW]
            theta = seg_f[k, K.F_ANG0]
            du, dv = -r * math.sin(theta) * sweep, r * math.cos(theta) * sweep
            norm = math.sqrt(du * du + dv * dv + rise * rise)
            t0[k, u], t0[k, v], t0[k, w] = du / norm, dv / norm, rise / norm
            theta += sweep
            du, dv = -r * math.sin(theta) * sweep, r * math.cos(theta) * sweep
            t1[k, u], t1[k, v], t1[k, w] = du / norm, dv / norm, rise / norm
        else:
            dx = seg_f[k, K.F_EX] - seg_f[k, K.F_SX]
            dy = seg_f[k, K.F_EY] - seg_f[k, K.F_SY]
            dz = seg_f[k, K.F_EZ] - seg_f[k, K.F_SZ]
            norm = max(math.sqrt(dx * dx + dy * dy + dz * dz), 1e-300)
            t0[k, 0], t0[k, 1], t0[k, 2] = dx / norm, dy / norm, dz / norm
            t1[k] = t0[k]
    return t0, t1


def _signed_turn(u_in: np.ndarray, u_out: np.ndarray) -> np.ndarray:
    """Turn at junctions: signed (counter-clockwise +) where both tangents lie in XY, else unsigned."""
    dot = np.clip(np.sum(u_in * u_out, axis=1), -1.0, 1.0)
    cross_z = u_in[:, 0] * u_out[:, 1] - u_in[:, 1] * u_out[:, 0]
    flat = (np.abs(u_in[:, 2]) < 1e-9) & (np.abs(u_out[:, 2]) < 1e-9)
    return np.where(flat, np.arctan2(cross_z, dot), np.arccos(dot))


def plan_schedule_v1(toolpath: Toolpath, machine: MachineConfig, *, limits: PathLimits | None = None,
                     margin: float = MARGIN_V1, max_override: float | None = None) -> Schedule:  # fmt: skip
    """Planner version 1's schedule of ``toolpath`` on ``machine`` (this module's docstring).

    ``limits``: the controller's static tables (:func:`cnc_gym.motion.limits.build_limits`), computed
    here when not given (an env's controller already holds them).
    """
    lim = limits if limits is not None else build_limits(toolpath, machine)
    tables = servo_tables(machine)
    ctl = machine.controller
    top = float(ctl.max_override if max_override is None else max_override)
    target = margin * float(ctl.contour_tolerance_mm)
    seg_f, seg_i, pt_f = lim.seg_f, lim.seg_i, lim.pt_f
    n = len(seg_f)
    if n == 0:
        return Schedule(s=np.zeros(1), cap_mm_s=np.full(1, np.inf), speed_mm_s=np.zeros(1),
                        override=np.full(1, top))  # fmt: skip
    s0, length = seg_f[:, K.F_S0], seg_f[:, K.F_LEN]
    cutting = seg_i[:, K.I_RAPID] == 0
    feed = np.where(cutting, seg_f[:, K.F_BASE], 0.0)
    locked = seg_i[:, K.I_LOCKED] != 0
    # ---- caps per move: the knob's range (programmed feed × max override) and the servo model. The
    # controller's own limits (its caps, corner speeds, stops) are left to the controller: putting them in
    # the knob would only make it slower to come back up (the applied override slews).
    piece_cap = np.where(cutting, feed * np.where(locked, 1.0, top), np.inf)
    kind = seg_i[:, K.I_KIND]
    straight = cutting & (kind == SegmentKind.LINE)
    if np.any(straight):
        tangent = (seg_f[straight, K.F_EX : K.F_EX + 3] - seg_f[straight, K.F_SX : K.F_SX + 3])
        tangent /= np.maximum(np.linalg.norm(tangent, axis=1), 1e-12)[:, None]
        lag = tangent * tables.lag_s[None, :]
        lateral = np.linalg.norm(lag - np.sum(lag * tangent, axis=1, keepdims=True) * tangent, axis=1)
        piece_cap[straight] = np.minimum(piece_cap[straight], np.where(lateral > 1e-12, target / np.maximum(
            lateral, 1e-12), SPEED_CEILING_MM_S))  # fmt: skip
    curved = cutting & (seg_f[:, K.F_CURV] > 1e-9)
    if np.any(curved):
        plane = np.where(kind[curved] == SegmentKind.ARC, toolpath.plane[seg_i[curved, K.I_TP]], 0)
        piece_cap[curved] = np.minimum(piece_cap[curved],
                                       arc_caps(tables, 1.0 / seg_f[curved, K.F_CURV], plane, target))
    # ---- junctions between cutting moves: the corner model
    junction = np.zeros(n + 1, dtype=bool)
    junction[1:n] = cutting[:-1] & cutting[1:]
    q = np.flatnonzero(junction)
    point_cap = np.full(n + 1, np.inf)
    turn = np.zeros(n + 1)
    if len(q):
        t_start, t_end = _piece_tangents(seg_f, seg_i, lim.curve_f)
        u_in, u_out = t_end[q - 1], t_start[q]
        turn[q] = _signed_turn(u_in, u_out)
        corner = np.abs(turn[q]) >= math.radians(CORNER_DEG)
        c = corner_error_per_speed(tables, u_in[corner], u_out[corner])
        point_cap[q[corner]] = np.where(c > 1e-12, target / np.maximum(c, 1e-12), SPEED_CEILING_MM_S)
        turn[q[corner]] = 0.0  # corners are the corner model's: leave them out of the chain curvature
    # ---- schedule points, corner holds, chain curvature, the scan and the knob: one compiled pass
    hold_s = HOLD_TIME_CONSTANTS / float(min(machine.axis_array("kv_1_s")))
    accel = float(min(machine.axis_array("max_accel_mm_s2")))
    jerk = float(min(machine.axis_array("max_jerk_mm_s3")))
    node_s, node_cap, speed, override = _schedule_nodes(
        s0, length, cutting, feed, piece_cap, point_cap, turn, np.ascontiguousarray(pt_f[:, K.P_S]), hold_s,
        tables.arc_omega, tables.arc_error[0], target, top, accel, jerk, float(ctl.override_slew_per_s))
    return Schedule(s=node_s, cap_mm_s=node_cap, speed_mm_s=speed, override=override)


@njit(cache=True)
def _schedule_nodes(s0, length, cutting, feed, piece_cap, point_cap, turn, point_s, hold_s, arc_omega,
                    arc_table, target, top, accel, jerk, slew_per_s):  # fmt: skip
    """Schedule points (every junction, and inside moves every NODE_SPACING_MM at most) with their caps:
    the move's cap, the junction's corner cap (held over ``cap·hold_s`` of travel after it), the chain
    curvature's arc cap (XY plane model); then the jerk-limited scan and the knob per point."""
    n = len(s0)
    count = np.empty(n, dtype=np.int64)
    total = 1
    for k in range(n):
        count[k] = max(math.ceil(length[k] / NODE_SPACING_MM), 1)
        total += count[k]
    node_s = np.empty(total)
    piece = np.empty(total, dtype=np.int64)
    point = np.full(total, -1, dtype=np.int64)  # the junction a point sits on, -1 inside a move
    i = 0
    for k in range(n):
        for j in range(count[k]):
            node_s[i] = s0[k] + j * length[k] / count[k]
            piece[i] = k
            if j == 0:
                point[i] = k
            i += 1
    node_s[i], piece[i], point[i] = s0[n - 1] + length[n - 1], n - 1, n
    cap = np.empty(total)
    for i in range(total):
        cap[i] = piece_cap[piece[i]]
        q = point[i]
        if q >= 0:
            cap[i] = min(cap[i], point_cap[q])
            if q > 0:
                cap[i] = min(cap[i], piece_cap[q - 1])
    # Corner holds.
    start = 0
    for q in range(n + 1):
        if not math.isfinite(point_cap[q]):
            continue
        while start < total and node_s[start] < point_s[q] - 1e-9:
            start += 1
        k = start
        while k < total and node_s[k] <= point_s[q] + point_cap[q] * hold_s:
            cap[k] = min(cap[k], point_cap[q])
            k += 1
    # Chain curvature: net turn over a window around each point.
    cum = np.cumsum(turn)
    for i in range(total):
        if not cutting[piece[i]]:
            continue
        q = point[i]
        if q >= 0:
            near = length[0] if q == 0 else (length[n - 1] if q == n else max(length[q - 1], length[q]))
        else:
            near = length[piece[i]]
        window = max(1.0, 2.5 * near)
        lo = np.searchsorted(point_s, node_s[i] - window / 2, side="left") - 1
        hi = np.searchsorted(point_s, node_s[i] + window / 2, side="right") - 1
        net = abs(cum[min(max(hi, 0), n)] - (cum[min(lo, n)] if lo >= 0 else 0.0))
        if net <= 1e-9:
            continue
        radius = window / net
        per_mm = target / radius
        if per_mm >= arc_table[-1]:
            continue
        if per_mm < arc_table[0]:  # below the table the error grows at least linearly with ω
            omega = arc_omega[0] * per_mm / max(arc_table[0], 1e-300)
        else:
            omega = np.interp(per_mm, arc_table, arc_omega)
        cap[i] = min(cap[i], omega * radius)
    # Reachable speeds, then the knob.
    accel_at = np.empty(total)
    finite = np.empty(total)
    for i in range(total):
        f = feed[piece[i]]
        accel_at[i] = max(min(accel, slew_per_s * f) if f > 0 else accel, 1e-3)
        finite[i] = cap[i] if math.isfinite(cap[i]) else SPEED_CEILING_MM_S
    speed = finite.copy()
    _scan(node_s, speed, accel_at, jerk)
    override = np.full(total, top)
    for i in range(total):
        f = feed[piece[i]]
        if cutting[piece[i]] and f > 0:
            override[i] = min(max(speed[i] / f, 0.0), top)
    return node_s, cap, speed, override


def _dependencies() -> None:
    from cnc_gym.numba_cache import refresh_on_change

    refresh_on_change(__name__, [K])


_dependencies()  # the compiled passes read the controller's table layout: drop them when it changes
