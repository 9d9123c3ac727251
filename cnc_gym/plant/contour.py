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
  inside the swept range, else the nearer end point. Helices and NURBS: the tool path's own exact
  service (:meth:`~cnc_gym.toolpath.Toolpath.nearest`), one call per such segment in the window. This
  module is a faster, window-cached re-implementation of ``cnc_gym/toolpath/nearest.py`` for lines
  and flat arcs (one matmul per call, see :class:`_Window`); the tests check the two agree.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cnc_gym.toolpath.segments import PLANE_AXES, Plane, SegmentKind, Toolpath

_PLANE_AXES_TABLE = np.array([PLANE_AXES[p] for p in Plane], dtype=np.int64)


@dataclass(frozen=True)
class _Window:
    """The cutting geometry of one window as k *elements*, laid out so that one matmul serves them all.

    Elements are line segments, flat arc pieces of at most half a turn (longer arcs are split), and the
    end points of both. Each element has five columns of ``weights`` (3, 5k); ``points @ weights −
    offsets`` gives per element ``(du, dv, dw, past_start, before_end)``, and the squared distance to the
    element is ``(hypot(du, dv) − radius)² + dw²`` where ``past_start ≥ 0`` and ``before_end ≥ 0``:

    - arc piece: the point relative to the centre in the arc's own (u, v, w) axes; the cross products
      with the unit radii to the piece's start and end (travel direction folded in) are both ≥ 0 exactly
      when the point's angle lies in the piece's range (≤ π);
    - line: du, dv = components along two unit normals (hypot = distance to the infinite line,
      radius 0), dw = 0; past_start / before_end = distance along the line past its start / before its end;
    - end point: du, dv, dw = the point minus it, radius 0, always "inside".

    The columns are selections, unit vectors and offsets: no |p|² − 2p·q + |q|² cancellation, so the
    result is exact to rounding of the coordinates. Helices and NURBS go to ``others``.
    """

    weights: np.ndarray  # (3, 5k)
    offsets: np.ndarray  # (5k,)
    radius: np.ndarray  # (k,)
    others: tuple[int, ...]  # helices and NURBS: measured with Toolpath.nearest, one call each


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
        self._cutting = (kind == SegmentKind.LINE) | (kind == SegmentKind.ARC) | (kind == SegmentKind.NURBS)
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
        return self._window_range(lo, hi)

    def _window_range(self, lo: int, hi: int) -> tuple[int, int]:
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
        window = _build_window(self.toolpath, first, last)
        self._cache[key] = window
        return window

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
        counted = None  # None: every point counts
        if np.ndim(segment_hint) == 0:
            lo = hi = int(segment_hint)
            if not (0 <= lo < self._n) or not self._cutting[lo]:
                return np.zeros(m)
        else:
            hint = np.asarray(segment_hint, dtype=np.intp)
            if hint.shape != (m,):
                raise ValueError(f"segment_hint must be an int or shape ({m},), got {hint.shape}")
            if m == 0:
                return np.zeros(0)
            lo, hi = int(hint.min()), int(hint.max())
            if lo >= 0 and hi < self._n:
                counted = self._cutting[hint]
            else:
                in_range = (hint >= 0) & (hint < self._n)
                counted = np.zeros(m, dtype=bool)
                counted[in_range] = self._cutting[hint[in_range]]
            if counted.all():
                counted = None
            elif not counted.any():
                return np.zeros(m)
            else:
                lo, hi = int(hint[counted].min()), int(hint[counted].max())
        first, last = self._window_range(lo, hi)
        dist = self._min_distance(pts, self._window_geometry(first, last))
        if counted is not None:
            dist = np.where(counted, dist, 0.0)
        return dist

    def _min_distance(self, pts: np.ndarray, win: _Window) -> np.ndarray:
        best = np.full(len(pts), np.inf)
        k = len(win.radius)
        if k:
            local = (pts @ win.weights - win.offsets).reshape(len(pts), 5, k)
            inside = np.minimum(local[:, 3], local[:, 4]) >= 0
            off_curve = np.hypot(local[:, 0], local[:, 1]) - win.radius  # in the element's normal plane
            best = np.where(inside, np.hypot(off_curve, local[:, 2]), np.inf).min(axis=1)
        for seg in win.others:
            d, _, _ = self.toolpath.nearest(pts, seg, seg + 1, cutting_only=True)
            best = np.minimum(best, d)
        return best


