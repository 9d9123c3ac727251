"""Chamfer and corner rounding between two G01/G02/G03 blocks: ``,L``/``,C`` (chamfer) and ``,R`` (corner
radius) (GSK 25i programming manual §3.2.11, chamfer and corner rounding; Fanuc's ``,C``/``,R``).

The ``,L``/``,R`` block is held (its geometry captured in program coordinates, nothing emitted) in
``State.pending`` until the next block; then the first block is emitted cut short, the chamfer line or
fillet arc, and the second block from the corner's end (or held in turn if it carries its own word).
Everything goes through the coordinate seam, so corners are rotated, scaled and compensated with the
contour. docs/gcode.md "Chamfer and corner rounding".

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, cast

from cnc_gym.toolpath import PLANE_AXES, Plane, SegmentMode

if TYPE_CHECKING:
    from cnc_gym.gcode.dialect import Seam

TWO_PI = 2.0 * math.pi
_PLANE_AXES = {int(p): axes for p, axes in PLANE_AXES.items()}


def _chamfer_word(core: Seam) -> str:
    return next((w for w in sorted(core.dialect.corner_words) if w != ",R"), ",L")


@dataclass
class PendingCorner:
    """A G01/G02/G03 block with ``,L`` (chamfer) or ``,R`` (corner radius), held until the next move.

    ``segment`` is the captured geometry in program coordinates: (kind, start, end, centre, sweep, feed).
    """

    word: str
    size_mm: float
    segment: tuple
    plane: Plane
    line: int
    modes: SegmentMode
    armed: bool = False

    def before_block(self, core: Seam) -> None:
        arm_corner(core)


def _capture(core: Seam, motion: int, x, y, z, values: dict):
    """This block's move as geometry in program coordinates, without emitting it (None: no motion)."""
    was = core.state.transformed
    saved = core.state.program_point
    pending = cast("PendingCorner | None", core.state.pending)
    # The block starts where the waiting block ends (that one is not emitted yet).
    core.state.program_point = pending.segment[2] if pending is not None else core.program_position
    core.state.transformed = True
    core.state.capture = []
    try:
        if motion >= 2:
            core.dialect.hooks.arc(core, motion, x, y, z, values)  # type: ignore[misc]
        else:
            core.move_linear(False, core.resolve_target(x, y, z))
        captured = core.state.capture
    finally:
        core.state.capture = None
        core.state.transformed = was
        core.state.program_point = saved
    if not captured:
        return None
    kind, start, end = captured[0][:3]
    if kind == "line" and math.dist(start, end) < 1e-9:
        return None
    return captured[0]


class CoordinateChangeMark:
    """Set after G92, G52-G59, G54.1, G28-G30 or a plane change: the next block may not chamfer or round a
    corner (§3.2.11). It rides in ``State.pending`` so the plain path pays nothing for it."""

    armed = False

    def before_block(self, core: Seam) -> None:
        arm_corner(core)


def _word(corner: object) -> str:
    return cast("PendingCorner", corner).word


def is_pending_corner(pending: object) -> bool:
    """Whether ``State.pending`` holds a chamfer/corner block (not a coordinate-change mark)."""
    return isinstance(pending, PendingCorner)


def mark_coordinate_change(core: Seam) -> None:
    corner = core.state.pending
    if corner is None or isinstance(corner, CoordinateChangeMark):
        core.state.pending = CoordinateChangeMark()
        return
    core.state.pending = None
    raise core.error(f"a coordinate system or plane change between a chamfer/corner {_word(corner)} block "
                     "and its next move (GSK 25i §3.2.11)", "bad-corner")  # fmt: skip


def arm_corner(core: Seam) -> None:
    """Called before each block while a chamfer/corner is pending: the block after it must move."""
    corner = core.state.pending
    if isinstance(corner, CoordinateChangeMark):
        if corner.armed:  # the block right after the change is over
            core.state.pending = None
        else:
            corner.armed = True
        return
    corner = cast("PendingCorner", corner)
    if corner.armed:
        core.state.pending = None
        raise core.error(f"the block after a chamfer/corner {corner.word} block (line {corner.line}) must "
                         "be a G01/G02/G03 move in the same plane (GSK 25i §3.2.11)",
                         "bad-corner")  # fmt: skip
    corner.armed = True


