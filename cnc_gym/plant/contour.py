"""Contour error: the exact distance from the actual tool point to the programmed path.

The rule (docs/architecture.md, the ``cnc-gym run`` contract): contour error is measured at every plant
sample, on cutting moves only, against the programmed path after compensation (the tool path's segments).

- **Which samples count.** A sample counts when the *reference* is on a cutting segment (line, arc,
  helix, NURBS). Where the reference segment is a rapid or a dwell the error is 0 by definition: rapids
  do not cut, and during a dwell the axes stand still on the path's end point.
- **Against what.** The nearest point on the programmed path in a window that moves with the reference:
  segments ``[hint − window_back, hint + window_ahead]``, stretched backwards until it covers at least
  ``window_back_mm`` of path (the actual position lags the reference by about v/Kv, which on short
  segments spans many of them). Candidates are the window's cutting segments and the rapids in it that
  the reference has already left (those before its own segment); dwells have no length. A window keeps
  a neighbouring pass of a pocket, which can be closer than the segment being cut, from hiding the error.
- **Rapids behind the reference** (the programmed-path rule). Contour error is the geometric deviation
  from the programmed path, and the rapid that brought the tool to a cut is part of it: a tool still on
  that rapid (released within the in-position width, or lagging along it) is late, not off the path. So
  at a rapid → cut junction the tool is measured against the rapid and the cut alike; at a junction
  that turns (a rapid in X, then a cut in Y) a tool short of the corner is on the rapid's line (error
  ≈ 0), and one beside the cut, past the corner, is measured against the cut. Rapids *ahead* of the
  reference never count (the tool cannot be there legitimately: the reference leads it), nor does a
  sample whose reference is on a rapid. The flag ``rapids_behind=False`` keeps the earlier rule
  (cutting segments only), with which ``cnc_gym/Feedrate-v0`` and ``-v1`` are registered so that their
  numbers reproduce; it charged the in-position residual at every rapid → cut junction as contour
  error (docs/plant.md, "Contour error at a rapid → cut junction").
- **Exactness.** Lines: clamped projection. Flat arcs: the radial distance where the point's angle lies
  inside the swept range, else the nearer end point. Helices: :func:`~cnc_gym.toolpath.nearest.helix_nearest`
  (the exact global minimum over the sweep). NURBS: :func:`~cnc_gym.toolpath.nearest.nurbs_distance2` (the
  curve's own exact search, compiled). The tests check the meter against the tool path's service
  (:meth:`~cnc_gym.toolpath.Toolpath.nearest`).
- **Speed.** One numba-compiled loop over points × window segments (:func:`measure_kernel`) on
  per-segment constants packed once per tool path (:class:`ContourTables`), with no per-call allocation
  beyond the result. Lines and flat arcs are measured first; a helix or NURBS segment is searched only
  where a lower bound on its distance is below the best distance so far (for a helix, cheapest first: its
  height range, its cylinder, its projected arc; for a curve, its bounding sphere), and each point's own
  segment first, so the searches that cannot win are skipped (on a helical bore most neighbouring turns
  fail on the height alone). One ``measure`` call of 5 points on a window of ~10 segments
  costs ~1–2 µs on lines and arcs. The env's fused step calls the same kernel.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from cnc_gym.toolpath.kinds import PLANE_AXES_TABLE, SegmentKind
from cnc_gym.toolpath.nearest import helix_nearest, nurbs_search, nurbs_table, nurbs_work_size
from cnc_gym.toolpath.segments import Toolpath

# Segment classes of the kernel: dwells (and rapids under the cuts-only rule) are SKIP; the cutting classes
# are LINE..NURBS; RAPID is a rapid line, a candidate only behind the point's own segment.
SKIP, LINE, FLAT_ARC, HELIX, NURBS, RAPID = 0, 1, 2, 3, 4, 5
# Columns of the packed per-segment float table ``geometry`` (n, 15).
#   lines: a (0..2), d = end − a (3..5), 1/|d|² or 0 for a zero-length line (6)
#   flat arcs and helices: centre u, v (0, 1), w at the start (2), radius (3), start angle (4), |sweep| (5),
#              direction ±1 (6), start point (7..9) and end point (10..12) from the arc's geometry;
#   helices also: rise along w (13), signed sweep (14)
N_GEOMETRY = 15
_TWO_PI = 2.0 * math.pi


class ContourTables(NamedTuple):
    """A tool path packed for :func:`measure_kernel` (built once per tool path by :func:`pack_contour`)."""

    seg_class: np.ndarray  # (n,) int64: SKIP (dwell; rapid under the cuts-only rule), LINE, FLAT_ARC, HELIX,
    #                        NURBS, RAPID (a rapid under the programmed-path rule)
    axes: np.ndarray  # (n, 3) int64: plane axes (u, v, w)
    geometry: np.ndarray  # (n, N_GEOMETRY) float64, see the column list above
    first_back: np.ndarray  # (n,) int64: first segment of the window for each lowest hint
    nurbs_f: np.ndarray  # (r,) float64: the NURBS rows' search tables, one after the other
    nurbs_i: np.ndarray  # (n, 5) int64: a NURBS row's header in nurbs_f (nurbs_table), 0 elsewhere


@njit(cache=True, nogil=True, inline="always")
def is_cutting(seg_class: int) -> bool:
    """Whether a segment of this kernel class is a cutting move (a sample whose reference is on it counts)."""
    return LINE <= seg_class <= NURBS


@njit(cache=True, nogil=True, inline="always")
def _line_or_arc_d2(c, g, iu, iv, iw, px, py, pz, pu, pv, pw) -> float:
    """Squared distance to a line (c = LINE or RAPID) or flat arc (c = FLAT_ARC) from its geometry row g."""
    if c != FLAT_ARC:
        rx = px - g[0]
        ry = py - g[1]
        rz = pz - g[2]
        t = (rx * g[3] + ry * g[4] + rz * g[5]) * g[6]
        if t < 0.0:
            t = 0.0
        elif t > 1.0:
            t = 1.0
        dx = rx - t * g[3]
        dy = ry - t * g[4]
        dz = rz - t * g[5]
        return dx * dx + dy * dy + dz * dz
    du = pu - g[0]
    dv = pv - g[1]
    # Angle travelled from the start in the arc's direction, in [0, 2π) (Python-style mod).
    phi = (math.atan2(dv, du) - g[4]) * g[6]
    phi = phi - _TWO_PI * math.floor(phi / _TWO_PI)
    if phi <= g[5]:
        off = math.hypot(du, dv) - g[3]
        dw = pw - g[2]
        return off * off + dw * dw
    # outside the swept range: the nearer end point
    ex = px - g[7]
    ey = py - g[8]
    ez = pz - g[9]
    d2 = ex * ex + ey * ey + ez * ez
    ex = px - g[10]
    ey = py - g[11]
    ez = pz - g[12]
    return min(d2, ex * ex + ey * ey + ez * ez)


@njit(cache=True, nogil=True, inline="always")
def _curved_d2(c, geometry, s, nurbs_i, nurbs_f, iu, iv, iw, px, py, pz, pu, pv, pw, bound2, work) -> float:
    """Squared distance to the helix or NURBS segment ``s``, or ``inf`` where a lower bound shows it cannot
    be below ``bound2``. (Reads the tables by index: a row view would cost a reference count per call.)"""
    if c == HELIX:
        # Lower bounds, cheapest first: the distance to the helix's height range along w, then to its
        # cylinder (the planar circle) and that range, then to the projected arc (an angle) and that range.
        w0 = geometry[s, 2]
        rise = geometry[s, 13]
        gap = max(min(w0, w0 + rise) - pw, pw - max(w0, w0 + rise), 0.0)
        gap2 = gap * gap
        if gap2 >= bound2:
            return math.inf
        cu = geometry[s, 0]
        cv = geometry[s, 1]
        radius = geometry[s, 3]
        du = pu - cu
        dv = pv - cv
        planar = abs(math.sqrt(du * du + dv * dv) - radius)
        if planar * planar + gap2 >= bound2:
            return math.inf
        theta0 = geometry[s, 4]
        if geometry[s, 5] < _TWO_PI:
            phi = (math.atan2(dv, du) - theta0) * geometry[s, 6]
            phi = phi - _TWO_PI * math.floor(phi / _TWO_PI)
            if phi > geometry[s, 5]:  # outside the swept angle: the nearer end, in the plane
                planar = min(math.hypot(pu - geometry[s, 7 + iu], pv - geometry[s, 7 + iv]),
                             math.hypot(pu - geometry[s, 10 + iu], pv - geometry[s, 10 + iv]))  # fmt: skip
                if planar * planar + gap2 >= bound2:
                    return math.inf
        d2, _ = helix_nearest(pu, pv, pw, cu, cv, w0, rise, radius, theta0, geometry[s, 14])
        return d2
    return nurbs_search(nurbs_f, nurbs_i[s], px, py, pz, bound2, work)


@njit(cache=True, nogil=True)
def measure_kernel(points, hints, seg_class, axes, geometry, first_back, nurbs_f, nurbs_i, window_ahead,
                   out) -> tuple[int, int]:  # fmt: skip
    """Contour error of each point into ``out``; returns ``(first, last)`` of the window used.

    ``hints``: one hint for all points (length 1) or one per point. A point counts where its own hint
    (or the common hint) is an in-range cutting segment (lines, flat arcs, helices, NURBS); the window is
    ``[first_back[lo], min(n, hi + window_ahead + 1))`` over the counted hints' range ``[lo, hi]``.
    Candidates are the window's cutting segments and its RAPID segments before the point's own segment
    (the path the reference has left). Points that do not count get 0; if no point counts the window is
    (0, 0).
    """
    n_segments = seg_class.shape[0]
    m = points.shape[0]
    per_point = hints.shape[0] != 1
    lo = n_segments
    hi = -1
    curved = False
    for i in range(hints.shape[0]):
        h = hints[i]
        if 0 <= h < n_segments and is_cutting(seg_class[h]):
            if h < lo:
                lo = h
            if h > hi:
                hi = h
    if hi < 0:
        for i in range(m):
            out[i] = 0.0
        return 0, 0
    first = first_back[lo]
    last = min(n_segments, hi + window_ahead + 1)
    samples = 0  # the most samples of a NURBS table in the window: the size of the search's scratch
    for s in range(first, last):
        if seg_class[s] == HELIX or seg_class[s] == NURBS:
            curved = True
        if seg_class[s] == NURBS:
            samples = max(samples, nurbs_i[s, 3])
    # (No window without a NURBS row allocates: an empty view of ``out`` stands for the scratch there.)
    work = np.empty(nurbs_work_size(samples)) if samples > 0 else out[:0]
    for i in range(m):
        own = hints[i] if per_point else hints[0]
        if per_point and not (0 <= own < n_segments and is_cutting(seg_class[own])):
            out[i] = 0.0
            continue
        px = points[i, 0]
        py = points[i, 1]
        pz = points[i, 2]
        best = np.inf
        # Lines and flat arcs, the point's own segment first: then an arc whose circle is farther than the
        # best so far (the lower bound leaves a margin for rounding) needs no angle.
        if LINE <= seg_class[own] <= FLAT_ARC and first <= own < last:
            iu, iv, iw = axes[own, 0], axes[own, 1], axes[own, 2]
            best = _line_or_arc_d2(seg_class[own], geometry[own], iu, iv, iw, px, py, pz, points[i, iu],
                                   points[i, iv], points[i, iw])  # fmt: skip
        for s in range(first, last):
            c = seg_class[s]
            if c == LINE or (c == RAPID and s < own):
                d2 = _line_or_arc_d2(c, geometry[s], 0, 1, 2, px, py, pz, px, py, pz)
            elif c == FLAT_ARC:
                g = geometry[s]
                pu = points[i, axes[s, 0]]
                pv = points[i, axes[s, 1]]
                pw = points[i, axes[s, 2]]
                du = pu - g[0]
                dv = pv - g[1]
                dw = pw - g[2]
                off = math.sqrt(du * du + dv * dv) - g[3]
                if off * off + dw * dw > best * (1.0 + 1e-9):
                    continue
                d2 = _line_or_arc_d2(c, g, axes[s, 0], axes[s, 1], axes[s, 2], px, py, pz, pu, pv, pw)
            else:
                continue
            if d2 < best:
                best = d2
        if curved:
            # Helices and NURBS, the point's own segment first (usually the nearest: the others then fail
            # their lower bound).
            for step in range(last - first + 1):
                s = own if step == 0 else first + step - 1
                if (step > 0 and s == own) or not first <= s < last or not HELIX <= seg_class[s] <= NURBS:
                    continue
                iu, iv, iw = axes[s, 0], axes[s, 1], axes[s, 2]
                d2 = _curved_d2(seg_class[s], geometry, s, nurbs_i, nurbs_f, iu, iv, iw, px, py, pz,
                                points[i, iu], points[i, iv], points[i, iw], best, work)  # fmt: skip
                if d2 < best:
                    best = d2
        out[i] = math.sqrt(best)
    return first, last


class ContourErrorMeter:
    """Exact contour error of actual tool points against a :class:`~cnc_gym.toolpath.Toolpath`.

    ``window_back`` / ``window_ahead``: segments searched before / after the reference segment;
    ``window_back_mm``: the window also reaches back at least this far along the path (set it to a
    bound on the following error, e.g. max feed / Kv, for programs of very short segments).
    ``rapids_behind``: the rapids the reference has left (within the window) are part of the path the
    tool is measured against (the programmed-path rule, the default); False: cutting moves only (the
    rule of ``cnc_gym/Feedrate-v0`` and ``-v1``). See the module docstring for the rule.
    """

    def __init__(
        self,
        toolpath: Toolpath,
        window_back: int = 2,
        window_ahead: int = 8,
        window_back_mm: float = 0.0,
        rapids_behind: bool = True,
    ) -> None:
        if window_back < 0 or window_ahead < 0 or window_back_mm < 0:
            raise ValueError("contour window sizes must not be negative")
        self.toolpath = toolpath
        self.window_back = int(window_back)
        self.window_ahead = int(window_ahead)
        self.window_back_mm = float(window_back_mm)
        self.rapids_behind = bool(rapids_behind)
        self._n = len(toolpath)
        self.tables = pack_contour(toolpath, self.window_back, self.window_back_mm, self.rapids_behind)
        self._hint1 = np.zeros(1, dtype=np.int64)
        self.reset()

    def reset(self) -> None:
        """Nothing to forget between episodes (kept for callers; the tool path itself is immutable)."""

    # ------------------------------------------------------------------ windows
    def window(self, segment_hint: int | np.ndarray) -> tuple[int, int]:
        """``[first, last)`` segments searched for a reference on ``segment_hint`` (int or array)."""
        hint = np.asarray(segment_hint)
        lo, hi = (int(hint.min()), int(hint.max())) if hint.ndim else (int(hint), int(hint))
        first = int(self.tables.first_back[lo]) if 0 <= lo < self._n else max(0, lo - self.window_back)
        return first, min(self._n, hi + self.window_ahead + 1)

    # ------------------------------------------------------------------ measuring
    def measure(self, points: np.ndarray, segment_hint: int | np.ndarray) -> np.ndarray:
        """Contour error (mm) of each actual point, shape (m,).

        ``segment_hint`` is the reference's segment index: one int for all points, or one per point
        (then the window spans all of them and points whose own hint is a rapid/dwell get 0).
        """
        pts = points
        usual = type(pts) is np.ndarray and pts.dtype == np.float64 and pts.ndim == 2
        if not (usual and pts.flags.c_contiguous):
            pts = np.ascontiguousarray(points, dtype=np.float64)
            if pts.ndim == 1:
                pts = pts[None]
        m = len(pts)
        if pts.shape[1:] != (3,):
            raise ValueError(f"points must be (m, 3), got {pts.shape}")
        if isinstance(segment_hint, int | np.integer):
            hints = self._hint1
            hints[0] = segment_hint
        else:
            hints = np.asarray(segment_hint)
            if hints.ndim == 0:
                hints = np.array([int(hints)], dtype=np.int64)
            else:
                if hints.shape != (m,):
                    raise ValueError(f"segment_hint must be an int or shape ({m},), got {hints.shape}")
                if m == 0:
                    return np.zeros(0)
                hints = np.ascontiguousarray(hints, dtype=np.int64)
        out = np.empty(m)
        t = self.tables
        measure_kernel(pts, hints, t.seg_class, t.axes, t.geometry, t.first_back, t.nurbs_f, t.nurbs_i,
                       self.window_ahead, out)  # fmt: skip
        return out


def pack_contour(tp: Toolpath, window_back: int, window_back_mm: float,
                 rapids_behind: bool = True) -> ContourTables:  # fmt: skip
    """Per-segment kernel class, plane axes, geometry, window start and NURBS tables of ``tp``.

    ``rapids_behind``: rapids are RAPID lines (candidates behind the reference), else SKIP (never).
    """
    n = len(tp)
    kind = np.asarray(tp.kind)
    axes = np.ascontiguousarray(PLANE_AXES_TABLE[np.asarray(tp.plane).astype(np.int64)], dtype=np.int64)
    seg_class = np.full(n, SKIP, dtype=np.int64)
    geometry = np.zeros((n, N_GEOMETRY))
    nurbs_i = np.zeros((n, 5), dtype=np.int64)
    nurbs_blocks: list[np.ndarray] = []
    rows = np.arange(n)
    u, v, w = axes[:, 0], axes[:, 1], axes[:, 2]
    is_arc = kind == SegmentKind.ARC
    rise = tp.end[rows, w] - tp.start[rows, w]
    seg_class[kind == SegmentKind.LINE] = LINE
    seg_class[is_arc & (rise == 0)] = FLAT_ARC
    seg_class[is_arc & (rise != 0)] = HELIX
    seg_class[kind == SegmentKind.NURBS] = NURBS
    if rapids_behind:
        seg_class[kind == SegmentKind.RAPID] = RAPID

    lines = (kind == SegmentKind.LINE) | (kind == SegmentKind.RAPID)
    delta = tp.end - tp.start
    len2 = np.einsum("ij,ij->i", delta, delta)
    geometry[lines, 0:3] = tp.start[lines]
    geometry[lines, 3:6] = delta[lines]
    geometry[lines, 6] = np.where(len2[lines] > 0, 1.0 / np.where(len2[lines] > 0, len2[lines], 1.0), 0.0)

    a = np.flatnonzero(is_arc)
    k = np.arange(len(a))
    center = tp.center[a]
    cu, cv = center[k, u[a]], center[k, v[a]]
    radius, theta0, sweep = tp.radius[a], tp.start_angle[a], tp.sweep[a]
    w0 = tp.start[a, w[a]]
    geometry[a, 0] = cu
    geometry[a, 1] = cv
    geometry[a, 2] = w0
    geometry[a, 3] = radius
    geometry[a, 4] = theta0
    geometry[a, 5] = np.abs(sweep)
    geometry[a, 6] = np.where(sweep >= 0, 1.0, -1.0)
    # End points from the arc's geometry (as the reference service evaluates them; w at the start).
    for col, theta in ((7, theta0), (10, theta0 + sweep)):
        ends = np.empty((len(a), 3))
        ends[k, u[a]] = cu + radius * np.cos(theta)
        ends[k, v[a]] = cv + radius * np.sin(theta)
        ends[k, w[a]] = w0
        geometry[a, col : col + 3] = ends
    geometry[a, 13] = rise[a]
    geometry[a, 14] = sweep

    offset = 0
    for row in np.flatnonzero(kind == SegmentKind.NURBS):
        floats, header = nurbs_table(tp.nurbs[int(row)], offset)
        nurbs_blocks.append(floats)
        nurbs_i[row] = header
        offset += len(floats)
    nurbs_f = np.concatenate(nurbs_blocks) if nurbs_blocks else np.zeros(1)

    # First segment of the window for each lowest hint: window_back segments back, stretched back to cover
    # window_back_mm of path.
    first = np.maximum(0, rows - window_back)
    if window_back_mm > 0 and n:
        s_from = tp.s_start[:n] - window_back_mm
        by_mm = np.maximum(0, np.searchsorted(tp.s_start, s_from, side="right") - 1)
        first = np.minimum(first, by_mm)
    return ContourTables(seg_class, axes.reshape(n, 3), np.ascontiguousarray(geometry),
                         np.ascontiguousarray(first, dtype=np.int64), nurbs_f, nurbs_i)  # fmt: skip


def _dependencies() -> None:
    from cnc_gym.numba_cache import refresh_on_change
    from cnc_gym.toolpath import nearest

    refresh_on_change(__name__, [nearest])


_dependencies()  # the meter links the compiled helix and NURBS searches: drop it when they change
