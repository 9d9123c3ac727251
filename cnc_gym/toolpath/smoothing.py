"""Corner smoothing of short line segments within a geometric tolerance (GSK 25i "transition of small line
segment fold", parameter 1401#1 EFL with tolerance P1473 and corner angle P1495; Syntec G05.1 Q1 E).

A junction between two cutting lines in continuous mode is replaced by a cubic B-spline blend with five
control points ``C − d·u_in, C − d/2·u_in, C, C + d/2·u_out, C + d·u_out`` (C the corner, u the unit
directions, knots 0 0 0 0 ½ 1 1 1 1). The first three and the last three control points lie on the
programmed lines, so the blend leaves and joins them with the same tangent and zero curvature: the path is
G2-continuous (curvature continuous) through the blend. Its largest distance from the programmed corner is
``d · e(θ)`` for the turning angle θ (``e`` sampled once per corner on the unit blend), so ``d`` is the
largest length with ``d · e(θ) ≤ tolerance`` that leaves each line at most half of itself (two blends never
overlap). The lines are trimmed by ``d`` at the blended ends.

Only junctions where the controller would otherwise slow down in continuous mode are blended: both sides
cutting lines (not rapids, not arcs), no exact stop (G09/G61), dwell, tool or spindle change or rotary
motion between them, a turn of at most 180° − the minimum included angle, and (if set) both lines at most
``max_segment_mm`` long. The programmed path itself is never changed: :func:`smooth_corners` returns a new
tool path for the controller to follow and, per row, the programmed row it came from.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from cnc_gym.toolpath.kinds import SegmentKind, SegmentMode
from cnc_gym.toolpath.nurbs import NurbsCurve
from cnc_gym.toolpath.segments import Toolpath

#: Knots of the blend (clamped cubic, one interior knot).
BLEND_KNOTS = np.array([0.0, 0.0, 0.0, 0.0, 0.5, 1.0, 1.0, 1.0, 1.0])
#: Samples of the unit blend used to find its largest deviation (the maximum lies at the middle by symmetry;
#: the dense sample makes the bound independent of that argument).
_DEVIATION_SAMPLES = 257
#: Blends shorter than this are not worth a row: the corner stays a corner.
MIN_BLEND_MM = 1e-6
#: Relative safety margin on the sampled deviation (the controller follows the blend through a sampled
#: table, within 1e-9 mm).
_MARGIN = 1e-3


@dataclass(frozen=True, slots=True)
class SmoothingRules:
    """When and how far a junction is blended. ``tolerance_mm``: the machine's tolerance (0 = only where the
    tool path carries its own, ``Toolpath.smoothing_tolerance_mm``); ``min_angle_deg``: the smallest
    included angle blended (180° = collinear); ``max_segment_mm``: longest line blended (0 = any)."""

    tolerance_mm: float
    min_angle_deg: float = 150.0
    max_segment_mm: float = 0.0


def _unit_blend_deviation(turn: np.ndarray) -> np.ndarray:
    """Largest distance of the unit blend (d = 1) from the two programmed half-lines, per turning angle."""
    from scipy.interpolate import BSpline  # here, not at import: the interpreter alone never needs scipy

    m = len(turn)
    u_in = np.zeros((m, 2))
    u_in[:, 0] = 1.0
    u_out = np.column_stack((np.cos(turn), np.sin(turn)))
    ctrl = np.stack((-u_in, -0.5 * u_in, np.zeros((m, 2)), 0.5 * u_out, u_out), axis=1)  # (m, 5, 2)
    t = np.linspace(0.0, 1.0, _DEVIATION_SAMPLES)
    basis = BSpline.design_matrix(t, BLEND_KNOTS, 3).toarray()  # (samples, 5)
    points = np.einsum("sc,mcd->msd", basis, ctrl)  # (m, samples, 2)

    def to_segment(direction: np.ndarray, sign: float) -> np.ndarray:
        # segment from the corner (origin) to sign·direction: clamp the projection to [0, 1]
        along = np.clip(sign * np.einsum("msd,md->ms", points, direction), 0.0, 1.0)
        foot = sign * along[:, :, None] * direction[:, None, :]
        return np.linalg.norm(points - foot, axis=2)

    distance = np.minimum(to_segment(u_in, -1.0), to_segment(u_out, 1.0))
    return distance.max(axis=1)


@dataclass(frozen=True, eq=False)
class BlendCurve(NurbsCurve):
    """A corner blend: a :class:`NurbsCurve` (cubic, five control points, :data:`BLEND_KNOTS`) made in bulk
    by :func:`blend_curves`, which measures all lengths at once. The general curve's evaluation tables are
    built on first use (``at_length``, ``nearest``, ...); the controller samples blends in bulk with
    :func:`blend_tables` and never needs them."""

    def __post_init__(self) -> None:
        pass  # valid by construction; ``length`` is set by blend_curves

    def __getattr__(self, name: str):
        # Only reached for attributes not set yet: NurbsCurve's private tables. Build them all once.
        if name.startswith("_") and not name.startswith("__") and "_built" not in self.__dict__:
            length = self.__dict__["length"]
            object.__setattr__(self, "_built", True)
            NurbsCurve.__post_init__(self)
            object.__setattr__(self, "length", length)  # the measured length the tool path uses
            return getattr(self, name)
        raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")


def _control_points(corner: np.ndarray, u_in: np.ndarray, u_out: np.ndarray, d: np.ndarray) -> np.ndarray:
    """(m, 5, 3) control points of the blends."""
    dd = d[:, None]
    return np.stack((corner - dd * u_in, corner - 0.5 * dd * u_in, corner, corner + 0.5 * dd * u_out,
                     corner + dd * u_out), axis=1)  # fmt: skip


def blend_curves(corner: np.ndarray, u_in: np.ndarray, u_out: np.ndarray, d: np.ndarray) -> list[BlendCurve]:
    """The G2 blends of half-lengths ``d`` (m,) at ``corner`` (m, 3) between unit directions ``u_in`` and
    ``u_out`` (m, 3), with their arc lengths (Gauss-Legendre, to rounding)."""
    ctrl = _control_points(corner, u_in, u_out, d)
    lengths = _Blends(ctrl).total
    weights = np.ones(5)
    weights.flags.writeable = False
    knots = BLEND_KNOTS.copy()
    knots.flags.writeable = False
    out = []
    for points, length in zip(ctrl, lengths.tolist(), strict=True):
        points.flags.writeable = False
        curve = BlendCurve(points, weights, knots, 4)
        object.__setattr__(curve, "length", length)
        out.append(curve)
    return out


def blend_curve(corner: np.ndarray, u_in: np.ndarray, u_out: np.ndarray, d: float) -> BlendCurve:
    """One blend (see :func:`blend_curves`)."""
    return blend_curves(corner[None], u_in[None], u_out[None], np.array([d]))[0]


# ------------------------------------------------------------------------------- bulk sampling by arc length
_GL_X, _GL_W = np.polynomial.legendre.leggauss(6)
_INTERVALS_PER_SPAN = 32  # arc-length table resolution (each interval integrated by 6-point Gauss-Legendre)
_NEWTON_STEPS = 3


def _span_coefficients() -> np.ndarray:
    """(2, 4, 5): per knot span, the power-basis coefficients (u⁰..u³, local u ∈ [0, 1]) of the five basis
    functions."""
    from scipy.interpolate import BSpline

    coef = np.zeros((2, 4, 5))
    u = np.array([0.0, 1.0 / 3.0, 2.0 / 3.0, 1.0])
    for span in range(2):
        basis = BSpline.design_matrix(0.5 * (span + u), BLEND_KNOTS, 3).toarray()
        coef[span] = np.linalg.solve(np.vander(u, 4, increasing=True), basis)
    return coef


class _Blends:
    """Exact evaluation of many blends at once, by the parameter τ = span + u ∈ [0, 2], and by arc length."""

    _coef: np.ndarray | None = None

    def __init__(self, ctrl: np.ndarray) -> None:
        if _Blends._coef is None:
            _Blends._coef = _span_coefficients()
        # poly[m, span, r, xyz]: coefficient of u^r
        self.poly = np.einsum("srk,mkd->msrd", _Blends._coef, ctrl)
        m = len(ctrl)
        g = 2 * _INTERVALS_PER_SPAN
        self.tau = np.linspace(0.0, 2.0, g + 1)
        a, b = self.tau[:-1], self.tau[1:]
        nodes = 0.5 * (a + b)[:, None] + 0.5 * (b - a)[:, None] * _GL_X[None, :]  # (g, q)
        blend = np.repeat(np.arange(m), nodes.size)
        speed = np.linalg.norm(self.derivatives(blend, np.tile(nodes.ravel(), m))[1], axis=1)
        pieces = (speed.reshape(m, g, -1) * _GL_W).sum(axis=2) * 0.5 * (b - a)
        self.cum = np.concatenate((np.zeros((m, 1)), np.cumsum(pieces, axis=1)), axis=1)  # (m, g + 1)
        self.total = self.cum[:, -1].copy()

    def derivatives(self, blend: np.ndarray, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Point, d/dτ and d²/dτ² of blend ``blend[i]`` at ``tau[i]``."""
        span = np.minimum(tau.astype(np.int64), 1)
        u = (tau - span)[:, None]
        c = self.poly[blend, span]  # (n, 4, 3)
        point = c[:, 0] + u * (c[:, 1] + u * (c[:, 2] + u * c[:, 3]))
        d1 = c[:, 1] + u * (2.0 * c[:, 2] + 3.0 * u * c[:, 3])
        d2 = 2.0 * c[:, 2] + 6.0 * u * c[:, 3]
        return point, d1, d2

    def at_length(self, blend: np.ndarray, s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Point, unit tangent and curvature of blend ``blend[i]`` at arc length ``s[i]``."""
        n = len(s)
        point, tangent, curvature = np.zeros((n, 3)), np.zeros((n, 3)), np.zeros(n)
        _at_length_kernel(self.poly, self.tau, self.cum, blend.astype(np.int64), s.astype(np.float64), _GL_X,
                          _GL_W, point, tangent, curvature)  # fmt: skip
        return point, tangent, curvature


@njit(cache=True, inline="always")
def _d1(poly: np.ndarray, b: int, tau: float, out: np.ndarray) -> None:
    span = min(int(tau), 1)
    u = tau - span
    for k in range(3):
        out[k] = poly[b, span, 1, k] + u * (2.0 * poly[b, span, 2, k] + 3.0 * u * poly[b, span, 3, k])


@njit(cache=True)
def _at_length_kernel(poly: np.ndarray, grid: np.ndarray, cum: np.ndarray, blend: np.ndarray, s: np.ndarray,
                      gl_x: np.ndarray, gl_w: np.ndarray, point: np.ndarray, tangent: np.ndarray,
                      curvature: np.ndarray) -> None:  # fmt: skip
    """Arc length → parameter (the blend's cumulative table, then Newton on a Gauss-Legendre length from the
    interval start), then point, unit tangent and curvature."""
    g = len(grid) - 1
    d1 = np.zeros(3)
    e1 = np.zeros(3)
    e2 = np.zeros(3)
    for i in range(len(s)):
        b = blend[i]
        target = s[i]
        lo, hi = 0, g - 1  # interval with cum[lo] <= target (bisection)
        while lo < hi:
            mid = (lo + hi + 1) // 2
            if cum[b, mid] <= target:
                lo = mid
            else:
                hi = mid - 1
        a, c = grid[lo], grid[lo + 1]
        width = cum[b, lo + 1] - cum[b, lo]
        frac = (target - cum[b, lo]) / width if width > 0.0 else 0.0
        tau = a + min(max(frac, 0.0), 1.0) * (c - a)
        for _ in range(_NEWTON_STEPS):
            length = 0.0
            for q in range(len(gl_x)):
                _d1(poly, b, 0.5 * (a + tau) + 0.5 * (tau - a) * gl_x[q], d1)
                length += gl_w[q] * math.sqrt(d1[0] ** 2 + d1[1] ** 2 + d1[2] ** 2)
            length = cum[b, lo] + 0.5 * (tau - a) * length
            _d1(poly, b, tau, d1)
            speed = math.sqrt(d1[0] ** 2 + d1[1] ** 2 + d1[2] ** 2)
            if speed > 0.0:
                tau = min(max(tau - (length - target) / speed, a), c)
        span = min(int(tau), 1)
        u = tau - span
        for k in range(3):
            p0, p1 = poly[b, span, 0, k], poly[b, span, 1, k]
            p2, p3 = poly[b, span, 2, k], poly[b, span, 3, k]
            point[i, k] = p0 + u * (p1 + u * (p2 + u * p3))
            e1[k] = p1 + u * (2.0 * p2 + 3.0 * u * p3)
            e2[k] = 2.0 * p2 + 6.0 * u * p3
        speed = math.sqrt(e1[0] ** 2 + e1[1] ** 2 + e1[2] ** 2)
        if speed > 0.0:
            for k in range(3):
                tangent[i, k] = e1[k] / speed
            cx = e1[1] * e2[2] - e1[2] * e2[1]
            cy = e1[2] * e2[0] - e1[0] * e2[2]
            cz = e1[0] * e2[1] - e1[1] * e2[0]
            curvature[i] = math.sqrt(cx * cx + cy * cy + cz * cz) / speed**3


def blend_tables(curves: list[BlendCurve], pieces: list[int], tolerance_mm: float, first_samples: int,
                 max_samples: int) -> list[list[tuple[np.ndarray, np.ndarray, np.ndarray]]]:  # fmt: skip
    """Per blend, per piece (``pieces[i]`` pieces of equal arc length): point, unit tangent and curvature at
    equally spaced samples, refined per piece (first_samples, 2·first_samples − 1, … up to max_samples) until
    the cubic Hermite between samples is within ``tolerance_mm`` of the blend at every interval midpoint —
    the controller's NURBS table, for all blends at once."""
    blends = _Blends(np.array([c.control_points for c in curves]))
    lengths = np.array([c.length for c in curves])
    owner = np.repeat(np.arange(len(curves)), pieces)
    index = np.arange(len(owner)) - np.repeat(np.cumsum(pieces) - np.asarray(pieces), pieces)
    h = lengths[owner] / np.asarray(pieces)[owner]
    s0 = index * h
    samples = np.full(len(owner), first_samples, dtype=np.int64)
    result: list = [None] * len(owner)
    pending = np.arange(len(owner))
    while pending.size:
        n_int = samples[pending] - 1
        counts = n_int + 1
        rep = np.repeat(np.arange(len(pending)), counts)
        j = np.arange(int(counts.sum())) - np.repeat(np.cumsum(counts) - counts, counts)
        step = (h[pending] / n_int)[rep]
        s = np.minimum(s0[pending][rep] + j * step, lengths[owner[pending]][rep])
        blend = owner[pending][rep]
        point, tangent, curvature = blends.at_length(blend, s)
        interval = j < counts[rep] - 1
        mid_point, _, _ = blends.at_length(blend[interval], s[interval] + 0.5 * step[interval])
        starts = np.flatnonzero(interval)
        hermite = ((point[starts] + point[starts + 1]) / 2
                   + step[interval][:, None] / 8 * (tangent[starts] - tangent[starts + 1]))  # fmt: skip
        error = np.linalg.norm(hermite - mid_point, axis=1)
        worst = np.maximum.reduceat(error, np.cumsum(n_int) - n_int)
        again = (worst > tolerance_mm) & (samples[pending] < max_samples)
        offsets = np.cumsum(counts) - counts
        for piece, start, count, more in zip(pending.tolist(), offsets.tolist(), counts.tolist(),
                                             again.tolist(), strict=True):  # fmt: skip
            if not more:
                rows = slice(start, start + count)
                result[piece] = (point[rows], tangent[rows], curvature[rows])
        samples[pending[again]] = 2 * n_int[again] + 1
        pending = pending[again]
    out = []
    first = 0
    for k in pieces:
        out.append(result[first : first + k])
        first += k
    return out


def smooth_corners(tp: Toolpath, rules: SmoothingRules,
                   lookahead: bool = True) -> tuple[Toolpath, np.ndarray]:  # fmt: skip
    """The tool path with its eligible corners blended (see the module docstring), and per row of it the
    programmed row it belongs to (a blend belongs to the line it leaves). ``lookahead=False`` (a control
    that ends every block at rest) blends nothing. Returns ``tp`` itself and ``arange`` when nothing is
    blended."""
    n = len(tp)
    identity = np.arange(n)
    if n < 2 or not lookahead:
        return tp, identity
    row_tol = tp.smoothing_tolerance_mm
    if rules.tolerance_mm <= 0.0 and not np.any(row_tol > 0):
        return tp, identity
    a, b = np.arange(n - 1), np.arange(1, n)
    line = SegmentKind.LINE
    ok = (tp.kind[a] == line) & (tp.kind[b] == line)
    ok &= (tp.modes[a] & SegmentMode.EXACT_STOP) == 0
    ok &= (tp.tool[a] == tp.tool[b]) & (tp.spindle_rpm[a] == tp.spindle_rpm[b])
    if tp.rotary_axes:
        moves = np.any(tp.rotary_start != tp.rotary_end, axis=1)
        ok &= ~moves[a] & ~moves[b]
    length = tp.length
    ok &= (length[a] > MIN_BLEND_MM) & (length[b] > MIN_BLEND_MM)
    if rules.max_segment_mm > 0:
        ok &= (length[a] <= rules.max_segment_mm) & (length[b] <= rules.max_segment_mm)
    # The tool path's own tolerance (both rows carry one: the smaller), else the machine's.
    both = (row_tol[a] > 0) & (row_tol[b] > 0)
    tol = np.where(both, np.minimum(row_tol[a], row_tol[b]), rules.tolerance_mm)
    ok &= tol > 0
    with np.errstate(invalid="ignore", divide="ignore"):
        u = (tp.end - tp.start) / length[:, None]
    cos_turn = np.clip(np.sum(u[a] * u[b], axis=1), -1.0, 1.0)
    turn = np.arccos(cos_turn)
    max_turn = math.radians(180.0 - rules.min_angle_deg)
    ok &= (turn > 1e-9) & (turn <= max_turn + 1e-12)
    ok &= np.all(np.abs(tp.end[a] - tp.start[b]) <= 1e-9, axis=1)  # a true junction
    corners = np.flatnonzero(ok)
    if not len(corners):
        return tp, identity
    dev = _unit_blend_deviation(turn[corners]) * (1.0 + _MARGIN)
    d = tol[corners] / dev
    # Each line gives at most half of itself to each of its two blends.
    d = np.minimum(d, np.minimum(0.5 * length[corners], 0.5 * length[corners + 1]))
    keep = d > MIN_BLEND_MM
    corners, d = corners[keep], d[keep]
    if not len(corners):
        return tp, identity
    return _with_blends(tp, corners, d, u), _origin(n, corners)


def _origin(n: int, corners: np.ndarray) -> np.ndarray:
    """Programmed row of each row of the smoothed path: row i, then (after each blended corner i) i again."""
    count = np.ones(n, dtype=np.int64)
    count[corners] = 2
    return np.repeat(np.arange(n), count)


def _with_blends(tp: Toolpath, corners: np.ndarray, d: np.ndarray, u: np.ndarray) -> Toolpath:
    n = len(tp)
    origin = _origin(n, corners)
    # position of each programmed row, and of each blend (right after its incoming line)
    first = np.searchsorted(origin, np.arange(n), side="left")
    blend_rows = first[corners] + 1
    trim_end = np.zeros(n)
    trim_start = np.zeros(n)
    trim_end[corners] = d
    trim_start[corners + 1] = d
    start = tp.start[origin].copy()
    end = tp.end[origin].copy()
    rows = first  # programmed rows in the new path
    start[rows] = tp.start + trim_start[:, None] * np.nan_to_num(u)
    end[rows] = tp.end - trim_end[:, None] * np.nan_to_num(u)
    nurbs = {int(first[r]): c for r, c in tp.nurbs.items()}
    kind = tp.kind[origin].copy()
    feed = tp.feed[origin].copy()
    curves = blend_curves(tp.end[corners], u[corners], u[corners + 1], d)
    for row, corner, curve in zip(blend_rows.tolist(), corners.tolist(), curves, strict=True):
        nurbs[row] = curve
        kind[row] = SegmentKind.NURBS
        start[row] = curve.control_points[0]
        end[row] = curve.control_points[-1]
        feed[row] = min(tp.feed[corner], tp.feed[corner + 1])
    # A trimmed line keeps its modes; a blend runs in the modes of the line it leaves.
    return Toolpath(
        kind=kind, start=start, end=end, center=tp.center[origin], plane=tp.plane[origin],
        radius=tp.radius[origin], start_angle=tp.start_angle[origin], sweep=tp.sweep[origin], feed=feed,
        dwell_s=tp.dwell_s[origin], line=tp.line[origin], file_index=tp.file_index[origin],
        modes=tp.modes[origin], tool=tp.tool[origin], spindle_rpm=tp.spindle_rpm[origin], files=tp.files,
        nurbs=nurbs, rotary_axes=tp.rotary_axes, rotary_start=tp.rotary_start[origin],
        rotary_end=tp.rotary_end[origin], smoothing_tolerance_mm=tp.smoothing_tolerance_mm[origin],
        machine_functions=_moved_rows(tp.machine_functions, origin, kind), notices=tp.notices,
    )  # fmt: skip


def _moved_rows(by_row, origin: np.ndarray, kind: np.ndarray) -> dict[int, str]:
    """A row → value mapping of the dwell rows, carried to their new indices (``origin[new] = old``)."""
    if not by_row:
        return {}
    dwells = np.flatnonzero(kind == SegmentKind.DWELL)
    return {int(new): by_row[int(origin[new])] for new in dwells if int(origin[new]) in by_row}
