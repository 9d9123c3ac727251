"""Nearest point on the tool path: the exact contour-error service.

Distances are computed for every (point, segment) pair in a window, vectorised with numpy, and the
minimum is kept. Lines use the clamped projection. Flat arcs use the angular projection onto the
circle, clamped to the swept range, compared with both end points. Helices start from the best point
of a grid (16 points per turn) and take a few Newton steps on the squared distance. NURBS segments use
their curve's own exact search (:meth:`cnc_gym.toolpath.nurbs.NurbsCurve.nearest`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from cnc_gym.toolpath.segments import _PLANE_AXES_TABLE, SegmentKind

if TYPE_CHECKING:
    from cnc_gym.toolpath.segments import Toolpath

_TWO_PI = 2.0 * np.pi
_NEWTON_STEPS = 6


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

    helix = rise != 0
    if np.any(helix):
        frac = np.where(helix, _helix_nearest_frac(points, seg, tp, helix, axes), frac)

    d_inner = dist_at_frac(frac)
    d_start = dist_at_frac(np.zeros_like(frac))
    d_end = dist_at_frac(np.ones_like(frac))
    choice = np.argmin(np.stack((d_inner, d_start, d_end)), axis=0)
    dist = np.choose(choice, (d_inner, d_start, d_end))
    frac = np.choose(choice, (frac, np.zeros_like(frac), np.ones_like(frac)))
    return seg, dist, frac * tp.length[seg][None, :]


def _helix_nearest_frac(points, seg, tp, helix, axes) -> np.ndarray:
    """Sweep fraction of the nearest point on each helix column (m, k); other columns are left at 0.

    A helix can have several local minima of the distance (one per turn, and more near the axis). Newton
    steps run from every point of a grid with 16 points per turn, so every basin holds a start; the best
    converged point wins.
    """
    h = np.flatnonzero(helix)
    cols = np.arange(len(h))
    u, v, w = axes[h, 0], axes[h, 1], axes[h, 2]
    cu, cv = tp.center[seg[h]][cols, u], tp.center[seg[h]][cols, v]
    w0 = tp.start[seg[h]][cols, w]
    rise = tp.end[seg[h]][cols, w] - w0
    radius, sweep, theta0 = tp.radius[seg[h]], tp.sweep[seg[h]], tp.start_angle[seg[h]]
    turns = float(np.max(np.abs(sweep))) / _TWO_PI
    grid = np.linspace(0.0, 1.0, int(min(16 * max(turns, 1.0), 512)) + 1)
    # Shapes: (m, kh, g).
    pu, pv, pw = (points[:, a][:, :, None] for a in (u, v, w))
    cu, cv, w0, rise, radius, sweep, theta0 = (
        x[None, :, None] for x in (cu, cv, w0, rise, radius, sweep, theta0)
    )
    frac = np.broadcast_to(grid, (len(points), len(h), len(grid))).copy()
    for _ in range(_NEWTON_STEPS):
        ang = theta0 + sweep * frac
        cos_a, sin_a = np.cos(ang), np.sin(ang)
        eu = cu + radius * cos_a - pu
        ev = cv + radius * sin_a - pv
        ew = w0 + rise * frac - pw
        du, dv = -radius * sin_a * sweep, radius * cos_a * sweep
        grad = eu * du + ev * dv + ew * rise
        hess = du * du + dv * dv + rise * rise - (eu * cos_a + ev * sin_a) * radius * sweep**2
        # Newton only where the model is convex; elsewhere the grid start stays (another start covers it).
        step = np.divide(grad, hess, out=np.zeros_like(grad), where=hess > 1e-12)
        frac = np.clip(frac - step, 0.0, 1.0)
    ang = theta0 + sweep * frac
    d2 = (cu + radius * np.cos(ang) - pu) ** 2 + (cv + radius * np.sin(ang) - pv) ** 2
    d2 += (w0 + rise * frac - pw) ** 2
    best = np.take_along_axis(frac, np.argmin(d2, axis=2)[:, :, None], axis=2)[:, :, 0]
    out = np.zeros((len(points), len(helix)))
    out[:, h] = best
    return out
