"""The deployable planner's schedule: speed caps along the path from the servo error model, the
jerk-limited bidirectional scan, and the override per path position (:func:`plan_schedule`).

The steps are those of :mod:`cnc_gym.motion.planner`'s docstring; this module holds them, compiled where
they loop over the path.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from cnc_gym.machine import MachineConfig
from cnc_gym.motion import kernel as K
from cnc_gym.motion.limits import PathLimits, build_limits
from cnc_gym.motion.planner.error_model import (
    SPEED_CEILING_MM_S,
    approach_tables,
    corner_approach_error,
    corner_approach_exceeds,
    corner_error_unit,
    servo_tables,
)
from cnc_gym.motion.planner.record import Schedule
from cnc_gym.toolpath import Toolpath


@njit(cache=True)
def _ramp_length(v0: float, v: float, accel: float, jerk: float) -> float:
    """Path length of the jerk-limited S-curve from ``v0`` to ``v`` (both at zero acceleration)."""
    dv = v - v0
    if dv <= 0:
        return 0.0
    t = 2.0 * math.sqrt(dv / jerk) if dv <= accel * accel / jerk else dv / accel + accel / jerk
    return 0.5 * (v0 + v) * t


@njit(cache=True)
def _ramp_time(dv: float, accel: float, jerk: float) -> float:
    """Duration of the jerk-limited S-curve changing the speed by ``dv`` (zero acceleration at both ends)."""
    if dv <= 0:
        return 0.0
    return 2.0 * math.sqrt(dv / jerk) if dv <= accel * accel / jerk else dv / accel + accel / jerk


def bidirectional_scan(s: np.ndarray, cap: np.ndarray, accel: float | np.ndarray, jerk: float,
                       decel_share: float = 1.0) -> np.ndarray:  # fmt: skip
    """Largest speed profile ≤ ``cap`` whose rises and falls are reachable under (A, J).

    Backward pass (can we slow down in time for every later cap?) then forward pass (can we speed up
    that fast?). Each pass keeps one anchor, the last point where the cap itself was binding; ``accel``
    may vary along the path (one value per point): a ramp uses the lowest value of the points it spans;
    decelerations use ``decel_share`` of it. Compiled (:func:`_scan`): O(n).
    """
    s = np.ascontiguousarray(s, dtype=np.float64)
    out = np.array(cap, dtype=np.float64)
    accel_at = np.ascontiguousarray(np.broadcast_to(np.asarray(accel, dtype=np.float64), out.shape))
    _scan(s, out, accel_at, float(jerk), float(decel_share))
    return out


@njit(cache=True)
def _scan(s: np.ndarray, out: np.ndarray, accel_at: np.ndarray, jerk: float, decel_share: float) -> None:
    n = len(s)
    for backward in (True, False):
        have = False
        anchor_s = anchor_v = anchor_a = 0.0
        share = decel_share if backward else 1.0
        for k in range(n):
            i = n - 1 - k if backward else k
            if have:
                # The ramp from the anchor crosses every point since: the lowest acceleration among them.
                anchor_a = min(anchor_a, share * accel_at[i])
                distance = abs(anchor_s - s[i])
                # Cheap test first: is the cap itself reachable from the anchor?
                if _ramp_length(anchor_v, out[i], anchor_a, jerk) > distance:
                    out[i] = K.reach_speed(anchor_v, distance, anchor_a, jerk)
                    continue
            have = True
            anchor_s, anchor_v, anchor_a = s[i], out[i], share * accel_at[i]


# --------------------------------------------------------------------------------------------- planner
# --------------------------------------------------------------------------------------------- planner
#: Fraction of the contour tolerance the schedule aims at (every model's error, corners with their
#: approach included). The models are exact on their closed forms (tests/motion/planner), so the margin
#: only has to cover what they leave out (superposed transients, the controller's own jerk-limited
#: response to the knob). Chosen on the train and val splits of cnc-bench-v1, never on test.
MARGIN = 0.85
#: Share of a corner's budget its constant-speed error may take; the rest is left to the excess lag of
#: the deceleration into it (the hold before the corner is as long as that needs).
CORNER_SHARE = 0.85
#: Junctions turning less than this are left to the window models (their single-corner error is nil).
MIN_TURN_DEG = 0.1
#: Longest distance between two schedule points inside a move, mm.
NODE_SPACING_MM = 0.5
#: How long after a corner its cap holds, in loop time constants 1/Kv (the transient's peak comes later).
HOLD_TIME_CONSTANTS = 3.0
#: Holds before a corner are searched in steps of this many loop time constants, up to HOLD_MAX.
HOLD_STEP = 0.25
HOLD_MAX = 8.0
#: Windows of the net-turn analysis (mm): the path's change of direction over each, centred on every
#: schedule point, is a corner of that net turn where the servo sees the window as a point (at speeds
#: above window × Kv / RESPONSE_TIME_CONSTANTS) and an arc of curvature turn / window below.
WINDOWS_MM = (0.25, 0.5, 1.0, 2.0, 4.0, 8.0)
#: The servo's response time in loop time constants 1/Kv (what "sees as a point" means above).
RESPONSE_TIME_CONSTANTS = 1.0
#: A window is an arc only where no single junction in it makes this share of its net turn.
SPREAD_SHARE = 0.5
CONTROLLER_LIMITS = True


class PlanSettings(NamedTuple):
    """What distinguishes the planner versions built on this module (version 2, frozen, and 3)."""

    #: Decelerations are scheduled at this share of the acceleration the path and the override's slew
    #: allow: the controller follows the knob with its jerk limit, and lags a steep ramp by ~a²/J.
    decel_share: float
    #: How a window of the net-turn analysis is told to be a point for the servo: by the extent of the
    #: junctions inside it (True) or by its width (False, version 2, which let two junctions a few tenths
    #: of a mm apart inside a wide window pass for an arc).
    junction_extent: bool
    #: The knob's anticipation baked into the schedule's overrides (0: none, version 2): each node asks for
    #: the lowest override of the stretch the scheduled speed covers in this time, and where the override
    #: must fall faster than its slew allows (at a change of programmed feed the same speed is another
    #: override) it starts falling earlier.
    knob_lead_s: float


#: Version 2 (the frozen planner of ``cnc_gym/Feedrate-v3``).
SETTINGS_V2 = PlanSettings(decel_share=0.5, junction_extent=False, knob_lead_s=0.0)
#: Version 3 (the live planner). Chosen on the train and val splits of cnc-bench-v1: decelerations at
#: 0.75 of the acceleration (0.85 broke a train program), 20 ms of baked anticipation (none, or 10 ms,
#: left 3–6 % of the programs of every split over tolerance).
SETTINGS_V3 = PlanSettings(decel_share=0.75, junction_extent=True, knob_lead_s=0.02)


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
            _arc_tangent(seg_f, seg_i, k, 0.0, t0[k])
            _arc_tangent(seg_f, seg_i, k, 1.0, t1[k])
        else:
            dx = seg_f[k, K.F_EX] - seg_f[k, K.F_SX]
            dy = seg_f[k, K.F_EY] - seg_f[k, K.F_SY]
            dz = seg_f[k, K.F_EZ] - seg_f[k, K.F_SZ]
            norm = max(math.sqrt(dx * dx + dy * dy + dz * dz), 1e-300)
            t0[k, 0], t0[k, 1], t0[k, 2] = dx / norm, dy / norm, dz / norm
            for a in range(3):  # (element by element: an array assignment compiles numba's shape check
                t1[k, a] = t0[k, a]  # and its error message, string formatting included: seconds)
    return t0, t1


@njit(cache=True)
def _arc_tangent(seg_f: np.ndarray, seg_i: np.ndarray, k: int, frac: float, out: np.ndarray) -> None:
    """Unit tangent of arc (or helix) piece ``k`` at fraction ``frac`` of its length, into ``out``."""
    r, sweep, rise = seg_f[k, K.F_RADIUS], seg_f[k, K.F_SWEEP], seg_f[k, K.F_RISE]
    u, v, w = seg_i[k, K.I_PU], seg_i[k, K.I_PV], seg_i[k, K.I_PW]
    theta = seg_f[k, K.F_ANG0] + sweep * frac
    du, dv = -r * math.sin(theta) * sweep, r * math.cos(theta) * sweep
    norm = max(math.sqrt(du * du + dv * dv + rise * rise), 1e-300)
    out[u], out[v], out[w] = du / norm, dv / norm, rise / norm


@njit(cache=True)
def _tangent_at(seg_f: np.ndarray, seg_i: np.ndarray, t0: np.ndarray, t1: np.ndarray, k: int, s: float,
                out: np.ndarray) -> None:  # fmt: skip
    """Unit tangent of piece ``k`` at path position ``s`` (NURBS pieces: between their end tangents)."""
    length = seg_f[k, K.F_LEN]
    frac = min(max((s - seg_f[k, K.F_S0]) / length, 0.0), 1.0) if length > 0 else 0.0
    if seg_i[k, K.I_TABLE] < 0 and seg_i[k, K.I_KIND] == K.KIND_ARC:
        _arc_tangent(seg_f, seg_i, k, frac, out)
        return
    norm = 0.0
    for a in range(3):
        out[a] = t0[k, a] * (1.0 - frac) + t1[k, a] * frac
        norm += out[a] * out[a]
    norm = max(math.sqrt(norm), 1e-300)
    for a in range(3):
        out[a] /= norm


@njit(cache=True, inline="always")
def _plane_of(normal_axis: int) -> int:
    """The arc-table plane (Plane value: XY 0, ZX 1, YZ 2) whose normal is ``normal_axis``."""
    return 2 - normal_axis


@njit(cache=True)
def _arc_cap(radius: float, turn_axis: np.ndarray, arc_omega: np.ndarray, arc_table: np.ndarray,
             target: float) -> float:  # fmt: skip
    """Largest speed on a circle of ``radius`` (mm) turning about ``turn_axis`` (unit, or zero for "any
    plane") whose steady error (:func:`servo_tables`' arc table) is at most ``target``: the lowest over
    the coordinate planes the turn has a share in."""
    cap = SPEED_CEILING_MM_S
    per_mm = target / radius
    biggest = max(abs(turn_axis[0]), abs(turn_axis[1]), abs(turn_axis[2]))
    for axis in range(3):
        if biggest > 0.0 and abs(turn_axis[axis]) < 0.2 * biggest:
            continue
        table = arc_table[_plane_of(axis)]
        if per_mm >= table[-1]:
            continue
        if per_mm < table[0]:  # below the table the error grows at least linearly with ω
            omega = arc_omega[0] * per_mm / max(table[0], 1e-300)
        else:
            omega = np.interp(per_mm, table, arc_omega)
        cap = min(cap, omega * radius)
    return cap


@njit(cache=True, inline="always")
def _window_max(values: np.ndarray, queue: np.ndarray, head: np.ndarray, tail: np.ndarray,
                pushed: np.ndarray, w: int, lo: int, hi: int) -> float:  # fmt: skip
    """max(values[lo..hi]) (0 when empty) by the monotone queue ``queue`` of window ``w``: ``lo`` and
    ``hi`` never decrease from one call to the next, so the cost is O(1) per call on average."""
    while pushed[w] <= hi:
        q = pushed[w]
        while tail[w] > head[w] and values[queue[tail[w] - 1]] <= values[q]:
            tail[w] -= 1
        queue[tail[w]] = q
        tail[w] += 1
        pushed[w] += 1
    while tail[w] > head[w] and queue[head[w]] < lo:
        head[w] += 1
    return values[queue[head[w]]] if tail[w] > head[w] and lo <= hi else 0.0


def plan_schedule(toolpath: Toolpath, machine: MachineConfig, *, limits: PathLimits | None = None,
                  margin: float = MARGIN, max_override: float | None = None,
                  settings: PlanSettings = SETTINGS_V3) -> Schedule:  # fmt: skip
    """The deployable schedule of ``toolpath`` on ``machine`` (:mod:`cnc_gym.motion.planner`'s docstring).

    ``limits``: the controller's static tables (:func:`cnc_gym.motion.limits.build_limits`), computed
    here when not given (an env's controller already holds them); ``settings``: the planner version's
    (:data:`SETTINGS_V3`, the live one, or :data:`SETTINGS_V2`).
    """
    lim = limits if limits is not None else build_limits(toolpath, machine)
    tables = servo_tables(machine)
    approach = approach_tables(machine)
    ctl = machine.controller
    top = float(ctl.max_override if max_override is None else max_override)
    target = margin * float(ctl.contour_tolerance_mm)
    seg_f, seg_i = lim.seg_f, lim.seg_i
    if len(seg_f) == 0:
        return Schedule(s=np.zeros(1), cap_mm_s=np.full(1, np.inf), speed_mm_s=np.zeros(1),
                        override=np.full(1, top))  # fmt: skip
    kv_min = float(min(machine.axis_array("kv_1_s")))
    accel = float(min(machine.axis_array("max_accel_mm_s2")))
    jerk = float(min(machine.axis_array("max_jerk_mm_s3")))
    node_s, node_cap, speed, override = _plan(
        seg_f, seg_i, lim.pt_f, np.ascontiguousarray(lim.pt_f[:, K.P_S]), lim.curve_f, tables.lag_s,
        tables.arc_omega, tables.arc_error, tables.ramp_t, approach.ramp_error, approach.excess_integral,
        target, top, 1.0 / kv_min, accel, jerk, float(ctl.override_slew_per_s),
        K.TRACK_PERIODS * float(ctl.interpolation_period_s), np.array(WINDOWS_MM),
        float(settings.decel_share), bool(settings.junction_extent), float(settings.knob_lead_s))
    return Schedule(s=node_s, cap_mm_s=node_cap, speed_mm_s=speed, override=override)


@njit(cache=True)
def _plan(seg_f, seg_i, pt_f, point_s, curve_f, lag, arc_omega, arc_table, ramp_t, ramp_e, excess_int, target,
          top, time_constant, accel, jerk, slew_per_s, settle_s, windows, decel_share, junction_extent,
          knob_lead_s):  # fmt: skip
    """The schedule (node positions, caps, speeds, overrides): piece caps, junction corners with their
    approach holds, the net-turn windows, the jerk-limited scan and the knob per node."""
    n = seg_f.shape[0]
    cutting = np.zeros(n, dtype=np.bool_)
    feed = np.zeros(n)
    for k in range(n):
        cutting[k] = seg_i[k, K.I_RAPID] == 0
        feed[k] = seg_f[k, K.F_BASE] if cutting[k] else 0.0
    t0, t1 = _piece_tangents(seg_f, seg_i, curve_f)
    piece_cap = _piece_caps(seg_f, seg_i, t0, cutting, feed, lag, arc_omega, arc_table, target, top)
    run_lo, run_hi = _runs(seg_f, cutting)
    corner_v, hold_lo, hold_hi, extra = _corners(
        seg_f, pt_f, t0, t1, cutting, feed, piece_cap, run_lo, run_hi, lag, ramp_t, ramp_e, excess_int,
        target, time_constant, accel, jerk, slew_per_s, settle_s, decel_share)
    node_s, piece, point = _nodes(seg_f, point_s, corner_v, hold_lo, hold_hi, extra)
    cap = _node_caps(seg_f, pt_f, cutting, piece_cap, corner_v, hold_lo, hold_hi, node_s, piece, point)
    _window_caps(seg_f, seg_i, point_s, t0, t1, cutting, run_lo, run_hi, node_s, piece, cap, lag, arc_omega,
                 arc_table, ramp_t, ramp_e, excess_int, target, time_constant, windows,
                 junction_extent)  # fmt: skip
    speed, override = _knob(node_s, cap, piece, cutting, feed, accel, jerk, slew_per_s, top, decel_share,
                            knob_lead_s)  # fmt: skip
    return node_s, cap, speed, override


@njit(cache=True)
def _piece_caps(seg_f, seg_i, t0, cutting, feed, lag, arc_omega, arc_table, target, top):  # fmt: skip
    """Speed cap per move (inf on rapids)."""
    n = seg_f.shape[0]
    axis = np.zeros(3)
    # ---- caps per move: the knob's range (programmed feed × max override), the line's lateral lag, the
    # arc's steady error. The controller's own limits are left to the controller.
    piece_cap = np.full(n, np.inf)
    for k in range(n):
        if not cutting[k]:
            continue
        piece_cap[k] = feed[k] * (1.0 if seg_i[k, K.I_LOCKED] != 0 else top)
        if seg_i[k, K.I_KIND] == K.KIND_LINE and seg_i[k, K.I_TABLE] < 0:
            along = 0.0
            for a in range(3):
                along += t0[k, a] * lag[a] * t0[k, a]
            lateral = 0.0
            for a in range(3):
                lateral += (t0[k, a] * lag[a] - along * t0[k, a]) ** 2
            lateral = math.sqrt(lateral)
            if lateral > 1e-12:
                piece_cap[k] = min(piece_cap[k], target / lateral)
        curvature = seg_f[k, K.F_CURV]
        if curvature > 1e-9:
            for a in range(3):
                axis[a] = 0.0
            if seg_i[k, K.I_TABLE] < 0 and seg_i[k, K.I_KIND] == K.KIND_ARC:
                axis[seg_i[k, K.I_PW]] = 1.0
            piece_cap[k] = min(piece_cap[k], _arc_cap(1.0 / curvature, axis, arc_omega, arc_table, target))
    return piece_cap


@njit(cache=True)
def _runs(seg_f, cutting):
    """Path positions of the start and end of the run of cutting moves each move is in."""
    n = seg_f.shape[0]
    # ---- the run of cutting moves each move is in (holds and windows never reach across a rapid)
    run_lo = np.empty(n)
    run_hi = np.empty(n)
    start = 0
    for k in range(n + 1):
        if k == n or not cutting[k]:
            for j in range(start, k):
                run_lo[j] = seg_f[start, K.F_S0]
                run_hi[j] = seg_f[k - 1, K.F_S0] + seg_f[k - 1, K.F_LEN]
            if k < n:
                run_lo[k] = seg_f[k, K.F_S0]
                run_hi[k] = seg_f[k, K.F_S0] + seg_f[k, K.F_LEN]
            start = k + 1
    return run_lo, run_hi


@njit(cache=True)
def _corners(seg_f, pt_f, t0, t1, cutting, feed, piece_cap, run_lo, run_hi, lag, ramp_t, ramp_e, excess_int,
             target, time_constant, accel, jerk, slew_per_s, settle_s, decel_share):  # fmt: skip
    """Speed at each junction taken as a corner (inf elsewhere), and the path span its hold covers; the
    number of hold ends (nodes the holds add)."""
    n = seg_f.shape[0]
    # ---- junctions between cutting moves: the corner model, held after the corner, and held before it
    # as long as the excess lag of the deceleration into it needs
    hold_after = HOLD_TIME_CONSTANTS * time_constant
    corner_target = CORNER_SHARE * target
    corner_v = np.full(n + 1, np.inf)
    hold_lo = np.zeros(n + 1)
    hold_hi = np.zeros(n + 1)
    u_in = np.zeros(3)
    u_out = np.zeros(3)
    extra = 0
    for q in range(1, n):
        if not (cutting[q - 1] and cutting[q]):
            continue
        dot = 0.0
        for a in range(3):
            u_in[a] = t1[q - 1, a]
            u_out[a] = t0[q, a]
            dot += u_in[a] * u_out[a]
        if dot > math.cos(math.radians(MIN_TURN_DEG)):
            continue
        per_speed = corner_error_unit(u_in, u_out, ramp_t, ramp_e, lag)
        if per_speed <= 1e-12:
            continue
        v_c = min(corner_target / per_speed, piece_cap[q - 1], piece_cap[q])
        # Where the controller's own junction limit is lower, the corner is taken at that speed: left to
        # the controller where even its own hard braking into the corner keeps within the budget, else
        # held at that speed (an acceleration out of the corner during its transient adds to the error).
        hard = pt_f[q, K.P_HARD]
        if 0.0 < hard < v_c:
            v_c = hard
            if math.isfinite(piece_cap[q - 1]):
                fall = max(piece_cap[q - 1] - hard, 0.0)
                if corner_approach_error(u_in, u_out, hard, fall, _ramp_time(fall, accel, jerk), 0.0, ramp_t,
                                         ramp_e, excess_int, lag, target) <= target:  # fmt: skip
                    continue
        # The approach: from the incoming move's cap down to v_c, a ramp at the path acceleration (the
        # override's slew bounds it too), then a hold at v_c of the shortest length that keeps the error
        # within the budget.
        v_b = piece_cap[q - 1]
        drop = v_b - v_c if math.isfinite(v_b) else 0.0
        hold = 0.0
        if drop > 1e-9:
            a_full = max(min(accel, slew_per_s * feed[q - 1]) if feed[q - 1] > 0 else accel, 1e-3)
            a_eff = decel_share * a_full
            ramp = _ramp_time(drop, a_eff, jerk)
            steps = int(HOLD_MAX / HOLD_STEP)
            failed_at = 0
            for m in range(steps + 1):
                hold = m * HOLD_STEP * time_constant
                failed_at = corner_approach_exceeds(u_in, u_out, v_c, drop, ramp, hold, ramp_t, ramp_e,
                                                    excess_int, lag, target, max(failed_at, 0))  # fmt: skip
                if failed_at < 0:
                    break
            # The controller reaches the knob's speed later than the scan's profile: it turns an
            # acceleration (up to the full one) into the deceleration and ends that with the jerk limit,
            # and settles on the target over a few periods, twice (the override, then the speed).
            hold += (a_full + a_eff) / jerk + 2.0 * settle_s
        corner_v[q] = v_c
        hold_lo[q] = max(seg_f[q, K.F_S0] - v_c * hold, run_lo[q - 1])
        hold_hi[q] = min(seg_f[q, K.F_S0] + v_c * hold_after, run_hi[q])
        extra += 2
    return corner_v, hold_lo, hold_hi, extra


@njit(cache=True)
def _nodes(seg_f, point_s, corner_v, hold_lo, hold_hi, extra):
    """Sorted node positions, the move each node lies on and the junction it sits on (−1 inside a move)."""
    n = seg_f.shape[0]
    # ---- nodes: every junction, inside moves every NODE_SPACING_MM at most, and the ends of the holds
    count = np.empty(n, dtype=np.int64)
    total = 1 + extra
    for k in range(n):
        count[k] = max(math.ceil(seg_f[k, K.F_LEN] / NODE_SPACING_MM), 1)
        total += count[k]
    node_s = np.empty(total)
    i = 0
    for k in range(n):
        for j in range(count[k]):
            node_s[i] = seg_f[k, K.F_S0] + j * seg_f[k, K.F_LEN] / count[k]
            i += 1
    node_s[i] = seg_f[n - 1, K.F_S0] + seg_f[n - 1, K.F_LEN]
    i += 1
    for q in range(1, n):
        if math.isfinite(corner_v[q]):
            node_s[i], node_s[i + 1] = hold_lo[q], hold_hi[q]
            i += 2
    node_s = np.sort(node_s)
    piece = np.empty(total, dtype=np.int64)
    point = np.full(total, -1, dtype=np.int64)  # the junction a node sits on, -1 inside a move
    k = 0
    for i in range(total):
        while k < n - 1 and node_s[i] >= point_s[k + 1]:
            k += 1
        piece[i] = k
        if node_s[i] == point_s[k] and (i == 0 or node_s[i - 1] != node_s[i]):
            point[i] = k
    point[total - 1] = n
    return node_s, piece, point


@njit(cache=True)
def _node_caps(seg_f, pt_f, cutting, piece_cap, corner_v, hold_lo, hold_hi, node_s, piece,
               point):  # fmt: skip
    """Cap per node: its move's, the controller's own limits, and the corner holds over it."""
    n = seg_f.shape[0]
    total = node_s.shape[0]
    cap = np.empty(total)
    for i in range(total):
        cap[i] = piece_cap[piece[i]]
        q = point[i]
        if 0 < q < n:
            cap[i] = min(cap[i], piece_cap[q - 1])
        if CONTROLLER_LIMITS and cutting[piece[i]]:
            cap[i] = min(cap[i], seg_f[piece[i], K.F_CAP])
            if 0 < q < n and cutting[q - 1] and pt_f[q, K.P_HARD] > 0.0:
                cap[i] = min(cap[i], pt_f[q, K.P_HARD])
    j0 = 0
    for q in range(1, n):
        if not math.isfinite(corner_v[q]):
            continue
        while j0 < total and node_s[j0] < hold_lo[q] - 1e-9:
            j0 += 1
        j = j0
        while j < total and node_s[j] <= hold_hi[q] + 1e-9:
            cap[j] = min(cap[j], corner_v[q])
            j += 1
    return cap


@njit(cache=True)
def _window_caps(seg_f, seg_i, point_s, t0, t1, cutting, run_lo, run_hi, node_s, piece, cap, lag, arc_omega,
                 arc_table, ramp_t, ramp_e, excess_int, target, time_constant, windows,
                 junction_extent):  # fmt: skip
    """Lower ``cap`` (in place) where the path's net turn over a window around a node is a corner or an arc
    the servo sees."""
    n = seg_f.shape[0]
    total = node_s.shape[0]
    axis = np.zeros(3)
    # ---- net-turn windows: clusters of junctions seen as one corner, chains of short moves as arcs
    junction_turn = np.zeros(n + 1)
    for q in range(1, n):
        if cutting[q - 1] and cutting[q]:
            dot = t1[q - 1, 0] * t0[q, 0] + t1[q - 1, 1] * t0[q, 1] + t1[q - 1, 2] * t0[q, 2]
            junction_turn[q] = math.acos(min(max(dot, -1.0), 1.0))
    ta = np.zeros(3)
    tb = np.zeros(3)
    # The sharpest junction inside each window, by a sliding maximum per window width: both ends of a
    # window only move forward from node to node, so each junction enters and leaves its queue once.
    queue = np.empty((len(windows), n + 1), dtype=np.int64)
    head = np.zeros(len(windows), dtype=np.int64)
    tail = np.zeros(len(windows), dtype=np.int64)
    pushed = np.zeros(len(windows), dtype=np.int64)  # junctions 1 .. pushed - 1 have been queued
    pushed[:] = 1
    widest = windows.max() if len(windows) > 0 else 0.0
    for i in range(total):
        k = piece[i]
        if not cutting[k]:
            continue
        s = node_s[i]
        # Inside one move even for the widest window: so for every window (most nodes of long moves)
        a_s = max(s - 0.5 * widest, run_lo[k])
        b_s = min(s + 0.5 * widest, run_hi[k])
        if (max(min(np.searchsorted(point_s, a_s, side="right") - 1, n - 1), 0)
                == max(min(np.searchsorted(point_s, b_s, side="left") - 1, n - 1), 0)):  # fmt: skip
            continue
        for wi in range(len(windows)):
            w = windows[wi]
            a_s = max(s - 0.5 * w, run_lo[k])
            b_s = min(s + 0.5 * w, run_hi[k])
            if b_s - a_s < 0.25 * w:
                continue
            ka = max(min(np.searchsorted(point_s, a_s, side="right") - 1, n - 1), 0)
            kb = max(min(np.searchsorted(point_s, b_s, side="left") - 1, n - 1), 0)
            if ka == kb:  # inside one move: its own cap covers it
                continue
            _tangent_at(seg_f, seg_i, t0, t1, ka, a_s, ta)
            _tangent_at(seg_f, seg_i, t0, t1, kb, b_s, tb)
            dot = ta[0] * tb[0] + ta[1] * tb[1] + ta[2] * tb[2]
            dot = min(max(dot, -1.0), 1.0)
            turn = math.acos(dot)
            if turn < math.radians(MIN_TURN_DEG):
                continue
            axis[0] = ta[1] * tb[2] - ta[2] * tb[1]
            axis[1] = ta[2] * tb[0] - ta[0] * tb[2]
            axis[2] = ta[0] * tb[1] - ta[1] * tb[0]
            span = b_s - a_s
            # Above v_point the servo sees the window's junctions as one point.
            extent = point_s[kb] - point_s[ka + 1] if junction_extent else span
            v_point = extent / (RESPONSE_TIME_CONSTANTS * time_constant)
            # Seen as an arc only where the turn is spread over the window: a turn most of which is one
            # junction's is that junction's corner (the corner model has it, at the speed at the corner).
            sharpest = _window_max(junction_turn, queue[wi], head, tail, pushed, wi, ka + 1, kb)
            v_arc = SPEED_CEILING_MM_S
            if sharpest < SPREAD_SHARE * turn:
                v_arc = _arc_cap(span / turn, axis, arc_omega, arc_table, target)
            if v_arc < v_point:
                cap_w = v_arc
            else:
                if kb - ka == 1:  # a single junction: the corner model above has it
                    continue
                if cap[i] <= v_point:  # the window's cap is at least v_point: it cannot lower this one
                    continue
                per_speed = corner_error_unit(ta, tb, ramp_t, ramp_e, lag)
                cap_w = max(v_point, target / per_speed) if per_speed > 1e-12 else SPEED_CEILING_MM_S
            cap[i] = min(cap[i], cap_w)



@njit(cache=True)
def _knob(node_s, cap, piece, cutting, feed, accel, jerk, slew_per_s, top, decel_share, knob_lead_s):
    """Reachable speed per node (the jerk-limited scan under the caps) and the override that asks for it."""
    total = node_s.shape[0]
    # ---- reachable speeds, then the knob
    accel_at = np.empty(total)
    finite = np.empty(total)
    for i in range(total):
        f = feed[piece[i]]
        accel_at[i] = max(min(accel, slew_per_s * f) if f > 0 else accel, 1e-3)
        finite[i] = cap[i] if math.isfinite(cap[i]) else SPEED_CEILING_MM_S
    speed = finite.copy()
    _scan(node_s, speed, accel_at, jerk, decel_share)
    override = np.full(total, top)
    for i in range(total):
        f = feed[piece[i]]
        if cutting[piece[i]] and f > 0:
            override[i] = min(max(speed[i] / f, 0.0), top)
    if knob_lead_s > 0.0:
        _anticipate(node_s, speed, override, slew_per_s, knob_lead_s)
    # On rapids (and before the first cut) the knob moves nothing (rapids run at their own override), so
    # it already asks for the next cut's override: the applied override slews there during the rapid.
    following = top
    for i in range(total - 1, -1, -1):
        if cutting[piece[i]] and feed[piece[i]] > 0:
            following = override[i]
        else:
            override[i] = following
    return speed, override


@njit(cache=True)
def _anticipate(node_s, speed, override, slew_per_s, lead_s):
    """The knob's anticipation (:attr:`PlanSettings.knob_lead_s`), in place: falls the override cannot
    slew in time start earlier, then each node asks for the lowest override the scheduled speed reaches
    within ``lead_s``."""
    total = node_s.shape[0]
    for i in range(total - 2, -1, -1):  # (the time to the next node at the scheduled speed: an upper bound)
        dt = (node_s[i + 1] - node_s[i]) / max(speed[i], 1e-3)
        override[i] = min(override[i], override[i + 1] + slew_per_s * dt)
    for i in range(total):
        reach = node_s[i] + speed[i] * lead_s
        j = i + 1
        while j < total and node_s[j] <= reach:
            override[i] = min(override[i], override[j])
            j += 1


def _dependencies() -> None:
    from cnc_gym.numba_cache import refresh_on_change

    refresh_on_change(__name__, [K])


_dependencies()  # the compiled passes read the controller's table layout: drop them when it changes
