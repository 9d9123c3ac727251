"""The controller's hot path: one interpolation period at a time, compiled with numba.

Everything here works on flat arrays packed by :mod:`cnc_gym.motion.limits` (column indices below) and
on a small state vector, so that a call from Python costs a handful of argument conversions. The entry,
:func:`advance_into`, takes them as small typed records in the manner of Ruckig's input and output
parameters (:class:`PathTables`, :class:`ControllerState`, :class:`Command`; rows out).

The planner is a *safe-set* jerk-limited tracker (details and guarantees: ``docs/motion.md``):

* ``brake(v, a, w, A, J)`` is the distance and time of the time-optimal jerk-limited manoeuvre that
  takes the path speed from ``v`` (with tangential acceleration ``a``) down to ``w`` and ends with zero
  acceleration (phases: jerk towards ``-A``, hold ``-A``, jerk back to 0).
* A state is *safe* when, for every limit point ``p`` ahead in the look-ahead window (junction speeds,
  segment speed caps, mandatory stops, and a stop at the end of the window), ``brake(v, a, w_p) <= d_p``.
  Because the manoeuvres to lower targets decelerate at least as hard at every instant, the single
  manoeuvre that stops at the window end then meets every point: the test is necessary *and* sufficient.
  The braking A and J are the lowest up to the next mandatory stop, so they never shrink as the window
  slides and a safe state stays safe.
* Each period applies one constant jerk: the largest whose end state is still safe and whose speed stays
  under the target (bisection; the tests are monotone in the jerk), bounded below by the acceleration
  limit and by "no reverse motion", and eased near the target by a settling law. Where the optimal braking
  switches inside a period (no constant jerk stays safe), the period follows the braking manoeuvre
  exactly. Where the operator's target cannot be met any more (override turned down), the speed falls as
  fast as the jerk allows without undershooting it, still capped by the hard (geometric) safety test.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

# ---------------------------------------------------------------- packed layout (see limits.py)
# Per motion segment, float columns.
F_S0 = 0  # arc length at the segment start, mm
F_LEN = 1  # length, mm
F_CAP = 2  # hard speed cap (geometry, axis limits, clamps), mm/s
F_BASE = 3  # speed at 100 % override: programmed path feed (cutting) or rapid rate (rapids), mm/s
F_ACC = 4  # tangential acceleration limit, mm/s^2
F_JERK = 5  # tangential jerk limit, mm/s^3
F_CURV = 6  # curvature, 1/mm
F_SX, F_SY, F_SZ = 7, 8, 9  # start point
F_EX, F_EY, F_EZ = 10, 11, 12  # end point
F_CX, F_CY, F_CZ = 13, 14, 15  # arc centre
F_RADIUS = 16
F_ANG0 = 17  # start angle, rad
F_SWEEP = 18  # signed sweep, rad
F_RISE = 19  # helix rise along the plane normal, mm
F_FEED = 20  # programmed path feed, mm/s (0 for rapids)
N_SEG_F = 21

# Per motion segment, int columns.
I_KIND = 0  # SegmentKind value
I_PU, I_PV, I_PW = 1, 2, 3  # plane axes (u, v, w) of an arc
I_TP = 4  # index of the segment in the Toolpath
I_LOCKED = 5  # 1 = override fixed at 100 % (G63)
I_RAPID = 6  # 1 = rapid
I_TABLE = 7  # NURBS piece: first row of its samples in the curve table (-1 otherwise)
I_NSAMP = 8  # NURBS piece: number of equally spaced samples (point, unit tangent) in the table
N_SEG_I = 9

# Per limit point q (the start of motion segment q; q = n is the program end), float columns.
P_S = 0  # arc length, mm
P_HARD = 1  # hard speed limit at the point (corner, caps of both sides; 0 = mandatory stop), mm/s
P_AIN = 2  # acceleration bound on arrival (backward-smoothed, see limits.py), mm/s^2
P_TURN = 3  # turning angle of the junction, rad
P_SPAN_A = 4  # lowest arrival acceleration bound from this point up to the next mandatory stop, mm/s^2
P_SPAN_J = 5  # lowest jerk limit of the segments from this point up to the next mandatory stop, mm/s^3
N_PT_F = 6

# Per limit point, int columns.
Q_STOP = 0  # 1 = mandatory stop (exact stop, dwell, mode change, program end)
Q_DW0 = 1  # dwells to run at this point: rows Q_DW0 .. Q_DW1-1 of the dwell table
Q_DW1 = 2
Q_NEXT_STOP = 3  # index of the first mandatory stop at or after this point
Q_WAIT = 4  # 1 = a stop with an in-position check (exact stop, rapid end or start, M/S/T, program end)
N_PT_I = 5

# State vectors.
S_T, S_S, S_V, S_A, S_OV, S_DWELL_LEFT, S_J = 0, 1, 2, 3, 4, 5, 6
N_STATE_F = 7
K_SEG, K_PHASE, K_DWELL = 0, 1, 2  # motion segment, phase, current dwell row
N_STATE_I = 3
# PHASE_WAIT: at rest on an in-position stop (K_SEG = the segment arrived on), until released from outside.
PHASE_MOVE, PHASE_DWELL, PHASE_DONE, PHASE_WAIT = 0, 1, 2, 3

# Output columns of advance().
O_T, O_X, O_Y, O_Z, O_S, O_V, O_A, O_J, O_SEG, O_CUT, O_DONE = range(11)  # O_DONE: finished after the tick
N_OUT = 11

KIND_LINE = 1
KIND_ARC = 2

BISECT_ITERS = 22
TRACK_PERIODS = 3.0  # time constant of the final approach to a speed target, in periods
#: Revisions of the controller's behaviour (``cfg[N_CFG - 1]``), so that an env id keeps the dynamics it
#: was published with. Revision 1: where the override was lowered while the reference was still
#: accelerating below the new target (from rest, say), its "slow down without undershooting the target"
#: rule asked for the largest jerk, since no jerk keeps a speed below the target at or above it; the
#: reference overshot the new target by up to about twice (F1475 from rest, 110 % lowered to 100 % after
#: 0.05 mm: 44.8 mm/s against 24.6). Revision 2 (the live one): below the target the rule only keeps the
#: speed from falling below where it is, and the tracking jerk lands it on the target.
CONTROLLER_REVISION = 2
#: Entries of the kernel's ``cfg``: dt, window blocks, override slew per s, rest x, y, z, revision.
N_CFG = 7
SNAP_MM = 1e-6  # a mandatory stop closer than this (with the stop manoeuvre done) is snapped onto
INF = 1e300


# The smallest helpers (_peak, _valley, _step, _tick_top, _bottom, _accel_bound) are plain calls, not
# inline="always": LLVM inlines them all the same, while numba's own inlining typed and lowered their
# bodies again at each of their dozens of call sites, seconds of a first run's compile. (_target and
# _track_jerk stay inlined: LLVM leaves them as calls in _tick.)
@njit(cache=True)
def _peak(v: float, a: float, jerk: float) -> float:
    """Highest speed reached if the acceleration is ramped to zero now at the full jerk."""
    if a > 0.0:
        return v + a * a / (2.0 * jerk)
    return v


@njit(cache=True)
def _valley(v: float, a: float, jerk: float) -> float:
    """Lowest speed reached if the (negative) acceleration is ramped to zero now at the full jerk."""
    if a < 0.0:
        return v - a * a / (2.0 * jerk)
    return v


@njit(cache=True, inline="always")
def _phases(v: float, a: float, w: float, acc: float,
            jerk: float) -> tuple[float, float, float, float, float]:  # fmt: skip
    """Phases of the braking manoeuvre ``brake(v, a, w)`` (the caller has checked _peak(v, a) > w):
    (t1, j1, t2, a1, t3) = jerk j1 for t1 (to the acceleration a1 ≥ −A), hold a1 for t2, jerk +J for t3 back
    to zero. Where even ramping the acceleration straight back to zero undershoots w (a < 0), the phases are
    that ramp alone (t1 = t2 = 0, t3 = −a/J): it crosses w and ends below it."""
    if a < 0.0 and _valley(v, a, jerk) <= w:
        return 0.0, jerk, 0.0, a, -a / jerk
    a1sq = 0.5 * a * a + jerk * (v - w)
    a1 = -math.sqrt(max(a1sq, 0.0))
    t2 = 0.0
    if a1 < -acc:
        a1 = -acc
        dv1 = (acc * acc - a * a) / (2.0 * jerk) if a < -acc else (a * a - acc * acc) / (2.0 * jerk)
        t2 = max((v - w + dv1 - acc * acc / (2.0 * jerk)) / acc, 0.0)
    if a >= a1:
        return (a - a1) / jerk, -jerk, t2, a1, -a1 / jerk
    return (a1 - a) / jerk, jerk, t2, a1, -a1 / jerk


@njit(cache=True)
def brake(v: float, a: float, w: float, acc: float, jerk: float) -> tuple[float, float]:
    """(distance, time) of the time-optimal jerk-limited slow-down from (v, a) to speed ``w`` with a = 0.

    Returns (0, 0) when the speed never exceeds ``w`` anyway. When even ramping the acceleration straight
    back to zero undershoots ``w``, returns the distance to the instant the speed first reaches ``w``.
    """
    if _peak(v, a, jerk) <= w:
        return 0.0, 0.0
    if a < 0.0 and _valley(v, a, jerk) <= w:
        # The immediate +J ramp crosses w: v + a t + J t^2 / 2 = w, first root.
        disc = a * a - 2.0 * jerk * (v - w)
        disc = max(disc, 0.0)
        t = (-a - math.sqrt(disc)) / jerk
        t = max(t, 0.0)
        return v * t + 0.5 * a * t * t + jerk * t * t * t / 6.0, t
    t1, j1, t2, a1, t3 = _phases(v, a, w, acc, jerk)
    d1, v1, _ = _step(v, a, j1, t1)
    d2 = v1 * t2 + 0.5 * a1 * t2 * t2
    v2 = v1 + a1 * t2
    d3 = v2 * t3 + 0.5 * a1 * t3 * t3 + jerk * t3 * t3 * t3 / 6.0
    return d1 + d2 + d3, t1 + t2 + t3


@njit(cache=True)
def brake_step(v: float, a: float, w: float, acc: float, jerk: float,
               dt: float) -> tuple[float, float, float]:  # fmt: skip
    """(ds, v', a') after following the ``brake(v, a, w)`` manoeuvre exactly for ``dt``.

    Its jerk may switch inside the period; after its end the speed holds. Used where no constant jerk can
    stay in the safe set."""
    if _peak(v, a, jerk) <= w:
        # Nothing to brake for: ramp the acceleration to zero at the full jerk, then hold the speed.
        h = min(abs(a) / jerk, dt)
        ds, v, a = _step(v, a, -jerk if a > 0.0 else jerk, h)
        return ds + v * (dt - h), v, 0.0 if h < dt else a
    t1, j1, t2, _, t3 = _phases(v, a, w, acc, jerk)
    left = dt
    ds = 0.0
    for phase in range(4):
        if phase == 0:
            h, jj = min(t1, left), j1
        elif phase == 1:
            h, jj = min(t2, left), 0.0
        elif phase == 2:
            h, jj = min(t3, left), jerk
        else:
            h, jj = left, 0.0
            a = 0.0  # the manoeuvre has ended: hold the speed
        if h > 0.0:
            d, v, a = _step(v, a, jj, h)
            ds += d
            left -= h
        if left <= 0.0:
            break
    return ds, v, a


@njit(cache=True)
def reach(v: float, a: float, w: float, level: float, acc: float, jerk: float) -> float:
    """Distance along the manoeuvre ``brake(v, a, w)`` after which the speed stays at or below ``level``
    (0 if it never exceeds it, INF if the manoeuvre ends above it).

    With ``w = 0`` this is the time-optimal stop, the lowest speed profile of every admissible motion from
    (v, a) (|j| ≤ J, |a| ≤ A, no reverse motion): any motion that slows down later or less hard is faster at
    every instant, hence also at every arc length. So ``reach(v, a, 0, w_p) ≤ d_p`` for every limit point p
    ahead is necessary and sufficient for a motion that keeps them all to exist (see :func:`_viable`)."""
    if _peak(v, a, jerk) <= level:
        return 0.0
    t1, j1, t2, _, t3 = _phases(v, a, w, acc, jerk)
    dist = 0.0
    for phase in range(3):
        if phase == 0:
            h, jj = t1, j1
        elif phase == 1:
            h, jj = t2, 0.0
        else:
            h, jj = t3, jerk
        if h <= 0.0:
            continue
        d, v_end, a_end = _step(v, a, jj, h)
        if v_end <= level:
            # The last crossing of the level inside this phase (the speed only falls from there on): the
            # later root of v + a t + jj t^2/2 = level (jj = -J, after a peak) or the earlier (jj = +J).
            if jj == 0.0:
                tau = (v - level) / -a if a < 0.0 else 0.0
            else:
                tau = (-a - math.sqrt(max(a * a - 2.0 * jj * (v - level), 0.0))) / jj
            tau = min(max(tau, 0.0), h)
            return dist + v * tau + 0.5 * a * tau * tau + jj * tau * tau * tau / 6.0
        dist += d
        v, a = v_end, a_end
    # The manoeuvre ends at w (to rounding): it reaches a level at or above w there.
    return dist if w <= level else INF


@njit(cache=True, inline="always")
def _safe_now(s: float, v: float, a: float, acc_b: float, jerk_b: float, cap_now: float, pts: np.ndarray,
              n_pts: int, col: int) -> bool:  # fmt: skip
    """Is the current state itself safe (continuous-time test, no period applied)?"""
    if _peak(v, a, jerk_b) > cap_now * (1.0 + 1e-12) + 1e-12:
        return False
    for i in range(n_pts):
        dist, _ = brake(v, a, pts[i, col], acc_b, jerk_b)
        if dist > (pts[i, 0] - s) * (1.0 + 1e-12) + 1e-12:
            return False
    return True


@njit(cache=True)
def _delayed_end(s: float, v: float, a: float, dt: float, j_pre: float, tau: float, w: float, acc_b: float,
                 jerk_b: float, cap_now: float, pts: np.ndarray, n_pts: int,
                 col: int) -> tuple[bool, float, float, float]:  # fmt: skip
    """Jerk ``j_pre`` for ``tau``, then the braking manoeuvre to ``w`` for the rest of the period:
    (still safe?, ds, v', a')."""
    ds1, v1, a1 = _step(v, a, j_pre, tau)
    ok = _bottom(v, a, j_pre, tau, jerk_b) >= 0.0 if tau > 0.0 else True
    ds2, v2, a2 = brake_step(v1, a1, w, acc_b, jerk_b, dt - tau)
    ds = ds1 + ds2
    top = max(v, v1, v2, _peak(v1, a1, jerk_b), _tick_top(v, a, j_pre, tau, v1))
    if ok:
        ok = _peak(v2, a2, jerk_b) <= cap_now * (1.0 + 1e-12) + 1e-12 and top <= max(cap_now, v) + 1e-12
    for m in range(n_pts):
        if not ok:
            break
        d = pts[m, 0] - s - ds
        if d <= 0.0:
            ok = top <= pts[m, col] * (1.0 + 1e-12) + 1e-12
        else:
            dist, _ = brake(v2, a2, pts[m, col], acc_b, jerk_b)
            ok = dist <= d * (1.0 + 1e-12) + 1e-12
    return ok, ds, v2, a2


@njit(cache=True)
def _delayed_manoeuvre(s: float, v: float, a: float, dt: float, j_pre: float, w: float, acc_b: float,
                       jerk_b: float, cap_now: float, pts: np.ndarray, n_pts: int,
                       col: int) -> tuple[float, float, float]:  # fmt: skip
    """One period that keeps going (jerk ``j_pre``) as long as it can and then brakes exactly (towards
    ``w``), so that it ends on the boundary of the safe set rather than braking early — otherwise a stop
    would be reached short of its point. The undelayed manoeuvre is the fallback."""
    ok, ds, v1, a1 = _delayed_end(s, v, a, dt, j_pre, dt, w, acc_b, jerk_b, cap_now, pts, n_pts, col)
    if ok:
        return ds, v1, a1
    lo, hi = 0.0, dt
    for _ in range(BISECT_ITERS):
        mid = 0.5 * (lo + hi)
        ok, _, _, _ = _delayed_end(s, v, a, dt, j_pre, mid, w, acc_b, jerk_b, cap_now, pts, n_pts, col)
        if ok:
            lo = mid
        else:
            hi = mid
    _, ds, v1, a1 = _delayed_end(s, v, a, dt, j_pre, lo, w, acc_b, jerk_b, cap_now, pts, n_pts, col)
    return ds, v1, a1


@njit(cache=True)
def _pick_manoeuvre(s: float, v: float, a: float, dt: float, acc_b: float, jerk_b: float, cap_now: float,
                    pts: np.ndarray, n_pts: int, col: int) -> tuple[float, bool]:  # fmt: skip
    """Target speed of the braking manoeuvre to follow for one period from a safe state, and whether the
    state one period along it is certified safe.

    Higher targets are tried first (least braking) and taken if the state one period along them is still
    safe and no point crossed inside the period is passed too fast. The lowest limit ahead is tried as well;
    where no target passes (the certificate is not monotone in the target, nor in the braking jerk, so a
    state may lose it when the window slides or the jerk grows), the caller falls back to :func:`_rescue`."""
    w_low = _lowest(pts, n_pts, col, cap_now)
    best = -1.0
    for i in range(-2, n_pts):
        w = w_low if i == -2 else (cap_now if i < 0 else pts[i, col])
        if w <= best:
            continue
        ds, v1, a1 = brake_step(v, a, w, acc_b, jerk_b, dt)
        top = max(v, v1, _peak(v, a, jerk_b))
        ok = _peak(v1, a1, jerk_b) <= cap_now * (1.0 + 1e-12) + 1e-12
        for m in range(n_pts):
            if not ok:
                break
            d = pts[m, 0] - s - ds
            if d <= 0.0:
                ok = top <= pts[m, col]
            else:
                dist, _ = brake(v1, a1, pts[m, col], acc_b, jerk_b)
                ok = dist <= d * (1.0 + 1e-12) + 1e-12
        if ok:
            best = w
    if best < 0.0:
        return w_low, False
    return best, True


@njit(cache=True)
def _viable_after(s: float, v: float, a: float, dt: float, w: float, acc_b: float, jerk_b: float,
                  cap_now: float, pts: np.ndarray, n_pts: int,
                  col: int) -> tuple[bool, float, float, float]:  # fmt: skip
    """One period along the manoeuvre ``brake(v, a, w)``: (does every limit stay reachable?, ds, v', a').

    Points crossed inside the period must be crossed no faster than their limit (along this manoeuvre);
    for the others the end state must be *viable*: the time-optimal stop from it (the lowest speed profile
    of all, :func:`reach`) gets below each limit before its point, and stops within the window."""
    ds, v1, a1 = brake_step(v, a, w, acc_b, jerk_b, dt)
    cap_tol = cap_now * (1.0 + 1e-12) + 1e-12
    if _peak(v, a, jerk_b) > cap_tol or _peak(v1, a1, jerk_b) > cap_tol:
        return False, ds, v1, a1
    for m in range(n_pts):
        d = pts[m, 0] - s
        if d <= ds:
            dist = reach(v, a, w, pts[m, col], acc_b, jerk_b)
        else:
            d -= ds
            dist = reach(v1, a1, 0.0, pts[m, col], acc_b, jerk_b)
        if dist > d * (1.0 + 1e-12) + 1e-12:
            return False, ds, v1, a1
    return True, ds, v1, a1


@njit(cache=True)
def _rescue(s: float, v: float, a: float, dt: float, acc_b: float, jerk_b: float, cap_now: float,
            pts: np.ndarray, n_pts: int, col: int) -> tuple[bool, float, float, float]:  # fmt: skip
    """One period for a state that the braking certificate does not cover but from which every limit is
    still reachable (is *viable*): along the least-braking manoeuvre ``brake(v, a, w)``, w in [0, lowest
    limit], after which the state is still viable — bisection, as the manoeuvres to lower targets are
    slower at every instant. Returns (viable?, ds, v', a'); where even the time-optimal stop (w = 0) does
    not keep every limit the state was not viable, and that stop is returned (the hardest braking there is).

    Viability is exact (necessary and sufficient) and, unlike the certificate, can only improve when the
    window slides (a limit rises from the window-end stop to the point's own limit) or the braking A and J
    grow, so a viable state stays viable: with the hard limits, the caps are never exceeded."""
    ok, ds, v1, a1 = _viable_after(s, v, a, dt, 0.0, acc_b, jerk_b, cap_now, pts, n_pts, col)
    if not ok:
        return False, ds, v1, a1
    w_low = _lowest(pts, n_pts, col, cap_now)
    ok, ds_hi, v_hi, a_hi = _viable_after(s, v, a, dt, w_low, acc_b, jerk_b, cap_now, pts, n_pts, col)
    if ok:
        return True, ds_hi, v_hi, a_hi
    lo, hi = 0.0, w_low
    for _ in range(BISECT_ITERS):
        mid = 0.5 * (lo + hi)
        ok, ds_mid, v_mid, a_mid = _viable_after(s, v, a, dt, mid, acc_b, jerk_b, cap_now, pts, n_pts, col)
        if ok:
            lo = mid
            ds, v1, a1 = ds_mid, v_mid, a_mid
        else:
            hi = mid
    return True, ds, v1, a1


@njit(cache=True, inline="always")
def _lowest(pts: np.ndarray, n_pts: int, col: int, cap_now: float) -> float:
    w = cap_now
    for i in range(n_pts):
        w = min(w, pts[i, col])
    return w


@njit(cache=True)
def reach_speed(v0: float, dist: float, acc: float, jerk: float) -> float:
    """Highest speed reachable from ``v0`` (a = 0) over ``dist`` ending with a = 0 (jerk-limited).

    Solves ``(v - v0)(v + v0)^2 = J L^2`` while ``v - v0 <= A^2/J`` and the trapezoidal-acceleration
    quadratic beyond. The same number is the highest speed from which one can slow to ``v0`` in ``dist``.
    """
    if dist <= 0.0:
        return v0
    dv_tri = acc * acc / jerk
    # Triangular acceleration profile: (v - v0)(v + v0)^2 = J L^2, monotone in v >= v0: Newton from above.
    target = jerk * dist * dist
    x = v0 + max(dv_tri, (target) ** (1.0 / 3.0)) + 1.0
    for _ in range(60):
        f = (x - v0) * (x + v0) ** 2 - target
        df = (x + v0) ** 2 + 2.0 * (x - v0) * (x + v0)
        step = f / df
        x -= step
        if abs(step) < 1e-12 * (1.0 + x):
            break
    if x - v0 <= dv_tri:
        return x
    # Trapezoidal: (v^2 - v0^2)/A + (v + v0) A / J = 2 L.
    qa = 1.0 / acc
    qb = acc / jerk
    qc = -v0 * v0 / acc + v0 * acc / jerk - 2.0 * dist
    return (-qb + math.sqrt(qb * qb - 4.0 * qa * qc)) / (2.0 * qa)


@njit(cache=True, inline="always")
def _target(seg_f: np.ndarray, seg_i: np.ndarray, k: int, mode: int, ov: float, rapid_ov: float,
            cmd: float) -> float:  # fmt: skip
    """The speed the operator asks for on motion segment k (soft), never above its hard cap."""
    cap = seg_f[k, F_CAP]
    if seg_i[k, I_RAPID] == 1:
        want = seg_f[k, F_BASE] * rapid_ov
    elif seg_i[k, I_LOCKED] == 1:
        want = seg_f[k, F_BASE]
    elif mode == 1:
        want = cmd
    else:
        want = seg_f[k, F_BASE] * ov
    return min(want, cap)


@njit(cache=True)
def _accel_bound(seg_f: np.ndarray, pt_f: np.ndarray, k: int, s: float) -> float:
    """Acceleration bound at arc length s inside motion segment k (falls linearly towards the next
    segment's arrival bound so that the acceleration can follow it with the jerk limit)."""
    s_end = seg_f[k, F_S0] + seg_f[k, F_LEN]
    rest = max(s_end - s, 0.0)
    jerk = min(seg_f[k, F_JERK], pt_f[k + 1, P_SPAN_J])  # the jerk the planner uses on k
    return min(seg_f[k, F_ACC], pt_f[k + 1, P_AIN] + jerk * rest / seg_f[k, F_CAP])


@njit(cache=True)
def _step(v: float, a: float, j: float, dt: float) -> tuple[float, float, float]:
    """Exact integration of a constant jerk over one period: (ds, v', a')."""
    ds = v * dt + 0.5 * a * dt * dt + j * dt * dt * dt / 6.0
    return ds, v + a * dt + 0.5 * j * dt * dt, a + j * dt


@njit(cache=True, inline="always")
def _track_jerk(v: float, a: float, target: float, jerk: float, dt: float) -> float:
    """Jerk that settles the speed on ``target`` without chattering.

    Far from the target it asks for the full jerk (the safety and overshoot bounds then decide); near it,
    the acceleration is steered to e/τ (e = target − v, τ = 3 periods), a critically damped approach that
    a greedy bound alone would turn into a ±J limit cycle."""
    e = target - v
    a_des = math.sqrt(2.0 * jerk * abs(e))
    a_des = min(a_des, abs(e) / (TRACK_PERIODS * dt))
    if e < 0.0:
        a_des = -a_des
    return min(max((a_des - a) / dt, -jerk), jerk)


@njit(cache=True)
def _tick_top(v: float, a: float, j: float, dt: float, v1: float) -> float:
    """Highest speed within one period of constant jerk j from (v, a) ending at speed v1."""
    if a > 0.0 and j < 0.0 and a + j * dt < 0.0:
        return v - a * a / (2.0 * j)
    return max(v, v1)


@njit(cache=True)
def _upper_ok(j: float, s: float, v: float, a: float, dt: float, acc_b: float, jerk_b: float,
              cap_now: float, pts: np.ndarray, n_pts: int, col: int) -> bool:  # fmt: skip
    """Is the end state of jerk j safe w.r.t. the current cap and the points in pts[:n_pts]?

    pts columns: 0 arc length, 1 hard limit, 2 soft limit; ``col`` picks hard (1) or soft (2)."""
    ds, v1, a1 = _step(v, a, j, dt)
    # Highest speed during this period and after it (if the acceleration is ramped down next).
    v_top = max(_peak(v1, a1, jerk_b), _tick_top(v, a, j, dt, v1))
    if v_top > cap_now:
        return False
    for i in range(n_pts):
        w = pts[i, col]
        d = pts[i, 0] - s - ds
        if d <= 0.0:
            if v_top > w:
                return False
        else:
            dist, _ = brake(v1, a1, w, acc_b, jerk_b)
            if dist > d:
                return False
    return True


@njit(cache=True)
def _largest_upper(lo: float, hi: float, s: float, v: float, a: float, dt: float, acc_b: float,
                   jerk_b: float, cap_now: float, pts: np.ndarray, n_pts: int,
                   col: int) -> float:  # fmt: skip
    """Largest j in [lo, hi] passing _upper_ok (caller checked lo passes and hi fails)."""
    for _ in range(BISECT_ITERS):
        mid = 0.5 * (lo + hi)
        if _upper_ok(mid, s, v, a, dt, acc_b, jerk_b, cap_now, pts, n_pts, col):
            lo = mid
        else:
            hi = mid
    return lo


@njit(cache=True)
def _smallest_valley(lo: float, hi: float, v: float, a: float, dt: float, jerk_b: float,
                     floor: float) -> float:  # fmt: skip
    """Smallest j in [lo, hi] whose speed stays at or above ``floor`` during the period and after it
    when the acceleration is then ramped back to zero (monotone increasing in j)."""
    if _bottom(v, a, lo, dt, jerk_b) >= floor:
        return lo
    if _bottom(v, a, hi, dt, jerk_b) < floor:
        return hi
    for _ in range(BISECT_ITERS):
        mid = 0.5 * (lo + hi)
        if _bottom(v, a, mid, dt, jerk_b) >= floor:
            hi = mid
        else:
            lo = mid
    return hi


@njit(cache=True)
def _bottom(v: float, a: float, j: float, dt: float, jerk_b: float) -> float:
    """Lowest speed within a period of constant jerk j and after it (valley of the end state)."""
    _, v1, a1 = _step(v, a, j, dt)
    low = min(v1, _valley(v1, a1, jerk_b))
    if a < 0.0 and j > 0.0 and a + j * dt > 0.0:
        low = min(low, v - a * a / (2.0 * j))
    return low


@njit(cache=True)
def _position(seg_f: np.ndarray, seg_i: np.ndarray, curve_f: np.ndarray, k: int, s: float, out: np.ndarray,
              row: int) -> None:  # fmt: skip
    """Point at arc length s on motion segment k, written to out[row, O_X:O_Z+1]."""
    length = seg_f[k, F_LEN]
    local = min(max(s - seg_f[k, F_S0], 0.0), length)
    frac = local / length if length > 0.0 else 0.0
    if seg_i[k, I_KIND] == KIND_ARC:
        iu, iv, iw = seg_i[k, I_PU], seg_i[k, I_PV], seg_i[k, I_PW]
        theta = seg_f[k, F_ANG0] + seg_f[k, F_SWEEP] * frac
        r = seg_f[k, F_RADIUS]
        out[row, O_X + iu] = seg_f[k, F_CX + iu] + r * math.cos(theta)
        out[row, O_X + iv] = seg_f[k, F_CX + iv] + r * math.sin(theta)
        out[row, O_X + iw] = seg_f[k, F_SX + iw] + seg_f[k, F_RISE] * frac
    elif seg_i[k, I_TABLE] >= 0:
        # NURBS piece: cubic Hermite through the sampled points and unit tangents (by arc length); the table
        # is dense enough that this is within 1e-10 mm of the exact curve (checked when it is built).
        n_int = seg_i[k, I_NSAMP] - 1
        h = length / n_int
        i = min(int(local / h), n_int - 1) if h > 0.0 else 0
        u = (local - i * h) / h if h > 0.0 else 0.0
        r0 = seg_i[k, I_TABLE] + i
        u2 = u * u
        u3 = u2 * u
        h00 = 2.0 * u3 - 3.0 * u2 + 1.0
        h10 = (u3 - 2.0 * u2 + u) * h
        h01 = -2.0 * u3 + 3.0 * u2
        h11 = (u3 - u2) * h
        for ax in range(3):
            out[row, O_X + ax] = (h00 * curve_f[r0, ax] + h10 * curve_f[r0, 3 + ax]
                                  + h01 * curve_f[r0 + 1, ax] + h11 * curve_f[r0 + 1, 3 + ax])  # fmt: skip
    else:
        for ax in range(3):
            p0 = seg_f[k, F_SX + ax]
            out[row, O_X + ax] = p0 + (seg_f[k, F_EX + ax] - p0) * frac


# ---------------------------------------------------------------- the entry's records
class PathTables(NamedTuple):
    """What holds still over a program (Ruckig's input parameters that do not change between calls): the
    tool path's limits on one machine, packed by :func:`cnc_gym.motion.limits.build_limits` (columns
    above), and the machine's ``cfg`` (:func:`cnc_gym.motion.controller.kernel_config`: [dt, window
    blocks, override slew per s, rest x, y, z, revision])."""

    seg_f: np.ndarray  # (n_seg, N_SEG_F) per motion segment
    seg_i: np.ndarray  # (n_seg, N_SEG_I)
    pt_f: np.ndarray  # (n_seg + 1, N_PT_F) per limit point
    pt_i: np.ndarray  # (n_seg + 1, N_PT_I)
    dwell_f: np.ndarray  # (n_dwell, 5): seconds, toolpath row, x, y, z
    curve_f: np.ndarray  # NURBS pieces' samples: point and unit tangent per row
    cfg: np.ndarray  # (N_CFG,)


class ControllerState(NamedTuple):
    """The controller's state, advanced in place: ``f`` (N_STATE_F: the S_* columns) and ``i``
    (N_STATE_I: the K_* columns). Views of a batch's state rows serve as well as the controller's own."""

    f: np.ndarray
    i: np.ndarray


#: Command.mode: the override scales the programmed feed, or the path feed is commanded instead of F.
MODE_OVERRIDE, MODE_FEED = 0, 1


class Command(NamedTuple):
    """What one :func:`advance_into` call is asked to do (Ruckig's input parameters beside the state).

    ``mode`` :data:`MODE_OVERRIDE` (programmed feed × ``override``, 0..max override) or :data:`MODE_FEED`
    (the path feed ``feed_mm_s`` instead of F, still clamped by every limit); ``rapid_override`` (0..1)
    scales rapids. ``wait``: the reference holds at every in-position stop (PHASE_WAIT) until
    :func:`release_wait`; ``stop_when_done``: the run ends on the period that finishes the program."""

    mode: int
    override: float
    rapid_override: float
    feed_mm_s: float
    wait: bool
    stop_when_done: bool


class Clock(NamedTuple):
    """The per-call constants of a period (from ``cfg`` and the path): the period, the look-ahead window in
    motion segments, the override's slew per period, the number of motion segments, the controller's
    revision (:data:`CONTROLLER_REVISION`)."""

    dt: float
    window: int
    slew_step: float
    n_seg: int
    revision: int


@njit(cache=True)
def advance_kernel(path: PathTables, state: ControllerState, command: Command, n_ticks: int,
                   pts: np.ndarray) -> np.ndarray:  # fmt: skip
    """Run ``n_ticks`` interpolation periods of ``command`` from ``state``; returns one row per period
    (fewer with ``command.stop_when_done``). ``pts`` is scratch space (window + 2 rows, 3 columns)."""
    out = np.zeros((n_ticks, N_OUT))
    done = advance_into(path, state, command, out, pts)
    return out[:done]


@njit(cache=True)
def advance_rows(path: tuple, state: tuple, command: tuple, n_ticks: int, pts: np.ndarray) -> np.ndarray:
    """:func:`advance_kernel` for a caller in Python, the records given as plain tuples in their fields'
    order: numba types a plain tuple argument in its fast path, a named one costs microseconds a call."""
    return advance_kernel(PathTables(*path), ControllerState(*state), Command(*command), n_ticks, pts)


@njit(cache=True)
def advance_into(path: PathTables, state: ControllerState, command: Command, out: np.ndarray,
                 pts: np.ndarray) -> int:  # fmt: skip
    """The controller's entry, in the manner of Ruckig's input and output parameters: run ``len(out)``
    interpolation periods of ``command`` (:class:`Command`) on ``path`` (:class:`PathTables`), advancing
    ``state`` (:class:`ControllerState`) in place; ``out`` gets one row per period, every ``O_*`` column
    written. ``pts`` is scratch space (window + 2 rows, 3 columns). Returns the number of rows run:
    ``len(out)``, or fewer with ``command.stop_when_done``."""
    cfg = path.cfg
    dt = cfg[0]
    clock = Clock(dt, int(cfg[1]), cfg[2] * dt, path.seg_f.shape[0], int(cfg[N_CFG - 1]))
    st_i = state.i
    for tick in range(out.shape[0]):
        for col in range(N_OUT):
            out[tick, col] = 0.0
        _tick(path, state, command, clock, pts, out, tick)
        if st_i[K_PHASE] == PHASE_DONE:
            out[tick, O_DONE] = 1.0
            if command.stop_when_done:
                return tick + 1
    return out.shape[0]


@njit(cache=True)
def reset_state(pt_i: np.ndarray, pt_f: np.ndarray, dwell_f: np.ndarray, n_seg: int, st_f: np.ndarray,
                st_i: np.ndarray) -> None:  # fmt: skip
    """The state at the program start: t = 0, at rest, override unset (the first period takes the command as
    it is), on the first segment or its leading dwells, or done where there is no motion at all."""
    st_f[:] = 0.0
    st_f[S_OV] = -1.0
    st_i[:] = 0
    st_i[K_DWELL] = -1
    if pt_i[0, Q_DW1] > pt_i[0, Q_DW0]:  # dwells before the first move
        st_i[K_PHASE] = PHASE_DWELL
        st_i[K_DWELL] = pt_i[0, Q_DW0]
        st_f[S_DWELL_LEFT] = dwell_f[pt_i[0, Q_DW0], 0]
    elif n_seg == 0:
        st_i[K_PHASE] = PHASE_DONE
    if n_seg:
        st_f[S_S] = pt_f[0, P_S]


@njit(cache=True, inline="always")
def segment_index(seg_i: np.ndarray, dwell_f: np.ndarray, st_i: np.ndarray) -> int:
    """Toolpath row the reference is on (a dwell's row while dwelling; -1 with no motion at all)."""
    if st_i[K_DWELL] >= 0 and st_i[K_PHASE] != PHASE_MOVE:
        return int(dwell_f[st_i[K_DWELL], 1])
    if seg_i.shape[0] == 0:
        return -1
    return seg_i[st_i[K_SEG], I_TP]


@njit(cache=True)
def _tick(path: PathTables, state: ControllerState, command: Command, clock: Clock, pts: np.ndarray,
          out: np.ndarray, tick: int) -> None:  # fmt: skip
    """One interpolation period (see the module docstring), written to row ``tick`` of ``out``."""
    seg_f, seg_i, pt_f, pt_i, dwell_f, curve_f, cfg = path
    st_f, st_i = state
    mode, commanded, rapid_ov, cmd = command.mode, command.override, command.rapid_override, command.feed_mm_s
    wait = command.wait
    dt, window, slew_step, n_seg, revision = clock
    phase = st_i[K_PHASE]
    k = st_i[K_SEG]
    # The applied override follows the commanded one at a bounded rate.
    ov = st_f[S_OV]
    if ov < 0.0:  # first period after reset: the override is wherever the operator left it
        ov = commanded
    ov = min(commanded, ov + slew_step) if commanded > ov else max(commanded, ov - slew_step)
    st_f[S_OV] = ov
    st_f[S_T] += dt
    out[tick, O_T] = st_f[S_T]
    if phase == PHASE_DWELL:
        row = st_i[K_DWELL]
        st_f[S_DWELL_LEFT] -= dt
        out[tick, O_X] = dwell_f[row, 2]
        out[tick, O_Y] = dwell_f[row, 3]
        out[tick, O_Z] = dwell_f[row, 4]
        out[tick, O_S] = st_f[S_S]
        out[tick, O_SEG] = dwell_f[row, 1]
        if st_f[S_DWELL_LEFT] <= 1e-12:
            _after_dwell(pt_i, dwell_f, st_f, st_i, n_seg)
        return
    if phase == PHASE_WAIT:  # at rest on the stop at the end of segment k, waiting to be in position
        _position(seg_f, seg_i, curve_f, k, st_f[S_S], out, tick)
        out[tick, O_S] = st_f[S_S]
        out[tick, O_SEG] = seg_i[k, I_TP]
        out[tick, O_CUT] = 1.0 if seg_i[k, I_RAPID] == 0 else 0.0
        return
    if phase == PHASE_DONE:
        out[tick, O_S] = st_f[S_S]
        if n_seg > 0:
            _position(seg_f, seg_i, curve_f, n_seg - 1, st_f[S_S], out, tick)
            out[tick, O_SEG] = seg_i[n_seg - 1, I_TP]
            out[tick, O_CUT] = 1.0 if seg_i[n_seg - 1, I_RAPID] == 0 else 0.0
        else:
            out[tick, O_X] = cfg[3]
            out[tick, O_Y] = cfg[4]
            out[tick, O_Z] = cfg[5]
            out[tick, O_SEG] = -1.0
        if st_i[K_DWELL] >= 0:
            out[tick, O_SEG] = dwell_f[st_i[K_DWELL], 1]
            out[tick, O_CUT] = 0.0
        return

    s = st_f[S_S]
    v = st_f[S_V]
    a = st_f[S_A]
    # ---- look-ahead window: points k+1 .. q_end; q_end counts as a stop.
    q_end = min(k + max(window, 1), pt_i[k + 1, Q_NEXT_STOP], n_seg)
    # Braking (certificate) limits: the lowest from here to the next mandatory stop. They can only grow
    # as the reference advances, so a state found safe stays provably safe when the window slides.
    acc_b = min(_accel_bound(seg_f, pt_f, k, s), pt_f[k + 1, P_SPAN_A])
    jerk_b = min(seg_f[k, F_JERK], pt_f[k + 1, P_SPAN_J])
    # Acceleration bound over this tick's reach (conservative: the tick may cross junctions).
    ds_far, _, _ = _step(v, a, jerk_b, dt)
    s_far = s + max(ds_far, 0.0)
    acc_tick = _accel_bound(seg_f, pt_f, k, s)
    kk = k
    while kk < n_seg - 1 and s_far > seg_f[kk, F_S0] + seg_f[kk, F_LEN]:
        acc_tick = min(acc_tick, pt_f[kk + 1, P_AIN])
        kk += 1
    acc_tick = min(acc_tick, _accel_bound(seg_f, pt_f, kk, min(s_far, seg_f[kk, F_S0] + seg_f[kk, F_LEN])))
    j_lo = max(-jerk_b, (-acc_tick - a) / dt)
    j_hi = min(jerk_b, (acc_tick - a) / dt)
    if j_lo > j_hi:  # |a| above the bound (limits changed): push it back at the full jerk
        if a > 0.0:
            j_lo = -jerk_b
            j_hi = -jerk_b
        else:
            j_lo = jerk_b
            j_hi = jerk_b

    # ---- snap onto a mandatory stop reached within this tick.
    q_stop = pt_i[k + 1, Q_NEXT_STOP]
    d_stop = pt_f[q_stop, P_S] - s
    if q_stop <= q_end:
        d_brk, t_brk = brake(v, a, 0.0, acc_b, jerk_b)
        if (t_brk <= dt * (1.0 + 1e-9) and d_stop <= d_brk + SNAP_MM) or (
                d_stop <= SNAP_MM and v <= 1e-6 and abs(a) <= 1e-3):  # fmt: skip
            _snap_to_stop(seg_f, seg_i, curve_f, pt_f, pt_i, dwell_f, st_f, st_i, out, tick, q_stop, n_seg,
                          dt, a, wait)
            return

    # ---- relevant points: those that the most aggressive jerk would violate.
    ds_hi, v_hi, a_hi = _step(v, a, j_hi, dt)
    top_hi = max(_peak(v_hi, a_hi, jerk_b), _tick_top(v, a, j_hi, dt, v_hi))
    # Beyond this distance no point can bind: any slow-down lasts at most as long as a full stop and runs
    # no faster than the peak speed. (The distance itself is not monotone in the target speed.)
    _, t_stop = brake(v_hi, a_hi, 0.0, acc_b, jerk_b)
    reach_far = top_hi * t_stop
    # Typed integers, not literals: numba compiles a called function once per literal argument, and a
    # counter that starts at a literal is first typed as that literal (compiled twice over, once wasted).
    n_pts = np.int64(0)
    hard, soft = np.int64(1), np.int64(2)  # the points' columns: the hard (geometric) and soft speed limits
    for q in range(k + 1, q_end + 1):
        d_q = pt_f[q, P_S] - s
        if d_q - ds_hi > reach_far:
            break
        if q == q_end:
            w_hard = 0.0
            w_soft = 0.0
        else:
            w_hard = pt_f[q, P_HARD]
            w_soft = min(w_hard, _target(seg_f, seg_i, q, mode, ov, rapid_ov, cmd))
        d = d_q - ds_hi
        if w_soft >= top_hi:
            bad = False
        elif d <= 0.0:
            bad = True
        else:
            # The braking distance is not monotone in the target speed: test the soft and the hard one.
            dist, _ = brake(v_hi, a_hi, w_soft, acc_b, jerk_b)
            bad = dist > d
            if not bad and w_hard < top_hi:
                dist, _ = brake(v_hi, a_hi, w_hard, acc_b, jerk_b)
                bad = dist > d
        if bad:
            pts[n_pts, 0] = pt_f[q, P_S]
            pts[n_pts, 1] = w_hard
            pts[n_pts, 2] = w_soft
            n_pts += 1

    # Never plan a state that must reverse: restrict the jerk range to valley(v', a') >= 0.
    j_lo = _smallest_valley(j_lo, j_hi, v, a, dt, jerk_b, 0.0)
    cap_hard = seg_f[k, F_CAP]
    cap_soft = _target(seg_f, seg_i, k, mode, ov, rapid_ov, cmd)
    manoeuvre = False
    rescued = False  # ds, v1, a1 of this period already computed by _rescue
    ds, v1, a1 = 0.0, v, a
    w_follow = 0.0
    m_cap = cap_hard
    m_col = hard
    # Where the override is still slewing down, the speed must not dip below where it will settle.
    cap_final = _target(seg_f, seg_i, k, mode, commanded, rapid_ov, cmd)
    j_track = max(_track_jerk(v, a, cap_soft, jerk_b, dt), j_lo)
    if v >= cap_final:
        j_track = max(j_track, _smallest_valley(j_lo, j_hi, v, a, dt, jerk_b, cap_final))
    if j_track < j_hi and _upper_ok(j_track, s, v, a, dt, acc_b, jerk_b, cap_soft, pts, n_pts, soft):
        j = j_track  # the largest safe jerk is at least this: no search needed (cruise, settling)
    elif _upper_ok(j_hi, s, v, a, dt, acc_b, jerk_b, cap_soft, pts, n_pts, soft):
        j = min(j_hi, j_track)
    elif _upper_ok(j_lo, s, v, a, dt, acc_b, jerk_b, cap_soft, pts, n_pts, soft):
        j = _largest_upper(j_lo, j_hi, s, v, a, dt, acc_b, jerk_b, cap_soft, pts, n_pts, soft)
        j = min(j, j_track)
    elif _safe_now(s, v, a, acc_b, jerk_b, cap_soft, pts, n_pts, soft):
        # Safe, but no constant jerk keeps it so (the braking switches inside this period): follow a
        # braking manoeuvre exactly for one period (see _pick_manoeuvre).
        manoeuvre = True
        w_follow, certified = _pick_manoeuvre(s, v, a, dt, acc_b, jerk_b, cap_soft, pts, n_pts, soft)
        j = min(j_track, j_hi)  # what the period would do before braking
        m_cap = cap_soft
        m_col = soft
        if not certified:
            rescued, ds, v1, a1 = _rescue(s, v, a, dt, acc_b, jerk_b, cap_soft, pts, n_pts, soft)
            if not rescued:
                _, ds, v1, a1 = _rescue(s, v, a, dt, acc_b, jerk_b, cap_hard, pts, n_pts, hard)
            rescued = True
    else:
        # The certificate is lost. Where every soft limit is still reachable (it was lost to the window
        # sliding or to the braking jerk growing, not to the override), keep them all (see _rescue).
        rescued, ds, v1, a1 = _rescue(s, v, a, dt, acc_b, jerk_b, cap_soft, pts, n_pts, soft)
        if not rescued:
            # The operator's target cannot be met any more (override turned down): slow down as fast as
            # the jerk allows without undershooting the lowest violated target ...
            floor = INF
            ds_lo, v_lo, a_lo = _step(v, a, j_lo, dt)
            top_lo = max(_peak(v_lo, a_lo, jerk_b), _tick_top(v, a, j_lo, dt, v_lo))
            if top_lo > cap_soft:
                floor = min(cap_soft, cap_final)
            for i in range(n_pts):
                d = pts[i, 0] - s - ds_lo
                if d <= 0.0:
                    if top_lo > pts[i, 2]:
                        floor = min(floor, pts[i, 2])
                else:
                    dist, _ = brake(v_lo, a_lo, pts[i, 2], acc_b, jerk_b)
                    if dist > d:
                        floor = min(floor, pts[i, 2])
            if floor >= INF:
                floor = min(cap_soft, cap_final)
            # (Still below the floor, no jerk keeps the speed at or above it: revision 1 then took the
            # largest jerk and overshot; revision 2 keeps the speed from falling below where it is.)
            valley_floor = floor if revision < 2 else min(floor, v)
            j = _smallest_valley(j_lo, j_hi, v, a, dt, jerk_b, valley_floor)
            j = max(j, min(_track_jerk(v, a, floor, jerk_b, dt), j_hi))
            # ... but never faster than the hard (geometric) limits allow.
            if not _upper_ok(j, s, v, a, dt, acc_b, jerk_b, cap_hard, pts, n_pts, hard):
                if _upper_ok(j_lo, s, v, a, dt, acc_b, jerk_b, cap_hard, pts, n_pts, hard):
                    j = _largest_upper(j_lo, j, s, v, a, dt, acc_b, jerk_b, cap_hard, pts, n_pts, hard)
                else:
                    manoeuvre = True
                    w_follow, certified = _pick_manoeuvre(s, v, a, dt, acc_b, jerk_b, cap_hard, pts, n_pts,
                                                          hard)
                    m_cap = cap_hard
                    m_col = hard
                    if not certified:
                        _, ds, v1, a1 = _rescue(s, v, a, dt, acc_b, jerk_b, cap_hard, pts, n_pts, hard)
                        rescued = True

    if rescued:
        j = (a1 - a) / dt  # the period's mean jerk (the manoeuvre may switch inside it)
    elif manoeuvre:
        ds, v1, a1 = _delayed_manoeuvre(s, v, a, dt, j, w_follow, acc_b, jerk_b, m_cap, pts, n_pts, m_col)
        j = (a1 - a) / dt
    else:
        ds, v1, a1 = _step(v, a, j, dt)
    s1 = s + ds
    # A period never passes a mandatory stop; reaching it to rounding leaves a residual speed of ~1e-7 mm/s
    # that the next period removes (the snap above).
    if s1 > pt_f[q_stop, P_S]:
        s1 = pt_f[q_stop, P_S]
    if v1 < 0.0:
        v1 = 0.0
    st_f[S_S] = s1
    st_f[S_V] = v1
    st_f[S_A] = a1
    st_f[S_J] = j
    while k < n_seg - 1 and s1 >= seg_f[k + 1, F_S0] and k + 1 < q_stop:
        k += 1
    st_i[K_SEG] = k
    _position(seg_f, seg_i, curve_f, k, s1, out, tick)
    out[tick, O_S] = s1
    out[tick, O_V] = v1
    out[tick, O_A] = a1
    out[tick, O_J] = j
    out[tick, O_SEG] = seg_i[k, I_TP]
    out[tick, O_CUT] = 1.0 if seg_i[k, I_RAPID] == 0 else 0.0


@njit(cache=True)
def _snap_to_stop(seg_f: np.ndarray, seg_i: np.ndarray, curve_f: np.ndarray, pt_f: np.ndarray,
                  pt_i: np.ndarray, dwell_f: np.ndarray, st_f: np.ndarray, st_i: np.ndarray, out: np.ndarray,
                  tick: int, q_stop: int, n_seg: int, dt: float, a: float, wait: bool) -> None:  # fmt: skip
    """End this period at rest exactly on mandatory stop q_stop (the braking manoeuvre ends inside it)."""
    j = -a / dt
    st_f[S_S] = pt_f[q_stop, P_S]
    st_f[S_V] = 0.0
    st_f[S_A] = 0.0
    st_f[S_J] = j
    k_last = q_stop - 1
    _position(seg_f, seg_i, curve_f, k_last, st_f[S_S], out, tick)
    out[tick, O_S] = st_f[S_S]
    out[tick, O_J] = j
    out[tick, O_SEG] = seg_i[k_last, I_TP]
    out[tick, O_CUT] = 1.0 if seg_i[k_last, I_RAPID] == 0 else 0.0
    if wait and pt_i[q_stop, Q_WAIT] == 1:
        st_i[K_PHASE] = PHASE_WAIT
        st_i[K_SEG] = k_last
        return
    _arrive_at_stop(pt_i, dwell_f, st_f, st_i, q_stop, n_seg)


@njit(cache=True)
def release_wait(pt_i: np.ndarray, dwell_f: np.ndarray, st_f: np.ndarray, st_i: np.ndarray,
                 n_seg: int) -> None:  # fmt: skip
    """End an in-position wait (PHASE_WAIT on the stop at the end of segment K_SEG): go on as on arrival."""
    if st_i[K_PHASE] == PHASE_WAIT:
        _arrive_at_stop(pt_i, dwell_f, st_f, st_i, st_i[K_SEG] + 1, n_seg)


@njit(cache=True)
def _arrive_at_stop(pt_i: np.ndarray, dwell_f: np.ndarray, st_f: np.ndarray, st_i: np.ndarray, q: int,
                    n_seg: int) -> None:  # fmt: skip
    """At rest on mandatory stop q (and in position): start its dwells, or go on with segment q, or
    finish."""
    if pt_i[q, Q_DW1] > pt_i[q, Q_DW0]:
        st_i[K_PHASE] = PHASE_DWELL
        st_i[K_DWELL] = pt_i[q, Q_DW0]
        st_f[S_DWELL_LEFT] = dwell_f[pt_i[q, Q_DW0], 0]
        st_i[K_SEG] = q  # the segment that follows the dwells (or n_seg at the end)
        return
    _leave_point(st_i, q, n_seg)


@njit(cache=True)
def _leave_point(st_i: np.ndarray, q: int, n_seg: int) -> None:
    if q >= n_seg:
        st_i[K_PHASE] = PHASE_DONE
        st_i[K_SEG] = max(n_seg - 1, 0)
    else:
        st_i[K_PHASE] = PHASE_MOVE
        st_i[K_SEG] = q
        st_i[K_DWELL] = -1


@njit(cache=True)
def _after_dwell(pt_i: np.ndarray, dwell_f: np.ndarray, st_f: np.ndarray, st_i: np.ndarray,
                 n_seg: int) -> None:  # fmt: skip
    q = st_i[K_SEG]
    row = st_i[K_DWELL] + 1
    if row < pt_i[q, Q_DW1]:
        st_i[K_DWELL] = row
        st_f[S_DWELL_LEFT] += dwell_f[row, 0]
        return
    st_f[S_DWELL_LEFT] = 0.0
    if q >= n_seg:
        st_i[K_PHASE] = PHASE_DONE
        st_i[K_SEG] = max(n_seg - 1, 0)
        # keep K_DWELL: the finished state reports the last dwell as its segment
    else:
        _leave_point(st_i, q, n_seg)


@njit(cache=True)
def lookahead_kernel(seg_f: np.ndarray, seg_i: np.ndarray, pt_f: np.ndarray, pt_i: np.ndarray, k: int,
                     s: float, done: bool, horizon: float, n: int) -> np.ndarray:  # fmt: skip
    """Features of the path ahead in ``n`` equal bins of ``horizon / n`` mm starting at arc length s
    (:func:`lookahead_into`); rows: limit, curvature, turn, feed; [4, 0] the distance to the next stop."""
    out = np.zeros((5, n))
    lookahead_into(seg_f, pt_f, pt_i, k, s, done, horizon, out)
    return out


@njit(cache=True)
def lookahead_into(seg_f: np.ndarray, pt_f: np.ndarray, pt_i: np.ndarray, k: int, s: float, done: bool,
                   horizon: float, out: np.ndarray) -> None:  # fmt: skip
    """Features of the path ahead in ``n = out.shape[1]`` equal bins of ``horizon / n`` mm starting at arc
    length s on motion segment k, into ``out`` (5, n) (zeroed first).

    Per bin: the static speed limit (100 % override; minimum over the bin, junction limits inside
    included, 0 at mandatory stops and beyond the end), the largest curvature, the largest junction
    turning angle, the programmed feed at the bin's far end. ``out[4, 0]``: the distance to the next
    mandatory stop.
    """
    n = out.shape[1]
    n_seg = seg_f.shape[0]
    out[:, :] = 0.0
    if n_seg == 0 or done:
        return
    if k >= n_seg:
        k = n_seg - 1
    q_stop = pt_i[k + 1, Q_NEXT_STOP]
    d_stop = max(pt_f[q_stop, P_S] - s, 0.0)
    width = horizon / n
    total = pt_f[n_seg, P_S]
    kk = k
    for b in range(n):
        lo = s + b * width
        hi = lo + width
        if lo >= total:
            break
        # advance to the segment containing lo
        while kk < n_seg - 1 and lo >= seg_f[kk, F_S0] + seg_f[kk, F_LEN]:
            kk += 1
        best = INF
        kmax = 0.0
        ang = 0.0
        m = kk
        while True:
            best = min(best, seg_f[m, F_CAP], seg_f[m, F_BASE])
            kmax = max(kmax, seg_f[m, F_CURV])
            s_end = seg_f[m, F_S0] + seg_f[m, F_LEN]
            if s_end > hi:
                break
            if s_end > lo:  # the junction at the end of m lies inside the bin
                best = min(best, pt_f[m + 1, P_HARD])
                ang = max(ang, pt_f[m + 1, P_TURN])
            if s_end >= hi or m + 1 >= n_seg:  # bins are (lo, hi]: a block starting at hi is not in it
                break
            m += 1
        out[0, b] = 0.0 if hi >= total else best
        out[1, b] = kmax
        out[2, b] = ang
        out[3, b] = seg_f[m, F_FEED] if hi < total else 0.0
    out[4, 0] = d_stop
