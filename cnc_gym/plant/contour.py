"""Contour error: the exact distance from the actual tool point to the programmed path.

The rule (DESIGN.md, ``cnc-gym run`` contract): contour error is measured at every plant sample, on
cutting moves only, against the programmed path after compensation (the tool path's segments).

- **Which samples count.** A sample counts when the *reference* is on a cutting segment (line, arc,
  helix). Where the reference segment is a rapid or a dwell the error is 0 by definition: rapids do not
  cut, and during a dwell the axes stand still on the path's end point.
- **Against what.** The nearest point on the *cutting* segments (rapids left out, dwells have no length)
  in a window that moves with the reference: segments ``[hint − window_back, hint + window_ahead]``,
  stretched backwards until it covers at least ``window_back_mm`` of path (the actual position lags the
  reference by about v/Kv, which on short segments spans many of them). A window keeps a neighbouring
  pass of a pocket, which can be closer than the segment being cut, from hiding the error. Consequence:
  just after a rapid → cut junction that the controller did not stop at, the lag left on the rapid is
  measured against the cutting segments (the rapid is not a candidate).
- **Exactness.** Lines: clamped projection. Flat arcs: the radial distance where the point's angle lies
  inside the swept range, else the nearer end point. Helices: the tool path's own exact service
  (:meth:`~cnc_gym.toolpath.Toolpath.nearest`), one call per helix in the window. This module is a
  faster, window-cached re-implementation of ``cnc_gym/toolpath/nearest.py`` for lines and flat arcs;
  the tests check the two agree.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cnc_gym.toolpath.segments import PLANE_AXES, Plane, SegmentKind, Toolpath

_PLANE_AXES_TABLE = np.array([PLANE_AXES[p] for p in Plane], dtype=np.int64)


@dataclass(frozen=True)
class _Window:
    """Geometry of the cutting segments of one window, laid out for broadcasting against points."""

    first: int
    last: int
    # Lines (k_l,): start (k_l, 3), direction end − start (k_l, 3), 1/|d|² (0 for zero-length lines).
    line_start: np.ndarray
    line_dir: np.ndarray
    line_inv_len2: np.ndarray
    # Flat arcs (k_a,): plane axes, centre in (u, v), height w0, radius, unit radial vectors to the
    # start and end, direction sign, whether |sweep| <= π, whether it is a full circle, end points.
    arc_u: np.ndarray
    arc_v: np.ndarray
    arc_w: np.ndarray
    arc_cu: np.ndarray
    arc_cv: np.ndarray
    arc_w0: np.ndarray
    arc_radius: np.ndarray
    arc_su: np.ndarray
    arc_sv: np.ndarray
    arc_eu: np.ndarray
    arc_ev: np.ndarray
    arc_dir: np.ndarray
    arc_small: np.ndarray
    arc_full: np.ndarray
    arc_ends: np.ndarray  # (2·k_a, 3): starts then ends
    helices: tuple[int, ...]


class ContourErrorMeter:
    """Exact contour error of actual tool points against a :class:`~cnc_gym.toolpath.Toolpath`.

    ``window_back`` / ``window_ahead``: segments searched before / after the reference segment;
    ``window_back_mm``: the window also reaches back at least this far along the path (set it to a
    bound on the following error, e.g. max feed / Kv, for programs of very short segments).
    See the module docstring for the rule.
    """

    def __init__(
        self,
        toolpath: Toolpath,
        window_back: int = 2,
        window_ahead: int = 8,
        window_back_mm: float = 0.0,
    ) -> None:
        if window_back < 0 or window_ahead < 0 or window_back_mm < 0:
            raise ValueError("contour window sizes must not be negative")
        self.toolpath = toolpath
        self.window_back = int(window_back)
        self.window_ahead = int(window_ahead)
        self.window_back_mm = float(window_back_mm)
        kind = np.asarray(toolpath.kind)
        self._cutting = (kind == SegmentKind.LINE) | (kind == SegmentKind.ARC)
        if np.any(kind == SegmentKind.NURBS):
            raise NotImplementedError("contour error on NURBS segments is not built yet")
        self._n = len(toolpath)
        self._cache: dict[tuple[int, int], _Window] = {}
        self.reset()

    def reset(self) -> None:
        """Forget cached windows (call at episode start; the tool path itself is immutable)."""
        self._cache.clear()

    # ------------------------------------------------------------------ windows
    def window(self, segment_hint: int | np.ndarray) -> tuple[int, int]:
        """``[first, last)`` segments searched for a reference on ``segment_hint`` (int or array)."""
        hint = np.asarray(segment_hint)
        lo, hi = (int(hint.min()), int(hint.max())) if hint.ndim else (int(hint), int(hint))
        first = max(0, lo - self.window_back)
        if self.window_back_mm > 0 and 0 <= lo < self._n:
            s_from = self.toolpath.s_start[lo] - self.window_back_mm
            first = min(first, max(0, int(np.searchsorted(self.toolpath.s_start, s_from, side="right")) - 1))
        last = min(self._n, hi + self.window_ahead + 1)
        return first, last

    def _window_geometry(self, first: int, last: int) -> _Window:
        key = (first, last)
        cached = self._cache.get(key)
        if cached is not None:
            return cached
        if len(self._cache) > 64:  # the hint moves forward: old windows are not needed again
            self._cache.clear()
        tp = self.toolpath
        idx = np.arange(first, last)
        kind = tp.kind[idx]
        lines = idx[kind == SegmentKind.LINE]
        arcs = idx[kind == SegmentKind.ARC]
        line_dir = tp.end[lines] - tp.start[lines]
        len2 = np.einsum("ij,ij->i", line_dir, line_dir)
        inv_len2 = np.divide(1.0, len2, out=np.zeros_like(len2), where=len2 > 0)

        axes = _PLANE_AXES_TABLE[tp.plane[arcs].astype(np.int64)]
        u, v, w = axes[:, 0], axes[:, 1], axes[:, 2]
        rows = np.arange(len(arcs))
        start, end, center = tp.start[arcs], tp.end[arcs], tp.center[arcs]
        rise = end[rows, w] - start[rows, w]
        helix = rise != 0
        flat = arcs[~helix]
        u, v, w, rows = u[~helix], v[~helix], w[~helix], np.arange(len(flat))
        start, center = start[~helix], center[~helix]
        radius = tp.radius[flat]
        sweep = tp.sweep[flat]
        theta0 = tp.start_angle[flat]
        theta1 = theta0 + sweep
        abs_sweep = np.abs(sweep)
        window = _Window(
            first=first,
            last=last,
            line_start=np.ascontiguousarray(tp.start[lines]),
            line_dir=line_dir,
            line_inv_len2=inv_len2,
            arc_u=u,
            arc_v=v,
            arc_w=w,
            arc_cu=center[rows, u],
            arc_cv=center[rows, v],
            arc_w0=start[rows, w],
            arc_radius=radius,
            arc_su=np.cos(theta0),
            arc_sv=np.sin(theta0),
            arc_eu=np.cos(theta1),
            arc_ev=np.sin(theta1),
            arc_dir=np.where(sweep >= 0, 1.0, -1.0),
            arc_small=abs_sweep <= np.pi,
            arc_full=abs_sweep >= 2.0 * np.pi * (1.0 - 1e-12),
            arc_ends=self._arc_points(u, v, w, center, radius, theta0, theta1),
            helices=tuple(int(i) for i in arcs[helix]),
        )
        self._cache[key] = window
        return window

    @staticmethod
    def _arc_points(u, v, w, center, radius, theta0, theta1) -> np.ndarray:
        """Start then end points of flat arcs from their geometry (as the reference service does)."""
        rows = np.arange(len(radius))
        points = np.empty((2 * len(radius), 3))
        for block, theta in enumerate((theta0, theta1)):
            part = points[block * len(radius) : (block + 1) * len(radius)]
            part[rows, u] = center[rows, u] + radius * np.cos(theta)
            part[rows, v] = center[rows, v] + radius * np.sin(theta)
            part[rows, w] = center[rows, w]
        return points

    # ------------------------------------------------------------------ measuring
    def measure(self, points: np.ndarray, segment_hint: int | np.ndarray) -> np.ndarray:
        """Contour error (mm) of each actual point, shape (m,).

        ``segment_hint`` is the reference's segment index: one int for all points, or one per point
        (then the window spans all of them and points whose own hint is a rapid/dwell get 0).
        """
        pts = np.asarray(points, dtype=float)
        if pts.ndim == 1:
            pts = pts[None]
        m = len(pts)
        hint = np.asarray(segment_hint)
        if hint.ndim == 0:
            h = int(hint)
            if not (0 <= h < self._n) or not self._cutting[h]:
                return np.zeros(m)
            counted = None
        else:
            if hint.shape != (m,):
                raise ValueError(f"segment_hint must be an int or shape ({m},), got {hint.shape}")
            inside = (hint >= 0) & (hint < self._n)
            counted = np.zeros(m, dtype=bool)
            counted[inside] = self._cutting[hint[inside]]
            if not counted.any():
                return np.zeros(m)
            hint = hint[counted]
        first, last = self.window(hint)
        dist = np.sqrt(self._min_squared_distance(pts, self._window_geometry(first, last)))
        if counted is not None:
            dist = np.where(counted, dist, 0.0)
        return dist

    def _min_squared_distance(self, pts: np.ndarray, win: _Window) -> np.ndarray:
        best = np.full(len(pts), np.inf)
        if len(win.line_start):
            rel = pts[:, None, :] - win.line_start[None, :, :]  # (m, k, 3)
            t = np.einsum("mkj,kj->mk", rel, win.line_dir) * win.line_inv_len2
            np.clip(t, 0.0, 1.0, out=t)
            diff = rel - t[:, :, None] * win.line_dir
            best = np.minimum(best, np.einsum("mkj,mkj->mk", diff, diff).min(axis=1))
        if len(win.arc_radius):
            du = pts[:, win.arc_u] - win.arc_cu  # (m, k): each arc reads the point in its own plane axes
            dv = pts[:, win.arc_v] - win.arc_cv
            dw = pts[:, win.arc_w] - win.arc_w0
            # Inside the swept range: on the travel side of the start radius and before the end radius.
            past_start = win.arc_dir * (win.arc_su * dv - win.arc_sv * du) >= 0
            before_end = win.arc_dir * (du * win.arc_ev - dv * win.arc_eu) >= 0
            inside = np.where(win.arc_small, past_start & before_end, past_start | before_end) | win.arc_full
            radial = np.sqrt(du * du + dv * dv) - win.arc_radius
            d2_inside = np.where(inside, radial * radial + dw * dw, np.inf)
            ends = pts[:, None, :] - win.arc_ends[None, :, :]
            d2_ends = np.einsum("mkj,mkj->mk", ends, ends).min(axis=1)
            best = np.minimum(best, np.minimum(d2_inside.min(axis=1), d2_ends))
        for seg in win.helices:
            d, _, _ = self.toolpath.nearest(pts, seg, seg + 1, cutting_only=True)
            best = np.minimum(best, d * d)
        return best