def finish_corner(core: Seam) -> None:
    """End of program with a chamfer/corner block still waiting: it has no next move (§3.2.11)."""
    corner = core.state.pending
    core.state.pending = None
    if isinstance(corner, CoordinateChangeMark):
        return
    corner = cast("PendingCorner", corner)
    raise core.error(f"chamfer/corner {corner.word} in the last move block: no next move to meet (GSK 25i "
                     "§3.2.11)",
                     "bad-corner").located(core.state.file, corner.line)  # fmt: skip


def corner_motion(core: Seam, motion: int, x, y, z, values: dict) -> None:
    """A motion block while a chamfer/corner is pending, or one that carries ``,L``/``,R`` (§3.2.11)."""
    words = [w for w in core.dialect.corner_words if w in values]
    has_geometry = x is not None or y is not None or z is not None or (motion >= 2 and "R" in values) or (
        motion >= 2 and any(k in values for k in "IJK"))  # fmt: skip
    if isinstance(core.state.pending, CoordinateChangeMark):
        if not has_geometry:
            return None  # the change's own block, or a block that does not move: the mark stays
        core.state.pending = None
        if words:
            raise core.error(f"chamfer/corner {words[0]} in the block right after a coordinate system or "
                             "plane change or a reference return (GSK 25i §3.2.11)",
                             "bad-corner")  # fmt: skip
        return core.run_action("motion", None, values)
    if len(words) > 1:
        raise core.error(f"a block takes either a chamfer {_chamfer_word(core)} or a corner radius ,R, not "
                         "both",
                         "bad-combination")  # fmt: skip
    pending = cast("PendingCorner | None", core.state.pending)
    if words:
        word = words[0]
        if core.state.polar is not None:
            raise core.error(f"chamfer/corner {word} in polar coordinate mode G16 (GSK 25i §3.2.16)",
                             "bad-corner")
        if motion == 0:
            raise core.error(f"chamfer/corner {word} needs a G01/G02/G03 block", "bad-corner")
        if not has_geometry:
            raise core.error(f"chamfer/corner {word} in a block that does not move", "bad-corner")
        if core.state.restore_modes:  # G09 in this block; other group-00 codes own the axis words
            raise core.error("G09 in a chamfer/corner block (GSK 25i §3.2.11: no group-00 code but G04)",
                             "bad-corner")  # fmt: skip
        size = values[word] * core.state.scale
        if size <= 0:
            raise core.error(f"chamfer/corner {word}{values[word]:g}: the size must be positive",
                             "bad-corner")  # fmt: skip
    if not has_geometry:
        if pending is not None:
            raise core.error(f"the block after a chamfer/corner {pending.word} block must be a G01/G02/G03 "
                             "move (GSK 25i §3.2.11)", "bad-corner")  # fmt: skip
        return
    if pending is not None and motion == 0:
        raise core.error(f"the block after a chamfer/corner {pending.word} block must be a G01/G02/G03 "
                         "move, not G00 (GSK 25i §3.2.11)", "bad-corner")  # fmt: skip
    segment = _capture(core, motion, x, y, z, values)
    if segment is None:
        if words or pending is not None:
            raise core.error("chamfer/corner: the block does not move (zero length)", "bad-corner")
        return
    u, v, w = _PLANE_AXES[int(core.state.plane)]
    if abs(segment[2][w] - segment[1][w]) > 1e-9 and (words or pending is not None):
        raise core.error("chamfer/corner: the block moves the axis normal to the plane; chamfers and "
                         "corner rounding are in the selected plane only (GSK 25i §3.2.11)",
                         "bad-corner")  # fmt: skip
    if pending is None:
        out = core.state.out
        core.state.pending = PendingCorner(words[0], size, segment, core.state.plane, out.line, out.modes)
        return
    core.state.pending = None
    if pending.plane != core.state.plane:
        raise core.error("chamfer/corner: the next block is in another plane (GSK 25i §3.2.11)", "bad-corner")
    first, element, second = corner_geometry(core, pending, segment, (u, v, w))
    line, modes = core.state.out.line, core.state.out.modes
    core.state.out.line, core.state.out.modes = pending.line, pending.modes
    try:
        for part in (first, element):
            if part is not None:
                _emit(core, part)
    finally:
        core.state.out.line, core.state.out.modes = line, modes
    if words:
        if second is None:  # the corner took all of this block: nothing is left for its own ,L/,R
            raise core.error(f"chamfer/corner {words[0]}: the previous corner {pending.word} takes all of "
                             "this block, so no corner of its own fits (GSK 25i §3.2.11)",
                             "bad-corner")  # fmt: skip
        core.state.pending = PendingCorner(words[0], size, second, core.state.plane, line, modes)
    elif second is not None:
        _emit(core, second)