def _build_window(tp: Toolpath, first: int, last: int) -> _Window:
    """Element columns (see :class:`_Window`) for the cutting segments in ``[first, last)``."""
    idx = np.arange(first, last)
    kind = tp.kind[idx]
    is_arc = kind == SegmentKind.ARC
    w_axis = _PLANE_AXES_TABLE[tp.plane[idx].astype(np.int64), 2]
    rise = np.where(is_arc, tp.end[idx, w_axis] - tp.start[idx, w_axis], 0.0)
    lines = idx[kind == SegmentKind.LINE]
    arcs = idx[is_arc & (rise == 0)]
    others = idx[(is_arc & (rise != 0)) | (kind == SegmentKind.NURBS)]

    # Lines.
    a = tp.start[lines]
    delta = tp.end[lines] - a
    length = np.linalg.norm(delta, axis=1)
    has_length = length > 0
    direction = delta / np.where(has_length, length, 1.0)[:, None]
    normal1, normal2 = _unit_normals(direction)
    along = np.einsum("ij,ij->i", a, direction)
    line_w = np.stack((normal1, normal2, np.zeros_like(a), direction, -direction), axis=1)  # (k, 5, 3)
    # A zero-length line gets past_start ≡ −1: only its end points count.
    past_start_offset = np.where(has_length, along, 1.0)
    line_o = np.stack((np.einsum("ij,ij->i", a, normal1), np.einsum("ij,ij->i", a, normal2),
                       np.zeros(len(a)), past_start_offset, -(along + length)), axis=1)  # fmt: skip

    # Flat arcs, split into pieces of at most half a turn so that "inside" is "both cross products ≥ 0".
    n_pieces = np.maximum(1, np.ceil(np.abs(tp.sweep[arcs]) / np.pi - 1e-12)).astype(np.int64)
    piece_arc = np.repeat(arcs, n_pieces)
    piece_no = np.arange(len(piece_arc)) - np.repeat(np.cumsum(n_pieces) - n_pieces, n_pieces)
    sweep = tp.sweep[piece_arc]
    piece_sweep = sweep / np.repeat(n_pieces, n_pieces)
    theta0 = tp.start_angle[piece_arc] + piece_no * piece_sweep
    theta1 = theta0 + piece_sweep
    axes = _PLANE_AXES_TABLE[tp.plane[piece_arc].astype(np.int64)]
    u, v, w = axes[:, 0], axes[:, 1], axes[:, 2]
    rows = np.arange(len(piece_arc))
    center = tp.center[piece_arc]
    cu, cv, w0 = center[rows, u], center[rows, v], tp.start[piece_arc][rows, w]
    sign = np.where(sweep >= 0, 1.0, -1.0)
    su, sv = sign * np.cos(theta0), sign * np.sin(theta0)
    eu, ev = sign * np.cos(theta1), sign * np.sin(theta1)
    arc_w = np.zeros((len(piece_arc), 5, 3))
    arc_w[rows, 0, u] = 1.0
    arc_w[rows, 1, v] = 1.0
    arc_w[rows, 2, w] = 1.0
    arc_w[rows, 3, v] = su  # past_start = sign·(su·dv − sv·du)
    arc_w[rows, 3, u] = -sv
    arc_w[rows, 4, u] = ev  # before_end = sign·(du·ev − dv·eu)
    arc_w[rows, 4, v] = -eu
    arc_o = np.stack((cu, cv, w0, su * cv - sv * cu, ev * cu - eu * cv), axis=1)
    radius = tp.radius[piece_arc]

    # End points of every line and arc piece (arc ends from the arc's geometry, as the reference does).
    arc_ends = _arc_points(u, v, w, center, radius, theta0, theta1)
    ends = np.unique(np.concatenate((tp.start[lines], tp.end[lines], arc_ends)), axis=0)
    end_w = np.zeros((len(ends), 5, 3))
    end_w[:, 0, 0] = end_w[:, 1, 1] = end_w[:, 2, 2] = 1.0
    end_o = np.concatenate((ends, np.full((len(ends), 2), -1.0)), axis=1)  # past_start = before_end = 1

    weights = np.concatenate((line_w, arc_w, end_w))  # (k, 5, 3)
    offsets = np.concatenate((line_o, arc_o, end_o))  # (k, 5)
    return _Window(
        weights=np.ascontiguousarray(weights.transpose(2, 1, 0).reshape(3, -1)),
        offsets=np.ascontiguousarray(offsets.T.reshape(-1)),
        radius=np.concatenate((np.zeros(len(lines)), radius, np.zeros(len(ends)))),
        others=tuple(int(i) for i in others),
    )


def _unit_normals(direction: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors perpendicular to each unit ``direction`` and to each other (any for zero rows)."""
    # Cross with the coordinate axis least aligned with the direction: well conditioned.
    helper = np.zeros_like(direction)
    helper[np.arange(len(direction)), np.argmin(np.abs(direction), axis=1)] = 1.0
    first = np.cross(direction, helper)
    norm = np.linalg.norm(first, axis=1)
    first = first / np.where(norm > 0, norm, 1.0)[:, None]
    second = np.cross(direction, first)
    return first, second


def _arc_points(u, v, w, center, radius, theta0, theta1) -> np.ndarray:
    """Start then end points of flat arc pieces from their geometry."""
    n = len(radius)
    rows = np.arange(n)
    points = np.empty((2 * n, 3))
    for block, theta in enumerate((theta0, theta1)):
        part = points[block * n : (block + 1) * n]
        part[rows, u] = center[rows, u] + radius * np.cos(theta)
        part[rows, v] = center[rows, v] + radius * np.sin(theta)
        part[rows, w] = center[rows, w]
    return points
