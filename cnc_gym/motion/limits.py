"""Static speed, acceleration and jerk limits of a tool path on a machine, computed once (vectorised).

The controller works on *motion segments*: the toolpath's rapids, lines and arcs with a length above
:data:`MIN_LENGTH_MM` (shorter ones are absorbed: their modes still count, their geometry does not), and
NURBS curves cut into pieces of at most :data:`NURBS_PIECE_MM` whose limits are sampled along the curve.
Between consecutive motion segments lies a *limit point* (junction); point 0 is the program start and
point n the program end. Dwells sit on points.

Per motion segment (mm, s):

* hard speed cap ``cap`` (independent of the override):
  cutting: min(composite clamp P1224, per-axis clamp P1225_k / max|u_k|, curvature limits on arcs);
  rapid: rapid rate min_k P1226_k / max|u_k|.
  Curvature κ on arcs: centripetal acceleration √(a_n/κ) (a_n = min(P1442, in-plane axis accelerations)),
  centripetal jerk (j_n/κ²)^(1/3), chord error at the interpolation period (2/T)·√(2ρδ − δ²) (δ = P1472),
  never below the arc floor P1505 (unless the feed itself is lower).
* ``base``: speed at 100 % override (programmed path feed, or the rapid rate).
* tangential acceleration and jerk: min_k limit_k / max|u_k| (the per-axis limits projected on the path;
  max|u_k| is the largest direction component over the segment, exact for arcs).

Per point: the hard junction limit (corner step P1227: v ≤ min_k step_k/|Δu_k|, Δu the change of unit
tangent; both neighbours' caps; with ``controller.corner_rule: jerk`` also the jerk-limited corner rule of
:func:`_junction_jerk_rule`, which may make a kink a stop and scales the jerk of the pieces around the
junctions it passes), 0 at mandatory stops (exact stop G09/G61, dwell, rapid ↔ cutting,
after every rapid, tool or spindle change, program end, or every junction when look-ahead is off), and
the acceleration bound on arrival ``a_in`` (a backward pass so that a lower acceleration limit ahead can
always be met: a_in[k] = min(A_k, a_in[k+1] + J_k·L_k/cap_k), restarted at every mandatory stop), and the
lowest acceleration bound and jerk from each point to the next mandatory stop (the braking limits).

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numba import njit

from cnc_gym.errors import ProgramError
from cnc_gym.machine import MachineConfig
from cnc_gym.motion import kernel as K
from cnc_gym.toolpath import SegmentKind, SegmentMode, Toolpath
from cnc_gym.toolpath.kinds import PLANE_AXES, Plane
from cnc_gym.toolpath.smoothing import BlendCurve, SmoothingRules, blend_tables, smooth_corners

#: Motion segments shorter than this are ignored (their modes still apply), mm.
MIN_LENGTH_MM = 1e-6

_PLANE_TABLE = np.array([PLANE_AXES[p] for p in Plane], dtype=np.int64)


@dataclass(frozen=True)
class PathLimits:
    """Packed arrays for the kernel (see the column constants in :mod:`cnc_gym.motion.kernel`)."""

    seg_f: np.ndarray  # (n, N_SEG_F)
    seg_i: np.ndarray  # (n, N_SEG_I)
    pt_f: np.ndarray  # (n + 1, N_PT_F)
    pt_i: np.ndarray  # (n + 1, N_PT_I)
    dwell_f: np.ndarray  # (m, 5): seconds, toolpath index, x, y, z
    curve_f: np.ndarray  # (r, 6): NURBS table, point and unit tangent per sample
    rest_position: np.ndarray  # (3,) where the reference rests when there is no motion at all
    #: Rotary-only moves (timed holds of the XYZ reference): toolpath row, seconds, and the profile's
    #: travel (deg), speed (deg/s), acceleration, jerk, one row each (m, 6).
    rotary_holds: np.ndarray = field(default_factory=lambda: np.zeros((0, 6)))
    #: The path the controller follows where corner smoothing changed it (arc lengths ``P_S``/``F_S0`` are
    #: along it); None: the programmed path itself.
    path: Toolpath | None = None


def rest_to_rest_time(distance: np.ndarray, speed: np.ndarray, accel: np.ndarray,
                      jerk: np.ndarray) -> np.ndarray:  # fmt: skip
    """Time of the fastest jerk-limited move over ``distance`` from rest to rest (vectorised; any unit).

    Accelerating to a speed v takes T(v) = v/a + a/j when v ≥ a²/j (the acceleration reaches a) and
    2·√(v/j) otherwise, covering v·T(v)/2. If two such ramps fit within the distance the move cruises at
    ``speed`` in between; otherwise its peak speed v_p solves v_p·T(v_p) = distance:
    v_p = (a/2)·(√(a²/j² + 4·d/a) − a/j) in the first case, (d·√j/2)^(2/3) in the second.
    """
    d, v, a, j = (np.asarray(x, dtype=float) for x in (distance, speed, accel, jerk))
    full_ramp = v >= a * a / j
    ramp = np.where(full_ramp, v / a + a / j, 2.0 * np.sqrt(v / j))
    cruise = d - v * ramp  # both ramps together cover v·T(v)
    peak_full = 0.5 * a * (np.sqrt((a / j) ** 2 + 4.0 * d / a) - a / j)
    peak = np.where(peak_full >= a * a / j, peak_full, np.cbrt((d * np.sqrt(j) / 2.0) ** 2))
    peak_ramp = np.where(peak >= a * a / j, peak / a + a / j, 2.0 * np.sqrt(peak / j))
    return np.where(d <= 0, 0.0, np.where(cruise >= 0, 2.0 * ramp + cruise / v, 2.0 * peak_ramp))


def rest_to_rest_position(t: np.ndarray, distance: np.ndarray, speed: np.ndarray, accel: np.ndarray,
                          jerk: np.ndarray) -> np.ndarray:  # fmt: skip
    """Position at time ``t`` along the move :func:`rest_to_rest_time` times (vectorised; clipped to
    [0, distance] outside the move). The profile: a jerk-limited ramp to the peak speed (jerk j for T_j,
    acceleration a_p for T_a, jerk −j for T_j), a cruise at ``speed`` if there is room, and the mirror
    image of the ramp down to rest (the move is point-symmetric about its middle)."""
    t, d, v, a, j = np.broadcast_arrays(*(np.asarray(x, dtype=float) for x in (t, distance, speed, accel,
                                                                                 jerk)))  # fmt: skip
    total = rest_to_rest_time(d, v, a, j)
    # Peak speed: ``speed`` if two ramps fit, otherwise the one rest_to_rest_time solved for.
    full = np.where(v >= a * a / j, v / a + a / j, 2.0 * np.sqrt(v / j))
    cruising = d - v * full >= 0
    peak_full = 0.5 * a * (np.sqrt((a / j) ** 2 + 4.0 * d / a) - a / j)
    peak = np.where(cruising, v, np.where(peak_full >= a * a / j, peak_full,
                                          np.cbrt((d * np.sqrt(j) / 2.0) ** 2)))  # fmt: skip
    t_jerk = np.where(peak >= a * a / j, a / j, np.sqrt(peak / j))
    t_hold = np.where(peak >= a * a / j, peak / a - a / j, 0.0)
    a_peak = j * t_jerk
    ramp_time = 2.0 * t_jerk + t_hold
    ramp_distance = 0.5 * peak * ramp_time

    def ramp(tau: np.ndarray) -> np.ndarray:  # distance after tau of the ramp up (0 ≤ tau ≤ ramp_time)
        x1, v1 = j * t_jerk**3 / 6.0, 0.5 * j * t_jerk**2
        rising = j * tau**3 / 6.0
        u = tau - t_jerk
        holding = x1 + v1 * u + 0.5 * a_peak * u * u
        left = ramp_time - tau  # the last jerk phase, mirrored from the end of the ramp
        easing = ramp_distance - (peak * left - j * left**3 / 6.0)
        return np.where(tau <= t_jerk, rising, np.where(tau <= t_jerk + t_hold, holding, easing))

    tt = np.clip(t, 0.0, total)
    up = ramp(np.minimum(tt, ramp_time))
    cruise_end = total - ramp_time
    middle = ramp_distance + peak * (tt - ramp_time)
    down = d - ramp(np.clip(total - tt, 0.0, ramp_time))
    out = np.where(tt <= ramp_time, up, np.where(tt <= cruise_end, middle, down))
    return np.where(d <= 0, 0.0, np.clip(out, 0.0, d))


def _rotary_rates(tp: Toolpath, machine: MachineConfig) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Per toolpath row, the rotary axes' degrees per mm of XYZ path (n, k), and their limits (k,) each."""
    letters = tp.rotary_axes
    missing = [a for a in letters if a not in machine.rotary_axes]
    if missing:
        raise ProgramError(f"the tool path moves rotary axis {missing[0]}, which machine {machine.name!r} "
                           "does not have", code="motion.no_rotary_axis")  # fmt: skip
    axes = [machine.rotary_axes[a] for a in letters]
    names = ("rapid_deg_min", "max_feed_deg_min", "max_accel_deg_s2", "max_jerk_deg_s3", "rapid_accel_deg_s2",
             "rapid_jerk_deg_s3", "corner_step_deg_min")  # fmt: skip
    limits = {name: np.array([float(getattr(axis, name)) for axis in axes]) for name in names}
    delta = np.abs(tp.rotary_end - tp.rotary_start)
    rates = np.divide(delta, tp.length[:, None], out=np.zeros_like(delta), where=tp.length[:, None] > 0)
    return rates, limits