def _emit(core: Seam, segment) -> None:
    kind, _, end, centre, sweep, feed = segment
    if kind == "line":
        core.move_linear(False, end, feed=feed)
    else:
        core.move_arc(end, centre, core.state.plane, sweep, feed)


def _angle(c, q, u: int, v: int) -> float:
    return math.atan2(q[v] - c[v], q[u] - c[u])


def _turn(a0: float, a1: float, ccw: bool) -> float:
    """Signed angle from a0 to a1 going CCW (>= 0) or CW (<= 0)."""
    return (a1 - a0) % TWO_PI if ccw else -((a0 - a1) % TWO_PI)


def _tangent(segment, at_end: bool, u: int, v: int) -> tuple[float, float]:
    kind, start, end, centre, sweep, _ = segment
    if kind == "line":
        du, dv = end[u] - start[u], end[v] - start[v]
        n = math.hypot(du, dv)
        return du / n, dv / n
    q = end if at_end else start
    ru, rv = q[u] - centre[u], q[v] - centre[v]
    n = math.hypot(ru, rv)
    sign = 1.0 if sweep > 0 else -1.0
    return -rv / n * sign, ru / n * sign


def _length(segment, u: int, v: int) -> float:
    kind, start, end, centre, sweep, _ = segment
    if kind == "line":
        return math.hypot(end[u] - start[u], end[v] - start[v])
    return math.hypot(start[u] - centre[u], start[v] - centre[v]) * abs(sweep)


def _along(segment, distance: float, from_end: bool, u: int, v: int) -> tuple[float, float]:
    """The point ``distance`` along the block from its end (backwards) or from its start (forwards)."""
    kind, start, end, centre, sweep, _ = segment
    if kind == "line":
        du, dv = _tangent(segment, True, u, v)
        if from_end:
            return end[u] - du * distance, end[v] - dv * distance
        return start[u] + du * distance, start[v] + dv * distance
    radius = math.hypot(start[u] - centre[u], start[v] - centre[v])
    step = distance / radius * (1.0 if sweep > 0 else -1.0)
    a = _angle(centre, end, u, v) - step if from_end else _angle(centre, start, u, v) + step
    return centre[u] + radius * math.cos(a), centre[v] + radius * math.sin(a)


def _offset_curve(segment, side: float, r: float, u: int, v: int):
    """The block's curve moved ``r`` to its left (side +1) or right (-1): ("line", point, dir) or
    ("circle", centre, radius)."""
    kind, start, _end, centre, sweep, _ = segment
    if kind == "line":
        du, dv = _tangent(segment, True, u, v)
        return "line", (start[u] - dv * side * r, start[v] + du * side * r), (du, dv)
    radius = math.hypot(start[u] - centre[u], start[v] - centre[v])
    # Travelling CCW the left side is towards the centre.
    return "circle", (centre[u], centre[v]), radius - side * r * (1.0 if sweep > 0 else -1.0)


