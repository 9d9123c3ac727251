"""Nearest point on the tool path: the exact contour-error service.

Distances are computed for every (point, segment) pair in a window, vectorised with numpy, and the
minimum is kept. Lines use the clamped projection. Flat arcs use the angular projection onto the
circle, clamped to the swept range, compared with both end points. Helices start from the planar
projection on the turn nearest in height and take a few Newton steps on the squared distance.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from cnc_gym.toolpath.segments import _PLANE_AXES_TABLE, SegmentKind

if TYPE_CHECKING:
    from cnc_gym.toolpath.segments import Toolpath

_TWO_PI = 2.0 * np.pi
_NEWTON_STEPS = 4


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
    if np.any(kind == SegmentKind.NURBS):
        raise NotImplementedError("nearest point on NURBS segments is not built yet")
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
    # Turn nearest in height for helices with more than one turn.
    frac_h = np.divide(pw - w0, rise, out=np.zeros_like(pw), where=rise != 0)
    turns = np.round((np.clip(frac_h, 0.0, 1.0) * abs_sweep - phi_dir) / _TWO_PI)
    turns = np.where(rise != 0, np.maximum(turns, 0.0), 0.0)
    travelled = np.clip(phi_dir + _TWO_PI * turns, 0.0, abs_sweep)
    frac = np.divide(travelled, abs_sweep, out=np.zeros_like(travelled), where=abs_sweep > 0)

    def position(frac: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        ang = theta0 + sweep * frac
        return cu + radius * np.cos(ang), cv + radius * np.sin(ang), w0 + rise * frac

    helix = rise != 0
    if np.any(helix):
        for _ in range(_NEWTON_STEPS):
            ang = theta0 + sweep * frac
            cos_a, sin_a = np.cos(ang), np.sin(ang)
            eu = cu + radius * cos_a - pu
            ev = cv + radius * sin_a - pv
            ew = w0 + rise * frac - pw
            du, dv, dw = -radius * sin_a * sweep, radius * cos_a * sweep, rise
            ddu, ddv = -radius * cos_a * sweep**2, -radius * sin_a * sweep**2
            grad = eu * du + ev * dv + ew * dw
            hess = du * du + dv * dv + dw * dw + eu * ddu + ev * ddv
            step = np.divide(grad, hess, out=np.zeros_like(grad), where=hess > 1e-12)
            frac = np.where(helix, np.clip(frac - step, 0.0, 1.0), frac)

    def dist_at(frac: np.ndarray) -> np.ndarray:
        qu, qv, qw = position(frac)
        return np.sqrt((qu - pu) ** 2 + (qv - pv) ** 2 + (qw - pw) ** 2)

    d_inner = dist_at(frac)
    d_start = dist_at(np.zeros_like(frac))
    d_end = dist_at(np.ones_like(frac))
    choice = np.argmin(np.stack((d_inner, d_start, d_end)), axis=0)
    dist = np.choose(choice, (d_inner, d_start, d_end))
    frac = np.choose(choice, (frac, np.zeros_like(frac), np.ones_like(frac)))
    return seg, dist, frac * tp.length[seg][None, :]
