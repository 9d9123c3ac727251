"""Syntec 8.20's hole-pattern cycles G134-G137.1 (Syntec 8.20 mill programming manual §G134 circumference,
§G135 angular straight line, §G136 arc, §G137.1 chess (grid)): one-shot codes that drill every hole of a
pattern with the canned cycle in force (stored by a ``G8x … K0`` block before them).

X, Y are the pattern's centre or start, absolute in G90 and from the current position in G91; I and J
lengths (G70/G71 units); angles in degrees, or 0.001° without a decimal point (``P15000`` = 15°):

* ``G134 X Y I(radius) J(first angle) K(holes)``: K holes 360°/|K| apart, counter-clockwise for K > 0,
  clockwise for K < 0, K ≠ 0;
* ``G135 X Y I(spacing) J(angle) K(holes)``: K holes from the start along the angle J (CCW +); a negative
  I runs the other way;
* ``G136 X Y I(radius) J(first angle) P(angle step, CCW +) K(holes)``;
* ``G137.1 X Y I(X spacing) P(holes per row) J(Y spacing) K(rows)``: row by row, each row back the way
  the last one came (the order of the controllers whose G37.1 this is; the manual's figure is lost).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from cnc_gym.gcode.dialects.syntec.modes import angle, count
from cnc_gym.gcode.lang.fanuc.cycles import cycle_block, limit

if TYPE_CHECKING:
    from cnc_gym.gcode.codes import CodeSpec
    from cnc_gym.gcode.dialect import Seam

Point = tuple[float, float]
#: Most holes one pattern may have (K and P are 1..9999, §G134-§G137.1).
MAX_COUNT = 9999


def circle_holes(centre: Point, radius: float, first_deg: float, count: int) -> list[Point]:
    """G134: |count| holes on the circle, the first at ``first_deg``, CCW for count > 0, CW for < 0."""
    step = math.copysign(360.0 / abs(count), count)
    return _polar_holes(centre, radius, [first_deg + n * step for n in range(abs(count))])


def arc_holes(centre: Point, radius: float, first_deg: float, step_deg: float, count: int) -> list[Point]:
    """G136: ``count`` holes on the arc from ``first_deg`` every ``step_deg`` (CCW +)."""
    return _polar_holes(centre, radius, [first_deg + n * step_deg for n in range(count)])


def _polar_holes(centre: Point, radius: float, degrees: list[float]) -> list[Point]:
    return [(centre[0] + radius * math.cos(math.radians(a)), centre[1] + radius * math.sin(math.radians(a)))
            for a in degrees]  # fmt: skip


def line_holes(start: Point, spacing: float, angle_deg: float, count: int) -> list[Point]:
    """G135: ``count`` holes from ``start`` (the first) every ``spacing`` along ``angle_deg``."""
    c, s = math.cos(math.radians(angle_deg)), math.sin(math.radians(angle_deg))
    return [(start[0] + n * spacing * c, start[1] + n * spacing * s) for n in range(count)]


def grid_holes(start: Point, dx: float, columns: int, dy: float, rows: int) -> list[Point]:
    """G137.1: ``rows`` rows of ``columns`` holes, row by row, alternating direction (zig-zag)."""
    holes: list[Point] = []
    for row in range(rows):
        order = range(columns) if row % 2 == 0 else range(columns - 1, -1, -1)
        holes.extend((start[0] + col * dx, start[1] + row * dy) for col in order)
    return holes


def _count(core: Seam, spec: CodeSpec, letter: str, values: dict, *, signed: bool = False) -> int:
    if letter not in values:
        raise core.error(f"{spec.name} needs {letter} (a number of holes)", "cycle-argument")
    n = count(core, letter, values)
    if n != int(n) or not (1 <= abs(n) <= MAX_COUNT if signed else 1 <= n <= MAX_COUNT):
        what = "1..9999 or -1..-9999 (the sign is the direction)" if signed else "1..9999"
        raise core.error(f"{spec.name} {letter}{n:g}: the number of holes is {what}", "cycle-argument")
    return int(n)


def _need(core: Seam, spec: CodeSpec, values: dict, letters: str) -> None:
    for letter in letters:
        if letter not in values:
            raise core.error(f"{spec.name} needs {letter}", "cycle-argument")


def hole_pattern(core: Seam, spec: CodeSpec, values: dict) -> None:
    """G134/G135/G136/G137.1 (``spec.value`` the G number; module docstring)."""
    st = core.state
    if st.cycle.spec is None:
        raise core.error(f"{spec.name} drills with the canned cycle in force: store one first (e.g. "
                         "G81 Z_ R_ K0)", "pattern-no-cycle")  # fmt: skip
    here = core.program_position
    target = core.resolve_target(values.get("X"), values.get("Y"), None)
    origin = (here[0] if target[0] is None else target[0], here[1] if target[1] is None else target[1])
    s = st.scale
    code = spec.value
    if code == 134:
        _need(core, spec, values, "IJ")
        count = _count(core, spec, "K", values, signed=True)
        if values["I"] <= 0:
            raise core.error(f"{spec.name} I{values['I']:g}: the radius must be positive", "cycle-argument")
        holes = circle_holes(origin, values["I"] * s, angle(core, "J", values), count)
    elif code == 135:
        _need(core, spec, values, "IJ")
        count = _count(core, spec, "K", values)
        holes = line_holes(origin, values["I"] * s, angle(core, "J", values), count)
    elif code == 136:
        _need(core, spec, values, "IJP")
        if values["I"] <= 0:
            raise core.error(f"{spec.name} I{values['I']:g}: the radius must be positive", "cycle-argument")
        holes = arc_holes(origin, values["I"] * s, angle(core, "J", values), angle(core, "P", values),
                          _count(core, spec, "K", values))  # fmt: skip
    else:
        _need(core, spec, values, "IJ")
        columns, rows = _count(core, spec, "P", values), _count(core, spec, "K", values)
        limit(core, columns * rows, f"{spec.name} holes (P x K)")
        holes = grid_holes(origin, values["I"] * s, columns, values["J"] * s, rows)
    for hole in holes:
        cycle_block(core, None, {}, hole_xy=hole)


ACTIONS = {"hole_pattern": hole_pattern}