def _rotary_only_profiles(tp: Toolpath, machine: MachineConfig, rows: np.ndarray,
                          limits: dict[str, np.ndarray]) -> np.ndarray:  # fmt: skip
    """Rotary-only moves (no XYZ travel), one row each: toolpath row, seconds, travel, speed, acceleration,
    jerk. Each is the fastest jerk-limited move along the rotary vector at F (deg/min: the composite rate
    with no linear part, §3.2.2) or the rapid rate, each axis's speed, acceleration and jerk limit
    projected on the vector. Timed at 100 % override."""
    delta = np.abs(tp.rotary_end[rows] - tp.rotary_start[rows])
    travel = np.linalg.norm(delta, axis=1)
    share = delta / travel[:, None]  # |direction component| per axis
    with np.errstate(divide="ignore"):
        inv = np.where(share > 1e-12, 1.0 / np.maximum(share, 1e-300), np.inf)

    def projected(name: str) -> np.ndarray:
        return np.min(limits[name][None, :] * inv, axis=1)

    rapid = tp.kind[rows] == SegmentKind.RAPID
    deg_per_mm = travel / tp.rotary_length[rows]  # 1, or 1/25.4 in a G20 program
    composite = machine.controller.max_feed_mm_min  # P1224 applies to the composite rate
    feed = np.minimum(np.minimum(tp.feed[rows], composite) * deg_per_mm, projected("max_feed_deg_min"))
    speed = np.where(rapid, projected("rapid_deg_min"), np.nan_to_num(feed)) / 60.0
    accel = np.where(rapid, projected("rapid_accel_deg_s2"), projected("max_accel_deg_s2"))
    jerk = np.where(rapid, projected("rapid_jerk_deg_s3"), projected("max_jerk_deg_s3"))
    seconds = rest_to_rest_time(travel, speed, accel, jerk)
    return np.column_stack((rows, seconds, travel, speed, accel, jerk))


def _max_abs_trig(theta0: np.ndarray, sweep: np.ndarray, offset: float) -> np.ndarray:
    """max |cos(θ − offset)| over θ in [θ0, θ0 + sweep] (offset = π/2 gives |sin|)."""
    lo = np.minimum(theta0, theta0 + sweep) - offset
    hi = np.maximum(theta0, theta0 + sweep) - offset
    # |cos| peaks (= 1) at multiples of π.
    n = np.ceil(lo / np.pi)
    inside = n * np.pi <= hi
    ends = np.maximum(np.abs(np.cos(lo)), np.abs(np.cos(hi)))
    return np.where(inside, 1.0, ends)