def _intersections(a, b) -> list[tuple[float, float]]:
    if a[0] == "circle" and b[0] == "line":
        a, b = b, a
    if a[0] == "line" and b[0] == "line":
        (p, d), (q, e) = a[1:], b[1:]
        den = d[0] * e[1] - d[1] * e[0]
        if abs(den) < 1e-12:
            return []
        t = ((q[0] - p[0]) * e[1] - (q[1] - p[1]) * e[0]) / den
        return [(p[0] + t * d[0], p[1] + t * d[1])]
    if a[0] == "line":
        (p, d), (c, r) = a[1:], b[1:]
        if r <= 0:
            return []
        fu, fv = p[0] - c[0], p[1] - c[1]
        t0 = -(fu * d[0] + fv * d[1])
        disc = t0 * t0 - (fu * fu + fv * fv - r * r)
        if disc < -1e-12:
            return []
        root = math.sqrt(max(disc, 0.0))
        return [(p[0] + t * d[0], p[1] + t * d[1]) for t in (t0 - root, t0 + root)]
    (c1, r1), (c2, r2) = a[1:], b[1:]
    if r1 <= 0 or r2 <= 0:
        return []
    du, dv = c2[0] - c1[0], c2[1] - c1[1]
    dist = math.hypot(du, dv)
    if dist < 1e-12 or dist > r1 + r2 + 1e-12 or dist < abs(r1 - r2) - 1e-12:
        return []
    along = (r1 * r1 - r2 * r2 + dist * dist) / (2 * dist)
    h = math.sqrt(max(r1 * r1 - along * along, 0.0))
    mu, mv = c1[0] + along * du / dist, c1[1] + along * dv / dist
    return [(mu - h * dv / dist, mv + h * du / dist), (mu + h * dv / dist, mv - h * du / dist)]


def _foot(segment, point, u: int, v: int) -> tuple[float, float]:
    """The point of the block's curve nearest ``point`` (the tangent point of a fillet centred there)."""
    kind, start, _end, centre, _sweep, _ = segment
    if kind == "line":
        du, dv = _tangent(segment, True, u, v)
        t = (point[0] - start[u]) * du + (point[1] - start[v]) * dv
        return start[u] + t * du, start[v] + t * dv
    radius = math.hypot(start[u] - centre[u], start[v] - centre[v])
    ru, rv = point[0] - centre[u], point[1] - centre[v]
    n = math.hypot(ru, rv)
    return centre[u] + radius * ru / n, centre[v] + radius * rv / n


def _within(segment, point, u: int, v: int, from_end: bool) -> bool:
    """Whether ``point`` (on the block's curve) lies on the block itself."""
    kind, start, _end, centre, sweep, _ = segment
    tol = 1e-7
    if kind == "line":
        du, dv = _tangent(segment, True, u, v)
        t = (point[0] - start[u]) * du + (point[1] - start[v]) * dv
        return -tol <= t <= _length(segment, u, v) + tol
    q = [0.0, 0.0, 0.0]
    q[u], q[v] = point
    turned = _turn(_angle(centre, start, u, v), _angle(centre, q, u, v), sweep > 0)
    radius = math.hypot(start[u] - centre[u], start[v] - centre[v])
    return abs(turned) <= abs(sweep) + tol / radius or abs(turned) < tol / radius


def _with_point(segment, point, at_end: bool, u: int, v: int):
    """The block cut at ``point``: its new end (``at_end``) or its new start."""
    kind, start, end, centre, sweep, feed = segment
    cut = list(end if at_end else start)
    cut[u], cut[v] = point
    new = tuple(cut)
    if kind == "line":
        return (kind, start, new, None, 0.0, feed) if at_end else (kind, new, end, None, 0.0, feed)
    ccw = sweep > 0
    if at_end:
        turned = _turn(_angle(centre, start, u, v), _angle(centre, new, u, v), ccw)
        return kind, start, new, centre, turned, feed
    turned = _turn(_angle(centre, new, u, v), _angle(centre, end, u, v), ccw)
    if abs(abs(sweep) - TWO_PI) < 1e-12 and abs(turned) < 1e-12:
        turned = sweep  # a full circle that starts at its own cut point
    return kind, new, end, centre, turned, feed


