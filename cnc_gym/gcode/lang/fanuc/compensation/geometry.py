"""Cutter compensation's plane geometry (pure functions, no state): GSK/Fanuc type C (§3.5.2-§3.5.3).

A programmed move projected on the compensation plane is a :class:`PlaneElement` (line or arc).
:func:`offset_curve` gives its offset line/circle, :func:`corner` the tool-centre points at the junction of
two elements: intersection points at inner corners and outer corners of 90° or more, extension points (two
or three extra points) at outer corners under 90°, start-up and cancel of type A or B.
:func:`correct_interference` is the interference check (alarm 41) with the manual's correction before it
alarms (interfering corner-vector pairs ignored from the inside out, an arc turned into a line, §3.5.3).
:func:`compensate` runs a whole sequence (start-up line, offset-mode moves, cancel line) the way the stage
(``stage.py``) does block by block.

Conventions: ``d`` is the signed offset, positive to the left of the direction of travel (G41 with a
positive D), negative to the right (G42, or G41 with a negative D: the manual's swap, §3.5.2). Arcs are
signed sweeps in radians, positive counter-clockwise in the plane (u, v).

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from cnc_gym.errors import ProgramError

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


def distance(a: Point, b: Point) -> float:
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
    return min(points, key=lambda p: distance(p, to)) if points else None


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

    @property
    def is_outer(self) -> bool:
        """An outer corner (by intersection or by extension points)."""
        return self.kind.startswith("outer")


def _dedupe(points: list[Point], after: Point) -> list[Point]:
    out: list[Point] = []
    last = after
    for p in points:
        if distance(p, last) > SAME_POINT:
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
            and distance(point, p) <= OUTER_REACH * r + SAME_POINT
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


def circle_point(element: PlaneElement, d: float, toward: Point) -> Point:
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
            c = cancel_with_direction(element, virtual, d)
        else:
            c = corner(element, nxt, d, role=role, startup_type=startup_type)
        starts = [tool, *lead]
        if element.is_arc and distance(starts[-1], start_b) > SAME_POINT:
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


def cancel_with_direction(a: PlaneElement, virtual: PlaneElement, d: float) -> Corner:
    """``G40 X_ Y_ I_ J_`` (§3.5.3): a ends where its offset path meets the offset of the (I, J)
    direction from its end; if they do not meet, perpendicular to a at its end."""
    point = _nearest(intersections(offset_curve(a, d), offset_curve(virtual, d)), a.end)
    if point is None:
        end = a.offset_point(True, d)
        return Corner(end, [], end, "perpendicular")
    return Corner(point, [], point, "cancel-ij")