def _direction_extent(tp: Toolpath, idx: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(max |u_k| over the segment (n,3), unit tangent at the start (n,3), at the end (n,3))."""
    n = len(idx)
    kind = tp.kind[idx]
    length = tp.length[idx]
    delta = tp.end[idx] - tp.start[idx]
    safe = np.where(length > 0, length, 1.0)[:, None]
    t_line = delta / safe
    extent = np.abs(t_line)
    t_start = t_line.copy()
    t_end = t_line.copy()
    arcs = np.flatnonzero(kind == SegmentKind.ARC)
    if len(arcs):
        i = idx[arcs]
        axes = _PLANE_TABLE[tp.plane[i].astype(np.int64)]
        u, v, w = axes[:, 0], axes[:, 1], axes[:, 2]
        rows = np.arange(len(arcs))
        r = tp.radius[i]
        sweep = tp.sweep[i]
        theta0 = tp.start_angle[i]
        ln = length[arcs]
        rise = tp.end[i, w] - tp.start[i, w]
        planar = r * np.abs(sweep) / ln  # in-plane share of the unit tangent
        ext = np.zeros((len(arcs), 3))
        ext[rows, u] = planar * _max_abs_trig(theta0, sweep, math.pi / 2)  # |d/dθ cos| = |sin|
        ext[rows, v] = planar * _max_abs_trig(theta0, sweep, 0.0)
        ext[rows, w] = np.abs(rise) / ln
        extent[arcs] = ext
        for theta, target in ((theta0, t_start), (theta0 + sweep, t_end)):
            d = np.zeros((len(arcs), 3))
            d[rows, u] = -r * np.sin(theta) * sweep
            d[rows, v] = r * np.cos(theta) * sweep
            d[rows, w] = rise
            target[arcs] = d / np.linalg.norm(d, axis=1)[:, None]
    assert extent.shape == (n, 3)
    return extent, t_start, t_end


def _arc_curvature(tp: Toolpath, idx: np.ndarray) -> np.ndarray:
    kind = tp.kind[idx]
    r = tp.radius[idx]
    sweep = np.abs(tp.sweep[idx])
    w = _PLANE_TABLE[tp.plane[idx].astype(np.int64), 2]
    rows = np.arange(len(idx))
    rise = tp.end[idx, w] - tp.start[idx, w]
    pitch = np.divide(rise, sweep, out=np.zeros_like(rise), where=sweep > 0)
    kappa = np.divide(r, r * r + pitch * pitch, out=np.zeros_like(r), where=r > 0)
    del rows
    return np.where(kind == SegmentKind.ARC, kappa, 0.0)


@njit(cache=True)
def _backward_bounds(acc: np.ndarray, jerk: np.ndarray, length: np.ndarray, cap: np.ndarray,
                     stop: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """Backward passes (O(n), compiled): the arrival acceleration bound per point, and the lowest
    acceleration bound / jerk limit from each point to the next mandatory stop (braking limits)."""
    n = len(acc)
    a_in = np.full(n + 1, 1e300)
    span_a = np.full(n + 1, 1e300)
    span_j = np.full(n + 1, 1e300)
    for q in range(n - 1, -1, -1):
        after_j = 1e300 if stop[q + 1] else span_j[q + 1]
        span_j[q] = min(jerk[q], after_j)
    for q in range(n - 1, -1, -1):
        # A mandatory stop is reached at rest: no bound is carried back across it. The bound may fall
        # along segment q only as fast as the jerk the planner uses there (the braking jerk).
        after = 1e300 if stop[q + 1] else a_in[q + 1]
        jerk_q = jerk[q] if stop[q + 1] else min(jerk[q], span_j[q + 1])
        a_in[q] = min(acc[q], after + jerk_q * length[q] / cap[q])
    for q in range(n + 1):
        if stop[q]:
            a_in[q] = 1e300
    for q in range(n - 1, -1, -1):
        after_a = 1e300 if stop[q + 1] else span_a[q + 1]
        span_a[q] = min(a_in[q], a_in[q + 1], after_a)
    # Read at point k+1 while on segment k: a stop there ends every braking manoeuvre.
    for q in range(n + 1):
        if stop[q]:
            span_a[q] = 1e300
            span_j[q] = 1e300
    return a_in, span_a, span_j


#: The share of an axis's jerk limit (and of the path-norm jerk) that the jerk-limited corner rule gives the
#: velocity and curvature steps of the junctions within reach of one 3-period difference; the rest stays
#: with the tangential motion around them (docs/motion.md §7).
JUNCTION_JERK_SHARE = 0.5
#: Tangent and curvature changes at or below this are float noise (as for the P1227 corner step).
JUNCTION_NOISE = 1e-12


@dataclass(frozen=True)
class JunctionJerkInput:
    """The junctions that the jerk-limited corner rule limits (m of them, none a mandatory stop) and the
    pieces (n) around them."""

    s: np.ndarray  # (m,) arc length of each junction, mm
    du: np.ndarray  # (m, 3) unit tangent out − in
    dc: np.ndarray  # (m, 3) curvature vector out − in, 1/mm (lines and arcs; 0 on NURBS pieces)
    d_rate: np.ndarray  # (m, r) rotary axes' rate out − in, deg/mm
    v_limit: np.ndarray  # (m,) the junction's other speed limits (P1227, both caps), mm/s
    a_near: np.ndarray  # (m,) largest tangential acceleration bound on either side, mm/s²
    axis_jerk: np.ndarray  # (3,) cutting jerk per linear axis, mm/s³
    rotary_jerk: np.ndarray  # (r,) cutting jerk per rotary axis, deg/s³
    path_jerk: float  # path-norm jerk, mm/s³ (inf = off)
    period_s: float  # interpolation period T
    acc_max: float  # largest tangential acceleration bound anywhere, mm/s²
    s0: np.ndarray  # (n,) piece starts, mm
    length: np.ndarray  # (n,) piece lengths, mm


@dataclass(frozen=True)
class JunctionJerkRule:
    """What the jerk-limited corner rule decides."""

    limit: np.ndarray  # (m,) speed limit at each junction (0 where it is a stop), mm/s
    stop: np.ndarray  # (m,) passed at rest: the acceleration term alone exceeds the junction's share
    jerk_scale: np.ndarray  # (n,) factor on every jerk limit of each piece (1 − the junctions' shares)


def _junction_jerk_rule(inp: JunctionJerkInput) -> JunctionJerkRule:
    """Speed limits per junction and jerk factors per piece such that the finite difference
    (p(t+T) − 3p(t) + 3p(t−T) − p(t−2T))/T³ of every axis (and its norm) stays within the jerk limit.

    The third difference is the path's third derivative averaged with the quadratic B-spline N (support
    3T, ∫N = 1, N ≤ ¾, |N′| ≤ 1/T) plus, per junction crossed at speed v and tangential acceleration a
    inside the window, Δu·(−v·N′ + a·N) + Δc·v²·N. So junction q adds at most
    ``|Δu_k|·(v/T² + ¾|a|/T) + ¾|Δc_k|·v²/T`` to axis k: its need β_q as a share of J_k. With |a| ≤ a_near
    and v ≤ the limit solved from β_q ≤ share (a stop where the acceleration term alone is above it), and
    every jerk limit of the pieces within reach (3 periods at up to v + 3T·acc_max) scaled by 1 − Σβ, the
    sum stays within J_k. Where Σβ over some piece exceeds the share, the junctions around it get
    proportionally smaller shares (one pass makes every sum fit)."""
    T = inp.period_s
    du = np.where(np.abs(inp.du) > JUNCTION_NOISE, np.abs(inp.du), 0.0)
    dc = np.where(np.abs(inp.dc) > JUNCTION_NOISE, np.abs(inp.dc), 0.0)
    dr = np.where(np.abs(inp.d_rate) > JUNCTION_NOISE, np.abs(inp.d_rate), 0.0)
    steps = [du / inp.axis_jerk, dr / inp.rotary_jerk]  # velocity steps per unit speed, share of J
    bends = [dc / inp.axis_jerk, np.zeros_like(dr)]  # acceleration steps per unit speed², share of J
    if math.isfinite(inp.path_jerk):
        steps.append(np.linalg.norm(du, axis=1, keepdims=True) / inp.path_jerk)
        bends.append(np.linalg.norm(dc, axis=1, keepdims=True) / inp.path_jerk)
    step = np.hstack(steps)
    c1 = step / T**2
    c0 = 0.75 * step * inp.a_near[:, None] / T
    c2 = 0.75 * np.hstack(bends) / T

    def need(v: np.ndarray) -> np.ndarray:
        return np.max(c2 * (v * v)[:, None] + c1 * v[:, None] + c0, axis=1, initial=0.0)

    def solve(budget: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        rest = budget[:, None] - c0
        stop = np.any(rest < 0.0, axis=1)
        rest = np.maximum(rest, 0.0)
        den = c1 + np.sqrt(c1 * c1 + 4.0 * c2 * rest)
        with np.errstate(divide="ignore", invalid="ignore"):
            v = np.min(np.where(den > 0.0, 2.0 * rest / den, np.inf), axis=1, initial=np.inf)
        v = np.where(stop, 0.0, np.minimum(v, inp.v_limit))
        return v, stop, np.where(stop, 0.0, need(v))

    n = len(inp.s0)
    share = np.full(len(inp.s), JUNCTION_JERK_SHARE)
    v, stop, beta = solve(share)
    # Pieces within reach of a 3-period difference straddling junction q: the speed there is at most
    # v_q + 3T·acc_max, so they lie within 3T of it at that speed.
    reach = 3.0 * T * (v + 3.0 * T * inp.acc_max) * (1.0 + 1e-9) + 1e-12
    ends = inp.s0 + inp.length
    lo = np.searchsorted(ends, inp.s - reach, side="left")
    hi = np.maximum(np.searchsorted(inp.s0, inp.s + reach, side="right") - 1, lo)
    pairs = np.column_stack((lo, hi + 1)).ravel()

    def per_piece(b: np.ndarray) -> np.ndarray:
        total = np.zeros(n + 1)
        np.add.at(total, lo, b)
        np.add.at(total, hi + 1, -b)
        return np.maximum(np.cumsum(total), 0.0)  # (n + 1,): the last entry is a sentinel (0)

    summed = per_piece(beta)
    if len(pairs):
        worst = np.maximum.reduceat(summed, pairs)[::2]
        crowded = worst > JUNCTION_JERK_SHARE
        if np.any(crowded):
            v, stop, beta = solve(np.where(crowded, beta * JUNCTION_JERK_SHARE / np.maximum(worst, 1e-300),
                                           share))  # fmt: skip
            summed = per_piece(beta)
    return JunctionJerkRule(limit=v, stop=stop, jerk_scale=1.0 - np.minimum(summed[:n], 1.0))


def _curvature_vectors(tp: Toolpath, idx: np.ndarray, kappa: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Curvature vectors κ·n (towards the centre, 1/mm) at the start and the end of each piece: arcs and
    helices (the normal lies in the plane); 0 on lines and NURBS pieces."""
    c_start = np.zeros((len(idx), 3))
    c_end = np.zeros((len(idx), 3))
    arcs = np.flatnonzero(tp.kind[idx] == SegmentKind.ARC)
    if len(arcs):
        i = idx[arcs]
        axes = _PLANE_TABLE[tp.plane[i].astype(np.int64)]
        rows = np.arange(len(arcs))
        for theta, out in ((tp.start_angle[i], c_start), (tp.start_angle[i] + tp.sweep[i], c_end)):
            vec = np.zeros((len(arcs), 3))
            vec[rows, axes[:, 0]] = -np.cos(theta) * kappa[arcs]
            vec[rows, axes[:, 1]] = -np.sin(theta) * kappa[arcs]
            out[arcs] = vec
    return c_start, c_end


