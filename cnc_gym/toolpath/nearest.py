"""Nearest point on the tool path: the exact contour-error service.

Distances are computed for every (point, segment) pair in a window, vectorised with numpy, and the
minimum is kept. Lines use the clamped projection. Flat arcs use the angular projection onto the
circle, clamped to the swept range, compared with both end points. Helices use :func:`helix_nearest`
(compiled): the distance along a helix has at most one local minimum in each stretch where it is convex
(one per turn, around the point's own angle), found there by safeguarded Newton, and the best of those
and the two ends is the global minimum. NURBS segments use their curve's own exact search
(:meth:`cnc_gym.toolpath.nurbs.NurbsCurve.nearest`); :func:`nurbs_table` and :func:`nurbs_distance2` search
the same sample table compiled, for the contour meter's hot loop, refining every bracket that a bounding
sphere of the curve between two neighbouring samples cannot rule out (and allocating nothing in the loop:
:func:`nurbs_search`).

Numba is imported with this module, which :meth:`~cnc_gym.toolpath.Toolpath.nearest` imports on first use
(the interpreter and ``cnc-gym trace`` never need it).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from cnc_gym.toolpath.kinds import PLANE_AXES_TABLE, SegmentKind, ToolpathRows

_TWO_PI = 2.0 * np.pi
#: The helix search's Newton iteration ends on a step of at most this much sweep fraction (a few units in
#: the last place of a fraction near 1; the distance is stationary there, so its error is far smaller).
_HELIX_STEP_TOLERANCE = 1e-15


def nearest_on_segments(
    tp: ToolpathRows, points: np.ndarray, first: int, last: int, cutting_only: bool
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


def _nearest_lines(tp: ToolpathRows, points: np.ndarray, seg: np.ndarray):
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


def _nearest_nurbs(tp: ToolpathRows, points: np.ndarray, seg: np.ndarray):
    """(segments, distance (m, k), local arc length (m, k)) for NURBS segments (cutting moves)."""
    if seg.size == 0:
        return seg, None, None
    dist = np.empty((len(points), len(seg)))
    local = np.empty((len(points), len(seg)))
    for col, i in enumerate(seg):
        dist[:, col], _, local[:, col] = tp.nurbs[int(i)].nearest(points)
    return seg, dist, local


def _nearest_arcs(tp: ToolpathRows, points: np.ndarray, seg: np.ndarray):
    if seg.size == 0:
        return seg, None, None
    axes = PLANE_AXES_TABLE[tp.plane[seg].astype(np.int64)]  # (k, 3)
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


@njit(cache=True, nogil=True, inline="always")
def _helix_slope(pu, pv, pw, cu, cv, w0, rise, radius, theta0, sweep, f) -> tuple[float, float, float]:
    """Half the first and second f-derivatives of the squared distance at sweep fraction f, and the squared
    distance itself."""
    ang = theta0 + sweep * f
    cos_a, sin_a = math.cos(ang), math.sin(ang)
    eu = cu + radius * cos_a - pu
    ev = cv + radius * sin_a - pv
    ew = w0 + rise * f - pw
    du, dv = -radius * sin_a * sweep, radius * cos_a * sweep
    grad = eu * du + ev * dv + ew * rise
    hess = du * du + dv * dv + rise * rise - (eu * cos_a + ev * sin_a) * radius * sweep * sweep
    return grad, hess, eu * eu + ev * ev + ew * ew


@njit(cache=True, nogil=True)
def _helix_root(pu, pv, pw, cu, cv, w0, rise, radius, theta0, sweep, lo, hi,
                f) -> tuple[bool, float, float, int]:  # fmt: skip
    """(found, fraction, squared distance there, slope evaluations): the root of the slope in a stretch
    [lo, hi] where the squared distance is convex (so the slope rises: at most one root, the stretch's
    minimum), from f in it, to full precision.

    Newton, bracketed by its own iterates; the slope's signs at the stretch's ends are evaluated only where
    a step leaves the bracket (near the root Newton never does, so a search usually costs two or three
    evaluations): a negative slope at lo and a positive one at hi hold the root, and bisection takes over;
    otherwise there is no root (found False: the stretch's minimum is at one of its ends). A Newton step
    below :data:`_HELIX_STEP_TOLERANCE` ends the search before the bracket is tested, because at the root
    ``f − step`` rounds to ``f``, an end of the bracket, and bisecting from there would walk the whole
    bracket down again (tens of steps)."""
    lo_known = False  # whether the slope is known to be negative at lo (positive at hi): an iterate was there
    hi_known = False
    for n in range(1, 101):
        grad, hess, d2 = _helix_slope(pu, pv, pw, cu, cv, w0, rise, radius, theta0, sweep, f)
        if grad == 0.0:
            return True, f, d2, n
        if grad > 0.0:
            hi, hi_known = f, True
        else:
            lo, lo_known = f, True
        step = grad / hess if hess > 0.0 else math.inf
        if abs(step) <= _HELIX_STEP_TOLERANCE:
            return True, f, d2, n
        f_new = f - step
        if not lo < f_new < hi or hi - lo <= _HELIX_STEP_TOLERANCE:
            if not lo_known:
                g_lo, _, _ = _helix_slope(pu, pv, pw, cu, cv, w0, rise, radius, theta0, sweep, lo)
                if not g_lo < 0.0:
                    return False, f, d2, n
                lo_known = True
            if not hi_known:
                g_hi, _, _ = _helix_slope(pu, pv, pw, cu, cv, w0, rise, radius, theta0, sweep, hi)
                if not g_hi > 0.0:
                    return False, f, d2, n
                hi_known = True
            if hi - lo <= _HELIX_STEP_TOLERANCE:
                return True, f, d2, n
            f_new = 0.5 * (lo + hi)
        f = f_new
    return True, f, d2, 100


@njit(cache=True, nogil=True)
def helix_nearest(pu, pv, pw, cu, cv, w0, rise, radius, theta0, sweep) -> tuple[float, float]:
    """(squared distance, sweep fraction) of the point of a helix (or arc) nearest to (pu, pv, pw).

    The helix: centre (cu, cv) in its plane's (u, v) axes, radius, start angle ``theta0``, signed
    ``sweep``, rising from w0 by ``rise`` along the plane normal w, linearly in the angle. With ψ the angle
    from the point's own direction, half the squared distance is, up to a constant,
    ``−Rρ·cos ψ + (Δw)²/2``: its second derivative is positive wherever cos ψ > −rise²/(Rρ·sweep²), one
    stretch around every ψ = 2πk (all of it where rise² ≥ Rρ·sweep²). Each such stretch holds at most one
    local minimum, and no minimum lies outside them except at the ends; so the exact global minimum is the
    best of the roots of the slope in the stretches (:func:`_helix_root`, from the stretch's planar
    nearest angle ψ = 2πk) and of the two ends. An end that lies in a stretch with a root is not
    evaluated: the distance falls from it to that root.
    """
    rho = math.hypot(pu - cu, pv - cv)
    phi_p = math.atan2(pv - cv, pu - cu)
    best_f = 0.0
    best = math.inf
    need_start = need_end = True  # whether an end of the sweep can still be the nearest point
    curve = radius * rho * sweep * sweep
    lift = rise * rise
    if sweep == 0.0:
        n_stretch, k0, half = 0, 0, 0.0
    elif lift >= curve:  # convex everywhere: one stretch, the whole sweep
        n_stretch, k0, half = 1, 0, 0.0
    else:
        half = math.acos(-lift / curve)  # the stretches: |ψ − 2πk| < half, half in (π/2, π]
        psi0 = theta0 - phi_p
        psi1 = psi0 + sweep
        k0 = math.ceil((min(psi0, psi1) - half) / _TWO_PI)
        n_stretch = math.floor((max(psi0, psi1) + half) / _TWO_PI) - k0 + 1
    for k in range(k0, k0 + n_stretch):
        if lift < curve:
            # ψ(f) = psi0 + sweep·f: the stretch's fractions, clipped to [0, 1]; start where the planar
            # distance is least (ψ = 2πk).
            a = (_TWO_PI * k - half - (theta0 - phi_p)) / sweep
            b = (_TWO_PI * k + half - (theta0 - phi_p)) / sweep
            lo_f, hi_f = max(min(a, b), 0.0), min(max(a, b), 1.0)
            if lo_f >= hi_f:
                continue
            start = (_TWO_PI * k - (theta0 - phi_p)) / sweep
        else:
            lo_f, hi_f = 0.0, 1.0
            start = (pw - w0) / rise if rise != 0.0 else 0.5  # steep: where the height matches
        start = min(max(start, lo_f), hi_f)
        found, f, d2, _ = _helix_root(pu, pv, pw, cu, cv, w0, rise, radius, theta0, sweep, lo_f, hi_f, start)
        if not found:
            continue  # the minimum over this stretch is at one of its ends: a range end or not a minimum
        if d2 < best:
            best, best_f = d2, f
        if lo_f == 0.0:
            need_start = False
        if hi_f == 1.0:
            need_end = False
    if need_start:
        d2 = _helix_d2(pu, pv, pw, cu, cv, w0, rise, radius, theta0, sweep, 0.0)
        if d2 <= best:
            best, best_f = d2, 0.0
    if need_end:
        d2 = _helix_d2(pu, pv, pw, cu, cv, w0, rise, radius, theta0, sweep, 1.0)
        if d2 < best:
            best, best_f = d2, 1.0
    return best, best_f


# ------------------------------------------------------------------------------- NURBS, compiled
# A curve's table for nurbs_distance2: ints [offset, order k, spans, samples n, samples per span], and floats
# [origin (3), Newton step tolerance, bounding-sphere centre (3) and radius, then the blocks below].
_NURBS_HEADER_F = 8
_NURBS_NEWTON_STEPS = 8
_SPHERE_MARGIN = 1e-9  # relative and absolute (mm): the pruning tests leave this much for rounding
#: Neighbouring intervals per group: one sphere holds a group's interval spheres, so that a point far from
#: the group skips its intervals with one test (a neighbouring curve, or the far side of the own one).
NURBS_GROUP = 8
# The group sphere's slack over its intervals' spheres: 1e-6 mm plus 1e-7 of the curve's extent, far above
# the rounding of the tests (about 1e-16 of the extent squared), far below any distance that matters.
_GROUP_MARGIN = 1e-6


def _interval_spheres(curve) -> tuple[np.ndarray, np.ndarray]:
    """A sphere (centre (n - 1, 3), radius (n - 1,)) holding the curve between each two neighbouring
    samples of its table. On each such interval the homogeneous polynomial is rewritten in Bernstein form:
    with positive weights the curve there is a convex combination of the projected Bernstein points, so
    the sphere around them holds it. A radius is ``inf`` where a Bernstein weight is not positive (the
    bound then prunes nothing)."""
    k = int(curve.order)
    t = np.asarray(curve._sample_t, dtype=np.float64)
    span = np.minimum(np.arange(len(t) - 1) // int(curve._per_span), len(curve._mid) - 1)
    a = (t[:-1] - curve._mid[span]) * curve._inv_half[span]
    width = (t[1:] - t[:-1]) * curve._inv_half[span]
    coef = curve._poly[span, :, :4]  # (intervals, k, 4): powers of u of the homogeneous coordinates
    # In s ∈ [0, 1] with u = a + width·s: q_j = Σ_r c_r C(r, j) a^(r-j) width^j.
    q = np.zeros_like(coef)
    for r in range(k):
        for j in range(r + 1):
            q[:, j] += coef[:, r] * (math.comb(r, j) * a ** (r - j) * width**j)[:, None]
    # Bernstein coefficients: b_j = Σ_{i ≤ j} C(j, i) / C(k - 1, i) q_i.
    bern = np.zeros_like(q)
    for j in range(k):
        for i in range(j + 1):
            bern[:, j] += q[:, i] * (math.comb(j, i) / math.comb(k - 1, i))
    weight = bern[:, :, 3]
    positive = np.all(weight > 0, axis=1)
    points = bern[:, :, :3] / np.where(weight > 0, weight, 1.0)[:, :, None]
    centre = points.mean(axis=1)
    radius = np.sqrt(np.max(np.sum((points - centre[:, None, :]) ** 2, axis=2), axis=1))
    return centre, np.where(positive, radius, np.inf)


def _group_spheres(centre: np.ndarray, radius: np.ndarray, extent: float) -> tuple[np.ndarray, np.ndarray]:
    """A sphere (centre (g, 3), radius (g,)) around each :data:`NURBS_GROUP` neighbouring interval spheres
    (``centre`` (n - 1, 3), ``radius`` (n - 1,)), with a slack of :data:`_GROUP_MARGIN` so that a point
    its test (in floating point) puts outside a group also fails each interval's own test there: the
    group's test then stands for its intervals' tests, and the search's result is the same."""
    n_groups = -(-len(radius) // NURBS_GROUP)
    group_centre = np.empty((n_groups, 3))
    group_radius = np.empty(n_groups)
    for g in range(n_groups):
        members = slice(g * NURBS_GROUP, (g + 1) * NURBS_GROUP)
        c, r = centre[members], radius[members]
        group_centre[g] = 0.5 * (c.min(axis=0) + c.max(axis=0))
        reach = np.sqrt(np.sum((c - group_centre[g]) ** 2, axis=1)) + r
        group_radius[g] = reach.max() + _GROUP_MARGIN * (1.0 + 0.1 * extent)
    return group_centre, group_radius


def nurbs_table(curve, offset: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """The arrays :func:`nurbs_distance2` searches: ``curve``'s span polynomials and coarse sample table
    (those of :meth:`~cnc_gym.toolpath.nurbs.NurbsCurve.nearest`) flattened into floats, with a bounding
    sphere of all control points (a NURBS curve with positive weights lies in their convex hull), one of
    the curve between each two neighbouring samples (:func:`_interval_spheres`) and one around each group of
    those (:func:`_group_spheres`), and the header
    ``[offset, order, spans, samples, samples per span]`` (``offset``: where the floats will start in a
    table holding several curves)."""
    k = int(curve.order)
    spans = len(curve._mid)
    n = len(curve._sample_t)
    hull = curve.control_points
    centre = hull.mean(axis=0)
    radius = float(np.sqrt(np.max(np.sum((hull - centre) ** 2, axis=1))))
    interval_centre, interval_radius = _interval_spheres(curve)
    interval_centre = interval_centre - curve._origin  # relative, as the sample table
    extent = float(np.max(np.abs(np.concatenate((interval_centre.ravel(), [0.0]))))) + radius
    group_centre, group_radius = _group_spheres(interval_centre, interval_radius, extent)
    blocks = [
        curve._origin, [curve._nearest_step_tolerance], centre, [radius],
        curve._poly.reshape(-1),  # (spans, k, 12)
        curve._interior_breaks, curve._mid, curve._inv_half,  # spans - 1, spans, spans
        curve._sample_t, curve._sample_rel_t.reshape(-1), curve._sample_rel_sq,  # n, 3 × n (x, y, z), n
        curve._sample_d1_t[0].T.reshape(-1), curve._sample_d1_t[1].T.reshape(-1),  # n × 3 right, left
        curve._sample_rel_d1[0], curve._sample_rel_d1[1],  # n, n
        interval_centre.T.reshape(-1), np.sum(interval_centre**2, axis=1),  # 3 × (n - 1) (blocks), n - 1
        interval_radius,  # n - 1
        group_centre.T.reshape(-1), np.sum(group_centre**2, axis=1), group_radius,  # 3 × g (blocks), g, g
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


@njit(cache=True, nogil=True, inline="always")
def _nurbs_homogeneous(poly, breaks, mid, inv_half, k, t):
    """Homogeneous coordinates (x, y, z, w) and their first two t-derivatives at t (12 values), by Horner's
    rule in registers."""
    span = np.searchsorted(breaks, t, side="right")
    u = (t - mid[span]) * inv_half[span]
    row = (span * k + k - 1) * 12
    h0, h1, h2, h3 = poly[row], poly[row + 1], poly[row + 2], poly[row + 3]
    h4, h5, h6, h7 = poly[row + 4], poly[row + 5], poly[row + 6], poly[row + 7]
    h8, h9, h10, h11 = poly[row + 8], poly[row + 9], poly[row + 10], poly[row + 11]
    for r in range(k - 2, -1, -1):
        row = (span * k + r) * 12
        h0, h1, h2, h3 = (h0 * u + poly[row], h1 * u + poly[row + 1], h2 * u + poly[row + 2],
                          h3 * u + poly[row + 3])  # fmt: skip
        h4, h5, h6, h7 = (h4 * u + poly[row + 4], h5 * u + poly[row + 5], h6 * u + poly[row + 6],
                          h7 * u + poly[row + 7])  # fmt: skip
        h8, h9, h10, h11 = (h8 * u + poly[row + 8], h9 * u + poly[row + 9], h10 * u + poly[row + 10],
                            h11 * u + poly[row + 11])  # fmt: skip
    return h0, h1, h2, h3, h4, h5, h6, h7, h8, h9, h10, h11


@njit(cache=True, nogil=True)
def _nurbs_refine(poly, breaks, mid, inv_half, k, p0, p1, p2, lo, hi, t, step_tolerance) -> float:
    """Squared distance at the root of the slope in [lo, hi] (one sample where lo = hi), from t:
    safeguarded Newton on g = (E·E') W − (E·E) W' (E = A − W p in homogeneous form; g has the slope's sign
    and root) until a step is below the step tolerance; then the quadratic model's drop finishes it."""
    t_at, ee, w, g, g_prime, accepted = t, 0.0, 1.0, 0.0, 0.0, False
    for _ in range(_NURBS_NEWTON_STEPS):
        t_at = t
        x, y, z, w, x1, y1, z1, w1, x2, y2, z2, w2 = _nurbs_homogeneous(poly, breaks, mid, inv_half, k, t)
        e0, e1, e2 = x - w * p0, y - w * p1, z - w * p2
        f0, f1, f2 = x1 - w1 * p0, y1 - w1 * p1, z1 - w1 * p2
        s0, s1, s2 = x2 - w2 * p0, y2 - w2 * p1, z2 - w2 * p2
        ee = e0 * e0 + e1 * e1 + e2 * e2
        ee1 = e0 * f0 + e1 * f1 + e2 * f2
        e1e1 = f0 * f0 + f1 * f1 + f2 * f2
        ee2 = e0 * s0 + e1 * s1 + e2 * s2
        g = ee1 * w - ee * w1
        g_prime = (e1e1 + ee2) * w - ee1 * w1 - ee * w2
        if lo == hi:
            return max(ee / (w * w), 0.0)  # a one-sample bracket: this point
        if g > 0.0:
            hi = t
        if g < 0.0:
            lo = t
        newton = t - g / g_prime if g_prime > 0.0 else math.nan
        accepted = lo <= newton <= hi  # False for NaN: a concave model bisects
        t = newton if accepted else 0.5 * (lo + hi)
        if abs(t - t_at) <= step_tolerance:
            break
    d2 = ee / (w * w)
    # A last Newton step below the tolerance: the quadratic model's drop g²/(g' W³) finishes it.
    if accepted and g_prime > 0.0 and abs(t - t_at) <= step_tolerance:
        d2 = d2 - g * g / (g_prime * w**3)
    return max(d2, 0.0)


@njit(cache=True, nogil=True, inline="always")
def nurbs_work_size(samples: int) -> int:
    """Size of the float scratch array of :func:`nurbs_search` on curves of at most ``samples`` samples
    (one array serves every call of a loop: the search itself allocates nothing)."""
    return samples


@njit(cache=True, nogil=True)
def nurbs_distance2(tab_f, header, p0, p1, p2, bound2) -> float:
    """Squared distance from (p0, p1, p2) to a NURBS curve (``header`` and floats from :func:`nurbs_table`)
    where it is below ``bound2``; otherwise some value at or above ``bound2`` (``inf`` where the curve's
    bounding sphere is already that far): the caller keeps the least distance, ``bound2`` its best so far.
    :func:`nurbs_search` with its own scratch array."""
    return nurbs_search(tab_f, header, p0, p1, p2, bound2, np.empty(nurbs_work_size(header[3])))


@njit(cache=True, nogil=True)
def nurbs_search(tab_f, header, p0, p1, p2, bound2, work) -> float:
    """:func:`nurbs_distance2` in a scratch array of :func:`nurbs_work_size` (for this curve or more).

    The search of :meth:`~cnc_gym.toolpath.nurbs.NurbsCurve.nearest`, for one point: the sample table
    brackets every local minimum of the distance; the nearest sample bounds the distance from above, and
    the brackets whose interval sphere (:func:`_interval_spheres`) comes closer than that bound (and than
    ``bound2``) are refined by safeguarded Newton on the slope of the homogeneous form, as is the nearest
    sample itself (never worse than the sampling); the closest wins.
    """
    o, k, spans, n = header[0], header[1], header[2], header[3]
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
    interval_centre, o = _take(tab_f, o, 3 * (n - 1))
    interval_centre_sq, o = _take(tab_f, o, n - 1)
    interval_radius, o = _take(tab_f, o, n - 1)
    n_groups = (n - 2) // NURBS_GROUP + 1
    group_centre, o = _take(tab_f, o, 3 * n_groups)
    group_centre_sq, o = _take(tab_f, o, n_groups)
    group_radius, o = _take(tab_f, o, n_groups)
    rel_sq_p = r0 * r0 + r1 * r1 + r2 * r2
    x_c, y_c, z_c = interval_centre[: n - 1], interval_centre[n - 1 : 2 * n - 2], interval_centre[2 * n - 2 :]
    x_g, y_g = group_centre[:n_groups], group_centre[n_groups : 2 * n_groups]
    z_g = group_centre[2 * n_groups :]
    d2_sample = work[:n]
    if bound2 < math.inf:
        # Under a bound (the caller's best so far, often from a neighbouring segment): nothing to search
        # unless some interval's sphere comes within it (tested group by group).
        reach0 = math.sqrt(bound2) * (1.0 + _SPHERE_MARGIN) + _SPHERE_MARGIN
        near = False
        for g in range(n_groups):
            if not _within(group_centre_sq[g], x_g[g], y_g[g], z_g[g], r0, r1, r2, rel_sq_p,
                           reach0 + group_radius[g]):  # fmt: skip
                continue
            for i in range(g * NURBS_GROUP, min((g + 1) * NURBS_GROUP, n - 1)):
                if _within(interval_centre_sq[i], x_c[i], y_c[i], z_c[i], r0, r1, r2, rel_sq_p,
                           reach0 + interval_radius[i]):  # fmt: skip
                    near = True
                    break
            if near:
                break
        if not near:
            return math.inf

    # The nearest sample: an upper bound of the distance. (Coordinates in x, y, z blocks: the loops
    # vectorise.)
    x_t, y_t, z_t = rel_t[:n], rel_t[n : 2 * n], rel_t[2 * n :]
    for i in range(n):
        d2_sample[i] = rel_sq[i] - 2.0 * (x_t[i] * r0 + y_t[i] * r1 + z_t[i] * r2) + rel_sq_p
    best_sample = np.argmin(d2_sample)
    upper = math.sqrt(max(min(d2_sample[best_sample], bound2), 0.0)) * (1.0 + _SPHERE_MARGIN) + _SPHERE_MARGIN
    # The nearest sample, refined in place (a one-sample bracket).
    t = sample_t[best_sample]
    best = _nurbs_refine(poly, breaks, mid, inv_half, k, p0, p1, p2, t, t, t, step_tolerance)
    # Brackets of a minimum inside an interval (the slope negative right of its first sample, positive left
    # of its second) whose sphere comes within the bound. (A minimum at a sample, an end or a kink at a
    # knot, other than the nearest sample is farther than it.)
    for g in range(n_groups):
        # (A group out of reach holds no interval within reach: the bound only shrinks along the loop.)
        if not _within(group_centre_sq[g], x_g[g], y_g[g], z_g[g], r0, r1, r2, rel_sq_p,
                       upper + group_radius[g]):  # fmt: skip
            continue
        for i in range(g * NURBS_GROUP, min((g + 1) * NURBS_GROUP, n - 1)):
            if not _within(interval_centre_sq[i], x_c[i], y_c[i], z_c[i], r0, r1, r2, rel_sq_p,
                           upper + interval_radius[i]):  # fmt: skip
                continue
            g_lo = rel_d1_right[i] - _dot3(d1_right, i, r0, r1, r2)
            if not g_lo < 0.0:
                continue
            g_hi = rel_d1_left[i + 1] - _dot3(d1_left, i + 1, r0, r1, r2)
            if not g_hi > 0.0:
                continue
            lo, hi = sample_t[i], sample_t[i + 1]
            t = lo + (hi - lo) * (-g_lo / (g_hi - g_lo))
            d2 = _nurbs_refine(poly, breaks, mid, inv_half, k, p0, p1, p2, lo, hi, t, step_tolerance)
            if d2 < best:
                best = d2
                upper = min(upper, math.sqrt(d2) * (1.0 + _SPHERE_MARGIN) + _SPHERE_MARGIN)
    return best


@njit(cache=True, nogil=True, inline="always")
def _within(centre_sq, x, y, z, r0, r1, r2, rel_sq_p, reach) -> bool:
    """Whether the point (r0, r1, r2) is within ``reach`` of the centre (x, y, z) (``centre_sq`` its
    squared norm, ``rel_sq_p`` the point's), by the expanded square (one form for every sphere test)."""
    centre2 = centre_sq - 2.0 * (x * r0 + y * r1 + z * r2) + rel_sq_p
    return centre2 <= reach * reach
