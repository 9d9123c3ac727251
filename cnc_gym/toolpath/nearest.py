"""Nearest point on the tool path: the exact contour-error service.

Distances are computed for every (point, segment) pair in a window, vectorised with numpy, and the
minimum is kept. Lines use the clamped projection. Flat arcs use the angular projection onto the
circle, clamped to the swept range, compared with both end points. Helices use :func:`helix_nearest`
(compiled): the distance along a helix has at most one local minimum in each stretch where it is convex
(one per turn, around the point's own angle), found there by safeguarded Newton, and the best of those
and the two ends is the global minimum. NURBS segments use their curve's own exact search
(:meth:`cnc_gym.toolpath.nurbs.NurbsCurve.nearest`); :func:`nurbs_table` and :func:`nurbs_distance2` are
the same search compiled, for the contour meter's hot loop.

Numba is imported with this module, which :meth:`~cnc_gym.toolpath.Toolpath.nearest` imports on first use
(the interpreter and ``cnc-gym trace`` never need it).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
from numba import njit

from cnc_gym.toolpath.segments import _PLANE_AXES_TABLE, SegmentKind

if TYPE_CHECKING:
    from cnc_gym.toolpath.segments import Toolpath

_TWO_PI = 2.0 * np.pi


def nearest_on_segments(
    tp: Toolpath, points: np.ndarray, first: int, last: int, cutting_only: bool
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    m = len(points)
    best_d = np.full(m, np.inf)
    best_i = np.full(m, -1, dtype=np.int64)
    best_s = np.zeros(m)
    if last <= first or m == 0:
        return best_d, best_i, best_s
    window = np.arange(first, last)
    kind = tp.kind[window]
    straight_kinds = [SegmentKind.LINE] if cutting_only else [SegmentKind.LINE, SegmentKind.RAPID]
    for seg, dist, local in (
        _nearest_lines(tp, points, window[np.isin(kind, straight_kinds)]),
        _nearest_arcs(tp, points, window[kind == SegmentKind.ARC]),
        _nearest_nurbs(tp, points, window[kind == SegmentKind.NURBS]),
    ):
        if seg.size == 0:
            continue
        col = np.argmin(dist, axis=1)
        rows = np.arange(m)
        d = dist[rows, col]
        better = d < best_d
        best_d = np.where(better, d, best_d)
        best_i = np.where(better, seg[col], best_i)
        best_s = np.where(better, tp.s_start[seg[col]] + local[rows, col], best_s)
    return best_d, best_i, best_s


def _nearest_lines(tp: Toolpath, points: np.ndarray, seg: np.ndarray):
    """(segments, distance (m, k), local arc length (m, k)) for straight segments."""
    if seg.size == 0:
        return seg, None, None
    a = tp.start[seg]  # (k, 3)
    d = tp.end[seg] - a
    ln2 = np.einsum("ij,ij->i", d, d)
    rel = points[:, None, :] - a[None, :, :]  # (m, k, 3)
    t = np.einsum("mkj,kj->mk", rel, d) / np.where(ln2 > 0, ln2, 1.0)
    t = np.clip(t, 0.0, 1.0)
    diff = rel - t[:, :, None] * d[None, :, :]
    dist = np.sqrt(np.einsum("mkj,mkj->mk", diff, diff))
    return seg, dist, t * np.sqrt(ln2)[None, :]


def _nearest_nurbs(tp: Toolpath, points: np.ndarray, seg: np.ndarray):
    """(segments, distance (m, k), local arc length (m, k)) for NURBS segments (cutting moves)."""
    if seg.size == 0:
        return seg, None, None
    dist = np.empty((len(points), len(seg)))
    local = np.empty((len(points), len(seg)))
    for col, i in enumerate(seg):
        dist[:, col], _, local[:, col] = tp.nurbs[int(i)].nearest(points)
    return seg, dist, local


def _nearest_arcs(tp: Toolpath, points: np.ndarray, seg: np.ndarray):
    if seg.size == 0:
        return seg, None, None
    axes = _PLANE_AXES_TABLE[tp.plane[seg].astype(np.int64)]  # (k, 3)
    k = len(seg)
    cols = np.arange(k)
    u, v, w = axes[:, 0], axes[:, 1], axes[:, 2]
    center = tp.center[seg]
    cu, cv = center[cols, u], center[cols, v]
    w0 = tp.start[seg][cols, w]
    rise = tp.end[seg][cols, w] - w0
    radius = tp.radius[seg]
    sweep = tp.sweep[seg]
    abs_sweep = np.abs(sweep)
    direction = np.where(sweep >= 0, 1.0, -1.0)
    theta0 = tp.start_angle[seg]

    pu = points[:, u]  # (m, k): each arc reads the point in its own plane axes
    pv = points[:, v]
    pw = points[:, w]
    phi = np.arctan2(pv - cv, pu - cu) - theta0
    phi_dir = np.mod(phi * direction, _TWO_PI)  # angle travelled from the start, in [0, 2π)
    travelled = np.minimum(phi_dir, abs_sweep)  # beyond the sweep: the end points are compared below
    frac = np.divide(travelled, abs_sweep, out=np.zeros_like(travelled), where=abs_sweep > 0)

    def position(frac: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        ang = theta0 + sweep * frac
        return cu + radius * np.cos(ang), cv + radius * np.sin(ang), w0 + rise * frac

    def dist_at_frac(frac: np.ndarray) -> np.ndarray:
        qu, qv, qw = position(frac)
        return np.sqrt((qu - pu) ** 2 + (qv - pv) ** 2 + (qw - pw) ** 2)

    helix = np.flatnonzero(rise != 0)
    if len(helix):
        frac = frac.copy()
        _helix_fracs(points, axes[helix], cu[helix], cv[helix], w0[helix], rise[helix], radius[helix],
                     theta0[helix], sweep[helix], helix, frac)  # fmt: skip

    d_inner = dist_at_frac(frac)
    d_start = dist_at_frac(np.zeros_like(frac))
    d_end = dist_at_frac(np.ones_like(frac))
    choice = np.argmin(np.stack((d_inner, d_start, d_end)), axis=0)
    dist = np.choose(choice, (d_inner, d_start, d_end))
    frac = np.choose(choice, (frac, np.zeros_like(frac), np.ones_like(frac)))
    return seg, dist, frac * tp.length[seg][None, :]


@njit(cache=True, nogil=True)
def _helix_fracs(points, axes, cu, cv, w0, rise, radius, theta0, sweep, columns, frac) -> None:
    """Sweep fraction of the nearest point of every point on every helix, into ``frac[:, columns]``."""
    for j in range(columns.shape[0]):
        iu, iv, iw = axes[j, 0], axes[j, 1], axes[j, 2]
        for i in range(points.shape[0]):
            _, f = helix_nearest(points[i, iu], points[i, iv], points[i, iw], cu[j], cv[j], w0[j], rise[j],
                                 radius[j], theta0[j], sweep[j])  # fmt: skip
            frac[i, columns[j]] = f


@njit(cache=True, nogil=True, inline="always")
def _helix_d2(pu, pv, pw, cu, cv, w0, rise, radius, theta0, sweep, f) -> float:
    """Squared distance from (pu, pv, pw) to the helix point at sweep fraction f."""
    ang = theta0 + sweep * f
    du = cu + radius * math.cos(ang) - pu
    dv = cv + radius * math.sin(ang) - pv
    dw = w0 + rise * f - pw
    return du * du + dv * dv + dw * dw


@njit(cache=True, nogil=True)
def _helix_slope(pu, pv, pw, cu, cv, w0, rise, radius, theta0, sweep, f) -> tuple[float, float]:
    """Half the first and second f-derivatives of the squared distance at sweep fraction f."""
    ang = theta0 + sweep * f
    cos_a, sin_a = math.cos(ang), math.sin(ang)
    eu = cu + radius * cos_a - pu
    ev = cv + radius * sin_a - pv
    ew = w0 + rise * f - pw
    du, dv = -radius * sin_a * sweep, radius * cos_a * sweep
    grad = eu * du + ev * dv + ew * rise
    hess = du * du + dv * dv + rise * rise - (eu * cos_a + ev * sin_a) * radius * sweep * sweep
    return grad, hess


@njit(cache=True, nogil=True)
def _helix_root(pu, pv, pw, cu, cv, w0, rise, radius, theta0, sweep, lo, hi, f) -> float:
    """The root of the slope in [lo, hi] (slope < 0 at lo, > 0 at hi, convex in between) from f:
    Newton, bisection where a step leaves the bracket; to full precision."""
    for _ in range(100):
        grad, hess = _helix_slope(pu, pv, pw, cu, cv, w0, rise, radius, theta0, sweep, f)
        if grad == 0.0:
            return f
        if grad > 0.0:
            hi = f
        else:
            lo = f
        step = grad / hess if hess > 0.0 else math.inf
        f_new = f - step
        if not lo < f_new < hi:
            f_new = 0.5 * (lo + hi)
        if abs(f_new - f) <= 1e-15 or hi - lo <= 1e-15:
            return f_new
        f = f_new
    return f


@njit(cache=True, nogil=True)
def helix_nearest(pu, pv, pw, cu, cv, w0, rise, radius, theta0, sweep) -> tuple[float, float]:
    """(squared distance, sweep fraction) of the point of a helix (or arc) nearest to (pu, pv, pw).

    The helix: centre (cu, cv) in its plane's (u, v) axes, radius, start angle ``theta0``, signed
    ``sweep``, rising from w0 by ``rise`` along the plane normal w, linearly in the angle. With ψ the angle
    from the point's own direction, half the squared distance is, up to a constant,
    ``−Rρ·cos ψ + (Δw)²/2``: its second derivative is positive wherever cos ψ > −rise²/(Rρ·sweep²), one
    stretch around every ψ = 2πk (all of it where rise² ≥ Rρ·sweep²). Each such stretch holds at most one
    local minimum, and no minimum lies outside them except at the ends; so the exact global minimum is the
    best of the roots of the slope in the stretches (safeguarded Newton) and of the two ends.
    """
    rho = math.hypot(pu - cu, pv - cv)
    phi_p = math.atan2(pv - cv, pu - cu)
    best_f = 0.0
    best = _helix_d2(pu, pv, pw, cu, cv, w0, rise, radius, theta0, sweep, 0.0)
    d2 = _helix_d2(pu, pv, pw, cu, cv, w0, rise, radius, theta0, sweep, 1.0)
    if d2 < best:
        best, best_f = d2, 1.0
    if sweep == 0.0:
        return best, best_f
    curve = radius * rho * sweep * sweep
    lift = rise * rise
    if lift >= curve:  # convex everywhere: one stretch, the whole sweep
        lo_f, hi_f, n_stretch = 0.0, 1.0, 1
        half = 0.0
        k0 = 0
    else:
        half = math.acos(-lift / curve)  # the stretches: |ψ − 2πk| < half, half in (π/2, π]
        psi0 = theta0 - phi_p
        psi1 = psi0 + sweep
        k0 = math.ceil((min(psi0, psi1) - half) / _TWO_PI)
        n_stretch = math.floor((max(psi0, psi1) + half) / _TWO_PI) - k0 + 1
    for k in range(k0, k0 + n_stretch):
        if lift < curve:
            # ψ(f) = psi0 + sweep·f: the stretch's fractions, clipped to [0, 1].
            a = (_TWO_PI * k - half - (theta0 - phi_p)) / sweep
            b = (_TWO_PI * k + half - (theta0 - phi_p)) / sweep
            lo_f, hi_f = max(min(a, b), 0.0), min(max(a, b), 1.0)
            if lo_f >= hi_f:
                continue
        g_lo, _ = _helix_slope(pu, pv, pw, cu, cv, w0, rise, radius, theta0, sweep, lo_f)
        g_hi, _ = _helix_slope(pu, pv, pw, cu, cv, w0, rise, radius, theta0, sweep, hi_f)
        if not (g_lo < 0.0 < g_hi):
            continue  # the minimum over this stretch is at one of its ends: a range end or not a minimum
        # Start where the planar distance is least (ψ = 2πk), clipped into the stretch.
        start = (_TWO_PI * k - (theta0 - phi_p)) / sweep if lift < curve else 0.5
        start = min(max(start, lo_f), hi_f)
        f = _helix_root(pu, pv, pw, cu, cv, w0, rise, radius, theta0, sweep, lo_f, hi_f, start)
        d2 = _helix_d2(pu, pv, pw, cu, cv, w0, rise, radius, theta0, sweep, f)
        if d2 < best:
            best, best_f = d2, f
    return best, best_f


# ------------------------------------------------------------------------------- NURBS, compiled
# A curve's table for nurbs_distance2: ints [order k, spans, samples n, samples per span], and floats
# [origin (3), Newton step tolerance, bounding-sphere centre (3) and radius, then the blocks below].
_NURBS_HEADER_F = 8
_NURBS_PRUNE_ABOVE_SAMPLES = 160  # as NurbsCurve.nearest: smaller tables are scanned whole
_NURBS_STARTS = 3  # Newton runs from the best-ranked brackets, plus one frozen at the best sample
_NURBS_NEWTON_STEPS = 8


def nurbs_table(curve, offset: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """The arrays :func:`nurbs_distance2` searches: ``curve``'s span polynomials and coarse sample table
    (those of :meth:`~cnc_gym.toolpath.nurbs.NurbsCurve.nearest`) flattened into floats, with a bounding
    sphere of all control points (a NURBS curve with positive weights lies in their convex hull), and the
    header ``[offset, order, spans, samples, samples per span]`` (``offset``: where the floats will start
    in a table holding several curves)."""
    k = int(curve.order)
    spans = len(curve._mid)
    n = len(curve._sample_t)
    hull = curve.control_points
    centre = hull.mean(axis=0)
    radius = float(np.sqrt(np.max(np.sum((hull - centre) ** 2, axis=1))))
    blocks = [
        curve._origin, [curve._nearest_step_tolerance], centre, [radius],
        curve._poly.reshape(-1),  # (spans, k, 12)
        curve._interior_breaks, curve._mid, curve._inv_half,  # spans - 1, spans, spans
        curve._sample_t, curve._sample_rel_t.T.reshape(-1), curve._sample_rel_sq,  # n, n × 3, n
        curve._sample_d1_t[0].T.reshape(-1), curve._sample_d1_t[1].T.reshape(-1),  # n × 3 right, left
        curve._sample_rel_d1[0], curve._sample_rel_d1[1],  # n, n
        curve._span_center_t.T.reshape(-1), curve._span_center_sq, curve._span_radius,  # spans × (3, 1, 1)
    ]  # fmt: skip
    tab_f = np.concatenate([np.asarray(b, dtype=np.float64).ravel() for b in blocks])
    tab_i = np.array([offset, k, spans, n, int(curve._per_span)], dtype=np.int64)
    return tab_f, tab_i


@njit(cache=True, nogil=True, inline="always")
def _take(table, at, size):
    """The next ``size`` values of a flat table from ``at``, and where the following block starts."""
    return table[at : at + size], at + size


@njit(cache=True, nogil=True, inline="always")
def _dot3(a, i, x0, x1, x2) -> float:
    """(a[3i], a[3i+1], a[3i+2]) · (x0, x1, x2)."""
    return a[3 * i] * x0 + a[3 * i + 1] * x1 + a[3 * i + 2] * x2


@njit(cache=True, nogil=True)
def _nurbs_homogeneous(poly, breaks, mid, inv_half, k, t, h) -> None:
    """Homogeneous coordinates (x, y, z, w) and their first two t-derivatives at t into h (12,)."""
    span = np.searchsorted(breaks, t, side="right")
    u = (t - mid[span]) * inv_half[span]
    base = span * k * 12
    for c in range(12):
        h[c] = 0.0
    power = 1.0
    for r in range(k):
        row = base + r * 12
        for c in range(12):
            h[c] += power * poly[row + c]
        power *= u


@njit(cache=True, nogil=True)
def nurbs_distance2(tab_f, header, p0, p1, p2, bound2) -> float:
    """Squared distance from (p0, p1, p2) to a NURBS curve (``header`` and floats from :func:`nurbs_table`)
    where it is below ``bound2``; otherwise some value at or above ``bound2`` (``inf`` where the curve's
    bounding sphere is already that far): the caller keeps the least distance, ``bound2`` its best so far.

    The search of :meth:`~cnc_gym.toolpath.nurbs.NurbsCurve.nearest`, for one point: the sample table
    brackets every local minimum of the distance (spans whose bounding sphere is farther than some span's
    start point, or than the bound, are skipped), the three best brackets and the best sample are refined
    by safeguarded Newton on the slope of the homogeneous form, and the closest wins.
    """
    o, k, spans, n, per_span = header[0], header[1], header[2], header[3], header[4]
    r0, r1, r2 = p0 - tab_f[o], p1 - tab_f[o + 1], p2 - tab_f[o + 2]
    step_tolerance = tab_f[o + 3]
    c0, c1, c2 = p0 - tab_f[o + 4], p1 - tab_f[o + 5], p2 - tab_f[o + 6]
    gap = math.sqrt(c0 * c0 + c1 * c1 + c2 * c2) - tab_f[o + 7]
    if gap > 0.0 and gap * gap >= bound2:
        return math.inf
    o += _NURBS_HEADER_F
    poly, o = _take(tab_f, o, spans * k * 12)
    breaks, o = _take(tab_f, o, spans - 1)
    mid, o = _take(tab_f, o, spans)
    inv_half, o = _take(tab_f, o, spans)
    sample_t, o = _take(tab_f, o, n)
    rel_t, o = _take(tab_f, o, 3 * n)
    rel_sq, o = _take(tab_f, o, n)
    d1_right, o = _take(tab_f, o, 3 * n)
    d1_left, o = _take(tab_f, o, 3 * n)
    rel_d1_right, o = _take(tab_f, o, n)
    rel_d1_left, o = _take(tab_f, o, n)
    span_centre, o = _take(tab_f, o, 3 * spans)
    span_centre_sq, o = _take(tab_f, o, spans)
    span_radius, o = _take(tab_f, o, spans)
    rel_sq_p = r0 * r0 + r1 * r1 + r2 * r2

    # The samples searched (all, or those of the spans not pruned) and whether neighbours are adjacent.
    index = np.empty(n, dtype=np.int64)
    if n > _NURBS_PRUNE_ABOVE_SAMPLES or bound2 < math.inf:
        # Keep the spans whose bounding sphere comes closer than some span's start point (or than the
        # caller's bound): the nearest point lies in one of them.
        upper2 = math.inf
        for j in range(0, n, per_span):
            upper2 = min(upper2, rel_sq[j] - 2.0 * _dot3(rel_t, j, r0, r1, r2))
        upper = min(math.sqrt(max(upper2 + rel_sq_p, 0.0)), math.sqrt(bound2))
        m = 0
        for j in range(spans):
            centre2 = span_centre_sq[j] - 2.0 * _dot3(span_centre, j, r0, r1, r2) + rel_sq_p
            if math.sqrt(max(centre2, 0.0)) - span_radius[j] <= upper * (1 + 1e-9) + 1e-9:
                first = j * per_span
                if m > 0 and index[m - 1] == first:
                    first += 1
                for i in range(first, (j + 1) * per_span + 1):
                    index[m] = i
                    m += 1
    else:
        m = n
        for i in range(n):
            index[i] = i
    if m == 0:
        return math.inf
    half_d2 = np.empty(m)
    slope_right = np.empty(m)
    slope_left = np.empty(m)
    for i in range(m):
        s = index[i]
        half_d2[i] = 0.5 * (rel_sq[s] - 2.0 * _dot3(rel_t, s, r0, r1, r2) + rel_sq_p)
        slope_right[i] = rel_d1_right[s] - _dot3(d1_right, s, r0, r1, r2)
        slope_left[i] = rel_d1_left[s] - _dot3(d1_left, s, r0, r1, r2)
    # Ranked brackets: slot i < m a minimum at sample i (an end, or a kink at a knot), slot m + i one inside
    # the interval (i, i + 1); the best _NURBS_STARTS are refined (lowest slot first among equals).
    n_starts = min(_NURBS_STARTS, 2 * m - 1)
    best_rank = np.full(_NURBS_STARTS, math.inf)
    best_slot = np.full(_NURBS_STARTS, -1, dtype=np.int64)
    best_sample = 0
    for slot in range(2 * m - 1):
        if slot < m:
            i = slot
            if half_d2[i] < half_d2[best_sample]:
                best_sample = i
            ok = (i == 0 or slope_left[i] <= 0.0) and (i == m - 1 or slope_right[i] >= 0.0)
            rank = half_d2[i] if ok else math.inf
        else:
            i = slot - m
            ok = slope_right[i] < 0.0 and slope_left[i + 1] > 0.0 and index[i + 1] - index[i] == 1
            rank = min(half_d2[i], half_d2[i + 1]) if ok else math.inf
        q = n_starts
        while q > 0 and (rank < best_rank[q - 1] or best_slot[q - 1] < 0):
            q -= 1
        if q < n_starts:
            for z in range(n_starts - 1, q, -1):
                best_rank[z] = best_rank[z - 1]
                best_slot[z] = best_slot[z - 1]
            best_rank[q] = rank
            best_slot[q] = slot
    # Runs: the brackets, and one frozen at the best sample (never worse than the sampling). A run whose
    # bracket is one sample stays there: it is evaluated once.
    n_runs = n_starts + 1
    lo = np.empty(n_runs)
    hi = np.empty(n_runs)
    t = np.empty(n_runs)
    valid = np.empty(n_runs, dtype=np.bool_)
    for r in range(n_runs):
        if r < n_starts:
            slot = best_slot[r]
            valid[r] = math.isfinite(best_rank[r])
            first = slot if slot < m else slot - m
            last = first if (slot < m or not valid[r]) else slot - m + 1
            g_lo, g_hi = slope_right[first], slope_left[last]
        else:
            first = last = best_sample
            g_lo = g_hi = 0.0
            valid[r] = True
        lo[r], hi[r] = sample_t[index[first]], sample_t[index[last]]
        denom = g_hi - g_lo
        t[r] = lo[r] + (hi[r] - lo[r]) * (-g_lo / denom if denom > 0.0 else 0.5)
    # Safeguarded Newton on g = (E·E') W − (E·E) W' (E = A − W p in homogeneous form; g has the slope's
    # sign and root), all runs together until none moves more than the step tolerance.
    h = np.empty(12)
    t_at = np.empty(n_runs)
    g = np.empty(n_runs)
    g_prime = np.empty(n_runs)
    ee = np.empty(n_runs)
    w = np.empty(n_runs)
    accepted = np.empty(n_runs, dtype=np.bool_)
    for step in range(_NURBS_NEWTON_STEPS):
        moved = 0.0
        for r in range(n_runs):
            if step > 0 and lo[r] == hi[r]:
                continue  # a one-sample bracket: the same point, the same numbers
            t_at[r] = t[r]
            _nurbs_homogeneous(poly, breaks, mid, inv_half, k, t[r], h)
            e0, e1, e2 = h[0] - h[3] * p0, h[1] - h[3] * p1, h[2] - h[3] * p2
            f0, f1, f2 = h[4] - h[7] * p0, h[5] - h[7] * p1, h[6] - h[7] * p2
            s0, s1, s2 = h[8] - h[11] * p0, h[9] - h[11] * p1, h[10] - h[11] * p2
            ee_r = e0 * e0 + e1 * e1 + e2 * e2
            ee1 = e0 * f0 + e1 * f1 + e2 * f2
            e1e1 = f0 * f0 + f1 * f1 + f2 * f2
            ee2 = e0 * s0 + e1 * s1 + e2 * s2
            g[r] = ee1 * h[3] - ee_r * h[7]
            g_prime[r] = (e1e1 + ee2) * h[3] - ee1 * h[7] - ee_r * h[11]
            ee[r] = ee_r
            w[r] = h[3]
            if g[r] > 0.0:
                hi[r] = t[r]
            if g[r] < 0.0:
                lo[r] = t[r]
            newton = t[r] - g[r] / g_prime[r] if g_prime[r] > 0.0 else math.nan
            accepted[r] = lo[r] <= newton <= hi[r]  # False for NaN: a concave model bisects
            t[r] = newton if accepted[r] else 0.5 * (lo[r] + hi[r])
            moved = max(moved, abs(t[r] - t_at[r]))
        if moved <= step_tolerance:
            break
    best = math.inf
    for r in range(n_runs):
        if not valid[r]:
            continue
        d2 = ee[r] / (w[r] * w[r])
        # A last Newton step below the tolerance: the quadratic model's drop g²/(g' W³) finishes it.
        if accepted[r] and g_prime[r] > 0.0 and abs(t[r] - t_at[r]) <= step_tolerance:
            d2 = d2 - g[r] * g[r] / (g_prime[r] * w[r] ** 3)
        best = min(best, max(d2, 0.0))
    return best