#: NURBS curves are cut into pieces of at most this arc length (and at least NURBS_MIN_PIECES), mm.
NURBS_PIECE_MM = 0.5
NURBS_MIN_PIECES = 4
#: At most this many pieces per curve: a curve longer than 10 m gets longer pieces (bounded work).
NURBS_MAX_PIECES = 20_000
NURBS_SAMPLES = 9  # samples per piece (at least): limits are sampled there, positions interpolated between
NURBS_TABLE_TOL_MM = 1e-10  # the Hermite table is refined until it is this close to the exact curve
NURBS_MAX_SAMPLES = 1025
#: At most this many curve evaluations per curve for its table (a curve full of near-cusps stops refining).
NURBS_MAX_EVALUATIONS = 1 << 19
_EVALUATION_CHUNK = 1 << 15  # points per at_length call: bounds the temporary arrays


def _at_length(curve, s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``curve.at_length`` in chunks (its Newton iterations hold some 100 floats per point)."""
    parts = [curve.at_length(s[i : i + _EVALUATION_CHUNK]) for i in range(0, len(s), _EVALUATION_CHUNK)]
    if not parts:
        return np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0)
    return tuple(np.concatenate(x) for x in zip(*parts, strict=True))  # type: ignore[return-value]


def _curve_table(curve, length: float, k: int) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Per piece of ``curve`` (``k`` pieces of equal arc length over ``length``): point, unit tangent and
    curvature at its equally spaced samples. Each piece is refined on its own (samples 9, 17, 33, …,
    NURBS_MAX_SAMPLES) until the cubic Hermite between its samples is within NURBS_TABLE_TOL_MM of the
    exact curve at every interval midpoint, so a near-cusp refines its own piece, not the whole curve."""
    h = length / k
    samples = np.full(k, NURBS_SAMPLES, dtype=np.int64)
    table: list = [None] * k
    pending = np.arange(k)
    evaluations = 0
    while pending.size:
        n_int = samples[pending] - 1
        # Sample positions of every pending piece, then the interval midpoints, in one evaluation.
        counts = n_int + 1
        first = np.repeat(np.cumsum(counts) - counts, counts)
        j = np.arange(int(counts.sum())) - first
        local = np.minimum(np.repeat(pending * h, counts) + j * np.repeat(h / n_int, counts), curve.length)
        interval = np.ones(len(local), dtype=bool)
        interval[np.cumsum(counts) - 1] = False  # the last sample of a piece starts no interval
        mid = np.minimum(local[:-1][interval[:-1]] + 0.5 * np.repeat(h / n_int, n_int), curve.length)
        point, tangent, curvature = _at_length(curve, np.concatenate((local, mid)))
        exact = point[len(local) :]
        point, tangent, curvature = point[: len(local)], tangent[: len(local)], curvature[: len(local)]
        evaluations += len(local) + len(mid)
        starts = np.flatnonzero(interval)
        step = np.repeat(h / n_int, n_int)[:, None]
        hermite = (point[starts] + point[starts + 1]) / 2 + step / 8 * (tangent[starts] - tangent[starts + 1])
        error = np.linalg.norm(hermite - exact, axis=1)
        worst = np.maximum.reduceat(error, np.cumsum(n_int) - n_int)
        more = (worst > NURBS_TABLE_TOL_MM) & (samples[pending] < NURBS_MAX_SAMPLES)
        if evaluations + 2 * int(np.sum(2 * n_int[more] + 1)) > NURBS_MAX_EVALUATIONS:
            more[:] = False  # bounded work: keep what the pieces have
        offsets = np.cumsum(counts) - counts
        for piece, start, count, again in zip(pending, offsets, counts, more, strict=True):
            if not again:
                rows = slice(start, start + count)
                table[piece] = (point[rows], tangent[rows], curvature[rows])
        samples[pending[more]] = 2 * n_int[more] + 1
        pending = pending[more]
    return table


def _pieces(tp: Toolpath, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, tuple | None]:
    """(toolpath row, start arc length, length) per piece, and for the NURBS pieces (in order) the sampled
    (extent, tangent at start, tangent at end, largest curvature, chord start, chord end, first table row,
    samples per piece) plus the curve table (point, unit tangent per row)."""
    nurbs = tp.kind[rows] == SegmentKind.NURBS
    if not np.any(nurbs):
        return rows, tp.s_start[rows].astype(float), tp.length[rows].astype(float), None
    counts = np.ones(len(rows), dtype=np.int64)
    lengths = tp.length[rows]
    pieces = np.ceil(lengths[nurbs] / NURBS_PIECE_MM)
    counts[nurbs] = np.clip(pieces, NURBS_MIN_PIECES, NURBS_MAX_PIECES).astype(np.int64)
    idx = np.repeat(rows, counts)
    first = np.repeat(np.cumsum(counts) - counts, counts)
    j = np.arange(len(idx)) - first
    count = np.repeat(counts, counts)
    piece_len = tp.length[idx] / count
    s0 = tp.s_start[idx] + j * piece_len
    geo: list[list] = [[] for _ in range(8)]
    table = []
    table_rows = 0
    # Corner blends (smoothing) are sampled in bulk; other curves one by one.
    blend_rows = [int(r) for r in rows[nurbs] if isinstance(tp.nurbs[int(r)], BlendCurve)]
    blend_pieces = [int(counts[np.searchsorted(rows, r)]) for r in blend_rows]
    blend_table = dict(zip(blend_rows, blend_tables([tp.nurbs[r] for r in blend_rows], blend_pieces,
                                                    NURBS_TABLE_TOL_MM, NURBS_SAMPLES, NURBS_MAX_SAMPLES),
                           strict=True)) if blend_rows else {}  # fmt: skip
    for r in rows[nurbs]:
        k = int(counts[np.searchsorted(rows, r)])
        length = float(tp.length[r])
        pieces_table = blend_table.get(int(r)) or _curve_table(tp.nurbs[int(r)], length, k)
        for point, tangent, curvature in pieces_table:
            samples = len(point)
            spacing = length / k / (samples - 1)
            kappa_max = float(curvature.max())
            # Between samples a tangent component moves by at most κ·(spacing/2): add it, so the sampled
            # extent bounds the true one (given the sampled curvature).
            geo[0].append(np.minimum(np.abs(tangent).max(axis=0) + kappa_max * spacing / 2, 1.0))
            geo[1].append(tangent[0])
            geo[2].append(tangent[-1])
            geo[3].append(kappa_max)
            geo[4].append(point[0])
            geo[5].append(point[-1])
            geo[6].append(table_rows)
            geo[7].append(samples)
            table.append(np.hstack((point, tangent)))
            table_rows += samples
    out = (np.array(geo[0]), np.array(geo[1]), np.array(geo[2]), np.array(geo[3]), np.array(geo[4]),
           np.array(geo[5]))  # fmt: skip
    return idx, s0, piece_len, (*out, np.array(geo[6]), np.array(geo[7]), np.concatenate(table))


def smoothing_rules(machine: MachineConfig) -> SmoothingRules:
    """The machine's corner-smoothing parameters (P1401#1 EFL / P1473, P1495, the segment-length rule)."""
    ctl = machine.controller
    return SmoothingRules(tolerance_mm=ctl.corner_smoothing_tolerance_mm,
                          min_angle_deg=ctl.corner_smoothing_min_angle_deg,
                          max_segment_mm=ctl.corner_smoothing_max_segment_mm)  # fmt: skip


def build_limits(tp: Toolpath, machine: MachineConfig) -> PathLimits:
    """Compute every static limit of ``tp`` on ``machine`` (see the module docstring).

    With corner smoothing (``controller.corner_smoothing_tolerance_mm``, or tolerances carried by the tool
    path) the limits describe the smoothed path (:func:`cnc_gym.toolpath.smoothing.smooth_corners`); the
    toolpath indices they report stay those of ``tp``."""
    ctl = machine.controller
    programmed = tp
    tp, origin = smooth_corners(tp, smoothing_rules(machine), lookahead=ctl.lookahead_blocks > 1)
    dt = float(ctl.interpolation_period_s)
    axis = {name: np.array(machine.axis_array(name)) for name in (
        "rapid_mm_min", "max_feed_mm_min", "max_accel_mm_s2", "max_jerk_mm_s3", "rapid_accel_mm_s2",
        "rapid_jerk_mm_s3", "corner_step_mm_min")}  # fmt: skip
    kind = tp.kind.astype(np.int64)
    moving = (kind == SegmentKind.RAPID) | (kind == SegmentKind.LINE) | (kind == SegmentKind.ARC) | (
        kind == SegmentKind.NURBS)
    rows = np.flatnonzero(moving & (tp.length > MIN_LENGTH_MM))
    rotary_only = np.flatnonzero(moving & (tp.length <= MIN_LENGTH_MM) & (tp.rotary_travel > 0))
    rotary_holds = np.zeros((0, 6))
    held = kind == SegmentKind.DWELL
    held[rotary_only] = True
    # Pieces: one per line/arc/rapid; a NURBS curve is cut into pieces of equal arc length, each with the
    # limits sampled over it (so the caps follow the curvature along the curve).
    idx, s0, length, nurbs_geo = _pieces(tp, rows)
    n = len(idx)
    cutting = tp.kind[idx] != SegmentKind.RAPID
    feed = tp.path_feed[idx] / 60.0
    bad = cutting & ~(np.isfinite(feed) & (feed > 0))
    if np.any(bad):
        i = int(idx[np.flatnonzero(bad)[0]])
        file, line = tp.source(i)
        raise ProgramError("cutting move without a positive feed", code="motion.no_feed", file=file,
                           line=line)  # fmt: skip

    extent, t_start, t_end = _direction_extent(tp, idx)
    kappa = _arc_curvature(tp, idx)
    is_nurbs = tp.kind[idx] == SegmentKind.NURBS
    if nurbs_geo is not None:
        extent[is_nurbs], t_start[is_nurbs], t_end[is_nurbs], kappa[is_nurbs] = nurbs_geo[:4]
    with np.errstate(divide="ignore"):
        inv = np.where(extent > 1e-12, 1.0 / np.maximum(extent, 1e-300), np.inf)  # 1/|u_k|

    def projected(limit_per_axis: np.ndarray) -> np.ndarray:
        return np.min(limit_per_axis[None, :] * inv, axis=1)

    rapid_rate = projected(axis["rapid_mm_min"] / 60.0)
    cut_axis_cap = np.minimum(projected(axis["max_feed_mm_min"] / 60.0), ctl.max_feed_mm_min / 60.0)
    # Curvature limits use the in-plane axes' limits (the centripetal vector turns within the plane).
    plane_axes = _PLANE_TABLE[tp.plane[idx].astype(np.int64)]
    acc_ax = axis["max_accel_mm_s2"]
    jerk_ax = axis["max_jerk_mm_s3"]
    a_n = np.minimum(ctl.max_centripetal_accel_mm_s2,
                     np.minimum(acc_ax[plane_axes[:, 0]], acc_ax[plane_axes[:, 1]]))  # fmt: skip
    j_n_axes = np.minimum(jerk_ax[plane_axes[:, 0]], jerk_ax[plane_axes[:, 1]])
    # A NURBS curve bends in any direction: all three axes count.
    a_n = np.where(is_nurbs, min(ctl.max_centripetal_accel_mm_s2, acc_ax.min()), a_n)
    j_n_axes = np.where(is_nurbs, jerk_ax.min(), j_n_axes)
    # Path-norm limits (controller.path_max_accel_mm_s2 / path_max_jerk_mm_s3; 0 = off). On a curve the
    # acceleration vector is a_t·t + v²κ·n and the jerk vector (j_t − κ²v³)·t + 3κv·a_t·n (+ κ'v³·n): each
    # term gets its share of the norm (√½ each for the acceleration, ⅓ each for the jerk), so the norms hold
    # on lines and arcs; on a line the tangential term is all there is.
    curved = kappa > 0
    path_a = ctl.path_max_accel_mm_s2 if ctl.path_max_accel_mm_s2 > 0 else np.inf
    path_j_machine = ctl.path_max_jerk_mm_s3 if ctl.path_max_jerk_mm_s3 > 0 else np.inf
    path_a_t = np.where(curved, path_a * math.sqrt(0.5), path_a)
    a_n = np.minimum(a_n, path_a * math.sqrt(0.5))
    with np.errstate(divide="ignore", invalid="ignore"):
        rho = np.where(kappa > 0, 1.0 / np.maximum(kappa, 1e-300), np.inf)
        v_centripetal = np.sqrt(a_n / kappa)
        delta = np.minimum(ctl.chord_tolerance_mm, rho)
        v_chord = (2.0 / dt) * np.sqrt(np.maximum(2.0 * rho * delta - delta * delta, 0.0))
    rotary_rate = np.zeros((n, 0))
    rotary_limits: dict[str, np.ndarray] = {}
    if tp.rotary_axes:
        rates, rotary_limits = _rotary_rates(tp, machine)
        rotary_rate = rates[idx]

    Limits = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]

    def kinematic_limits(jerk_scale: np.ndarray | None) -> Limits:
        """(cap, base, acc, jerk) per piece; ``jerk_scale`` (per piece, ≤ 1) scales every jerk limit there
        (the jerk-limited corner rule's share, :func:`_junction_jerk_rule`; None = 1)."""
        j_n, path_j = j_n_axes, path_j_machine
        if jerk_scale is not None:
            j_n, path_j = j_n * jerk_scale, path_j * jerk_scale
        path_j_t = np.where(curved, path_j / 3.0, path_j)
        j_n = np.minimum(j_n, path_j / 3.0)
        with np.errstate(divide="ignore", invalid="ignore"):
            v_cjerk = np.cbrt(j_n / kappa**2)
        v_curv = np.where(kappa > 0, np.minimum(np.minimum(v_centripetal, v_cjerk), v_chord), np.inf)
        v_curv = np.maximum(v_curv, ctl.min_arc_feed_mm_min / 60.0)  # P1505 floor (F itself may be lower)
        cap = np.where(cutting, np.minimum(cut_axis_cap, v_curv), rapid_rate)
        base = np.where(cutting, feed, rapid_rate)
        acc = np.where(cutting, projected(acc_ax), projected(axis["rapid_accel_mm_s2"]))
        jerk = np.where(cutting, projected(jerk_ax), projected(axis["rapid_jerk_mm_s3"]))
        if jerk_scale is not None:
            jerk = jerk * jerk_scale
        acc = np.minimum(acc, path_a_t)
        jerk = np.minimum(jerk, path_j_t)
        if math.isfinite(path_j_machine):  # the cross term 3κ·v·a_t ≤ J/3 at every speed up to the cap
            with np.errstate(divide="ignore"):
                cross = np.where(curved, path_j / np.maximum(9.0 * kappa * cap, 1e-300), np.inf)
            acc = np.minimum(acc, cross)
        if tp.rotary_axes:
            # A rotary axis moving with the XYZ path turns at rate·v (deg per mm of path × mm/s): its speed,
            # acceleration and jerk limits cap the path's like a linear axis's projected ones.
            with np.errstate(divide="ignore"):
                inv_rate = np.where(rotary_rate > 1e-12, 1.0 / np.maximum(rotary_rate, 1e-300), np.inf)

            def rotary_projected(name: str) -> np.ndarray:
                return np.min(rotary_limits[name][None, :] * inv_rate, axis=1, initial=np.inf)

            cap = np.minimum(cap, np.where(cutting, rotary_projected("max_feed_deg_min"),
                                           rotary_projected("rapid_deg_min")) / 60.0)  # fmt: skip
            # P1224 clamps the composite rate (degrees counted as mm), so the XYZ share of it.
            xyz_share = tp.length[idx] / np.hypot(tp.length[idx], tp.rotary_length[idx])
            cap = np.minimum(cap, np.where(cutting, ctl.max_feed_mm_min / 60.0 * xyz_share, np.inf))
            base = np.minimum(base, cap)
            acc = np.minimum(acc, np.where(cutting, rotary_projected("max_accel_deg_s2"),
                                           rotary_projected("rapid_accel_deg_s2")))  # fmt: skip
            rotary_jerk = np.where(cutting, rotary_projected("max_jerk_deg_s3"),
                                   rotary_projected("rapid_jerk_deg_s3"))  # fmt: skip
            if jerk_scale is not None:
                rotary_jerk = rotary_jerk * jerk_scale
            jerk = np.minimum(jerk, rotary_jerk)
        return cap, base, acc, jerk

    cap, base, acc, jerk = kinematic_limits(None)

    # ------------------------------------------------------------------ junctions
    hard = np.zeros(n + 1)
    stop = np.zeros(n + 1, dtype=bool)
    turn = np.zeros(n + 1)
    stop[n] = True
    # Stops with an in-position check before the next block (P1471): exact stops (G09/G61 block ends,
    # G04 without P/X, M00), both ends of every rapid, M/S/T changes and the program end. Plain dwells and
    # the block ends of look-ahead off are stops without it.
    wait = np.zeros(n + 1, dtype=bool)
    wait[n] = n > 0
    modes = tp.modes.astype(np.int64)
    if n:
        hard[0] = cap[0]
        stop[0] = True
    if n > 1:
        prev, nxt = idx[:-1], idx[1:]
        u_in, u_out = t_end[:-1], t_start[1:]
        du = np.abs(u_out - u_in)
        step = axis["corner_step_mm_min"] / 60.0
        with np.errstate(divide="ignore"):
            corner = np.min(np.where(du > 1e-12, step[None, :] / np.maximum(du, 1e-300), np.inf), axis=1)
        if tp.rotary_axes:  # a rotary axis's speed steps by v·Δrate at the junction (P1227 per axis)
            rotary_step = rotary_limits["corner_step_deg_min"] / 60.0
            d_rate = np.abs(rotary_rate[1:] - rotary_rate[:-1])
            with np.errstate(divide="ignore"):
                rotary_corner = np.where(d_rate > 1e-12, rotary_step[None, :] / np.maximum(d_rate, 1e-300),
                                         np.inf)  # fmt: skip
            corner = np.minimum(corner, np.min(rotary_corner, axis=1, initial=np.inf))
        hard[1:n] = np.minimum(corner, np.minimum(cap[:-1], cap[1:]))
        turn[1:n] = np.arccos(np.clip(np.sum(u_in * u_out, axis=1), -1.0, 1.0))
        # Everything between two motion segments (short moves, dwells) may carry a stop.
        exact = (modes & SegmentMode.EXACT_STOP) != 0
        exact_cum = np.concatenate(([0], np.cumsum(exact)))
        dwell_cum = np.concatenate(([0], np.cumsum(held)))
        # stops from prev (inclusive) up to nxt (exclusive)
        has_exact = exact_cum[nxt] - exact_cum[prev] > 0
        has_dwell = dwell_cum[nxt] - dwell_cum[prev] > 0
        rapid_prev = tp.kind[prev] == SegmentKind.RAPID
        mode_change = rapid_prev | (tp.kind[nxt] == SegmentKind.RAPID)
        aux_change = (tp.tool[prev] != tp.tool[nxt]) | (tp.spindle_rpm[prev] != tp.spindle_rpm[nxt])
        # Without look-ahead every block ends at rest — but the pieces of one NURBS block are one block, and
        # a block in tapping mode (G63, TAPPING_MODE) "is not decelerated at the end point of a block, but
        # the next block is executed" (manual §3.8): it runs on as in G64 with look-ahead.
        tapping_prev = (modes[prev] & SegmentMode.TAPPING_MODE) != 0
        no_lookahead = (ctl.lookahead_blocks <= 1) & (prev != nxt) & ~tapping_prev
        # A kink where some axis allows no velocity step (P1227 = 0) can only be passed at rest: it is a
        # stop with an in-position check, as an exact stop (a limit of 0 that is no stop would leave the
        # reference creeping towards the kink forever).
        kink_stop = hard[1:n] <= 0.0
        stop[1:n] = has_exact | has_dwell | mode_change | aux_change | no_lookahead | kink_stop
        wait[1:n] = has_exact | mode_change | aux_change | kink_stop
        if ctl.corner_rule == "jerk":
            # The jerk-limited corner rule (docs/motion.md §7): a speed limit per junction, a stop where even
            # crossing at rest-speed would not fit, and a lower jerk around the junctions that are passed.
            free = ~stop[1:n]
            c_start, c_end = _curvature_vectors(tp, idx, kappa)
            d_rate = rotary_rate[1:] - rotary_rate[:-1]
            rule = _junction_jerk_rule(JunctionJerkInput(
                s=s0[1:][free], du=(u_out - u_in)[free], dc=(c_start[1:] - c_end[:-1])[free],
                d_rate=d_rate[free], v_limit=hard[1:n][free], a_near=np.maximum(acc[:-1], acc[1:])[free],
                axis_jerk=jerk_ax, rotary_jerk=rotary_limits.get("max_jerk_deg_s3", np.zeros(0)),
                path_jerk=path_j_machine, period_s=dt, acc_max=float(np.max(acc)), s0=s0,
                length=length))  # fmt: skip
            cap, base, acc, jerk = kinematic_limits(rule.jerk_scale)
            limit = np.full(n - 1, np.inf)
            limit[free] = rule.limit
            jerk_stop = np.zeros(n - 1, dtype=bool)
            jerk_stop[free] = rule.stop
            hard[0] = cap[0]
            hard[1:n] = np.minimum(np.minimum(corner, limit), np.minimum(cap[:-1], cap[1:]))
            # Passed at rest, as with look-ahead off: deceleration only, no in-position check.
            stop[1:n] |= jerk_stop
    hard[stop] = 0.0

    # ------------------------------------------------------------------ dwells per point
    # A dwell belongs to the first point after it: point q = number of motion segments before it.
    # Rotary-only moves (no XYZ travel) are timed holds of the XYZ reference, like dwells.
    dwell_rows = np.flatnonzero(held)
    dwell_point = np.searchsorted(idx, dwell_rows)
    dw0 = np.searchsorted(dwell_point, np.arange(n + 1), side="left")
    dw1 = np.searchsorted(dwell_point, np.arange(n + 1), side="right")
    dwell_f = np.zeros((max(len(dwell_rows), 1), 5))
    if len(dwell_rows):
        dwell_f[: len(dwell_rows), 0] = tp.dwell_s[dwell_rows]
        if len(rotary_only):
            at = np.searchsorted(dwell_rows, rotary_only)
            rotary_holds = _rotary_only_profiles(tp, machine, rotary_only, _rotary_rates(tp, machine)[1])
            dwell_f[at, 0] = rotary_holds[:, 1]
        dwell_f[: len(dwell_rows), 1] = origin[dwell_rows]
        if len(rotary_holds):
            rotary_holds[:, 0] = origin[rotary_holds[:, 0].astype(np.int64)]
        dwell_f[: len(dwell_rows), 2:5] = tp.start[dwell_rows]

    # next mandatory stop at or after each point
    stop_idx = np.flatnonzero(stop)
    next_stop = stop_idx[np.searchsorted(stop_idx, np.arange(n + 1), side="left")]

    # ------------------------------------------------------------------ acceleration bound on arrival
    a_in, span_a, span_j = _backward_bounds(acc, jerk, length, cap, stop)

    seg_f = np.zeros((n, K.N_SEG_F))
    seg_f[:, K.F_S0] = s0
    seg_f[:, K.F_LEN] = length
    seg_f[:, K.F_CAP] = cap
    seg_f[:, K.F_BASE] = base
    seg_f[:, K.F_ACC] = acc
    seg_f[:, K.F_JERK] = jerk
    seg_f[:, K.F_CURV] = kappa
    seg_f[:, K.F_SX : K.F_SX + 3] = tp.start[idx]
    seg_f[:, K.F_EX : K.F_EX + 3] = tp.end[idx]
    if nurbs_geo is not None:  # the kernel draws the chord; the controller puts the exact curve in place
        seg_f[is_nurbs, K.F_SX : K.F_SX + 3] = nurbs_geo[4]
        seg_f[is_nurbs, K.F_EX : K.F_EX + 3] = nurbs_geo[5]
    seg_f[:, K.F_CX : K.F_CX + 3] = np.nan_to_num(tp.center[idx])
    seg_f[:, K.F_RADIUS] = tp.radius[idx]
    seg_f[:, K.F_ANG0] = tp.start_angle[idx]
    seg_f[:, K.F_SWEEP] = tp.sweep[idx]
    w = plane_axes[:, 2]
    seg_f[:, K.F_RISE] = np.where(tp.kind[idx] == SegmentKind.ARC,
                                  tp.end[idx, w] - tp.start[idx, w], 0.0)  # fmt: skip
    seg_f[:, K.F_FEED] = base
    seg_i = np.zeros((n, K.N_SEG_I), dtype=np.int64)
    seg_i[:, K.I_KIND] = tp.kind[idx]
    seg_i[:, K.I_PU : K.I_PW + 1] = plane_axes
    seg_i[:, K.I_TP] = origin[idx]
    seg_i[:, K.I_LOCKED] = (modes[idx] & SegmentMode.OVERRIDE_LOCKED) != 0
    seg_i[:, K.I_RAPID] = ~cutting
    seg_i[:, K.I_TABLE] = -1
    curve_f = np.zeros((1, 6))
    if nurbs_geo is not None:
        seg_i[is_nurbs, K.I_TABLE] = nurbs_geo[6]
        seg_i[is_nurbs, K.I_NSAMP] = nurbs_geo[7]
        curve_f = nurbs_geo[8]
    pt_f = np.zeros((n + 1, K.N_PT_F))
    pt_f[:, K.P_S] = np.concatenate((s0, [s0[-1] + length[-1]])) if n else 0.0
    pt_f[:, K.P_HARD] = hard
    pt_f[:, K.P_AIN] = a_in
    pt_f[:, K.P_TURN] = turn
    pt_f[:, K.P_SPAN_A] = span_a
    pt_f[:, K.P_SPAN_J] = span_j
    pt_i = np.zeros((n + 1, K.N_PT_I), dtype=np.int64)
    pt_i[:, K.Q_STOP] = stop
    pt_i[:, K.Q_DW0] = dw0
    pt_i[:, K.Q_DW1] = dw1
    pt_i[:, K.Q_NEXT_STOP] = next_stop
    pt_i[:, K.Q_WAIT] = wait
    if n:
        rest = tp.end[idx[-1]].astype(float)
    elif len(dwell_rows):
        rest = tp.start[dwell_rows[-1]].astype(float)
    else:
        rest = np.zeros(3)
    for arr in (seg_f, seg_i, pt_f, pt_i, dwell_f, curve_f):
        arr.flags.writeable = False
    return PathLimits(seg_f=np.ascontiguousarray(seg_f), seg_i=seg_i, pt_f=pt_f, pt_i=pt_i,
                      dwell_f=dwell_f, curve_f=np.ascontiguousarray(curve_f), rest_position=rest,
                      rotary_holds=rotary_holds, path=None if tp is programmed else tp)  # fmt: skip