def corner_geometry(core: Seam, pending: PendingCorner, second, axes):
    """(first block cut short, chamfer line or fillet arc, second block from the corner's end); all in
    program coordinates. ``,L``: the chamfer ends lie L along each block from the virtual corner (along
    an arc: arc length). ``,R``: the fillet is tangent to both blocks, on the inner side of the turn."""
    u, v, _ = axes
    first = pending.segment
    size = pending.size_mm
    corner = first[2]
    feed = first[5]
    t_in, t_out = _tangent(first, True, u, v), _tangent(second, False, u, v)
    cross = t_in[0] * t_out[1] - t_in[1] * t_out[0]
    dot = t_in[0] * t_out[0] + t_in[1] * t_out[1]
    if abs(cross) < 1e-9:
        what = "a straight continuation" if dot > 0 else "a reversal"
        raise core.error(f"chamfer/corner {pending.word}: the blocks meet in {what}, there is no corner to "
                         f"{'chamfer' if pending.word == ',L' else 'round'}", "bad-corner")  # fmt: skip
    if pending.word != ",R":  # a chamfer: ,L (GSK) or ,C (Fanuc)
        for segment in (first, second):
            if size > _length(segment, u, v) + 1e-9:
                raise core.error(f"chamfer ,L{size / core.state.scale:g} is longer than the block "
                                 f"({_length(segment, u, v) / core.state.scale:.4f}) (GSK 25i §3.2.11)",
                                 "bad-corner")  # fmt: skip
        end_first = _along(first, size, True, u, v)
        start_second = _along(second, size, False, u, v)
        cut_first = _with_point(first, end_first, True, u, v)
        cut_second = _with_point(second, start_second, False, u, v)
        chamfer = ("line", cut_first[2], cut_second[1], None, 0.0, feed)
        return _nonzero(cut_first, u, v), chamfer, _nonzero(cut_second, u, v)
    side = 1.0 if cross > 0 else -1.0
    candidates = _intersections(_offset_curve(first, side, size, u, v),
                                _offset_curve(second, side, size, u, v))  # fmt: skip
    tangent_first = tangent_second = centre = None
    for c in sorted(candidates, key=lambda q: math.hypot(q[0] - corner[u], q[1] - corner[v])):
        tf, ts = _foot(first, c, u, v), _foot(second, c, u, v)
        if _within(first, tf, u, v, True) and _within(second, ts, u, v, False):
            tangent_first, tangent_second, centre = tf, ts, c
            break
    if centre is None:
        raise core.error(f"corner rounding ,R{size / core.state.scale:g} does not fit the blocks (it would "
                         "go beyond a block, GSK 25i §3.2.11)", "bad-corner")  # fmt: skip
    cut_first = _with_point(first, tangent_first, True, u, v)
    cut_second = _with_point(second, tangent_second, False, u, v)
    centre3 = list(corner)
    centre3[u], centre3[v] = centre
    sweep = _turn(_angle(centre3, cut_first[2], u, v), _angle(centre3, cut_second[1], u, v), side > 0)
    fillet = ("arc", cut_first[2], cut_second[1], tuple(centre3), sweep, feed)
    return _nonzero(cut_first, u, v), fillet, _nonzero(cut_second, u, v)


def _nonzero(segment, u: int, v: int):
    """None for a block cut down to nothing (the chamfer/fillet takes all of it)."""
    return None if _length(segment, u, v) < 1e-9 else segment


def finish(core: Seam) -> None:
    """End of the program (a block hook): a chamfer/corner block still waiting has no next move."""
    if core.state.pending is not None:
        finish_corner(core)
