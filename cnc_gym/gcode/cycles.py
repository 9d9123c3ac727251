"""Canned cycles (G73-G89, group 09), special pocket/boss cycles (G110-G137) and hole patterns
(G120-G127) of the GSK 25i (seed notes §4, manual L2338-L5077).

The geometry is pure: :func:`drill_steps`, :func:`pocket_steps`, :func:`pattern_holes` and
:func:`face_mill_steps` take the cycle's numbers and return a list of *steps* in program coordinates (mm,
after G20 scaling, before work offsets and transforms). :func:`emit` sends steps through the
interpreter's coordinate seam (``Interpreter.move_linear`` / ``move_arc``), so G52/G54/G92, scaling,
rotation and tool offsets apply to cycle moves exactly as to programmed ones. :func:`cycle_block` and
friends are the interpreter's actions; all cycle state lives in :class:`CycleState` on the interpreter.

Steps are tuples (cheap to build, easy to compare in tests):

``("rapid", (x, y, z))``                 rapid; a ``None`` coordinate keeps the axis where it is
``("feed", (x, y, z), feed, locked)``    feed move at ``feed`` mm/min; ``locked`` = override fixed at 100 %
``("arc", (x, y, z), (cx, cy, cz), sweep, feed)``  XY arc (sweep in rad, + = CCW) to the end
``("dwell", seconds)``
``("spindle", direction)``               spindle +1 CW (M03), -1 CCW (M04), 0 stop (M05)
``("orient",)``                          oriented spindle stop (M19): a 0 s exact-stop dwell, spindle 0
``("hold",)``                            feed hold for an operator action (G88, G87 I): a 0 s exact-stop dwell
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

from cnc_gym.errors import ConfigError
from cnc_gym.toolpath import PLANE_AXES, Plane, SegmentMode

if TYPE_CHECKING:
    from cnc_gym.gcode.interpreter import Interpreter

Vec = tuple[float, float, float]
Step = tuple
TWO_PI = 2.0 * math.pi
#: Drilling cycles (group 09) by G number.
DRILLING = frozenset({73, 74, 76, 81, 82, 83, 84, 85, 86, 87, 88, 89})
#: Special pocket/boss cycles (group 09) by G number.
POCKETS = frozenset({*range(110, 118), *range(130, 138)})
#: Cycles that need Q (alarm 45).
PECKING = frozenset({73, 83})
TAPPING = frozenset({74, 84})
#: Cycles with a shift at the hole bottom (Q, or I/J with 022#6 SIJ).
SHIFTING = frozenset({76, 87})
#: Words each cycle gives a meaning to (besides the axis words, F, S, T, O). I/J of G76/G87 are accepted
#: here and rejected in :func:`cycle_block` unless the SIJ parameter selects the I/J shift.
CYCLE_WORDS = {
    **{n: "RQPK" for n in DRILLING},
    76: "RQPKIJ", 87: "RQPKIJ",
    110: "RIKLWQVDP", 111: "RIKLWQVDP", 114: "RIJKLWQVDP", 115: "RIJKLWQVDP",
    112: "RIJDKQPL", 113: "RIJDKQPL", 116: "RIJDKQPL", 117: "RIJDKQPL",
    130: "RIJLWQVUDKP", 131: "RIJLWQVUDKP", 132: "RIJDLUKQP", 133: "RIJDLUKQP",
    134: "RIJLWQVEUDKP", 135: "RIJLWQVEUDKP", 136: "RIJDLUKQP", 137: "RIJDLUKQP",
}  # fmt: skip
#: Words of the one-shot pattern cycles.
PATTERN_WORDS = {120: "IJK", 121: "IJK", 122: "IJPK", 123: "IJPK", 124: "RIJPK", 125: "RIJPK", 126: "RIJL",
                 127: "RIJL"}  # fmt: skip


@dataclass(frozen=True)
class CycleParameters:
    """Machine parameters the cycles read (GSK number and standard setting beside each)."""

    #: P2010: G73 retract amount d, mm.
    g73_retract_mm: float = 0.5
    #: P2011: G83 clearance d (rapid re-approach stops d above the last depth), mm.
    g83_clearance_mm: float = 0.5
    #: P2000#0 FXY: False = the drilling axis is always Z; True = the axis normal to the selected plane.
    drilling_axis_follows_plane: bool = False
    #: P2000#5 RD2, #4 RD1 as 2·RD2 + RD1: G76/G87 shift 0 = +1st plane axis (G17 +X), 1 = -1st axis,
    #: 2 = +2nd axis (G17 +Y), 3 = -2nd axis.
    shift_direction: int = 0
    #: P2000#6 M5B: False = spindle stop (M05) is output before the oriented stop in G76/G87.
    no_m05_before_orient: bool = False
    #: P2141/P2142: largest spindle speed in rigid tapping, r/min (P2140, gear 1, is not printed; one gear).
    rigid_tap_max_rpm: float = 1000.0
    #: P1225/P1224: cutting-feed upper limit, mm/min (rigid tapping F above it is an alarm).
    max_cutting_feed: float = 4000.0
    #: The unnamed G124/G125 parameter: hole-to-hole moves as cutting feed (True) or rapid (False).
    pattern_moves_cutting: bool = False
    #: "022#6 SIJ" (L2618; not in the Parameter volume): True = the G76/G87 shift is the incremental
    #: vector I (X), J (Y), modal in the cycle mode, moved at the feed F; Q then shifts nothing (it stays
    #: the modal peck depth of G73/G83). False = the shift is |Q| in the 2000#4/#5 direction, at rapid.
    shift_by_ij: bool = False
    #: G87 variant (L3030-L3044): 2 = back boring (the manual's example X41), 1 = boring with a feed
    #: hold and manual retract at the bottom (like G88, without the shift). The manual names no selector
    #: but "canned cycle I / II"; its only parameter there, 009#7 FIX2, is not in the Parameter volume.
    g87_variant: int = 2

    def __post_init__(self) -> None:
        if self.shift_direction not in (0, 1, 2, 3):
            raise ConfigError(f"cycle parameter shift_direction {self.shift_direction!r}: must be 0..3 "
                              "(2000#5 RD2, #4 RD1 as 2·RD2 + RD1)")  # fmt: skip
        if self.g87_variant not in (1, 2):
            raise ConfigError(f"cycle parameter g87_variant {self.g87_variant!r}: must be 1 (manual retract) "
                              "or 2 (back boring)")  # fmt: skip


@dataclass
class CycleState:
    """Modal canned-cycle data of one run (group 09). ``code`` 0 = G80 (no cycle)."""

    code: int = 0
    #: Initial level: the program coordinate of the drilling axis when the cycle mode was entered.
    initial: float = 0.0
    #: R level (program mm, absolute: a G91 R is taken from the initial level when programmed) and the
    #: bottom Z: absolute, or (``z_from_r``, programmed in G91) the distance from the R level.
    z: float | None = None
    r: float | None = None
    z_from_r: bool = False
    q: float | None = None  # peck depth / shift, mm (|Q|)
    dwell_s: float = 0.0  # P, seconds
    words: dict = field(default_factory=dict)  # special-cycle data (I J L W V U D E), mm / plain
    #: G76/G87 I/J shift (SIJ), program mm; modal in the cycle mode (L2618), None = not programmed.
    shift_i: float | None = None
    shift_j: float | None = None
    rigid: bool = False  # M29 rigid tapping active
    rigid_pending: bool = False  # M29 given, the tapping cycle not yet

    def cancel(self) -> None:
        """G80 or a group-01 code: cycle off, Z, R and all hole data cleared (F is kept, L2655)."""
        self.code = 0
        self.z = self.r = self.q = None
        self.shift_i = self.shift_j = None
        self.z_from_r = False
        self.dwell_s = 0.0
        self.words = {}
        self.rigid = self.rigid_pending = False


# ====================================================================== pure geometry: drilling
def _at(hole: Vec, w: int, level: float) -> Vec:
    p = list(hole)
    p[w] = level
    return (p[0], p[1], p[2])


def drill_steps(code: int, hole: Vec, w: int, initial: float, r_level: float, bottom: float, *,
                return_initial: bool, feed: float, q: float = 0.0, dwell_s: float = 0.0,
                params: CycleParameters = CycleParameters(), spindle: int = 1, rigid: bool = False,
                shift: Vec = (0.0, 0.0, 0.0), shift_feed: float | None = None) -> list[Step]:  # fmt: skip
    """Moves of one hole of drilling cycle ``code`` (73..89), the tool already positioned over ``hole``
    (its drilling-axis coordinate ignored). ``w``: drilling axis index; levels are program coordinates
    of that axis. ``shift``: the G76/G87 shift vector (mm: the full |Q| in the parameter's direction, or
    the SIJ I/J vector). ``shift_feed``: None = the shift and the shift back are rapids (Q form); a feed
    = linear interpolation at that feed (the SIJ form, L2618). ``spindle``: the programmed spindle
    direction restored after a reversal or stop. ``params.g87_variant`` picks G87 I (manual retract) or
    II (back boring). Sequences: seed notes §4.2 (L2474-L3288)."""
    at = _at
    retract = initial if return_initial else r_level
    steps: list[Step] = []
    if code == 87 and params.g87_variant == 2:
        return _back_boring(hole, w, initial, r_level, bottom, feed, dwell_s, params, shift, shift_feed)
    steps.append(("rapid", at(hole, w, r_level)))
    if code in PECKING:
        d = params.g73_retract_mm if code == 73 else params.g83_clearance_mm
        depth = r_level
        while True:
            target = max(depth - q, bottom)
            steps.append(("feed", at(hole, w, target), feed, False))
            if target <= bottom:
                break
            if code == 73:
                steps.append(("rapid", at(hole, w, target + d)))  # up by d, the next feed starts there
            else:
                steps.append(("rapid", at(hole, w, r_level)))  # back to R, then down to d above the depth
                steps.append(("rapid", at(hole, w, min(target + d, r_level))))
            depth = target
        steps.append(("rapid", at(hole, w, retract)))
        return steps
    if code in TAPPING:
        tap = -1 if code == 74 else 1  # G74 left-hand (CCW in), G84 right-hand (CW in)
        steps.append(("spindle", tap))
        steps.append(("feed", at(hole, w, bottom), feed, True))
        if rigid:
            steps.append(("spindle", 0))
        if dwell_s > 0:
            steps.append(("dwell", dwell_s))
        steps.append(("spindle", -tap))
        steps.append(("feed", at(hole, w, r_level), feed, True))
        steps.append(("spindle", 0 if rigid else tap))
        if return_initial:
            steps.append(("rapid", at(hole, w, initial)))
        return steps
    steps.append(("feed", at(hole, w, bottom), feed, False))
    if code in (82, 87, 88, 89, 76) and dwell_s > 0:
        steps.append(("dwell", dwell_s))
    if code == 76:
        steps.extend(_oriented_stop(params))
        shifted = (hole[0] + shift[0], hole[1] + shift[1], hole[2] + shift[2])
        steps.append(_shift_move(at(shifted, w, bottom), shift_feed))
        steps.append(("rapid", at(shifted, w, retract)))
        steps.append(_shift_move(at(hole, w, retract), shift_feed))
        steps.append(("spindle", 1))  # M03 after the shift back (L2600)
        return steps
    if code in (85, 89):
        steps.append(("feed", at(hole, w, r_level), feed, False))
        if return_initial:
            steps.append(("rapid", at(hole, w, initial)))
        return steps
    if code == 86:
        steps.append(("spindle", 0))
        steps.append(("rapid", at(hole, w, retract)))
        steps.append(("spindle", spindle))
        return steps
    if code in (87, 88):
        # Spindle stop and feed hold at the bottom; the operator retracts (modelled as a rapid to the
        # return level), cycle start restarts the spindle CW (G88 L3075-L3121; G87 I L3030-L3034, whose
        # dwell P is the example's "stop at point Z", L3063).
        steps.append(("spindle", 0))
        steps.append(("hold",))
        steps.append(("rapid", at(hole, w, retract)))
        steps.append(("spindle", 1))
        return steps
    steps.append(("rapid", at(hole, w, retract)))  # G81, G82
    return steps


def _oriented_stop(params: CycleParameters) -> list[Step]:
    """Spindle stop (unless 2000#6 M5B) and oriented stop, before a G76/G87 shift."""
    return [("orient",)] if params.no_m05_before_orient else [("spindle", 0), ("orient",)]


def _shift_move(target: Vec, shift_feed: float | None) -> Step:
    """A G76/G87 shift or shift back: rapid (Q form) or linear at F (SIJ form, L2618)."""
    return ("rapid", target) if shift_feed is None else ("feed", target, shift_feed, False)


def _back_boring(hole: Vec, w: int, initial: float, r_level: float, top: float, feed: float, dwell_s: float,
                 params: CycleParameters, shift: Vec, shift_feed: float | None = None,
                 ) -> list[Step]:  # fmt: skip
    """G87 II (L2999-L3073): R is the hole bottom below the part, Z the top; always back to the initial
    level (the R level is under the part, so G99 cannot return there)."""
    at = _at
    shifted = (hole[0] + shift[0], hole[1] + shift[1], hole[2] + shift[2])
    steps: list[Step] = []
    steps.extend(_oriented_stop(params))
    steps.append(_shift_move(at(shifted, w, initial), shift_feed))
    steps.append(("rapid", at(shifted, w, r_level)))
    steps.append(_shift_move(at(hole, w, r_level), shift_feed))
    steps.append(("spindle", 1))
    steps.append(("feed", at(hole, w, top), feed, False))
    if dwell_s > 0:
        steps.append(("dwell", dwell_s))
    steps.extend(_oriented_stop(params))
    steps.append(_shift_move(at(shifted, w, top), shift_feed))
    steps.append(("rapid", at(shifted, w, initial)))
    steps.append(_shift_move(at(hole, w, initial), shift_feed))
    steps.append(("spindle", 1))
    return steps


def shift_vector(q: float, plane_u: int, plane_v: int, direction: int) -> Vec:
    """The G76/G87 shift: |q| along the plane's 1st (direction 0/1) or 2nd (2/3) axis, + or - (P2000#4/#5)."""
    axis = plane_v if direction >= 2 else plane_u
    out = [0.0, 0.0, 0.0]
    out[axis] = -abs(q) if direction % 2 else abs(q)
    return (out[0], out[1], out[2])


# ====================================================================== pure geometry: patterns
def pattern_holes(code: int, x: float, y: float, *, i: float = 0.0, j: float = 0.0, k: int = 0,
                  p: float = 0.0) -> list[tuple[float, float]]:  # fmt: skip
    """Hole positions (XY, mm) of G120-G123 (L4873-L4985). Angles in degrees.

    G120 bolt circle: centre (x, y), radius i, first angle j, k holes 360°/k apart.
    G121 line: start (x, y), spacing i (negative = the other way), angle j, k holes including the start.
    G122 arc: centre (x, y), radius i, first angle j, angular step p (CCW +), k holes.
    G123 grid: start (x, y), Δx i, nx = p holes, Δy j, ny = k rows, row by row alternating direction.
    """
    if code == 120:
        step = 360.0 / k
        return [(x + i * math.cos(math.radians(j + n * step)), y + i * math.sin(math.radians(j + n * step)))
                for n in range(k)]  # fmt: skip
    if code == 121:
        c, s = math.cos(math.radians(j)), math.sin(math.radians(j))
        return [(x + n * i * c, y + n * i * s) for n in range(k)]
    if code == 122:
        return [(x + i * math.cos(math.radians(j + n * p)), y + i * math.sin(math.radians(j + n * p)))
                for n in range(k)]  # fmt: skip
    if code == 123:
        holes = []
        nx = int(p)
        for row in range(k):
            cols = range(nx) if row % 2 == 0 else range(nx - 1, -1, -1)
            holes.extend((x + col * i, y + row * j) for col in cols)
        return holes
    raise ValueError(code)


def rectangle_holes(x: float, y: float, side1: float, side2: float, n1: int, n2: int, ccw: bool,
                    ) -> list[tuple[float, float]]:  # fmt: skip
    """G124 (CW) / G125 (CCW) rectangle drilling: first corner (x, y), side 1 along +X of length
    ``side1``, side 2 of length ``side2`` turning right (CW) or left (CCW). Sides 1 and 3 carry ``n1``
    holes, sides 2 and 4 ``n2``; a side's holes start at its first corner and are ``length / n`` apart
    (its end corner is the next side's first hole). docs/gcode.md explains this reading."""
    turn = 1.0 if ccw else -1.0
    corners = [(x, y), (x + side1, y), (x + side1, y + turn * side2), (x, y + turn * side2)]
    holes = []
    for side, count in enumerate((n1, n2, n1, n2)):
        (ax, ay), (bx, by) = corners[side], corners[(side + 1) % 4]
        holes.extend((ax + (bx - ax) * n / count, ay + (by - ay) * n / count) for n in range(count))
    return holes


def face_mill_steps(x: float, y: float, width_x: float, width_y: float, step: float, level: float,
                    r_level: float, initial: float, feed: float, zigzag: bool) -> list[Step]:  # fmt: skip
    """G126 (zig-zag) / G127 (one-way) face milling (L5025-L5062): passes along X of length
    ``width_x`` from (x, y), stepping ``step`` toward +Y (or -Y for a negative width) until ``width_y``
    is covered; the last pass lies exactly on ``y + width_y``. One-way: rapid up to R, back, feed down."""
    n = max(1, math.ceil(abs(width_y) / step - 1e-9))
    ys = [y + width_y * m / n for m in range(n + 1)]
    steps: list[Step] = [("rapid", (x, y, None)), ("rapid", (x, y, r_level)),
                         ("feed", (x, y, level), feed, False)]  # fmt: skip
    forward = True
    for index, py in enumerate(ys):
        if index:
            if zigzag:  # step over at the end of the previous pass
                steps.append(("feed", (steps[-1][1][0], py, level), feed, False))
            else:  # one way: up to R, back to the start side, down again
                steps.append(("rapid", (x + width_x, ys[index - 1], r_level)))
                steps.append(("rapid", (x, py, r_level)))
                steps.append(("feed", (x, py, level), feed, False))
        steps.append(("feed", (x + width_x if forward else x, py, level), feed, False))
        if zigzag:
            forward = not forward
    last = steps[-1][1]
    steps.append(("rapid", (last[0], last[1], r_level)))
    steps.append(("rapid", (last[0], last[1], initial)))
    return steps


# ====================================================================== pure geometry: pockets
def _loop_rect(cx: float, cy: float, hx: float, hy: float, corner: float, ccw: bool, z: float,
               feed: float) -> list[Step]:  # fmt: skip
    """Closed rounded-rectangle loop about (cx, cy), half-widths hx, hy, corner radius ``corner``
    (clipped to the half-widths), from the middle of the +X side back to it."""
    rho = max(0.0, min(corner, hx, hy))
    # The CCW walk in local coordinates: (side end, corner end, corner centre) per corner; the CW walk
    # from the same start is its mirror image (y -> -y), in the same order.
    walk = [
        ((hx, hy - rho), (hx - rho, hy), (hx - rho, hy - rho)),
        ((-hx + rho, hy), (-hx, hy - rho), (-hx + rho, hy - rho)),
        ((-hx, -hy + rho), (-hx + rho, -hy), (-hx + rho, -hy + rho)),
        ((hx - rho, -hy), (hx, -hy + rho), (hx - rho, -hy + rho)),
    ]
    sign = 1.0 if ccw else -1.0
    if not ccw:
        walk = [((a[0], -a[1]), (b[0], -b[1]), (c[0], -c[1])) for a, b, c in walk]
    steps: list[Step] = []
    for enter, leave, centre in walk:
        steps.append(("feed", (cx + enter[0], cy + enter[1], z), feed, False))
        if rho > 1e-9:
            steps.append(("arc", (cx + leave[0], cy + leave[1], z), (cx + centre[0], cy + centre[1], z),
                          sign * math.pi / 2.0, feed))  # fmt: skip
    steps.append(("feed", (cx + hx, cy, z), feed, False))
    return steps


def _circle(cx: float, cy: float, radius: float, ccw: bool, z: float, feed: float) -> list[Step]:
    """Full circle from (cx + radius, cy) as two half arcs (each record is an unambiguous half turn)."""
    sweep = math.pi if ccw else -math.pi
    return [("arc", (cx - radius, cy, z), (cx, cy, z), sweep, feed),
            ("arc", (cx + radius, cy, z), (cx, cy, z), sweep, feed)]  # fmt: skip


def _layers(r_level: float, bottom: float, first: float, step: float) -> list[float]:
    """Cut levels: ``first`` below R (clipped to the bottom), then ``step`` deeper each, the last = bottom."""
    levels = [max(r_level - first, bottom)]
    while levels[-1] > bottom + 1e-9:
        levels.append(max(levels[-1] - step, bottom))
    return levels


def pocket_steps(code: int, cx: float, cy: float, r_level: float, bottom: float, initial: float, *,
                 return_initial: bool, feed: float, tool_radius: float, i: float, j: float = 0.0,
                 l_step: float = 0.0, w_first: float = 0.0, q_step: float = 0.0, v_clear: float = 0.0,
                 u_corner: float = 0.0, e_stock: float = 0.0) -> list[Step]:  # fmt: skip
    """Tool-centre path of the special cycles G110-G117, G130-G137 in the XY plane (values already
    checked by :func:`check_pocket`). The figures are lost (seed notes §4.4-§4.8): the geometry below is
    our design, described in docs/gcode.md. Every cycle ends over (cx, cy) at the return level."""
    ccw = code % 2 == 0
    retract = initial if return_initial else r_level
    rt = tool_radius
    steps: list[Step] = []
    if code in (110, 111, 114, 115, 130, 131, 134, 135):
        if code in (110, 111):
            outer = i - rt
            radii = [min(outer, n * l_step) for n in range(1, math.ceil(outer / l_step - 1e-9) + 1)]
            start = (cx, cy)
            rings = [("circle", rad) for rad in radii]
        elif code in (114, 115):
            first, last = j + rt, i + rt
            count = math.ceil((first - last) / l_step - 1e-9)
            rings = [("circle", max(last, first - n * l_step)) for n in range(1, count + 1)]
            start = (cx + first, cy)
        else:
            hx, hy = i / 2.0, j / 2.0
            if code in (130, 131):
                ax, ay, rho = hx - rt, hy - rt, max(u_corner - rt, 0.0)
                m = min(ax, ay)
                offsets = [max(m - n * l_step, 0.0) for n in range(math.ceil(m / l_step - 1e-9) + 1)]
                rings = [("rect", ax - o, ay - o, max(rho - o, 0.0)) for o in offsets]
                start = (cx, cy)
            else:
                ax, ay, rho = hx + rt, hy + rt, u_corner + rt
                grow = (e_stock - 1.0) * max(hx, hy)
                count = max(1, math.ceil(grow / l_step - 1e-9))
                offsets = [max(grow - n * l_step, 0.0) for n in range(1, count + 1)]
                rings = [("rect", ax + o, ay + o, rho + o) for o in offsets]
                start = (cx + ax + grow, cy)
        levels = _layers(r_level, bottom, w_first, q_step)
        steps.append(("rapid", (start[0], start[1], None)))
        steps.append(("rapid", (start[0], start[1], r_level)))
        for index, level in enumerate(levels):
            if index:
                steps.append(("rapid", (start[0], start[1], min(levels[index - 1] + v_clear, r_level))))
            steps.append(("feed", (start[0], start[1], level), feed, False))
            for ring in rings:
                if ring[0] == "circle":
                    rad = ring[1]
                    steps.append(("feed", (cx + rad, cy, level), feed, False))
                    steps.extend(_circle(cx, cy, rad, ccw, level, feed))
                else:
                    _, hx_, hy_, rho_ = ring
                    steps.append(("feed", (cx + hx_, cy, level), feed, False))
                    steps.extend(_loop_rect(cx, cy, hx_, hy_, rho_, ccw, level, feed))
            last = steps[-1][1]
            steps.append(("rapid", (last[0], last[1], r_level)))
            steps.append(("rapid", (start[0], start[1], r_level)))
        steps.pop()  # no move back to the start after the last layer
    else:
        inside = code in (112, 113, 132, 133)
        if code in (112, 113, 116, 117):
            path = i - rt if inside else i + rt
            start_x = cx + j
            loop = _circle(cx, cy, path, ccw, bottom, feed)
            contact = cx + path
        else:
            hx, hy = i / 2.0 + (-rt if inside else rt), j / 2.0 + (-rt if inside else rt)
            rho = u_corner - rt if inside else u_corner + rt
            start_x = cx + i / 2.0 + (-l_step if inside else l_step)
            loop = _loop_rect(cx, cy, hx, hy, rho, ccw, bottom, feed)
            contact = cx + hx
        # Tangential half-circle lead-in and lead-out between the start point and the contact point on
        # the +X side: inside the pocket they turn the finishing way, outside the boss the other way
        # (L3568, L3805).
        mid = ((start_x + contact) / 2.0, cy, bottom)
        lead = math.pi if ccw else -math.pi
        if not inside:
            lead = -lead
        steps.append(("rapid", (start_x, cy, None)))
        steps.append(("rapid", (start_x, cy, r_level)))
        steps.append(("feed", (start_x, cy, bottom), feed, False))
        steps.append(("arc", (contact, cy, bottom), mid, lead, feed))
        steps.extend(loop)
        steps.append(("arc", (start_x, cy, bottom), mid, lead, feed))
        start = (start_x, cy)
    last = steps[-1][1]
    steps.append(("rapid", (last[0], last[1], retract)))
    steps.append(("rapid", (cx, cy, retract)))
    return steps


def check_pocket(code: int, *, tool_radius: float, i: float | None, j: float | None, l_step: float | None,
                 w_first: float | None, q_step: float | None, v_clear: float | None, u_corner: float | None,
                 e_stock: float | None) -> tuple[str, int] | None:  # fmt: skip
    """The special-cycle argument checks (alarms 210-228, seed notes §4.8): ``(message, alarm)`` or None."""
    rt = tool_radius
    rough = code in (110, 111, 114, 115, 130, 131, 134, 135)
    rect = code >= 130
    if not i:
        return "I (radius or X width) is missing or 0", 215
    if (rect or code not in (110, 111)) and j is None:
        return "J is missing", 216
    if rect and not j:
        return "J (Y width) is 0", 216
    if u_corner is not None and u_corner < 0:
        return f"U{u_corner:g} < 0", 224
    if rough:
        if w_first is None or w_first <= 0:
            return "W (first cut depth below R) is missing or not positive", 217
        if q_step is None or q_step <= 0:
            return "Q (depth per layer) is missing or not positive", 218
        if v_clear is None or v_clear <= 0:
            return "V (clearance above the uncut face) is missing or not positive", 220
        # "Less than the tool diameter" (G114: "radius"), yet every example steps L10 with D1 = 5: the
        # examples' reading, L up to the tool diameter, is the rule (docs/gcode.md).
        if l_step is None or l_step <= 0 or (rt > 0 and l_step > 2.0 * rt):
            return f"L (step over) must be > 0 and at most the tool diameter {2.0 * rt:g}", 219
    if code in (110, 111, 112, 113):
        if rt >= i:
            return f"tool radius {rt:g} is not smaller than the circle radius I{i:g}", 222
        if code in (112, 113) and abs(j) >= i - rt:
            return f"J{abs(j):g} leaves no room for the lead-in arc inside radius {i - rt:g}", 212
    if code in (114, 115) and j <= i:
        return f"the stock radius J{j:g} must be larger than the boss radius I{i:g}", 212
    if code in (116, 117) and abs(j) <= i + rt:
        return f"the start distance J{abs(j):g} must be larger than I + tool radius = {i + rt:g}", 212
    if rect:
        i, j = abs(i), abs(j)
        u = u_corner or 0.0
        if 2.0 * u > min(i, j):
            return f"corner radius U{u:g} is bigger than half of I{i:g}/J{j:g}", 210
        inside = code in (130, 131, 132, 133)
        if inside and 2.0 * rt >= min(i, j):
            return f"tool diameter {2 * rt:g} does not fit in I{i:g} x J{j:g}", 222
        if code in (132, 133) and rt > 0 and u < rt:
            return f"corner radius U{u:g} is smaller than the tool radius {rt:g}", 211
        if code in (130, 131) and u_corner and u_corner < rt:
            return f"corner radius U{u_corner:g} is smaller than the tool radius {rt:g}", 211
        if code in (132, 133, 136, 137):
            if l_step is None or l_step <= rt:
                return f"L (start distance from the side) must be larger than the tool radius {rt:g}", 213
            if inside and (l_step > i / 2.0 or (l_step - rt) / 2.0 > j / 2.0 - rt):
                return f"L{l_step:g}: the lead-in does not fit inside the pocket", 213
        if code in (134, 135):
            if not e_stock:
                return "E (stock size as a multiple of I and J) is missing or 0", 228
            if e_stock <= 1.0:
                return f"E{e_stock:g} must be more than 1", 226
    return None


# ====================================================================== interpreter side
def emit(interp: Interpreter, steps: list[Step]) -> None:
    """Send steps through the coordinate seam (program coordinates → transforms → offsets → machine)."""
    runner = interp.macro
    if runner is not None:  # a cycle block may drill thousands of holes: keep the run's bounds
        runner.check_bounds()
    out = interp.out
    for step in steps:
        kind = step[0]
        if kind == "rapid":
            interp.move_linear(True, step[1])
        elif kind == "feed":
            if step[3]:  # tapping: override fixed at 100 % (L2557, L3194)
                saved = out.modes
                out.modes = saved | SegmentMode.OVERRIDE_LOCKED
                try:
                    interp.move_linear(False, step[1], feed=step[2])
                finally:
                    out.modes = saved
            else:
                interp.move_linear(False, step[1], feed=step[2])
        elif kind == "arc":
            interp.move_arc(step[1], step[2], Plane.XY, step[3], step[4])
        elif kind == "dwell":
            out.dwell(step[1])
        elif kind == "spindle":
            interp.spindle_direction = step[1]
            out.spindle_rpm = interp.spindle_speed * step[1]
        elif kind == "orient":
            interp.spindle_direction = 0
            out.spindle_rpm = 0.0
            out.dwell(0.0, SegmentMode.EXACT_STOP)
            interp.spindle_orients += 1
        elif kind == "hold":
            out.dwell(0.0, SegmentMode.EXACT_STOP)
            interp.stops.append((out.line, "feed_hold"))
        else:  # pragma: no cover - the generators emit only the kinds above
            raise ValueError(kind)


def drilling_axes(interp: Interpreter) -> tuple[int, int, int]:
    """(u, v, w): the positioning axes and the drilling axis (P2000#0 FXY)."""
    if interp.cycle_params.drilling_axis_follows_plane:
        return PLANE_AXES[interp.plane]
    return (0, 1, 2)


def _level_now(interp: Interpreter, w: int) -> float:
    return interp.program_position[w]


#: Most pecks, passes or holes one cycle block may generate, counted across its K repeats and its pattern's
#: holes (a bound against a tiny Q or L, or a huge K, filling the memory: G73 Q0.011 K9999 made 60 million
#: moves).
MAX_STEPS = 100_000


def _limit(interp: Interpreter, count: float, what: str) -> None:
    if not count <= MAX_STEPS:  # also catches NaN
        raise interp.error(f"{what}: {count:.0f} is more than the {MAX_STEPS} one block may make",
                           "cycle-too-long", alarm=61)  # fmt: skip


def _times(repeats: int, holes: int) -> str:
    """How a per-hole count is multiplied in a block: `` x 99 repeats x 9801 holes``."""
    return (f" x {repeats} repeats" if repeats > 1 else "") + (f" x {holes} holes" if holes > 1 else "")


def _dwell_from_p(interp: Interpreter, values: dict) -> float:
    """Cycle P: dwell in ms, an integer like G04 P (L2395)."""
    text = interp._word_text("P")
    if text is not None and "." in text:
        raise interp.error(f"P{text}: the cycle dwell P is in milliseconds and takes no decimal point",
                           "decimal-point-not-allowed")  # fmt: skip
    if values["P"] < 0:
        raise interp.error(f"P{values['P']:g}: negative dwell", "bad-dwell")
    return round(values["P"]) / 1000.0


def _repeats(interp: Interpreter, values: dict) -> int:
    """K: repeat count of this block only; default 1, |K| for a negative K, K0 stores data only (L2410)."""
    if "K" not in values:
        return 1
    k = abs(values["K"])
    if k != int(k) or k > 99999:
        raise interp.error(f"K{values['K']:g}: the repeat count must be a whole number 0..99999", "bad-cycle")
    return int(k)


def _store_shift_ij(interp: Interpreter, code: int, values: dict, scale: float) -> None:
    """I/J of G76/G87: the shift increment when 022#6 SIJ is set (L2618), modal in the cycle mode (a block
    with only I/J stores them, it does not bore); without SIJ they mean nothing (``unused-word``). I is the
    X and J the Y increment ("X and Y axes move"); one along the drilling axis (2000#0 FXY in G18/G19)
    would move the tool in the hole, which the shift never does: an error."""
    if "I" not in values and "J" not in values:
        return
    letter = "I" if "I" in values else "J"
    if not interp.cycle_params.shift_by_ij:
        raise interp.error(f"address {letter} has no meaning with G{code}: the I/J shift needs parameter "
                           "022#6 SIJ (CycleParameters.shift_by_ij); the standard shift is Q", "unused-word")
    w = drilling_axes(interp)[2]
    for axis, letter in ((0, "I"), (1, "J")):
        if letter in values and axis == w and values[letter] != 0.0:
            raise interp.error(f"G{code} {letter}{values[letter]:g}: {letter} would shift along the drilling "
                               f"axis {interp.dialect.axes[w]}", "cycle-argument", alarm=61)  # fmt: skip
    state = interp.cycle
    if "I" in values:
        state.shift_i = values["I"] * scale
    if "J" in values:
        state.shift_j = values["J"] * scale


def _tool_radius(interp: Interpreter, values: dict, stored: dict) -> float:
    """Tool radius from the D offset number (D0 = radius 0, L3350); D missing is alarm 221."""
    if "D" in values:
        stored["D"] = int(values["D"])
    if "D" not in stored:
        raise interp.error("the special cycle needs D (tool radius offset number)", "cycle-argument",
                           alarm=221)  # fmt: skip
    number = stored["D"]
    if number == 0:
        return 0.0
    comp = getattr(interp, "comp", None)  # compensation.py's offset memory (G10 L12/L13, #2001...)
    if comp is None:
        raise interp.error(f"D{number}: tool radius offsets are not available yet", "not-implemented")
    return abs(comp.offsets.radius(number))


def cycle_block(interp: Interpreter, code: int | None, values: dict,
                hole_xy: tuple[float, float] | None = None, holes: int = 1) -> None:  # fmt: skip
    """One block in canned-cycle mode: ``code`` is the block's group-09 cycle (None: the modal one).
    Stores the hole data, then drills at the block's position (K times) if the block has an axis word or
    R (L2629); otherwise the block only updates data. ``hole_xy``: a pattern's hole (program mm) instead
    of the block's axis words; ``holes``: how many holes the pattern drills in all (the bound on the
    block's moves counts them)."""
    state = interp.cycle
    u, v, w = drilling_axes(interp)
    if code is not None:
        if state.rigid_pending and code not in TAPPING:
            raise interp.error(f"M29 rigid tapping is followed by G{code}, not G74/G84", "rigid-tap",
                               alarm=61)  # fmt: skip
        if state.rigid and state.code in TAPPING and code != state.code:
            raise interp.error(f"G{code} in rigid tapping mode: cancel with G80 first", "rigid-tap", alarm=61)
        if code in POCKETS and state.code in DRILLING:
            # Alarm 214 "CANNED CYCLE PUNCHING G73-G89 DEFINED": a special cycle while a drilling cycle is
            # modal (our reading of the alarm text; the manual's examples always start them from G80).
            raise interp.error(f"G{code} while the drilling cycle G{state.code} is active: cancel it with "
                               "G80", "cycle-argument", alarm=214)  # fmt: skip
        if state.code == 0:
            state.initial = _level_now(interp, w)  # latched on entering the cycle mode (L2386)
        state.code = code
        if state.rigid_pending:
            state.rigid, state.rigid_pending = True, False
    code = state.code
    if code in POCKETS and interp.plane != Plane.XY:
        raise interp.error(f"G{code} works in the G17 plane only", "cycle-argument", alarm=227)
    s = interp.scale
    letters = interp.dialect.axes
    bottom_letter = letters[w]
    if "R" in values:
        state.r = values["R"] * s + (state.initial if interp.incremental else 0.0)
    if bottom_letter in values:
        state.z = values[bottom_letter] * s
        state.z_from_r = interp.incremental
    if "P" in values:
        state.dwell_s = _dwell_from_p(interp, values)
    drills = hole_xy is not None or "R" in values or not interp._axis_letters.isdisjoint(values)
    if "Q" in values and (drills or code not in PECKING):
        state.q = abs(values["Q"]) * s  # the sign of Q is ignored (L2802); stored only when drilling (L2806)
    if code in SHIFTING:
        _store_shift_ij(interp, code, values, s)
    else:
        for letter in "IJLWVUE":
            if letter in values:
                state.words[letter] = values[letter] * (s if letter != "E" else 1.0)
    repeats = _repeats(interp, values)
    if not drills or repeats == 0:
        return
    if state.r is None or state.z is None:
        missing = " and ".join(n for n, val in (("R", state.r), (bottom_letter, state.z)) if val is None)
        raise interp.error(f"G{code} needs {missing}: the first drilling block gives all the hole data",
                           "cycle-missing-data", alarm=61)  # fmt: skip
    comp = getattr(interp, "comp", None)
    if comp is not None and comp.side:
        # "In the canned cycle mode, the tool offset is ignored" (L2516): compensation is suspended for the
        # block like for G53/G27-G30 (compensation.py: the last compensated block ends with its vector
        # perpendicular, the cycle's moves run uncompensated, and the next move in the plane after the cycle
        # starts the compensation up again).
        comp.before_machine_move()
    feed = interp.feed
    if not feed:
        raise interp.error(f"G{code} needs a feed: no F programmed yet" if feed is None else
                           f"G{code} with F0: the feed is zero", "missing-feed")  # fmt: skip
    if code in PECKING and not state.q:
        raise interp.error(f"G{code} needs Q (peck depth) in a drilling block", "cycle-missing-q", alarm=45)
    if state.rigid:
        params = interp.cycle_params
        if interp.spindle_speed > params.rigid_tap_max_rpm:
            raise interp.error(f"rigid tapping at S{interp.spindle_speed:g} exceeds the gear maximum "
                               f"{params.rigid_tap_max_rpm:g} r/min (P2140-P2142)", "rigid-tap",
                               alarm=200)  # fmt: skip
        if feed > params.max_cutting_feed:
            raise interp.error(f"rigid tapping F{feed:g} mm/min exceeds the cutting-feed limit "
                               f"{params.max_cutting_feed:g} (P1225)", "rigid-tap", alarm=61)  # fmt: skip
    return_initial = interp.modal.get(10) != 990
    words = (values.get("X"), values.get("Y"), values.get("Z"))
    words = tuple(None if a == w else t for a, t in enumerate(words))
    for _ in range(repeats):
        initial = state.initial
        r_level = state.r
        bottom = state.z + (r_level if state.z_from_r else 0.0)
        if code == 87 and interp.cycle_params.g87_variant == 2:
            if bottom <= r_level:
                raise interp.error(f"G87 back boring needs {bottom_letter} above R", "cycle-levels", alarm=61)
        elif bottom >= r_level:
            raise interp.error(f"G{code}: the hole bottom {bottom_letter} must lie below the R level",
                               "cycle-levels", alarm=61)  # fmt: skip
        here = interp.program_position
        target = (hole_xy[0], hole_xy[1], None) if hole_xy is not None else interp.resolve_target(*words)
        hole = tuple(here[a] if target[a] is None else target[a] for a in range(3))
        position = list(hole)
        position[w] = None
        emit(interp, [("rapid", tuple(position))])
        if code in DRILLING:
            params = interp.cycle_params
            q = state.q or 0.0
            shift_feed = None
            if params.shift_by_ij:
                # SIJ (L2618): the shift is the programmed increment I (X), J (Y), cut at F.
                shift = (state.shift_i or 0.0, state.shift_j or 0.0, 0.0)
                shift_feed = feed
            else:
                shift = shift_vector(q, u, v, params.shift_direction)
            chain = getattr(interp, "chain", None)
            if chain is not None and chain.active:
                # Scaling does not scale Q, d or the shift (L1962): they are machine amounts, so in
                # program coordinates they are divided by the map's factor along the drilling axis. The Q
                # shift is the program vector the map sends onto the machine-axis shift (2000#4/#5 name a
                # machine direction); the I/J shift is a programmed increment, so it turns and mirrors with
                # the map like any other but keeps its length.
                k = math.sqrt(sum(chain.linear[a][w] ** 2 for a in range(3))) or 1.0
                q = q / k
                params = replace(params, g73_retract_mm=params.g73_retract_mm / k,
                                 g83_clearance_mm=params.g83_clearance_mm / k)  # fmt: skip
                if shift_feed is None:
                    inv = chain.inverse_linear
                    shift = tuple(sum(inv[a][b] * shift[b] for b in range(3)) for a in range(3))
                else:
                    lin = chain.linear
                    mapped = math.hypot(*(sum(lin[a][b] * shift[b] for b in range(3)) for a in range(3)))
                    if mapped > 0.0:
                        factor = math.hypot(*shift) / mapped
                        shift = (shift[0] * factor, shift[1] * factor, shift[2] * factor)
            if code in PECKING:
                _limit(interp, (r_level - bottom) / q * repeats * holes,
                       f"G{code} pecks (depth / Q){_times(repeats, holes)}")  # fmt: skip
            else:
                _limit(interp, repeats * holes, f"G{code} holes{_times(repeats, holes)}")
            steps = drill_steps(code, hole, w, initial, r_level, bottom, return_initial=return_initial,
                                feed=feed, q=q, dwell_s=state.dwell_s, params=params,
                                spindle=interp.spindle_direction or 1, rigid=state.rigid,
                                shift=shift, shift_feed=shift_feed)  # fmt: skip
        else:
            steps = _pocket(interp, code, hole, values, r_level, bottom, initial, return_initial, feed,
                            repeats)  # fmt: skip
        emit(interp, steps)


def _pocket(interp: Interpreter, code: int, hole: Vec, values: dict, r_level: float, bottom: float,
            initial: float, return_initial: bool, feed: float, repeats: int) -> list[Step]:  # fmt: skip
    state = interp.cycle
    words = state.words
    radius = _tool_radius(interp, values, words)
    i, j = words.get("I"), words.get("J")
    problem = check_pocket(code, tool_radius=radius, i=None if i is None else abs(i),
                           j=None if j is None else abs(j), l_step=words.get("L"), w_first=words.get("W"),
                           q_step=state.q, v_clear=words.get("V"), u_corner=words.get("U"),
                           e_stock=words.get("E"))  # fmt: skip
    if problem is not None:
        raise interp.error(f"G{code}: {problem[0]}", "cycle-argument", alarm=problem[1])
    if code in (110, 111, 114, 115, 130, 131, 134, 135):
        span = max(abs(i), abs(j or 0.0)) * max(words.get("E", 1.0), 1.0)
        _limit(interp, (1 + (r_level - bottom) / state.q) * (1 + span / words["L"]) * repeats,
               f"G{code} passes{_times(repeats, 1)}")  # fmt: skip
    return pocket_steps(code, hole[0], hole[1], r_level, bottom, initial, return_initial=return_initial,
                        feed=feed, tool_radius=radius, i=abs(i), j=abs(j or 0.0), l_step=words.get("L", 0.0),
                        w_first=words.get("W", 0.0), q_step=state.q or 0.0, v_clear=words.get("V", 0.0),
                        u_corner=words.get("U", 0.0), e_stock=words.get("E", 0.0))  # fmt: skip


def cancel(interp: Interpreter) -> None:
    """G80 / a group-01 code: the cycle mode ends and its data are cleared."""
    interp.cycle.cancel()
    interp.modal[9] = 800


def rigid_tap(interp: Interpreter) -> None:
    """M29: rigid tapping for the next G74/G84 (L3198-L3212)."""
    state = interp.cycle
    if state.rigid or state.rigid_pending:
        raise interp.error("M29 while rigid tapping is already selected", "rigid-tap", alarm=61)
    state.rigid_pending = True


def _angle(interp: Interpreter, letter: str, values: dict) -> float:
    """Pattern angles: with a decimal point in degrees, without one in 0.001° (L4882)."""
    text = interp._word_text(letter)
    value = values[letter]
    if text is not None and "." not in text:
        return value / 1000.0
    return value


def _count(interp: Interpreter, letter: str, values: dict, code: int, *, required: bool) -> int:
    if letter not in values:
        if required:
            raise interp.error(f"G{code} needs {letter} (number of holes, 1..9999)", "cycle-argument",
                               alarm=225)  # fmt: skip
        return 0
    n = values[letter]
    if code in (124, 125):
        return max(0, int(n))  # negatives invalid, decimals truncated (L5071)
    if n != int(n) or not 1 <= n <= 9999:
        raise interp.error(f"G{code} {letter}{n:g}: the number of holes must be 1..9999", "cycle-argument",
                           alarm=225)  # fmt: skip
    return int(n)


def pattern_block(interp: Interpreter, code: int, values: dict, cycle_code: int | None) -> None:
    """G120-G127 (one-shot). G120-G125 drill every hole with the modal canned cycle (only positioning
    when none is active); G124/G125 take the cycle code of their own block; G126/G127 face-mill."""
    if code <= 123 and interp.cycle.code in POCKETS:
        # "G110 ... G137 isn't with the function of continuous drilling holes" (L5075): the patterns
        # drill with the standard cycles only (L4881), never a pocket per hole.
        raise interp.error(f"G{code} while the special cycle G{interp.cycle.code} is modal: the hole "
                           "patterns drill with G73-G89 only; cancel it with G80", "cycle-conflict",
                           alarm=61)  # fmt: skip
    comp = getattr(interp, "comp", None)
    if comp is not None and comp.side:
        comp.before_machine_move()  # the radius offset is ignored by the cycles (L2516): see cycle_block
    s = interp.scale
    here = interp.program_position
    target = interp.resolve_target(values.get("X"), values.get("Y"), None)
    x = here[0] if target[0] is None else target[0]
    y = here[1] if target[1] is None else target[1]
    if code in (126, 127):
        for letter in "IJLZR":
            if letter not in values:
                raise interp.error(f"G{code} needs {letter}", "cycle-argument", alarm=61)
        step = values["L"] * s
        if step <= 0:
            raise interp.error(f"G{code}: L (step over) must be > 0", "cycle-argument", alarm=219)
        initial = here[2]
        r_level = values["R"] * s + (initial if interp.incremental else 0.0)
        level = values["Z"] * s + (r_level if interp.incremental else 0.0)
        if level >= r_level:
            raise interp.error(f"G{code}: the milling level Z must lie below R", "cycle-levels", alarm=61)
        feed = interp.feed
        if not feed:
            raise interp.error(f"G{code} needs a feed", "missing-feed")
        _limit(interp, abs(values["J"] * s) / step, f"G{code} passes (J / L)")
        emit(interp, face_mill_steps(x, y, values["I"] * s, values["J"] * s, step, level, r_level, initial,
                                     feed, zigzag=code == 126))  # fmt: skip
        return
    if code in (124, 125):
        if cycle_code is None or cycle_code not in DRILLING - {76, 87}:
            raise interp.error(f"G{code} needs a drilling-mode G code (G73 G74 G81-G86 G88 G89) in its block",
                               "cycle-argument", alarm=61)  # fmt: skip
        if "J" not in values:
            raise interp.error(f"G{code} needs J (length of sides 2 and 4)", "cycle-argument", alarm=216)
        # The block's cycle code, R, Z, Q, P, F are the modal cycle data (stored without drilling).
        data = {k: v for k, v in values.items() if k in "RZQ"}  # P and K are the hole counts here
        data["K"] = 0.0  # store only: the pattern drills the holes
        cycle_block(interp, cycle_code, data)
        n13 = _count(interp, "P", values, code, required=False)
        n24 = _count(interp, "K", values, code, required=False)
        holes = rectangle_holes(x, y, values.get("I", 0.0) * s, values["J"] * s, n13, n24, ccw=code == 125)
        moves_cutting = interp.cycle_params.pattern_moves_cutting
    else:
        k = _count(interp, "K", values, code, required=True)
        for letter in ("I", "J") if code != 123 else ("I", "J", "P"):
            if letter not in values:
                raise interp.error(f"G{code} needs {letter}", "cycle-argument", alarm=61)
        if code == 120 and values["I"] <= 0:
            raise interp.error("G120: the radius I must be positive", "cycle-argument", alarm=215)
        if code == 122 and "P" not in values:
            raise interp.error("G122 needs P (angular step)", "cycle-argument", alarm=61)
        if code == 123:
            _limit(interp, k * values["P"], "G123 holes (P x K)")
            holes = pattern_holes(123, x, y, i=values["I"] * s, j=values["J"] * s, k=k,
                                  p=float(_count(interp, "P", values, code, required=True)))  # fmt: skip
        else:
            holes = pattern_holes(code, x, y, i=values["I"] * s, j=_angle(interp, "J", values), k=k,
                                  p=_angle(interp, "P", values) if code == 122 else 0.0)  # fmt: skip
        moves_cutting = False
    _drill_holes(interp, holes, last_uses_return=code in (124, 125), moves_cutting=moves_cutting)


def _drill_holes(interp: Interpreter, holes: list[tuple[float, float]], *, last_uses_return: bool,
                 moves_cutting: bool) -> None:  # fmt: skip
    """Drill each hole with the modal cycle, or only position when no cycle is active (L4869).
    ``last_uses_return``: G124/G125 return to R between holes, G98/G99 only after the last (L5069)."""
    state = interp.cycle
    saved_return = interp.modal.get(10)
    try:
        for index, (hx, hy) in enumerate(holes):
            if moves_cutting and index:
                emit(interp, [("feed", (hx, hy, None), interp.feed, False)])
            if state.code == 0:
                emit(interp, [("rapid", (hx, hy, None))])
                continue
            if last_uses_return and index < len(holes) - 1:
                interp.modal[10] = 990
            else:
                interp.modal[10] = saved_return
            cycle_block(interp, None, {}, hole_xy=(hx, hy), holes=len(holes))
    finally:
        if saved_return is not None:
            interp.modal[10] = saved_return


def check_rigid_pending(interp: Interpreter, values: dict, cycle_code: int | None) -> None:
    """Between M29 and its G74/G84 no S and no axis move may come (L3212, L3276)."""
    if cycle_code is None and ("S" in values or not interp._axis_letters.isdisjoint(values)):
        raise interp.error("S or an axis move between M29 and G74/G84", "rigid-tap", alarm=61)


_NOT_IN_CYCLE = {"G27": 44, "G28": 44, "G29": 44, "G30": 44, "G10": 61}


def check_block(interp: Interpreter, by_group: dict, motion_spec, axis_owner, items: list, values: dict):
    """Block checks of the cycle modes (the interpreter's hook; returns the owner of the axis words).

    A group-01 code in the block of a cycle code is alarm 61 (L2514); in a later block, and G80, it ends
    the cycle (L2655). G27-G30 in cycle mode: alarm 44; G10: must cancel first (L1500). G124/G125 take
    the drilling code of their block; with G120-G123 a cycle code is an error (ours: the manual ignores
    the cycle code, L4933)."""
    state = interp.cycle
    cycle_spec = by_group.get(9)
    owners = [spec for spec in items if getattr(spec, "uses_axes", False)]
    interp._block_cycle = None
    group01 = by_group.get(1)  # G00-G03, also G06.2 (not a "motion" action)
    if cycle_spec is not None and cycle_spec.action == "cycle":
        if group01 is not None:
            raise interp.error(f"{group01.name} (group 01) in the block of the canned cycle "
                               f"{cycle_spec.name}", "cycle-group01", alarm=61)  # fmt: skip
        pattern = next((spec for spec in owners if spec.action == "pattern"), None)
        if pattern is not None:
            if pattern.value not in (124, 125):
                raise interp.error(f"{pattern.name} and the canned cycle {cycle_spec.name} in one block",
                                   "cycle-conflict", alarm=61)  # fmt: skip
            interp._block_cycle = cycle_spec.value
            items.remove(cycle_spec)
            owners.remove(cycle_spec)
            axis_owner = pattern
    if len(owners) > 1 and not interp._axis_letters.isdisjoint(values):
        raise interp.error(f"{owners[0].name} and {owners[1].name} both use the axis words of the block",
                           "axis-word-conflict")  # fmt: skip
    if state.rigid_pending:
        check_rigid_pending(interp, values, cycle_spec.value if cycle_spec is not None else None)
    if (cycle_spec is not None and cycle_spec.action == "cycle_cancel") or group01 is not None:
        cancel(interp)
    elif state.code:
        one_shot = by_group.get(0)
        alarm = _NOT_IN_CYCLE.get(one_shot.name) if one_shot is not None else None
        if alarm is not None:
            raise interp.error(f"{one_shot.name} in canned-cycle mode: cancel the cycle with G80 first",
                               "cycle-not-allowed", alarm=alarm)  # fmt: skip
        plane = by_group.get(2)
        follows = interp.cycle_params.drilling_axis_follows_plane
        if plane is not None and follows and plane.value != interp.plane:
            # With FXY = 1 the plane picks the drilling axis, which may not change in a cycle (L2620).
            raise interp.error(f"{plane.name} changes the drilling axis in canned-cycle mode: cancel the "
                               "cycle with G80 first", "cycle-not-allowed", alarm=61)  # fmt: skip
    return axis_owner
