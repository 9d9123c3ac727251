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

from cnc_gym.toolpath.nurbs import NurbsCurve
from cnc_gym.toolpath.segments import SegmentKind, SegmentMode, Toolpath

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


def blend_curve(corner: np.ndarray, u_in: np.ndarray, u_out: np.ndarray, d: float) -> NurbsCurve:
    """The G2 blend of half-length ``d`` at ``corner`` between directions ``u_in`` and ``u_out``."""
    ctrl = np.array([corner - d * u_in, corner - 0.5 * d * u_in, corner, corner + 0.5 * d * u_out,
                     corner + d * u_out])  # fmt: skip
    return NurbsCurve(ctrl, np.ones(5), BLEND_KNOTS, order=4)


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
    for row, corner, dd in zip(blend_rows.tolist(), corners.tolist(), d.tolist(), strict=True):
        c = tp.end[corner]
        curve = blend_curve(c, u[corner], u[corner + 1], dd)
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
    )  # fmt: skip
