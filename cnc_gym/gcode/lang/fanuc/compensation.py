"""Tool compensation: cutter radius compensation C (G40/G41/G42, G39), tool length and position offsets.

Two layers:

* **Plane geometry** (pure functions): a programmed move projected on the compensation plane is a
  :class:`PlaneElement` (line or arc). :func:`offset_curve` gives its offset line/circle,
  :func:`corner` the tool-centre points at the junction of two elements (GSK/Fanuc type C, §3.5.2-§3.5.3):
  intersection points at inner corners and outer corners of 90° or more, extension points (two or three extra
  points) at outer corners under 90°, start-up and cancel of type A or B. :func:`correct_interference` is the
  interference check (alarm 41) with the manual's correction before it alarms (interfering corner-vector pairs
  ignored from the inside out, an arc turned into a line, §3.5.3). :func:`compensate` runs a whole sequence
  (start-up line, offset-mode moves, cancel line).
* **The stage** (:class:`OffsetStage`): sits between the interpreter and the
  :class:`~cnc_gym.gcode.canonical.CanonicalMachine` with the same interface (``straight_traverse``,
  ``straight_feed``, ``arc_feed``, ``dwell``, ``position``, context attributes). It receives programmed
  moves in machine coordinates (after the work offsets), keeps the look-ahead the corners need (the
  manual's three-block buffer: a corner is resolved with the next move in the plane if it comes within
  the next two blocks, else the vector is perpendicular to the block, §3.5.3), and emits
  compensated moves (the tool length vector is already in every target: ``OffsetStack.tool_length``).
  ``position`` reports the *programmed* position, so the interpreter's incremental and arc arithmetic
  stays in programmed coordinates.

Conventions: ``d`` is the signed offset, positive to the left of the direction of travel (G41 with a
positive D), negative to the right (G42, or G41 with a negative D: the manual's swap, §3.5.2). Arcs are
signed sweeps in radians, positive counter-clockwise in the plane (u, v).

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from cnc_gym.errors import ProgramError
from cnc_gym.toolpath import PLANE_AXES, Plane, SegmentMode

if TYPE_CHECKING:
    from cnc_gym.gcode.codes import CodeSpec
    from cnc_gym.gcode.dialect import Seam

Point = tuple[float, float]
Vec = tuple[float, float, float]
TWO_PI = 2.0 * math.pi
#: Tangent directions closer than this (|cross| of unit vectors) count as a smooth junction.
SMOOTH = 1e-9
#: Tangents closer than this (rad, about 0.006°) make a smooth corner: programs print tangent joins
#: rounded to the least increment (0.0001 mm on a 10 mm block is 1e-5 rad), and a real corner this small
#: changes the path by less than r·1e-4.
TANGENT_JOIN = 1e-4
#: Points closer than this (mm) are one point (no zero-length connecting moves).
SAME_POINT = 1e-9
#: An outer-corner intersection farther than this many offsets from the corner is not used (extension
#: points instead); line-line corners of 90° or more have theirs within sqrt(2) offsets.
OUTER_REACH = 2.0
#: Blocks the stage reads past a block to find the next move in the plane (executing + 2 buffered).
LOOKAHEAD_BLOCKS = 2


class CompensationError(ProgramError):
    """A compensation alarm raised by the geometry (the interpreter adds the dialect's alarm number)."""

    def __init__(self, message: str, code: str, line: int = 0) -> None:
        super().__init__(message, code=code, line=line)


# ====================================================================== plane geometry
@dataclass(frozen=True, slots=True)
class PlaneElement:
    """One programmed move in the compensation plane: a line, or an arc about ``center``."""

    start: Point
    end: Point
    center: Point | None = None
    sweep: float = 0.0  # signed rad, + = counter-clockwise; arcs only

    @property
    def is_arc(self) -> bool:
        return self.center is not None

    @property
    def arc_center(self) -> Point:
        """The centre of an arc (lines have none)."""
        assert self.center is not None
        return self.center

    @property
    def radius(self) -> float:
        c = self.arc_center
        return math.hypot(self.start[0] - c[0], self.start[1] - c[1])

    def tangent(self, at_end: bool) -> Point:
        """Unit direction of travel at the start or the end."""
        if self.center is None:
            return _unit(self.end[0] - self.start[0], self.end[1] - self.start[1])
        p = self.end if at_end else self.start
        ru, rv = _unit(p[0] - self.center[0], p[1] - self.center[1])
        return (-rv, ru) if self.sweep > 0 else (rv, -ru)

    def offset_point(self, at_end: bool, d: float) -> Point:
        """The point at offset ``d`` (left +) from the start or end, perpendicular to the travel there."""
        tu, tv = self.tangent(at_end)
        p = self.end if at_end else self.start
        return (p[0] - d * tv, p[1] + d * tu)


def _unit(du: float, dv: float) -> Point:
    n = math.hypot(du, dv)
    if n == 0.0:
        raise ValueError("zero-length direction")
    return (du / n, dv / n)


def _dist(a: Point, b: Point) -> float:
    return math.hypot(a[0] - b[0], a[1] - b[1])


def offset_radius(element: PlaneElement, d: float) -> float:
    """Radius of an arc's offset circle: smaller by d on the left of a CCW arc (the centre side)."""
    return element.radius - d if element.sweep > 0 else element.radius + d


def offset_curve(element: PlaneElement, d: float) -> tuple:
    """``("line", point, unit direction)`` or ``("circle", centre, radius)`` of the element offset by d."""
    if element.center is None:
        t = element.tangent(False)
        return ("line", element.offset_point(False, d), t)
    return ("circle", element.center, offset_radius(element, d))


def intersections(a: tuple, b: tuple) -> list[Point]:
    """Intersection points of two offset curves (infinite lines, full circles)."""
    if a[0] == "circle" and b[0] == "line":
        a, b = b, a
    if a[0] == "line" and b[0] == "line":
        (pu, pv), (tu, tv) = a[1], a[2]
        (qu, qv), (su, sv) = b[1], b[2]
        cross = tu * sv - tv * su
        if abs(cross) < SMOOTH:
            return []
        s = ((qu - pu) * sv - (qv - pv) * su) / cross
        return [(pu + s * tu, pv + s * tv)]
    if a[0] == "line":
        (pu, pv), (tu, tv) = a[1], a[2]
        (cu, cv), r = b[1], b[2]
        # |p + s t - c|^2 = r^2 with |t| = 1: s^2 + 2 s (t.(p-c)) + |p-c|^2 - r^2 = 0
        wu, wv = pu - cu, pv - cv
        half_b = tu * wu + tv * wv
        disc = half_b * half_b - (wu * wu + wv * wv - r * r)
        if disc < 0.0:
            if disc > -1e-12 * max(1.0, r * r):
                disc = 0.0
            else:
                return []
        root = math.sqrt(disc)
        return [(pu + s * tu, pv + s * tv) for s in (-half_b - root, -half_b + root)]
    (au, av), ra = a[1], a[2]
    (bu, bv), rb = b[1], b[2]
    dist = math.hypot(bu - au, bv - av)
    if dist < SAME_POINT:
        return []  # concentric: no point, or the whole circle (then the corner is smooth)
    x = (dist * dist + ra * ra - rb * rb) / (2.0 * dist)
    h2 = ra * ra - x * x
    if h2 < 0.0:
        if h2 > -1e-12 * max(1.0, ra * ra):
            h2 = 0.0
        else:
            return []
    h = math.sqrt(h2)
    eu, ev = (bu - au) / dist, (bv - av) / dist
    mu, mv = au + x * eu, av + x * ev
    return [(mu - h * ev, mv + h * eu), (mu + h * ev, mv - h * eu)]


def _nearest(points: list[Point], to: Point) -> Point | None:
    return min(points, key=lambda p: _dist(p, to)) if points else None


@dataclass(slots=True)
class Corner:
    """Tool-centre points at the junction P of blocks a and b.

    ``end_a``: where a's compensated move ends. ``lead_b``: straight moves that belong to block b (its feed
    or rapid) before its own compensated element. ``start_b``: where b's element starts (for an arc: on
    its offset circle); for a line it is the last point of the lead (or ``end_a``).
    """

    end_a: Point
    lead_b: list[Point] = field(default_factory=list)
    start_b: Point | None = None
    kind: str = ""  # smooth | inner | outer-intersection | outer-extension | perpendicular | switch

    def __post_init__(self) -> None:
        if self.start_b is None:
            self.start_b = self.lead_b[-1] if self.lead_b else self.end_a


def _dedupe(points: list[Point], after: Point) -> list[Point]:
    out: list[Point] = []
    last = after
    for p in points:
        if _dist(p, last) > SAME_POINT:
            out.append(p)
            last = p
    return out


def corner(
    a: PlaneElement,
    b: PlaneElement | None,
    d_a: float,
    d_b: float | None = None,
    *,
    role: str = "offset",
    startup_type: str = "B",
) -> Corner:
    """Tool-centre points at the end of ``a`` / start of ``b`` (type C, §3.5.2).

    ``role``: ``offset`` (both blocks compensated), ``startup`` (``a`` is the start-up line: its start
    has no vector), ``cancel`` (``b`` is the cancel line: it ends without a vector). ``b`` None: no next
    move in the plane within the look-ahead (end of program, G40 without a move): the vector is
    perpendicular to ``a`` at its end. ``d_b``: b's offset; only a G41/G42 switch (the opposite sign) uses
    it here: a D change applies from the end vector of the block that carries it (§3.5.3), so b's start
    vector is computed with the old offset ``d_a`` (an arc then steps radially onto its new offset circle).
    ``startup_type``: ``A`` or ``B`` for outer corners of start-up and cancel (parameter 2602#2 TPH).

    Raises :class:`CompensationError` ``comp-no-intersection`` (alarm 33) when an inner corner's offset
    curves do not meet.
    """
    p = a.end
    if b is None:
        end = a.offset_point(True, d_a)
        return Corner(end, [], end, "perpendicular")
    if d_b is None:
        d_b = d_a
    switch = d_a * d_b < 0.0
    # A D change applies from the end vector of the block that carries it (§3.5.3): b's start vector uses
    # the previous offset (a line tapers to the new one; an arc steps radially onto its new circle).
    if not switch:
        d_b = d_a
    ta, tb = a.tangent(True), b.tangent(False)
    cross = ta[0] * tb[1] - ta[1] * tb[0]
    dot = ta[0] * tb[0] + ta[1] * tb[1]
    va = a.offset_point(True, d_a)
    vb = b.offset_point(False, d_b)
    curve_a = offset_curve(a, d_a)
    curve_b = offset_curve(b, d_b)

    def perpendicular(kind: str) -> Corner:
        lead = _dedupe([vb], va)
        return Corner(va, lead, vb, kind)

    if switch:
        # G41 <-> G42 (§3.5.3): no inside/outside; the intersection if the offset paths meet, else a
        # vector perpendicular to b at its start.
        point = _nearest(intersections(curve_a, curve_b), p)
        if point is None:
            return perpendicular("switch")
        return Corner(point, [], point, "switch")
    if abs(cross) < TANGENT_JOIN and dot > 0.0:
        # Smooth join: one point. A line ending before an arc ends on the arc's offset circle; a line
        # starting after anything starts where the previous block ended; arc to arc: both vectors (one is
        # on each circle; they differ by at most r·1e-4).
        if not b.is_arc:
            return Corner(va, [], va, "smooth")
        if not a.is_arc:
            return Corner(vb, [], vb, "smooth")
        return perpendicular("smooth")
    r = abs(d_a)
    inner = d_a * cross > 0.0
    if inner:
        point = _nearest(intersections(curve_a, curve_b), p)
        if point is None:
            raise CompensationError(
                "cutter compensation: the offset paths of an inner corner do not intersect "
                f"(offset {r:g} mm is too large for the corner at ({p[0]:g}, {p[1]:g}))",
                "comp-no-intersection",
            )
        return Corner(point, [], point, "inner")
    if role in ("startup", "cancel") and startup_type == "A":
        if role == "startup":
            return Corner(vb, [], vb, "type-a")  # straight to the vector perpendicular to b (§3.5.2)
        return Corner(va, [], va, "type-a")  # cancel: perpendicular to a, then straight to the end
    obtuse = dot >= -1e-12  # alpha >= 90 deg on the workpiece side
    if obtuse:
        point = _nearest(intersections(curve_a, curve_b), p)
        if (
            point is not None
            and _dist(point, p) <= OUTER_REACH * r + SAME_POINT
            and _forward(point, va, ta)
            and _forward(vb, point, tb)
        ):
            return Corner(point, [], point, "outer-intersection")
        # The offset curves do not meet near the corner (arcs): straight from one vector to the other
        # ("moving the corner", §3.5.3).
        return perpendicular("outer-vectors")
    # Acute outer corner: extension points r beyond the end of a and r before the start of b along their
    # tangents (two or three extra points, §3.5.3).
    q1 = (va[0] + r * ta[0], va[1] + r * ta[1])
    q2 = (vb[0] - r * tb[0], vb[1] - r * tb[1])
    if a.is_arc:
        end_a, lead = va, [q1, q2]
    else:
        end_a, lead = q1, [q2]  # a line simply runs on to q1
    if b.is_arc:
        lead.append(vb)
    return Corner(end_a, _dedupe(lead, end_a), vb, "outer-extension")


def _forward(point: Point, origin: Point, direction: Point) -> bool:
    """``point`` lies ahead of ``origin`` along ``direction`` (or on it)."""
    return (point[0] - origin[0]) * direction[0] + (point[1] - origin[1]) * direction[1] >= -1e-9


def arc_sweep_between(center: Point, start: Point, end: Point, programmed_sweep: float) -> float:
    """Sweep from ``start`` to ``end`` about ``center`` in the programmed direction: magnitude in [0, 2π)
    (a full circle's 2π when the programmed arc is one and the ends meet), signed like ``programmed_sweep``.
    With ``programmed_sweep`` 0: the shorter way round."""
    a0 = math.atan2(start[1] - center[1], start[0] - center[0])
    a1 = math.atan2(end[1] - center[1], end[0] - center[0])
    if programmed_sweep == 0.0:
        return math.remainder(a1 - a0, TWO_PI)
    raw = (a1 - a0) % TWO_PI if programmed_sweep > 0 else (a0 - a1) % TWO_PI
    if abs(programmed_sweep) > TWO_PI - 1e-9 and raw < math.pi:
        raw += TWO_PI  # a programmed full circle stays a full turn (a little more or less)
    return math.copysign(raw, programmed_sweep)


def block_interference(
    element: PlaneElement, d: float, start: Point, end: Point, as_line: bool = False, line: int = 0
) -> str | None:
    """Interference check of one block's compensated movement from ``start`` to ``end`` (Remark 9,
    §3.5.3); returns why it interferes, or None.

    (a) the tool-centre path runs 90°-270° against the programmed path: for a line (or an arc turned into
    a line by the correction, compared with its chord), the dot product of the two directions is negative;
    for an arc, its offset radius is negative (an inner arc smaller than the offset: the centre runs the
    other way round). (b) for an arc, the sweep from ``start`` to ``end`` in the programmed direction
    differs from the programmed sweep by more than 180° (X60: a one-quadrant arc becomes four quadrants).
    An inner arc whose radius equals the offset raises ``comp-arc-centre`` (alarm 38) at once.
    """
    if element.center is None or as_line:
        pu, pv = element.end[0] - element.start[0], element.end[1] - element.start[1]
        cu, cv = end[0] - start[0], end[1] - start[1]
        dot = pu * cu + pv * cv
        if dot > 0.0:
            return None  # the common case, decided without square roots (this runs once per block)
        programmed, compensated = math.hypot(pu, pv), math.hypot(cu, cv)
        if compensated <= SAME_POINT:
            return None
        if programmed <= SAME_POINT:
            return "check (a): a full circle turned into a line has no direction to keep"
        if dot < -1e-12 * max(1.0, programmed * compensated):
            return "check (a): the tool-centre path runs against the programmed direction"
        return None
    radius = offset_radius(element, d)
    if abs(radius) <= 1e-9:
        raise CompensationError(
            "cutter compensation: the arc's radius equals the offset, so the tool centre "
            "arc has its centre on its start and end",
            "comp-arc-centre",
            line,
        )
    if radius < 0.0:
        return (
            f"check (a): inner arc radius {element.radius:g} mm is smaller than the offset {abs(d):g} mm "
            "(the tool centre would run the other way round)"
        )
    sweep = arc_sweep_between(element.center, start, end, element.sweep)
    if abs(sweep - element.sweep) > math.pi:
        return (
            f"check (b): the tool-centre arc sweeps {math.degrees(sweep):.1f} deg against the programmed "
            f"{math.degrees(element.sweep):.1f} deg"
        )
    return None


def correct_interference(
    element: PlaneElement,
    d: float,
    start_vectors: list[Point],
    end_vectors: list[Point],
    line: int = 0,
) -> tuple[list[Point], list[Point], bool]:
    """The controller's correction of interference before it alarms (§3.5.3, §3.5.2).

    ``start_vectors``: the tool-centre points at the block's start corner in path order (the first is
    where the previous block ended, the last where this block's own movement starts); ``end_vectors``:
    those at its end corner (the first is where this block's movement ends, the last where the next
    block's own movement starts; the ones between are the next block's extra corner moves). The pair
    nearest the block (the last start vector, the first end vector) is checked with
    :func:`block_interference`; an interfering pair is ignored (both vectors dropped) and the next pair
    out is checked, until a pair does not interfere. The last vector at a corner is never dropped: when
    only one side can give one up, only that one is dropped (a step smaller than the tool radius
    machined with an arc: "one vector is ignored and the tool traverses toward the 2nd vector",
    §3.5.3); when neither can (a single pair from the start, or interference left after
    correcting) it is ``comp-interference`` (alarm 41). Once a vector has been dropped an arc block runs
    as a straight line (§3.5.3).

    Returns the kept start vectors, the kept end vectors and whether an arc now runs as a line.
    """
    reason = block_interference(element, d, start_vectors[-1], end_vectors[0], False, line)
    if reason is None:
        return start_vectors, end_vectors, False  # no interference: nothing to copy (the common case)
    starts = list(start_vectors)
    ends = list(end_vectors)
    as_line = False
    dropped = 0
    while True:
        if reason is None:
            return starts, ends, as_line
        if len(starts) == 1 and len(ends) == 1:
            plural = "s" if dropped > 1 else ""
            after = f" (after ignoring {dropped} corner vector{plural})" if dropped else ""
            raise CompensationError(
                f"cutter compensation interference{after}: {reason}", "comp-interference", line
            )
        if len(starts) > 1:
            starts.pop()
            dropped += 1
        if len(ends) > 1:
            ends.pop(0)
            dropped += 1
        as_line = True
        reason = block_interference(element, d, starts[-1], ends[0], as_line, line)


def _circle_point(element: PlaneElement, d: float, toward: Point) -> Point:
    """The point of the arc's offset circle (radius for ``d``) in the direction of ``toward``."""
    cu, cv = element.arc_center
    radius = offset_radius(element, d)
    du, dv = toward[0] - cu, toward[1] - cv
    n = math.hypot(du, dv)
    if n <= SAME_POINT:
        return element.offset_point(False, d)
    return (cu + radius * du / n, cv + radius * dv / n)


@dataclass(slots=True)
class OutputMove:
    """One compensated move in the plane: a line to ``end``, or an arc to ``end`` about ``center``."""

    end: Point
    center: Point | None = None
    sweep: float = 0.0
    block: int = 0  # index of the programmed element it belongs to


def compensate(
    elements: list[PlaneElement], d: float, *, startup_type: str = "A", cancel_direction: Point | None = None
) -> list[OutputMove]:
    """Tool-centre path of a whole sequence: ``elements[0]`` is the start-up line (from a tool with no
    vector), the rest are compensated by ``d``; the last one is a cancel line unless it is an arc
    (then the program ends in offset mode with the vector perpendicular to it). Pure, with the same
    corner rules as the stage (which adds the look-ahead, D changes, G41/G42 switches and the 3-D part).
    """
    if not elements:
        return []
    if elements[0].is_arc:
        raise CompensationError("cutter compensation start-up with an arc", "comp-arc-startup")
    out: list[OutputMove] = []
    cancel_last = len(elements) > 1 and not elements[-1].is_arc
    body = elements if not cancel_last else elements[:-1]
    tool: Point = elements[0].start
    lead: list[Point] = []
    start_b: Point = tool
    for i, element in enumerate(body):
        nxt = body[i + 1] if i + 1 < len(body) else (elements[-1] if cancel_last else None)
        role = "startup" if i == 0 else "offset"
        if nxt is not None and cancel_last and i + 1 == len(body):
            role = "cancel" if i > 0 else "startup"
        if role == "cancel" and cancel_direction is not None:
            virtual = PlaneElement(
                element.end, (element.end[0] + cancel_direction[0], element.end[1] + cancel_direction[1])
            )
            c = _cancel_with_direction(element, virtual, d)
        else:
            c = corner(element, nxt, d, role=role, startup_type=startup_type)
        starts = [tool, *lead]
        if element.is_arc and _dist(starts[-1], start_b) > SAME_POINT:
            starts.append(start_b)
        ends_at = [c.end_a, *c.lead_b]
        as_line = False
        if i > 0:
            starts, ends_at, as_line = correct_interference(element, d, starts, ends_at)
        for q in starts[1:]:
            out.append(OutputMove(q, block=i))
        if element.is_arc and not as_line:
            sweep = arc_sweep_between(element.arc_center, starts[-1], ends_at[0], element.sweep)
            out.append(OutputMove(ends_at[0], element.arc_center, sweep, block=i))
        else:
            out.append(OutputMove(ends_at[0], block=i))
        tool = ends_at[0]
        lead = ends_at[1:]
        start_b = c.start_b if c.start_b is not None else tool  # set by Corner.__post_init__
    if cancel_last:
        for q in lead:
            out.append(OutputMove(q, block=len(elements) - 1))
        out.append(OutputMove(elements[-1].end, block=len(elements) - 1))
    return out


def _cancel_with_direction(a: PlaneElement, virtual: PlaneElement, d: float) -> Corner:
    """``G40 X_ Y_ I_ J_`` (§3.5.3): a ends where its offset path meets the offset of the (I, J)
    direction from its end; if they do not meet, perpendicular to a at its end."""
    point = _nearest(intersections(offset_curve(a, d), offset_curve(virtual, d)), a.end)
    if point is None:
        end = a.offset_point(True, d)
        return Corner(end, [], end, "perpendicular")
    return Corner(point, [], point, "cancel-ij")


# ====================================================================== the stage
@dataclass(slots=True)
class _Item:
    """A programmed move or dwell waiting in the look-ahead buffer, with its block's context."""

    kind: str  # "rapid" | "line" | "arc" | "dwell"
    target: Vec  # programmed machine-coordinate end (dwell: the position)
    feed: float | None
    context: tuple  # (line, file_index, modes, tool, spindle_rpm)
    element: PlaneElement | None = None  # in-plane moves only
    d: float = 0.0
    seconds: float = 0.0
    dwell_modes: SegmentMode = SegmentMode.NONE
    helix_w: float = 0.0
    lead: list[Point] = field(default_factory=list)
    start_b: Point | None = None
    role: str = "offset"

    @property
    def move(self) -> PlaneElement:
        """The element of a move in the plane (every item the corner logic sees has one)."""
        assert self.element is not None
        return self.element


class OffsetStage:
    """Compensation stage with the :class:`CanonicalMachine` interface (see the module docstring).

    The interpreter installs it in place of its canonical machine the first time a program uses G41/G42,
    G43/G44 or G45-G48, and drives it through :meth:`set_cutter`,
    :meth:`set_position_offset`, :meth:`corner_arc` and :meth:`flush`.
    """

    def __init__(self, machine, *, startup_type: str = "A", alarms=None, outer_corner_arcs: bool = False,
                 correct_interference: bool = True) -> None:  # fmt: skip
        self.machine = machine
        self.alarms = alarms or {}
        self.startup_type = startup_type
        self.outer_corner_arcs = outer_corner_arcs  # CompensationSettings.outer_corner_arcs
        self.correct_interference = correct_interference  # CompensationSettings.correct_interference
        self._position: Vec = machine.position  # programmed (uncompensated) position
        self.file_index = machine.file_index
        self.modes = machine.modes
        self.tool = machine.tool
        self.spindle_rpm = machine.spindle_rpm
        self.line = machine.line
        # Cutter compensation state.
        self.d = 0.0  # signed offset of the blocks to come (left +)
        self.plane = Plane.XY
        self.active = False  # a vector is (or is about to be) applied
        self.pending: _Item | None = None  # the last in-plane block, waiting for its end corner
        self.deferred: list[_Item] = []  # moves without plane motion and dwells after it
        self.blocks_since = 0
        self.cancel_requested = False
        self.cancel_direction: Point | None = None
        self.corner_arc_pending = False
        self.corner_arc_direction: Point | None = None
        self.corner_arc_feed: float | None = None
        # The tool length vector lives in OffsetStack.tool_length (it is in every target already).
        # ``length_pending``: the change of that vector an incremental move of
        # the offset axis in the block that changes it must carry (``G43 G91 Z0 H_`` moves by H, §3.5.1).
        self.length_pending: Vec | None = None
        self.suspended = False  # this block's moves pass through uncompensated (G53, G27-G30, G60)
        self._position_offset: tuple[int, float, frozenset[int], bool] | None = None

    # ------------------------------------------------------------------ context
    @property
    def position(self) -> Vec:
        """The programmed position (machine coordinates without the cutter compensation vector)."""
        pending = self.length_pending
        if pending is None:
            return self._position
        p = self._position
        return (p[0] + pending[0], p[1] + pending[1], p[2] + pending[2])

    def _guard(self, fn, *args):
        """Run ``fn``; a compensation error gets the dialect's alarm number."""
        try:
            return fn(*args)
        except CompensationError as err:
            if err.alarm is None:
                err.alarm = self.alarms.get(err.code)
            raise

    def begin_block(self) -> None:
        """The interpreter starts a block (after setting ``line``): the look-ahead counts blocks here."""
        self._guard(self._new_block)

    def _new_block(self) -> None:
        self.length_pending = None
        self.suspended = False
        self._position_offset = None
        if self.cancel_requested and self.pending is not None:
            # G40 in a block without a move in the plane: the vector stays perpendicular to the last
            # block and is cancelled on the next move (§3.5.3).
            self._resolve(None)
            self.active = False
        elif self.pending is not None:
            self.blocks_since += 1
            if self.blocks_since > LOOKAHEAD_BLOCKS:
                # The two blocks after the pending one have no move in the plane: the next block cannot
                # be seen, so its end vector is perpendicular to it (the overcut of §3.5.3).
                self._resolve(None)
        if self.cancel_requested and self.pending is None:
            self.cancel_requested = False
            self.active = False

    def _context(self) -> tuple:
        return (self.line, self.file_index, self.modes, self.tool, self.spindle_rpm)

    # ------------------------------------------------------------------ controls
    def set_cutter(self, d: float, plane: Plane, *, cancel_direction: Point | None = None) -> None:
        """G41/G42 (``d`` signed, left +) or G40 (``d`` 0, optional I/J direction). The change applies to
        the blocks to come; a cancel happens on the next move in the plane (or at the next block)."""
        if d == 0.0:
            if self.active:
                self.cancel_requested = True
                self.cancel_direction = cancel_direction
            self.d = 0.0
            return
        self.cancel_requested = False
        self.d = d
        self.plane = plane

    def set_position_offset(
        self, factor: int, amount: float, axes: frozenset[int], incremental: bool
    ) -> None:
        """G45 (+1), G46 (-1), G47 (+2), G48 (-2) for the move of this block on ``axes``."""
        self._position_offset = (factor, amount, axes, incremental)

    def corner_arc(self, direction: Point | None, feed: float | None) -> None:
        """G39 [I J]: a corner arc of radius |d| at the end of the pending block (§3.5.4)."""
        self.corner_arc_pending = True
        self.corner_arc_direction = direction
        self.corner_arc_feed = feed

    def __getattr__(self, name: str):
        # Canonical operations the stage does not compensate (added by other stages, e.g. NURBS): emit
        # what is buffered, then pass through; the programmed position follows the machine.
        if name.startswith("_") or name == "machine":
            raise AttributeError(name)
        attribute = getattr(self.machine, name)
        if not callable(attribute):
            return attribute

        def passthrough(*args, **kwargs):
            self.flush()
            self._set_machine_context(self._context())
            result = attribute(*args, **kwargs)
            self._position = self.machine.position
            self.active = False
            return result

        return passthrough

    def flush(self) -> None:
        """End of program (or a move that must see the true position): resolve and emit everything."""
        self._guard(self._flush)

    def _flush(self) -> None:
        if self.pending is not None:
            self._resolve(None)
        self._emit_deferred()
        self.cancel_requested = False
        if self.d == 0.0:
            self.active = False

    # ------------------------------------------------------------------ CanonicalMachine interface
    def straight_traverse(self, target: Vec) -> None:
        self._guard(self._straight_traverse, target)

    def straight_feed(self, target: Vec, feed: float) -> None:
        self._guard(self._move, "line", self._adjust(target), feed)

    def arc_feed(self, end: Vec, center: Vec, plane: Plane, sweep: float, feed: float) -> None:
        self._guard(self._arc_feed, end, center, plane, sweep, feed)

    def dwell(self, seconds: float, modes: SegmentMode = SegmentMode.NONE) -> None:
        self._guard(self._dwell, seconds, modes)

    def _straight_traverse(self, target: Vec) -> None:
        self._move("rapid", self._adjust(target), None)

    def _arc_feed(self, end: Vec, center: Vec, plane: Plane, sweep: float, feed: float) -> None:
        if self._position_offset is not None:
            end, center = self._adjust_arc(end, center, plane, sweep)
        u, v, _w = PLANE_AXES[plane]
        start = self._position
        if (self.active or self.d != 0.0) and plane != self.plane:
            raise CompensationError(
                f"arc in the {Plane(plane).name} plane while cutter compensation works in "
                f"the {Plane(self.plane).name} plane",
                "comp-plane-change",
            )
        if self.suspended or (not self.active and self.d == 0.0):
            self._set_machine_context(self._context())
            self.machine.arc_feed(end, center, plane, sweep, feed)
            self._position = end
            return
        element = PlaneElement((start[u], start[v]), (end[u], end[v]), (center[u], center[v]), sweep)
        item = _Item("arc", end, feed, self._context(), element, self.d)
        self._plane_move(item)

    def _dwell(self, seconds: float, modes: SegmentMode = SegmentMode.NONE) -> None:
        item = _Item("dwell", self._position, None, self._context(), seconds=seconds, dwell_modes=modes)
        if self.pending is not None:
            self.deferred.append(item)
        else:
            self._emit_dwell(item)

    def suspend(self) -> None:
        """G53, G27-G30, G60 come next: everything buffered is emitted first (the last block ending with its
        vector perpendicular to it) and this block's moves go through uncompensated; the next move in the
        plane is a new start-up. A simplification of the manual's temporary cancel (§3.2.12, §3.5.3):
        the vector is gone at the intermediate point and comes back with the next block's start-up."""
        self.flush()
        self.suspended = True
        self.active = False

    # ------------------------------------------------------------------ internals
    def _adjust(self, target: Vec) -> Vec:
        """G45-G48 on a straight move: each commanded axis's travel grows/shrinks by factor x D (§3.5.7)."""
        request = self._position_offset
        if request is None:
            return target
        self._position_offset = None
        factor, amount, axes, incremental = request
        pos = self._position
        out = list(target)
        for a in axes:
            delta = target[a] - pos[a]
            if delta != 0.0:
                delta += math.copysign(1.0, delta) * factor * amount
            elif incremental:
                delta = factor * amount  # a zero move in G91 moves by the offset (§3.5.7, N9/N11)
            out[a] = pos[a] + delta
        return (out[0], out[1], out[2])

    def _adjust_arc(self, end: Vec, center: Vec, plane: Plane, sweep: float) -> tuple[Vec, Vec]:
        """G45-G48 on a quarter or three-quarter I/J/K circle: the radius changes by factor x D (§3.5.7)."""
        assert self._position_offset is not None  # the caller checked it
        factor, amount, _axes, _incremental = self._position_offset
        self._position_offset = None
        u, v, _w = PLANE_AXES[plane]
        pos = self._position
        du, dv = end[u] - pos[u], end[v] - pos[v]
        iu, iv = center[u] - pos[u], center[v] - pos[v]
        radius = math.hypot(iu, iv)
        quarter = (
            abs(abs(du) - radius) < 1e-6 and abs(abs(dv) - radius) < 1e-6 and min(abs(iu), abs(iv)) < 1e-6
        )
        if not quarter or abs(abs(sweep) - math.pi) < 1e-6:
            raise CompensationError(
                "G45-G48 on an arc: only quarter and three-quarter circles with the "
                "centre on an axis direction can be offset (GSK 25i §3.5.7)",
                "position-offset-arc",
            )
        change = factor * amount
        new_end, new_center = list(end), list(center)
        new_end[u] = pos[u] + du + math.copysign(1.0, du) * change
        new_end[v] = pos[v] + dv + math.copysign(1.0, dv) * change
        new_center[u] = pos[u] + (iu + math.copysign(1.0, iu) * change if abs(iu) > 1e-6 else 0.0)
        new_center[v] = pos[v] + (iv + math.copysign(1.0, iv) * change if abs(iv) > 1e-6 else 0.0)
        if radius + change <= 0.0:
            raise CompensationError(
                "G45-G48: the offset makes the arc radius zero or negative", "position-offset-arc"
            )
        return (new_end[0], new_end[1], new_end[2]), (new_center[0], new_center[1], new_center[2])

    def _set_machine_context(self, context: tuple) -> None:
        m = self.machine
        m.line, m.file_index, m.modes, m.tool, m.spindle_rpm = context

    def _move(self, kind: str, target: Vec, feed: float | None) -> None:
        u, v, _w = PLANE_AXES[self.plane]
        start = self._position
        in_plane = abs(target[u] - start[u]) > SAME_POINT or abs(target[v] - start[v]) > SAME_POINT
        passthrough = not self.active and (self.d == 0.0 or not in_plane) and self.pending is None
        if self.suspended or (passthrough and not self.deferred):
            # Cancel mode (or G41/G42 waiting for its start-up block): straight through.
            self._set_machine_context(self._context())
            self._emit_straight(kind, target, feed)
            self._position = target
            return
        item = _Item(kind, target, feed, self._context())
        if in_plane:
            item.element = PlaneElement((start[u], start[v]), (target[u], target[v]))
            item.d = self.d
            self._plane_move(item)
        elif self.pending is None:
            # Offset mode with nothing waiting (after a look-ahead-starved block): the tool keeps its
            # compensated position in the plane.
            pos = self.machine.position
            self._set_machine_context(item.context)
            self._emit_straight(kind, self._with_plane(target, (pos[u], pos[v])), feed)
            self._position = target
        else:
            self.deferred.append(item)
            self._position = target

    def _emit_straight(self, kind: str, target: Vec, feed: float | None) -> None:
        if kind == "rapid":
            self.machine.straight_traverse(target)
        else:
            self.machine.straight_feed(target, feed)

    def _plane_move(self, item: _Item) -> None:
        element = item.move
        line = self.line
        if not self.active:
            if item.kind == "arc":
                raise CompensationError(
                    "cutter compensation start-up in an arc block: the start-up block must be G00 or G01",
                    "comp-arc-startup",
                    line,
                )
            item.role = "startup"
            item.start_b = element.start
            self.active = True
            self.pending = item
            self.blocks_since = 0
            self._position = item.target
            return
        if self.cancel_requested or item.d == 0.0:
            if item.kind == "arc":
                raise CompensationError(
                    "cutter compensation cancel in an arc block: the cancel block must be G00 or G01",
                    "comp-arc-startup",
                    line,
                )
            item.role = "cancel"
            self._resolve(item)
            self._emit_deferred()
            # The cancel line: from the last compensated point straight to the programmed end.
            self._set_machine_context(item.context)
            for q in item.lead:
                self._emit_plane_point(q, item)
            self._emit_straight(item.kind, item.target, item.feed)
            self.active = False
            self.cancel_requested = False
            self._position = item.target
            return
        if self.pending is None:
            # The previous block was resolved without seeing this one (look-ahead starved, §3.5.3): the tool
            # sits on the old vector and runs straight to this block's end vector (an arc: to its start).
            item.start_b = element.offset_point(False, item.d)
        else:
            self._resolve(item)
        self.pending = item
        self.blocks_since = 0
        self._position = item.target

    def _resolve(self, nxt: _Item | None) -> None:
        """Compute the corner at the end of the pending block with the next move ``nxt`` and emit it."""
        a = self.pending
        if a is None:
            return
        line = a.context[0]
        if self.corner_arc_pending:
            if nxt is not None and nxt.role != "cancel":
                self._corner_arc_resolve(a, nxt)
                return
            self.corner_arc_pending = False  # G39 before a cancel or the end: no corner to round
        b_el = nxt.move if nxt is not None else None
        role = "cancel"
        try:
            if nxt is not None and nxt.role == "cancel" and self.cancel_direction is not None:
                virtual = PlaneElement(
                    a.move.end,
                    (
                        a.move.end[0] + self.cancel_direction[0],
                        a.move.end[1] + self.cancel_direction[1],
                    ),
                )
                c = _cancel_with_direction(a.move, virtual, a.d)
            else:
                role = (
                    "startup"
                    if a.role == "startup"
                    else ("cancel" if nxt is not None and nxt.role == "cancel" else "offset")
                )
                d_b = None if nxt is None or nxt.role == "cancel" else nxt.d
                c = corner(a.move, b_el, a.d, d_b, role=role, startup_type=self.startup_type)
        except CompensationError as err:
            err.line = err.line or line
            raise
        if self.outer_corner_arcs and role == "offset" and nxt is not None and c.kind.startswith("outer"):
            # An arc round the outer corner, as G39 would make one (CompensationSettings.outer_corner_arcs).
            self.corner_arc_direction = self.corner_arc_feed = None
            self._corner_arc_resolve(a, nxt)
            return
        try:
            rest = self._emit_block(a, [c.end_a, *c.lead_b])
        except CompensationError as err:
            err.line = err.line or line
            raise
        if nxt is not None:
            nxt.lead = rest
            nxt.start_b = c.start_b
        self.pending = None
        self._emit_deferred()

    def _corner_arc_resolve(self, a: _Item, nxt: _Item) -> None:
        """G39: a ends with the vector perpendicular to its end; an arc of radius |d| about the corner
        takes the tool to the vector perpendicular to the next block's start (or to the I/J direction)."""
        self.corner_arc_pending = False
        p = a.move.end
        end_a = a.move.offset_point(True, a.d)
        if self.corner_arc_direction is not None:
            virtual = PlaneElement(
                p, (p[0] + self.corner_arc_direction[0], p[1] + self.corner_arc_direction[1])
            )
            target = virtual.offset_point(False, a.d)
        else:
            target = nxt.move.offset_point(False, nxt.d)
        self._emit_block(a, [end_a])
        sweep = arc_sweep_between(p, end_a, target, 0.0)
        if abs(sweep) > SMOOTH:
            # The short way round the corner point: at an outer corner, the way the path turns.
            self._set_machine_context(a.context)
            u, v, w = PLANE_AXES[self.plane]
            pos = self.machine.position
            end3 = [0.0, 0.0, 0.0]
            end3[u], end3[v], end3[w] = target[0], target[1], pos[w]
            center3 = [0.0, 0.0, 0.0]
            center3[u], center3[v], center3[w] = p[0], p[1], pos[w]
            feed = self.corner_arc_feed or a.feed or nxt.feed
            if not feed:
                raise CompensationError("G39 needs a feed: no F programmed yet", "missing-feed", a.context[0])
            self.machine.arc_feed(tuple(end3), tuple(center3), self.plane, sweep, feed)
        nxt.lead = []
        nxt.start_b = target
        self.pending = None
        self._emit_deferred()

    def _with_plane(self, target: Vec, point: Point) -> Vec:
        """Machine target: programmed ``target`` with its plane coordinates replaced by ``point``."""
        out = list(target)
        u, v, _w = PLANE_AXES[self.plane]
        out[u], out[v] = point
        return (out[0], out[1], out[2])

    def _emit_plane_point(self, point: Point, item: _Item) -> None:
        """A straight connecting move in the plane (the normal axis stays) with the item's feed/rapid."""
        u, v, _w = PLANE_AXES[self.plane]
        target = list(self.machine.position)
        target[u], target[v] = point
        self._emit_straight(
            "rapid" if item.kind == "rapid" else "line", (target[0], target[1], target[2]), item.feed
        )

    def _emit_block(self, item: _Item, end_vectors: list[Point]) -> list[Point]:
        """Emit a resolved in-plane block: its lead moves, then its element to the first of
        ``end_vectors`` (the tool-centre points at its end corner; the rest are the next block's lead).

        The interference check and its correction (:func:`correct_interference`) run first and may drop
        vectors at both corners (an arc then runs as a straight line); returns the end corner's vectors
        that are left for the next block's lead. An arc whose start vector is not on its offset circle
        (D changed in this block: the start vector keeps the old offset, §3.5.3) steps radially onto it."""
        self._set_machine_context(item.context)
        element = item.move
        line = item.context[0]
        u, v, _w = PLANE_AXES[self.plane]
        pos = self.machine.position
        starts = [(pos[u], pos[v]), *item.lead]
        if item.kind == "arc" and item.start_b is not None and _dist(starts[-1], item.start_b) > 1e-7:
            starts.append(item.start_b)
        as_line = False
        if item.role != "startup":
            if self.correct_interference:
                starts, end_vectors, as_line = correct_interference(element, item.d, starts, end_vectors,
                                                                    line)  # fmt: skip
            else:
                reason = block_interference(element, item.d, starts[-1], end_vectors[0], False, line)
                if reason is not None:
                    raise CompensationError(f"contour violation: {reason}", "comp-interference", line)
        for q in starts[1:]:
            self._emit_plane_point(q, item)
        end = end_vectors[0]
        target = self._with_plane(item.target, end)
        if item.kind == "arc" and not as_line:
            start = _circle_point(element, item.d, starts[-1])
            if _dist(starts[-1], start) > 1e-7:
                self._emit_plane_point(start, item)
            sweep = arc_sweep_between(element.arc_center, start, end, element.sweep)
            center = list(target)
            center[u], center[v] = element.arc_center
            self.machine.arc_feed(target, (center[0], center[1], center[2]), self.plane, sweep, item.feed)
        else:
            self._emit_straight("line" if item.kind == "arc" else item.kind, target, item.feed)
        return end_vectors[1:]

    def _emit_deferred(self) -> None:
        items, self.deferred = self.deferred, []
        u, v, _w = PLANE_AXES[self.plane]
        for item in items:
            if item.kind == "dwell":
                self._emit_dwell(item)
                continue
            pos = self.machine.position
            here = (pos[u], pos[v])
            self._set_machine_context(item.context)
            self._emit_straight(item.kind, self._with_plane(item.target, here), item.feed)

    def _emit_dwell(self, item: _Item) -> None:
        self._set_machine_context(item.context)
        self.machine.dwell(item.seconds, item.dwell_modes)


# ====================================================================== interpreter glue
# The actions and hooks of tool compensation. The state is ``core.state.comp`` (CompensationState): the
# offset memory, the D and H numbers, the G40-G42 and G43/G44/G49 modes, and the OffsetStage, installed in
# place of the output stage the first time a program needs it (plain programs keep the direct path).


def _incremental(core: Seam) -> bool:
    """G91 in force for this block's move: G90/G91 of the block have not run yet at the compensation
    steps (order of execution), but the raw modal table already holds them."""
    roles = core.dialect.roles
    key = core.state.modal.get(roles.distance_group)  # type: ignore[arg-type]
    return core.state.incremental if key is None else key == roles.incremental


_LETTERS = "XYZ"
_IJK = "IJK"


def install(core: Seam) -> OffsetStage:
    """The compensation stage, put in front of the output the first time it is needed."""
    st = core.state
    comp = st.comp
    if comp.stage is None:
        settings = comp.settings
        comp.stage = OffsetStage(st.out, startup_type=settings.startup_type, alarms=core.dialect.alarms,
                                 outer_corner_arcs=settings.outer_corner_arcs,
                                 correct_interference=settings.correct_interference)  # fmt: skip
        st.out = comp.stage
        st.block_listeners.append(before_block)
    return comp.stage


def before_block(core: Seam, values: dict) -> None:
    """Each block once the stage is installed: the look-ahead counts blocks; after G28/G30 the tool
    length vector comes back with the next block that commands its axis."""
    comp = core.state.comp
    comp.stage.begin_block()
    if comp.length_restore is not None:  # the tool length vector after G28/G30 (§3.5.1)
        restore_length(core, values)


def signed_offset(core: Seam) -> float:
    """The signed compensation offset (left +) for the D and G41/G42 in force.

    A mirror image in the plane (G51.1, or G51 with one negative factor) interchanges G41 and G42, so
    the machine path is the mirror image of the compensated programmed path (Fanuc's rule; GSK's
    manual is silent). The stage sees the mirrored moves, hence the sign. Scaling never scales the
    offset."""
    st = core.state
    comp = st.comp
    if not comp.side:
        return 0.0
    sign = 1.0
    chain = st.chain
    if chain.active:
        u, v, _w = PLANE_AXES[comp.plane if comp.side else st.plane]
        a = chain.linear
        if a[u][u] * a[v][v] - a[u][v] * a[v][u] < 0.0:
            sign = -1.0
    return sign * comp.side * comp.offsets.radius(comp.d_number)


def _direction(core: Seam, values: dict) -> Point | None:
    st = core.state
    u, v, _w = PLANE_AXES[st.plane]
    iu, iv = values.get(_IJK[u]), values.get(_IJK[v])
    if iu is None and iv is None:
        return None
    du, dv = (iu or 0.0) * st.scale, (iv or 0.0) * st.scale
    if du == 0.0 and dv == 0.0:
        raise core.error("the I/J/K direction is zero", "comp-bad-direction")
    return (du, dv)


# ---------------------------------------------------------------------- D and H words
def offset_words(core: Seam, spec: CodeSpec, values: dict) -> None:
    """D and H words: select the offset numbers (D and H are modal, §3.5.3, §3.5.1); D and H in one block
    are one item."""
    if spec.name == "D" or "D" not in values:
        words(core, values)


def words(core: Seam, values: dict) -> None:
    comp = core.state.comp
    if "D" in values:
        comp.d_number = int(values["D"])
        if comp.side and comp.stage is not None:
            # A D change in offset mode applies from this block's end vector (§3.5.3); D00 cancels.
            comp.stage.set_cutter(signed_offset(core), comp.plane)
    if "H" in values:
        comp.length_restore = None  # an H in G43/G44 mode sets the vector afresh
        comp.h_number = int(values["H"])
        if comp.length_sign:
            _apply_length(core, values)


# ---------------------------------------------------------------------- G40 / G41 / G42
def cutter(core: Seam, spec: CodeSpec, values: dict) -> None:
    """G41/G42 (cutter compensation left/right) and G40 (cancel, optional I/J direction)."""
    st = core.state
    comp = st.comp
    side = int(spec.value)  # type: ignore[call-overload]
    if side:
        if comp.side and st.plane != comp.plane:
            raise core.error("G41/G42: the plane changed in cutter compensation mode", "comp-plane-change")
        comp.side = side
        comp.plane = st.plane
        stage = install(core)
        stage.set_cutter(signed_offset(core), comp.plane)
        return
    comp.side = 0
    direction = _direction(core, values)
    if comp.stage is not None:
        comp.stage.set_cutter(0.0, comp.plane, cancel_direction=direction)


def check_plane(core: Seam, plane) -> None:
    """G17/G18/G19 while G41/G42 is in force: a different plane is alarm 37 (§3.5.3)."""
    comp = core.state.comp
    if comp.side and plane != comp.plane:
        raise core.error(f"plane change to {Plane(plane).name} in cutter compensation mode (cancel with G40 "
                         "first)", "comp-plane-change")  # fmt: skip


def corner_arc(core: Seam, spec: CodeSpec, values: dict) -> None:
    """G39 [I_J_]: corner arc of the compensation radius (§3.5.4); only in offset mode."""
    comp = core.state.comp
    if not comp.side or comp.stage is None or not comp.stage.active:
        raise core.error("G39 is only allowed in cutter compensation mode (G41/G42 after start-up)",
                         "g39-without-comp")  # fmt: skip
    comp.stage.corner_arc(_direction(core, values), core.state.feed)


# ---------------------------------------------------------------------- G43 / G44 / G49
def length(core: Seam, spec: CodeSpec, values: dict) -> None:
    """G43/G44 (tool length offset + / -) and G49 (cancel)."""
    st = core.state
    comp = st.comp
    comp.length_restore = None  # G43/G44/G49 set the vector afresh (after a G28/G30 cancel too)
    sign = int(spec.value)  # type: ignore[call-overload]
    deferred = False
    if sign and not any(letter in values for letter in _LETTERS):
        if comp.settings.length_needs_axis:
            raise core.error(f"{spec.name} needs an axis word in its block", "length-no-axis")
        deferred = True  # the next move of the tool axis carries the vector
    if st.modal.get(1) in core.dialect.roles.arcs:  # G02/G03 in force: an arc block with the normal axis …
        # … is a helix
        u, v, w = PLANE_AXES[st.plane]
        arc_words = ("IJK"[u], "IJK"[v], "R", _LETTERS[u], _LETTERS[v])
        if _LETTERS[w] in values and any(letter in values for letter in arc_words):
            raise core.error(f"{spec.name} cannot be given in a helical block (GSK 25i §3.2.3)",
                             "length-helical")  # fmt: skip
    comp.length_sign = sign
    if sign:
        comp.length_axis = 2 if comp.settings.tool_length_type == "A" else PLANE_AXES[st.plane][2]
    if deferred:
        _defer_length(core)
    else:
        _apply_length(core, values)


def _defer_length(core: Seam) -> None:
    """``G43 H_`` without an axis word (where the dialect allows it): the new vector waits, as after a
    G28 cancel, for the next block that commands its axis, whose move carries it in G90 and G91 alike
    (:func:`restore_length`)."""
    st = core.state
    comp = st.comp
    new = [0.0, 0.0, 0.0]
    new[comp.length_axis] = comp.length_sign * comp.offsets.length(comp.h_number)
    old = st.offsets.tool_length
    delta = [new[a] - old[a] for a in range(3)]
    if any(delta):
        comp.length_restore = delta
        install(core)


def cancel_length_at_intermediate(core: Seam, axes) -> None:
    """G28/G30 reached the intermediate point: the tool length vector of the commanded axes is cancelled
    (§3.5.1: "G28 and G30 are canceled after moving into the intermediate point"; the mode stays
    G43/G44). The next block commanding the axis restores it (:func:`restore_length`)."""
    st = core.state
    comp = st.comp
    vector = st.offsets.tool_length
    cancelled = [vector[a] if a in axes else 0.0 for a in range(3)]
    if not any(cancelled):
        return
    st.offsets.tool_length = [vector[a] - cancelled[a] for a in range(3)]
    st.offsets.update()
    restore = comp.length_restore or [0.0, 0.0, 0.0]
    comp.length_restore = [restore[a] + cancelled[a] for a in range(3)]
    install(core)  # its per-block hook lets the restore see the next blocks


def restore_length(core: Seam, values: dict) -> None:
    """At the start of a block after G28/G30: the cancelled vector of each axis the block commands comes
    back, and the block's move of that axis carries it (in G90 and G91 alike: ``length_pending``)."""
    st = core.state
    comp = st.comp
    restore = comp.length_restore
    axes = [a for a in range(3) if restore[a] and _LETTERS[a] in values]  # type: ignore[index]
    if not axes:
        return
    vector = list(st.offsets.tool_length)
    delta = [0.0, 0.0, 0.0]
    for a in axes:
        vector[a] += restore[a]  # type: ignore[index]
        delta[a] = restore[a]  # type: ignore[index]
        restore[a] = 0.0  # type: ignore[index]
    if not any(restore):  # type: ignore[arg-type]
        comp.length_restore = None
    st.offsets.tool_length = vector
    st.offsets.update()
    if not st.transformed and comp.stage is not None:
        # The programmed position moves with the vector, so an incremental move adds to the restored
        # position and an absolute one goes to program + offsets + vector (the transformed path keeps
        # its program position and gets this from the origin by itself).
        comp.stage.length_pending = (delta[0], delta[1], delta[2])


def _apply_length(core: Seam, values: dict) -> None:
    """Put the tool length vector into the offset chain (OffsetStack.tool_length, canonical.py): the
    next absolute move of the axis goes to program + offsets + vector; H replaces, never adds (§3.5.1)."""
    st = core.state
    comp = st.comp
    new = [0.0, 0.0, 0.0]
    if comp.length_sign:
        new[comp.length_axis] = comp.length_sign * comp.offsets.length(comp.h_number)
    old = st.offsets.tool_length
    if new == list(old):
        return
    delta = (new[0] - old[0], new[1] - old[1], new[2] - old[2])
    st.offsets.tool_length = new
    st.offsets.update()
    if (
        _incremental(core)
        and not st.transformed
        and any(_LETTERS[a] in values and delta[a] != 0.0 for a in range(3))
    ):
        # G91 with the axis in this block: the move carries the change (G43 G91 Z0 H_, §3.5.1). The
        # transformed path does this by itself (its program position ignores the machine's).
        stage = install(core)
        moved = [delta[a] if _LETTERS[a] in values else 0.0 for a in range(3)]
        stage.length_pending = (moved[0], moved[1], moved[2])


# ---------------------------------------------------------------------- G45-G48
def position_offset(core: Seam, spec: CodeSpec, values: dict) -> None:
    """G45/G46/G47/G48: the block's travel on each commanded axis grows or shrinks by 1x or 2x the D
    value (§3.5.7). Not in G41/G42 mode (§3.5.7); ignored in canned-cycle mode (§3.5.7)."""
    comp = core.state.comp
    if comp.side:
        raise core.error(f"{spec.name} cannot be used in cutter compensation mode G41/G42 (GSK 25i §3.5.7)",
                         "position-offset-in-comp")  # fmt: skip
    if core.state.cycle.spec is not None:
        return
    axes = frozenset(a for a in range(3) if _LETTERS[a] in values)
    amount = comp.offsets.position_offset(comp.d_number)
    install(core).set_position_offset(int(spec.value), amount, axes, _incremental(core))  # type: ignore[call-overload]


# ---------------------------------------------------------------------- G53, G27-G30, end
def before_machine_move(core: Seam) -> None:
    """G53 (and G27-G30, G60) are about to move: compensation is suspended for this block."""
    stage = core.state.comp.stage
    if stage is not None:
        stage.suspend()


def finish(core: Seam) -> None:
    """End of the program (a block hook): emit what the look-ahead still holds (the vector stays, §3.5.3)."""
    stage = core.state.comp.stage
    if stage is not None:
        try:
            stage.flush()
        except ProgramError as err:
            raise err.located(core.state.file, stage.line) from None


ACTIONS = {
    "offset_words": offset_words, "cutter_comp": cutter, "length_comp": length,
    "position_offset": position_offset, "corner_arc": corner_arc,
}  # fmt: skip
