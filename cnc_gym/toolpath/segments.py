"""The canonical tool path: what the interpreter emits and every later stage reads.

A :class:`Toolpath` is immutable and array-backed: one row per segment, one numpy array per field, in
machine coordinates (mm, s, mm/min). Building one goes through :class:`ToolpathBuilder`, which the
interpreter appends to block by block; ``build()`` freezes the arrays.

Arc convention (the same as the ``cnc-gym trace`` contract): a plane is named by its two in-plane axes
``(u, v)`` and its normal ``w`` with ``u × v = w`` — XY (normal +Z), ZX (normal +Y), YZ (normal +X). The
sweep is signed: positive is counter-clockwise seen from the + end of the normal (G03), negative is
clockwise (G02). The centre's normal coordinate is the start's; a helix rises linearly in ``w``.

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from itertools import chain
from operator import itemgetter

import numpy as np

from cnc_gym.defaults import INCH_MM
from cnc_gym.frozen import FrozenDict
from cnc_gym.toolpath.kinds import PLANE_AXES, PLANE_AXES_TABLE, Plane, SegmentKind, SegmentMode
from cnc_gym.toolpath.nurbs import NurbsCurve

_FIELDS = (
    "kind", "start", "end", "center", "plane", "radius", "start_angle", "sweep", "feed",
    "dwell_s", "line", "file_index", "modes", "tool", "spindle_rpm",
)  # fmt: skip


@dataclass(frozen=True, eq=False)
class Toolpath:
    """An immutable sequence of segments. Every array has one row per segment.

    Fields (n = number of segments):

    ==============  ===========  ====================================================================
    kind            int8 (n)     :class:`SegmentKind`
    start, end      float (n,3)  start and end point, machine coordinates, mm
    center          float (n,3)  arc centre (NaN for non-arcs); normal coordinate = start's
    plane           int8 (n)     :class:`Plane` of an arc (0 otherwise)
    radius          float (n)    arc radius, mm (0 otherwise)
    start_angle     float (n)    angle of ``start - center`` in the (u, v) plane, rad
    sweep           float (n)    signed swept angle, rad (+ = CCW about the plane normal)
    feed            float (n)    programmed feed, mm/min (NaN for rapids and dwells)
    dwell_s         float (n)    dwell time, s (0 otherwise)
    line            int32 (n)    1-based source line of the block that produced the segment
    file_index      int16 (n)    index into ``files`` (subprograms live in other files)
    modes           uint8 (n)    :class:`SegmentMode` flags
    tool            int32 (n)    active tool number (T)
    spindle_rpm     float (n)    commanded spindle speed (S), signed by direction (M03 +, M04 -, M05 0)
    ==============  ===========  ====================================================================

    ``nurbs`` maps the index of every NURBS row to its exact :class:`NurbsCurve` (read-only mapping); the
    row's ``start``/``end`` are the curve's first/last control points and its ``length`` the curve's arc
    length. A NURBS row is evaluated by arc length like every other row.

    ``machine_functions`` maps the index of a dwell row to the machine function it stands for (``"M13"``):
    an M code the control hands to the machine (coolant, clamps, conveyors …), which waits for it at rest
    (a 0 s exact-stop dwell). ``notices``: one-line notes the interpreter made about the program (text it
    did not run, a setting the program seems to need), ``FILE:LINE: note: … [code]``.

    Rotary axes (machines with A/B/C): ``rotary_axes`` names them (``"B"``; ``""`` on a 3-axis path) and
    ``rotary_start``/``rotary_end`` (n, k) hold each row's start and end angle in degrees, machine
    coordinates. Only rapids and lines move them (linearly with the row). ``length`` stays the XYZ length;
    ``rotary_travel`` is the rotary part of the move and ``path_feed`` the resulting XYZ feed.
    """

    kind: np.ndarray
    start: np.ndarray
    end: np.ndarray
    center: np.ndarray
    plane: np.ndarray
    radius: np.ndarray
    start_angle: np.ndarray
    sweep: np.ndarray
    feed: np.ndarray
    dwell_s: np.ndarray
    line: np.ndarray
    file_index: np.ndarray
    modes: np.ndarray
    tool: np.ndarray
    spindle_rpm: np.ndarray
    files: tuple[str, ...] = ("<program>",)
    #: exact NURBS curves by segment index (exactly the rows with kind == NURBS).
    nurbs: Mapping[int, NurbsCurve] = field(default_factory=dict)
    rotary_axes: str = ""
    rotary_start: np.ndarray | None = None
    rotary_end: np.ndarray | None = None
    smoothing_tolerance_mm: np.ndarray | None = None
    #: Dwell rows that stand for a machine function: row index → its M code (``"M13"``).
    machine_functions: Mapping[int, str] = field(default_factory=dict)
    #: One-line notes about the program (``FILE:LINE: note: message [code]``), in the order they were made.
    notices: tuple[str, ...] = ()
    # Derived geometry, filled in __post_init__.
    length: np.ndarray = field(init=False, repr=False)
    planar_length: np.ndarray = field(init=False, repr=False)
    s_start: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        n = len(self.kind)
        for name in _FIELDS:
            arr = getattr(self, name)
            if len(arr) != n:
                raise ValueError(f"toolpath field {name!r} has {len(arr)} rows, expected {n}")
        delta = self.end - self.start
        chord = np.linalg.norm(delta, axis=1)
        is_arc = self.kind == SegmentKind.ARC
        arc_planar = self.radius * np.abs(self.sweep)
        rise = self._rise()
        helix = np.hypot(arc_planar, rise)
        length = np.where(is_arc, helix, np.where(self.kind == SegmentKind.DWELL, 0.0, chord))
        nurbs_rows = np.flatnonzero(self.kind == SegmentKind.NURBS)
        if set(self.nurbs) != set(nurbs_rows.tolist()):
            raise ValueError(f"toolpath NURBS curves are given for rows {sorted(self.nurbs)}, but the NURBS "
                             f"rows are {nurbs_rows.tolist()}")  # fmt: skip
        for row, curve in self.nurbs.items():
            if not isinstance(curve, NurbsCurve):
                raise ValueError(f"toolpath row {row}: a NURBS row needs a NurbsCurve, "
                                 f"got {type(curve).__name__}")  # fmt: skip
            length[row] = curve.length
        object.__setattr__(self, "nurbs", FrozenDict(self.nurbs))
        for row in self.machine_functions:
            if not 0 <= row < n or self.kind[row] != SegmentKind.DWELL:
                raise ValueError(f"toolpath row {row}: a machine function stands on a dwell row")
            if not self.modes[row] & SegmentMode.MACHINE_FUNCTION:
                raise ValueError(f"toolpath row {row}: a machine function's row carries MACHINE_FUNCTION")
        object.__setattr__(self, "machine_functions", FrozenDict(self.machine_functions))
        object.__setattr__(self, "notices", tuple(self.notices))
        k = len(self.rotary_axes)
        for name in ("rotary_start", "rotary_end"):
            arr = getattr(self, name)
            arr = np.zeros((n, k)) if arr is None else np.asarray(arr, dtype=np.float64).reshape(n, k)
            object.__setattr__(self, name, arr)
        smoothing = (np.zeros(n) if self.smoothing_tolerance_mm is None else
                     np.asarray(self.smoothing_tolerance_mm, dtype=np.float64).reshape(n))  # fmt: skip
        if np.any(~(smoothing >= 0.0)):
            raise ValueError("toolpath smoothing tolerances must be non-negative numbers")
        object.__setattr__(self, "smoothing_tolerance_mm", smoothing)
        if k:
            moved = np.any(self.rotary_start != self.rotary_end, axis=1)
            bad = moved & (self.kind != SegmentKind.LINE) & (self.kind != SegmentKind.RAPID)
            if np.any(bad):
                raise ValueError(f"toolpath row {int(np.flatnonzero(bad)[0])}: only rapids and lines move "
                                 "rotary axes")  # fmt: skip
        planar = np.where(is_arc, arc_planar, length)
        s_start = np.concatenate(([0.0], np.cumsum(length)))
        object.__setattr__(self, "length", length)
        object.__setattr__(self, "planar_length", planar)
        object.__setattr__(self, "s_start", s_start)
        for name in (*_FIELDS, "length", "planar_length", "s_start", "rotary_start", "rotary_end",
                     "smoothing_tolerance_mm"):
            getattr(self, name).flags.writeable = False

    # ------------------------------------------------------------------ basics
    def __len__(self) -> int:
        return len(self.kind)

    @property
    def total_length(self) -> float:
        """Path length of all motion segments (rapids included), mm."""
        return float(self.s_start[-1])

    @property
    def rotary_travel(self) -> np.ndarray:
        """Length of each row's rotary move, √(ΣΔ²) over the rotary axes, degrees (0 without them)."""
        if not self.rotary_axes:
            return np.zeros(len(self))
        return np.linalg.norm(self.rotary_end - self.rotary_start, axis=1)

    @property
    def rotary_length(self) -> np.ndarray:
        """The rotary travel as the feed counts it: degrees as mm, or as inch in a G20 program (so 25.4 mm
        per degree there), mm. F covers √(length² + rotary_length²) per minute (§3.2.2)."""
        inch = (self.modes & SegmentMode.INCH_PROGRAM) != 0
        return self.rotary_travel * np.where(inch, INCH_MM, 1.0)

    @property
    def path_feed(self) -> np.ndarray:
        """Programmed feed along the 3-D path, mm/min.

        GSK 25i (manual §3.2.3): on a helix, F is the speed of the arc's projection on the plane, so the
        speed along the helix is F · length / planar_length. Lines and flat arcs: F itself.
        With rotary axes (§3.2.2) F is the rate along the composite vector with degrees counted as mm,
        so the XYZ feed of a line is F · length / √(length² + rotary_travel²).
        """
        ratio = np.divide(self.length, self.planar_length, out=np.ones_like(self.length),
                          where=self.planar_length > 0)  # fmt: skip
        if self.rotary_axes:
            composite = np.hypot(self.length, self.rotary_length)
            ratio = ratio * np.divide(self.length, composite, out=np.ones_like(self.length),
                                      where=composite > 0)  # fmt: skip
        return self.feed * ratio

    def _rise(self) -> np.ndarray:
        """Helix rise along the plane normal (0 for flat arcs and non-arcs)."""
        w = PLANE_AXES_TABLE[self.plane.astype(np.int64), 2]
        rows = np.arange(len(self.kind))
        rise = self.end[rows, w] - self.start[rows, w]
        return np.where(self.kind == SegmentKind.ARC, rise, 0.0)

    def source(self, index: int) -> tuple[str, int]:
        """(file, line) of segment ``index``."""
        return self.files[int(self.file_index[index])], int(self.line[index])

    # --------------------------------------------------------------- geometry
    def extreme_points(self, rows: np.ndarray | None = None) -> list[tuple[np.ndarray, np.ndarray]]:
        """The points a range check must see, as (segment indices, points (k, 3)) pairs: the end of each
        segment of ``rows`` (default all), and for its arcs the axis extremes their sweep passes (0°, 90°,
        180°, 270° in the plane). Travel and software-limit checks use it."""
        rows = np.arange(len(self.kind)) if rows is None else rows
        out = [(rows, self.end[rows])]
        arcs = rows[self.kind[rows] == SegmentKind.ARC]
        if not len(arcs):
            return out
        axes = PLANE_AXES_TABLE[self.plane[arcs].astype(np.int64)]
        k = np.arange(len(arcs))
        start_angle, sweep = self.start_angle[arcs], self.sweep[arcs]
        radius, center = self.radius[arcs], self.center[arcs]
        for theta in (0.0, 0.5 * np.pi, np.pi, 1.5 * np.pi):
            ccw_turn = (theta - start_angle) % (2 * np.pi)
            turned = np.where(sweep >= 0, ccw_turn, (2 * np.pi - ccw_turn) % (2 * np.pi))
            passed = turned <= np.abs(sweep) + 1e-12
            point = self.start[arcs].copy()
            point[k, axes[:, 0]] = center[k, axes[:, 0]] + radius * np.cos(theta)
            point[k, axes[:, 1]] = center[k, axes[:, 1]] + radius * np.sin(theta)
            out.append((arcs[passed], point[passed]))
        return out

    def segment_at(self, s: np.ndarray | float) -> np.ndarray:
        """Index of the segment containing arc length ``s`` (zero-length segments are never returned).
        An empty tool path has no segment to return: ValueError."""
        if not len(self):
            raise ValueError("the tool path is empty: no segment contains any arc length")
        s_arr = np.clip(np.asarray(s, dtype=float), 0.0, self.total_length)
        idx = np.searchsorted(self.s_start, s_arr, side="right") - 1
        idx = np.clip(idx, 0, max(len(self) - 1, 0))
        # Skip backwards over zero-length segments (dwells) at the very end of the path.
        if np.any(self.length[idx] == 0) and len(self):
            nonzero = np.flatnonzero(self.length > 0)
            if len(nonzero):
                pos = np.searchsorted(nonzero, idx, side="right") - 1
                idx = nonzero[np.clip(pos, 0, len(nonzero) - 1)]
        return idx

    def evaluate(self, s: np.ndarray | float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Point, unit tangent and curvature (1/mm) at arc length(s) ``s``. Vectorised over ``s``.

        Returns arrays of shape (m, 3), (m, 3), (m,) (m = number of query values).
        """
        s_arr = np.atleast_1d(np.asarray(s, dtype=float))
        idx = self.segment_at(s_arr)
        local = np.clip(s_arr - self.s_start[idx], 0.0, self.length[idx])
        return self._evaluate_local(idx, local)

    def _evaluate_local(
        self, idx: np.ndarray, local: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        m = len(idx)
        point = np.empty((m, 3))
        tangent = np.zeros((m, 3))
        curvature = np.zeros(m)
        kind = self.kind[idx]
        length = self.length[idx]

        straight = (kind == SegmentKind.LINE) | (kind == SegmentKind.RAPID) | (kind == SegmentKind.DWELL)
        if np.any(straight):
            i = idx[straight]
            delta = self.end[i] - self.start[i]
            ln = length[straight]
            safe = np.where(ln > 0, ln, 1.0)
            frac = np.where(ln > 0, local[straight] / safe, 0.0)
            point[straight] = self.start[i] + delta * frac[:, None]
            tangent[straight] = delta / safe[:, None]

        arcs = kind == SegmentKind.ARC
        if np.any(arcs):
            i = idx[arcs]
            frac = np.where(length[arcs] > 0, local[arcs] / np.where(length[arcs] > 0, length[arcs], 1), 0)
            p, t, k = self._arc_geometry(i, frac)
            point[arcs], tangent[arcs], curvature[arcs] = p, t, k

        nurbs = kind == SegmentKind.NURBS
        if np.any(nurbs):
            rows = np.flatnonzero(nurbs)
            for segment in np.unique(idx[rows]):  # usually one curve per call
                sel = rows[idx[rows] == segment]
                point[sel], tangent[sel], curvature[sel] = self.nurbs[int(segment)].at_length(local[sel])
        return point, tangent, curvature

    def _arc_geometry(self, i: np.ndarray, frac: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Point, unit tangent and curvature on arcs ``i`` at fraction ``frac`` of their sweep."""
        axes = PLANE_AXES_TABLE[self.plane[i].astype(np.int64)]
        u, v, w = axes[:, 0], axes[:, 1], axes[:, 2]
        rows = np.arange(len(i))
        radius = self.radius[i]
        sweep = self.sweep[i]
        rise = self.end[i, w] - self.start[i, w]
        theta = self.start_angle[i] + sweep * frac
        cos_t, sin_t = np.cos(theta), np.sin(theta)
        point = np.empty((len(i), 3))
        point[rows, u] = self.center[i, u] + radius * cos_t
        point[rows, v] = self.center[i, v] + radius * sin_t
        point[rows, w] = self.start[i, w] + rise * frac
        # d(point)/d(frac), then normalise.
        deriv = np.empty((len(i), 3))
        deriv[rows, u] = -radius * sin_t * sweep
        deriv[rows, v] = radius * cos_t * sweep
        deriv[rows, w] = rise
        norm = np.linalg.norm(deriv, axis=1)
        tangent = deriv / np.where(norm > 0, norm, 1.0)[:, None]
        # Helix curvature r / (r² + c²), c = rise per radian.
        pitch = np.divide(rise, np.abs(sweep), out=np.zeros_like(rise), where=np.abs(sweep) > 0)
        curvature = np.divide(radius, radius**2 + pitch**2, out=np.zeros_like(radius),
                              where=radius > 0)  # fmt: skip
        return point, tangent, curvature

    def sample(self, spacing_mm: float) -> tuple[np.ndarray, np.ndarray]:
        """Points every ``spacing_mm`` of arc length (plus every segment end). Returns (s, points)."""
        if spacing_mm <= 0:
            raise ValueError("spacing_mm must be positive")
        s = np.concatenate((np.arange(0.0, self.total_length, spacing_mm), self.s_start))
        s = np.unique(s)
        point, _, _ = self.evaluate(s)
        return s, point

    def nearest(
        self,
        points: np.ndarray,
        first: int = 0,
        last: int | None = None,
        *,
        cutting_only: bool = True,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Exact distance from each point to the path between segments ``first`` and ``last`` (exclusive).

        ``cutting_only`` leaves rapids out (contour error is defined on cutting moves only). Returns
        ``(distance_mm, segment_index, s)`` arrays of shape (m,). Where no segment qualifies the distance
        is ``inf`` and the index ``-1``. Vectorised over points × segments; pass a moving window for speed.
        """
        from cnc_gym.toolpath.nearest import nearest_on_segments

        last = len(self) if last is None else min(last, len(self))
        return nearest_on_segments(self, np.atleast_2d(np.asarray(points, dtype=float)), first, last,
                                   cutting_only)  # fmt: skip

    def to_records(self) -> list[dict]:
        """One dict per segment in the ``cnc-gym trace`` JSON Lines shape."""
        from cnc_gym.toolpath.records import toolpath_records

        return toolpath_records(self)


#: Row fields of :class:`ToolpathBuilder`'s tuples, by position (the order of ``_FIELDS``).
_KIND, _START, _END, _RADIUS, _SWEEP, _FEED, _DWELL_S, _TOOL, _LINE, _FILE_INDEX = (
    _FIELDS.index(name)
    for name in ("kind", "start", "end", "radius", "sweep", "feed", "dwell_s", "tool", "line", "file_index"))
_NAN3 = (float("nan"),) * 3
_RAPID, _LINE_KIND, _ARC, _DWELL, _NURBS = (int(k) for k in SegmentKind)
_NO_MODES = SegmentMode.NONE
_DTYPES = {"kind": np.int8, "plane": np.int8, "line": np.int32, "file_index": np.int16, "modes": np.uint8,
           "tool": np.int32}  # fmt: skip
_POINT_FIELDS = ("start", "end", "center")


def _nominal_seconds(row: tuple, rapid_mm_min: float) -> float:
    """One builder row's seconds at its programmed feed (rapids at ``rapid_mm_min``; no acceleration)."""
    kind = row[_KIND]
    if kind == _DWELL:
        return row[_DWELL_S]
    start, end = row[_START], row[_END]
    if kind == _ARC:
        plane_length = abs(row[_SWEEP]) * row[_RADIUS]
        chord = math.dist(start, end)
        length = math.hypot(plane_length, chord) if plane_length < chord else plane_length
    else:
        length = math.dist(start, end)
    speed = rapid_mm_min if kind == _RAPID else row[_FEED]
    return 60.0 * length / speed if speed and math.isfinite(speed) else 0.0


#: Most notes one tool path keeps (a program that repeats one oddity a million times gets one line for it,
#: and a program with a thousand different ones a bounded list).
MAX_NOTICES = 50


class ToolpathBuilder:
    """Appends segments row by row (one plain tuple per row, fields in the order of ``_FIELDS``: one list
    append per segment on the interpreter's hot path) and freezes them into a Toolpath."""

    def __init__(self, files: tuple[str, ...] = ("<program>",), rotary_axes: str = "",
                 rotary_position: tuple[float, ...] | None = None) -> None:  # fmt: skip
        self.files = list(files)
        self._rows: list[tuple] = []
        self.nurbs_curves: dict[int, NurbsCurve] = {}
        # Rotary axes: the start position, then (row, start, end) for every row that moves them (the rows
        # in between hold the position: filled in by build()).
        self.rotary_axes = rotary_axes
        self.rotary_origin = tuple(rotary_position or (0.0,) * len(rotary_axes))
        self._rotary_moves: list[tuple[int, tuple[float, ...], tuple[float, ...]]] = []
        # Smoothing tolerances: (first row, {segment kind: tolerance mm}) from that row on (sparse: the
        # rows in between cost nothing while they are appended; build() fills the column).
        self._smoothing: list[tuple[int, dict[int, float]]] = []
        #: The M codes of the machine-function dwells, in the order they were made (build() pairs them with
        #: the rows flagged MACHINE_FUNCTION, which a look-ahead stage may append later), and the notes.
        self.machine_functions: list[str] = []
        self.notices: list[str] = []
        self._notices_dropped = 0

    def notice(self, text: str) -> None:
        """Keep one note about the program (each text once, at most :data:`MAX_NOTICES` of them; the rest
        are counted in a last line)."""
        if text in self.notices:
            return
        if len(self.notices) >= MAX_NOTICES:
            self._notices_dropped += 1
            return
        self.notices.append(text)

    def __len__(self) -> int:
        return len(self._rows)

    def last_source(self) -> tuple[int, int] | None:
        """(file index, line) of the last row, or None before the first."""
        if not self._rows:
            return None
        row = self._rows[-1]
        return int(row[_FILE_INDEX]), int(row[_LINE])

    def kinds_since(self, first: int) -> list[int]:
        """The :class:`SegmentKind` values of the rows from ``first`` on."""
        return [row[_KIND] for row in self._rows[first:]]

    def nominal_seconds_since(self, first: int, rapid_mm_min: float, total: float = 0.0) -> float:
        """``total`` plus the seconds of the rows from ``first`` on at their programmed feeds (rapids at
        ``rapid_mm_min``, dwells their time; no acceleration): the clock of a controller without a motion
        model."""
        for row in self._rows[first:]:
            total += _nominal_seconds(row, rapid_mm_min)
        return total

    def tool_seconds_since(self, first: int, rapid_mm_min: float, totals: dict[int, list[float]]) -> None:
        """Add to ``totals`` (tool number → [seconds in the spindle, seconds cutting]) the nominal seconds of
        the rows from ``first`` on (the clock of :meth:`nominal_seconds_since`), by the row's tool."""
        for row in self._rows[first:]:
            seconds = _nominal_seconds(row, rapid_mm_min)
            entry = totals.setdefault(int(row[_TOOL]), [0.0, 0.0])
            entry[0] += seconds
            if row[_KIND] not in (_RAPID, _DWELL):
                entry[1] += seconds

    def file_index(self, file: str) -> int:
        if file not in self.files:
            self.files.append(file)
        return self.files.index(file)

    def rapid(self, start, end, line: int, file_index: int = 0, modes: SegmentMode = _NO_MODES, tool: int = 0,
              spindle_rpm: float = 0.0) -> None:  # fmt: skip
        self._rows.append((_RAPID, tuple(start), tuple(end), _NAN3, 0, 0.0, 0.0, 0.0, math.nan, 0.0, line,
                           file_index, modes, tool, spindle_rpm))  # fmt: skip

    def line(self, start, end, feed: float, line: int, file_index: int = 0, modes: SegmentMode = _NO_MODES,
             tool: int = 0, spindle_rpm: float = 0.0) -> None:  # fmt: skip
        self._rows.append((_LINE_KIND, tuple(start), tuple(end), _NAN3, 0, 0.0, 0.0, 0.0, feed, 0.0, line,
                           file_index, modes, tool, spindle_rpm))  # fmt: skip

    def arc(self, start, end, center, plane: Plane, sweep: float, feed: float, line: int, file_index: int = 0,
            modes: SegmentMode = _NO_MODES, tool: int = 0, spindle_rpm: float = 0.0) -> None:  # fmt: skip
        """Append an arc/helix. ``center``'s normal coordinate is replaced by the start's."""
        u, v, w = PLANE_AXES[plane]
        c = list(center)
        c[w] = start[w]
        du, dv = float(start[u] - c[u]), float(start[v] - c[v])
        # Scalar math, not numpy scalars: this runs once per arc block on the interpreter's hot path.
        self._rows.append((_ARC, tuple(start), tuple(end), tuple(c), int(plane), math.hypot(du, dv),
                           math.atan2(dv, du), sweep, feed, 0.0, line, file_index, modes, tool,
                           spindle_rpm))  # fmt: skip

    def nurbs(self, curve: NurbsCurve, feed: float, **kw) -> None:
        """Append an exact NURBS segment from the curve's first to its last control point."""
        if not isinstance(curve, NurbsCurve):
            raise TypeError(f"ToolpathBuilder.nurbs needs a NurbsCurve, got {type(curve).__name__}")
        self.nurbs_curves[len(self)] = curve
        start = tuple(float(x) for x in curve.control_points[0])
        end = tuple(float(x) for x in curve.control_points[-1])
        self._append(_NURBS, start, end, feed=feed, **kw)

    def dwell(self, position, seconds: float, **kw) -> None:
        self._append(_DWELL, tuple(position), tuple(position), dwell_s=seconds, **kw)

    def _append(self, kind: int, start: tuple, end: tuple, *, line: int, file_index: int = 0,
                feed: float = math.nan, dwell_s: float = 0.0, modes: SegmentMode = _NO_MODES, tool: int = 0,
                spindle_rpm: float = 0.0) -> None:  # fmt: skip
        """A row without arc data (NURBS, dwell)."""
        self._rows.append((kind, start, end, _NAN3, 0, 0.0, 0.0, 0.0, feed, dwell_s, line, file_index, modes,
                           tool, spindle_rpm))  # fmt: skip

    def move_rotary(self, start: tuple[float, ...], end: tuple[float, ...]) -> None:
        """The row just appended (a rapid or a line) also moves the rotary axes from ``start`` to ``end``."""
        self._rotary_moves.append((len(self) - 1, tuple(start), tuple(end)))

    def smoothing(self, tolerances: Mapping[SegmentKind, float]) -> None:
        """From the next row on, rows of each kind in ``tolerances`` carry its smoothing tolerance (mm);
        rows of other kinds carry 0. ``{}`` ends smoothing."""
        self._smoothing.append((len(self), {int(k): float(v) for k, v in tolerances.items() if v > 0}))

    def _smoothing_array(self, kinds: np.ndarray) -> np.ndarray:
        out = np.zeros(len(kinds))
        runs = self._smoothing
        for index, (first, tolerances) in enumerate(runs):
            last = runs[index + 1][0] if index + 1 < len(runs) else len(kinds)
            for kind, tolerance in tolerances.items():
                rows = np.flatnonzero(kinds[first:last] == kind) + first
                out[rows] = tolerance
        return out

    def _rotary_arrays(self, n: int) -> tuple[np.ndarray, np.ndarray]:
        k = len(self.rotary_axes)
        start = np.empty((n, k))
        end = np.empty((n, k))
        position = self.rotary_origin
        done = 0
        for row, first, last in self._rotary_moves:
            start[done:row] = end[done:row] = position
            start[row], end[row] = first, last
            position, done = last, row + 1
        start[done:] = end[done:] = position
        return start, end

    def build(self) -> Toolpath:
        rows, n = self._rows, len(self._rows)
        arrays = {}
        # Column by column, straight from the row tuples (np.fromiter: no intermediate lists).
        for index, name in enumerate(_FIELDS):
            dtype = _DTYPES.get(name, np.float64)
            if name in _POINT_FIELDS:
                points = chain.from_iterable(map(itemgetter(index), rows))
                arrays[name] = np.fromiter(points, dtype, count=3 * n).reshape(n, 3)
            else:
                arrays[name] = np.fromiter(map(itemgetter(index), rows), dtype, count=n)
        rotary_start, rotary_end = self._rotary_arrays(len(self))
        smoothing = self._smoothing_array(arrays["kind"]) if self._smoothing else None
        flagged = np.flatnonzero(arrays["modes"] & SegmentMode.MACHINE_FUNCTION).tolist()
        if len(flagged) != len(self.machine_functions):
            raise ValueError(f"{len(flagged)} machine-function rows for {len(self.machine_functions)} codes")
        functions = dict(zip(flagged, self.machine_functions, strict=True))
        notices = tuple(self.notices)
        if self._notices_dropped:
            notices += (f"... and {self._notices_dropped} more notes",)
        return Toolpath(**arrays, files=tuple(self.files), nurbs=dict(self.nurbs_curves),
                        rotary_axes=self.rotary_axes, rotary_start=rotary_start,
                        rotary_end=rotary_end, smoothing_tolerance_mm=smoothing,
                        machine_functions=functions, notices=notices)  # fmt: skip
