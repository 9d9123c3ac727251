"""Coordinate transforms of the GSK 25i dialect: G16 polar input, G51/G51.1 scaling and mirror, G68
rotation, and how arcs go through them.

The stages themselves live in :mod:`cnc_gym.gcode.canonical` (:class:`~cnc_gym.gcode.canonical.
TransformChain`); this module holds the parts that need the interpreter's modal state: polar input (a
block's words → a Cartesian program point) and mapping an arc (given in program coordinates) to
machine coordinates. See docs/gcode.md, "Coordinates and transforms".
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

from cnc_gym.errors import ProgramError
from cnc_gym.toolpath import PLANE_AXES, Plane, SegmentMode

if TYPE_CHECKING:
    from cnc_gym.gcode.interpreter import Interpreter

TWO_PI = 2.0 * math.pi
_PLANE_AXES = {int(p): axes for p, axes in PLANE_AXES.items()}


class PolarState:
    """G16 polar input (L1775-L1865): the plane's first axis word is the radius, the second the angle
    (degrees, CCW from the first axis's + direction).

    * radius word in G90: the origin is the work zero; in G91: the origin is the current position
      (L1791-L1801);
    * angle word in G90: the angle itself; in G91: added to the last angle (L1833-L1845);
    * an omitted radius or angle keeps the last one (with the last origin), so ``G91 Y120`` steps round
      the same circle;
    * the plane's normal axis is an ordinary Cartesian word.
    """

    def __init__(self, program_position, plane: Plane) -> None:
        u, v, _ = _PLANE_AXES[int(plane)]
        # Start from the current point seen from the work zero.
        self.origin = (0.0, 0.0)
        self.radius = math.hypot(program_position[u], program_position[v])
        self.angle_deg = math.degrees(math.atan2(program_position[v], program_position[u]))

    def resolve(self, interp: Interpreter, words, plane: Plane | None = None):
        """Program-unit words (x, y, z; None = absent) → program target in mm (None = not commanded).

        ``plane``: the plane whose axes are (radius, angle); canned cycles pass XY whatever the plane
        (L1839-L1841)."""
        u, v, w = _PLANE_AXES[int(interp.plane if plane is None else plane)]
        s = interp.scale
        incremental = interp.incremental
        p = interp.program_position
        out: list[float | None] = [None, None, None]
        radius_word, angle_word = words[u], words[v]
        if radius_word is not None or angle_word is not None:
            if radius_word is not None:
                self.origin = (p[u], p[v]) if incremental else (0.0, 0.0)
                self.radius = radius_word * s
            if angle_word is not None:
                self.angle_deg = self.angle_deg + angle_word if incremental else angle_word
            a = math.radians(self.angle_deg)
            out[u] = self.origin[0] + self.radius * math.cos(a)
            out[v] = self.origin[1] + self.radius * math.sin(a)
        normal = words[w]
        if normal is not None:
            out[w] = p[w] + normal * s if incremental else normal * s
        return tuple(out)


def map_arc(interp: Interpreter, start, end, center, plane: Plane, sweep: float):
    """An arc in program coordinates → (end, centre, sweep) in machine coordinates.

    The chain is affine and keeps the arc's plane (G68 only rotates in the selected plane and a plane
    change in G68 mode is an error). With equal in-plane factors the image of the circle is a circle: the
    sweep keeps its size and flips its sign under a mirror (G02 ↔ G03, L1915). With unequal factors the
    controller traces no ellipse (L1936; the figures are lost): we keep the mapped centre and the mapped
    start, so the radius is the mapped start's distance from the mapped centre, and move the mapped end
    radially onto that circle; a full circle stays a full circle.
    """
    u, v, w = _PLANE_AXES[int(plane)]
    shape = interp.chain.plane_map(plane)
    if shape is None:
        raise interp.error(f"an arc in the {plane.name} plane while G68 rotates another plane",
                           "plane-change-in-rotation")  # fmt: skip
    a, b, c, d, _, similar = shape
    mirror = a * d - b * c < 0
    centre_program = list(center)
    centre_program[w] = start[w]
    start_m = interp.out.position
    end_m = list(interp.to_machine(end))
    centre_m = list(interp.to_machine(centre_program))
    centre_m[w] = start_m[w]
    if similar:
        return tuple(end_m), tuple(centre_m), -sweep if mirror else sweep
    radius = math.hypot(start_m[u] - centre_m[u], start_m[v] - centre_m[v])
    full = abs(abs(sweep) - TWO_PI) < 1e-12
    ccw = (sweep > 0) != mirror
    if full:
        end_m[u], end_m[v] = start_m[u], start_m[v]
        return tuple(end_m), tuple(centre_m), TWO_PI if ccw else -TWO_PI
    r_end = math.hypot(end_m[u] - centre_m[u], end_m[v] - centre_m[v])
    if radius < 1e-9 or r_end < 1e-9:
        raise interp.error("the scaled arc has radius 0", "arc-impossible")
    k = radius / r_end
    end_m[u] = centre_m[u] + (end_m[u] - centre_m[u]) * k
    end_m[v] = centre_m[v] + (end_m[v] - centre_m[v]) * k
    a0 = math.atan2(start_m[v] - centre_m[v], start_m[u] - centre_m[u])
    a1 = math.atan2(end_m[v] - centre_m[v], end_m[u] - centre_m[u])
    turned = (a1 - a0) % TWO_PI if ccw else -((a0 - a1) % TWO_PI)
    return tuple(end_m), tuple(centre_m), turned


# --------------------------------------------------------------------------- modal restrictions
def check_coordinate_command(interp: Interpreter, name: str, *, reference: bool = False,
                             local: bool = False) -> None:  # fmt: skip
    """Codes the transform modes forbid: G27-G30 (``reference``), G52 (``local``, G68 only), G54-G59,
    G54.1, G92 in G51 mode (alarm 109, L1935) and in G68 mode (L2041)."""
    if interp.chain.stages["scaling"] is not None and not local:
        raise interp.error(f"{name} is not allowed in scaling mode G51: cancel it with G50 first (L1935)",
                           "forbidden-in-scaling")  # fmt: skip
    if interp.chain.stages["rotation"] is not None:
        raise interp.error(f"{name} is not allowed in rotation mode G68: cancel it with G69 first (L2041)",
                           "forbidden-in-rotation")  # fmt: skip
    del reference


def check_plane_change(interp: Interpreter, plane: Plane) -> None:
    """G17/G18/G19 in G68 mode: alarm (L2039) unless it selects the plane already in use."""
    rotation = interp.chain.stages["rotation"]
    if rotation is not None and plane != interp.plane:
        raise interp.error(f"plane change to {plane.name} in rotation mode G68 (L2039)",
                           "plane-change-in-rotation")  # fmt: skip


# --------------------------------------------------------------------------- G68 / G69
def _centre(interp: Interpreter, values: dict, axes) -> tuple[float, float, float]:
    """A centre given by absolute axis words whatever G90/G91 (L1905, L2036), Cartesian even in G16;
    an omitted axis takes the current program position."""
    p = interp.program_position
    s = interp.scale
    letters = interp.dialect.axes
    return tuple(values[letters[a]] * s if a in axes and letters[a] in values else p[a]
                 for a in range(3))  # type: ignore[return-value]  # fmt: skip


def do_g68(interp: Interpreter, spec, values: dict) -> None:
    """``G68 α_ β_ R_`` (L2018-L2098): rotate the program about the centre (α, β in the plane, absolute;
    omitted = current position) by R degrees CCW. In G91, R adds to the angle in force (explanation 3,
    L2036: parameter 1850#0 RIN = 1). A G68 in G68 mode replaces the rotation (example 3 re-issues it)."""
    u, v, w = _PLANE_AXES[int(interp.plane)]
    letters = interp.dialect.axes
    if letters[w] in values:
        raise interp.error(f"G68 in the {interp.plane.name} plane takes the centre in "
                           f"{letters[u]}/{letters[v]}; {letters[w]} has no meaning",
                           "unused-word")  # fmt: skip
    centre = _centre(interp, values, (u, v))
    if "R" in values:
        angle = values["R"]
        if not -360.0 <= angle <= 360.0:
            raise interp.error(f"G68 R{angle:g}: the angle is -360..360 degrees", "bad-rotation-angle")
        if interp.incremental:
            angle += interp.rotation_deg
    else:
        angle = interp.parameters.rotation_deg()  # P1860
    angle = round(angle * 1000.0) / 1000.0  # least increment 0.001° (L2031)
    from cnc_gym.gcode.canonical import rotation_stage

    interp.rotation_deg = angle
    interp.chain.set("rotation", rotation_stage(interp.plane, centre, angle))
    interp.set_transform_state()


def do_g69(interp: Interpreter, spec, values: dict) -> None:
    """G69: rotation off. The tool's position is the start of the next move, which must be absolute
    (L2044: an incremental one "will not perform correctly": we make it an error)."""
    if interp.chain.stages["rotation"] is None:
        return
    interp.chain.set("rotation", None)
    interp.rotation_deg = 0.0
    interp.resync_program_position()
    interp.after_g69 = True  # cleared by the next move (resolve_target checks it)
    interp.set_transform_state()


# --------------------------------------------------------------------------- G51 / G50, G51.1 / G50.1
SCALE_RANGE = (0.001, 99.999)  # L1892


def _factor(interp: Interpreter, letter: str, value: float) -> float:
    if not SCALE_RANGE[0] <= abs(value) <= SCALE_RANGE[1]:
        raise interp.error(f"G51 {letter}{value:g}: the magnification is "
                           f"{SCALE_RANGE[0]:g}..{SCALE_RANGE[1]:g} (negative = mirror)",
                           "bad-scale-factor")  # fmt: skip
    return value


def do_g51(interp: Interpreter, spec, values: dict) -> None:
    """``G51 X_Y_Z_ P_`` or ``G51 X_Y_Z_ I_J_K_`` (L1866-L2016): scale about the centre (absolute;
    omitted = current position); a negative factor mirrors that axis. Alone in its block (L1898)."""
    letters = [w[0] for w in interp._block_words]
    if letters.count("G") > 1 or any(letter in "MFSTHD" for letter in letters):
        raise interp.error("G51 must be alone in its block (L1898): no other G, M, F, S, T, H or D word",
                           "g51-not-alone")  # fmt: skip
    if "P" in values and any(k in values for k in "IJK"):
        raise interp.error("G51 takes either P (all axes) or I/J/K (per axis), not both", "bad-combination")
    centre = _centre(interp, values, (0, 1, 2))
    if "P" in values:
        factors = (_factor(interp, "P", values["P"]),) * 3
    elif any(k in values for k in "IJK"):
        factors = tuple(_factor(interp, k, values[k]) if k in values else interp.parameters.scale(a)
                        for a, k in enumerate("IJK"))  # fmt: skip
    else:
        factors = (interp.parameters.scale(None),) * 3  # P1861, latched now (L1954)
    from cnc_gym.gcode.canonical import scaling_stage

    interp.chain.set("scaling", scaling_stage("G51", centre, factors))  # type: ignore[arg-type]
    interp.set_transform_state()


def do_g50(interp: Interpreter, spec, values: dict) -> None:
    """G50: scaling off; the tool's position is the start of the next move (L1932)."""
    if interp.chain.stages["scaling"] is None:
        return
    interp.chain.set("scaling", None)
    interp.resync_program_position()
    interp.set_transform_state()


def do_g51_1(interp: Interpreter, spec, values: dict) -> None:
    """``G51.1 X_Y_Z_``: programmable mirror of the commanded axes about the given coordinates (absolute);
    mirrors already set on other axes stay. (GSK lists G50.1/G51.1 in #4022 only; Fanuc semantics.)"""
    letters = interp.dialect.axes
    if not any(letter in values for letter in letters):
        raise interp.error("G51.1 needs the mirror axis coordinates (e.g. G51.1 X50)", "missing-value")
    s = interp.scale
    for a, letter in enumerate(letters):
        if letter in values:
            interp.mirror_axes[a] = values[letter] * s
    _install_mirror(interp)


def do_g50_1(interp: Interpreter, spec, values: dict) -> None:
    """``G50.1 X_Y_Z_``: cancel the mirror of the commanded axes (the values are not used); alone = all."""
    letters = interp.dialect.axes
    named = [a for a, letter in enumerate(letters) if letter in values]
    for a in named or list(interp.mirror_axes):
        interp.mirror_axes.pop(a, None)
    interp.resync_program_position()
    _install_mirror(interp)


def _install_mirror(interp: Interpreter) -> None:
    from cnc_gym.gcode.canonical import scaling_stage

    if interp.mirror_axes:
        centre = tuple(interp.mirror_axes.get(a, 0.0) for a in range(3))
        factors = tuple(-1.0 if a in interp.mirror_axes else 1.0 for a in range(3))
        interp.chain.set("mirror", scaling_stage("G51.1", centre, factors))  # type: ignore[arg-type]
    else:
        interp.chain.set("mirror", None)
        interp.resync_program_position()
    interp.set_transform_state()


# --------------------------------------------------------------------------- G16 / G15
def do_g16(interp: Interpreter, spec, values: dict) -> None:
    """G16: polar coordinate input on (L1775-L1865)."""
    if interp.polar is None:
        interp.polar = PolarState(interp.program_position, interp.plane)
        interp.set_transform_state()


def do_g15(interp: Interpreter, spec, values: dict) -> None:
    """G15: polar input off; the next move starts from the current tool position (L1843)."""
    if interp.polar is not None:
        interp.polar = None
        interp.resync_program_position()
        interp.set_transform_state()


# --------------------------------------------------------------------------- G54.1, G10 L20
EXTRA_WCS = 48  # G54.1 P1..P48 (L2131-L2187)


def do_g54_1(interp: Interpreter, spec, values: dict) -> None:
    """``G54.1 Pn``: additional work coordinate system n = 1..48; no P = P1 (L2131-L2187). A P in the
    block belongs to G54.1 alone (L2185: ``G54.1 G04 P1000`` is an error)."""
    check_coordinate_command(interp, "G54.1")
    for word in interp._block_words:  # (letter, digits) or (letter, value, text); text None = expression
        text = word[-1]
        if word[0] == "G" and text is not None and round(float(text) * 10) in (40, 100, 650, 300):
            raise interp.error(f"in a G54.1 block P is the work offset number; G{text} cannot use it "
                               "(L2185)", "bad-combination")  # fmt: skip
    number = values.get("P", 1.0)
    if number != int(number) or not 1 <= number <= EXTRA_WCS:
        raise interp.error(f"G54.1 P{number:g}: additional work coordinate systems are P1..P{EXTRA_WCS}",
                           "bad-offset-number", alarm=30)  # fmt: skip
    interp.offsets.select_wcs(interp.offsets.n_standard_wcs + int(number) - 1)
    interp.extra_wcs = int(number)
    interp.resync_program_position()
    mark_coordinate_change(interp)



# --------------------------------------------------------------------------- G10 data input
def do_g10(interp: Interpreter, spec, values: dict) -> None:
    """``G10 L2 Pp IP_`` (p = 0 external, 1..6 G54..G59), ``G10 L20 Pn IP_`` (G54.1 P1..P48), ``G10
    L10..L13 Pn R_`` (tool offsets, offsets.py), ``G10 L50`` (parameter input mode until G11). For L2 and
    L20 G90 sets and G91 adds (L1567-L1573, L2162)."""
    if "L" not in values:
        raise interp.error("G10 needs an L word (L2/L20 work offsets, L10-L13 tool offsets, L50 parameters)",
                           "missing-value")  # fmt: skip
    kind = int(values["L"])
    if kind in (10, 11, 12, 13):
        return _g10_tool_offset(interp, kind, values)
    if kind == 50:
        return _g10_parameter_mode(interp, values)
    if kind not in (2, 20):
        raise interp.error(f"G10 L{kind} does not exist (L2, L10-L13, L20, L50)", "bad-g10")
    if "R" in values:
        raise interp.error(f"address R has no meaning with G10 L{kind}", "unused-word")
    top = 6 if kind == 2 else EXTRA_WCS
    what = "0..6 (0 = external offset, 1..6 = G54..G59)" if kind == 2 else f"1..{EXTRA_WCS} (G54.1 P1..P48)"
    if "P" not in values:
        raise interp.error(f"G10 L{kind} needs P{what}", "bad-g10")
    text = interp._word_text("P")
    p = values["P"]
    low = 0 if kind == 2 else 1
    if (text is not None and "." in text) or p != int(p) or not low <= p <= top:
        raise interp.error(f"G10 L{kind} P{text or p:}: P must be {what}", "bad-g10")
    offsets = interp.offsets
    if kind == 2:
        target = offsets.external if p == 0 else offsets.wcs[int(p) - 1]
    else:
        target = offsets.wcs[offsets.n_standard_wcs + int(p) - 1]
    for axis, letter in enumerate(interp.dialect.axes):
        if letter in values:
            mm = values[letter] * interp.scale
            target[axis] = target[axis] + mm if interp.incremental else mm
    offsets.update()
    interp.resync_program_position()


def _g10_tool_offset(interp: Interpreter, kind: int, values: dict) -> None:
    """G10 L10-L13 P R: written through the compensation module's table (offsets.apply_g10)."""
    table = getattr(interp, "tool_offsets", None)
    if table is None:
        raise interp.error(f"G10 L{kind}: the tool offset table is not available", "not-implemented")
    for letter in interp.dialect.axes:
        if letter in values:
            raise interp.error(f"address {letter} has no meaning with G10 L{kind} (P number, R value)",
                               "unused-word")  # fmt: skip
    from cnc_gym.gcode.offsets import apply_g10

    value = values.get("R")
    apply_g10(table, kind, values.get("P"), None if value is None else value * interp.scale,
              incremental=interp.incremental, error=interp.error)  # fmt: skip


# --------------------------------------------------------------------------- controller parameters
#: Axis parameters among those the interpreter reads, and the raw ranges it checks.
AXIS_PARAMETERS = frozenset({1051, 1052, 1053, 1862, 1880})
PARAMETER_RANGES = {1051: 99999999, 1052: 99999999, 1053: 99999999, 1880: 9999999, 1860: 360000, 1861: 99999,
                    1862: 99999}  # fmt: skip


class Parameters:
    """The controller parameters the interpreter reads, as G10 L50 writes them (L1466-L1517).

    R takes no decimal point, so values are integers in the parameter's unit: lengths in 0.0001 mm (the
    least increment, L2101; P1051-P1053, P1880), the rotation angle in 0.001° (P1860), magnifications in
    0.001× (P1861, P1862; 1850#7 SCR = 0). Axis parameters take P1..P5 (display order: X, Y, Z, 4th,
    5th). Every write is kept in ``raw``; only the numbers below change what the interpreter does.
    """

    def __init__(self) -> None:
        self.raw: dict[tuple[int, int], int] = {}

    def write(self, interp: Interpreter, number: int, axis: int, value: int) -> None:
        if (number in AXIS_PARAMETERS and not 1 <= axis <= 5) or not 0 <= axis <= 5:
            raise interp.error(f"parameter {number} is an axis parameter: give P1..P5", "bad-g10")
        if number in (1860, 1861) and axis:  # other numbers: we do not know, P1..P5 accepted
            raise interp.error(f"parameter {number} is not an axis parameter: P has no meaning",
                               "unused-word")  # fmt: skip
        limit = PARAMETER_RANGES.get(number)
        if limit is not None and abs(value) > limit:
            raise interp.error(f"parameter {number} value {value} is out of range ±{limit}", "bad-parameter")
        if number in (1861, 1862) and value == 0:
            raise interp.error(f"parameter {number}: a magnification of 0 is not allowed", "bad-parameter")
        self.raw[(number, axis)] = value

    def axis_mm(self, number: int, axis: int) -> float:
        return self.raw.get((number, axis + 1), 0) * 0.0001

    def rotation_deg(self) -> float:
        return self.raw.get((1860, 0), 0) * 0.001

    def scale(self, axis: int | None) -> float:
        """P1861 (uniform, ``axis`` None) or P1862 (per axis); standard 1."""
        raw = self.raw.get((1861, 0)) if axis is None else self.raw.get((1862, axis + 1))
        return 1.0 if raw is None else raw * 0.001


def _g10_parameter_mode(interp: Interpreter, values: dict) -> None:
    """``G10 L50;`` opens parameter input; it must be alone in its block (L1496)."""
    others = [w[0] for w in interp._block_words if w[0] not in "GLNO"]
    gs = [w for w in interp._block_words if w[0] == "G"]
    if others or len(gs) > 1:
        raise interp.error("G10 L50 must be alone in its block (L1496)", "bad-g10")
    if interp.modal.get(9, 800) != 800:
        raise interp.error("G10 L50 in a canned cycle: cancel it with G80 first (L1500)", "bad-g10")
    interp.parameter_input = True


def parameter_block(interp: Interpreter, block) -> None:
    """A block inside G10 L50 mode: ``N_ R_`` or ``N_ P_ R_``, or ``G11`` (L1466-L1517)."""
    # (letter, digits) or (letter, value, text), text None = an expression; a plain block keeps its N word.
    words = [w for w in block.words if w[0] not in "NO"]
    letters = [w[0] for w in words]
    if letters == ["G"] and words[0][-1] is not None and round(float(words[0][-1]) * 10) == 110:
        interp.parameter_input = False
        return
    if block.number is None or not set(letters) <= {"P", "R"} or "R" not in letters:
        raise interp.error("inside G10 L50 only parameter blocks N_ R_ / N_ P_ R_ and G11 are allowed "
                           "(L1466-L1517)", "bad-g10")  # fmt: skip
    fields = {}
    wide = interp.dialect.parameter_input_r
    for word in words:
        letter, text = word[0], word[-1]
        if text is None and wide is not None and isinstance(word[1], tuple) and word[1][0] == "deferred":
            text = word[1][2]  # a literal beyond the R address's range (reader.py): the parameter rule's
            if "." not in text and not wide.low <= float(text) <= wide.high:
                raise interp.error(f"{letter}{text}: out of range {wide.low:.0f} to {wide.high:.0f}",
                                   "value-out-of-range", alarm=wide.alarm)  # fmt: skip
        if text is None:
            raise interp.error(f"{letter} of a parameter block takes a plain number (no variable: R has no "
                               "decimal point even from a variable, L1512)", "bad-g10")  # fmt: skip
        if "." in text:
            raise interp.error(f"{letter}{text}: no decimal point in a parameter block (L1512)",
                               "decimal-point-not-allowed")  # fmt: skip
        fields[letter] = int(float(text))
    interp.parameters.write(interp, int(block.number), fields.get("P", 0), fields["R"])


# --------------------------------------------------------------------------- G27 / G28 / G29 / G30
def reference_point(interp: Interpreter, n: int) -> tuple[float, float, float]:
    """Reference position n (1..4) in machine coordinates: the machine preset's ``reference_<n>_mm`` per
    axis (default the machine origin); P1051-P1053 written by G10 L50 override points 2-4."""
    machine = interp.machine
    base = [0.0, 0.0, 0.0]
    if machine is not None:
        base = [float(getattr(axis, f"reference_{n}_mm", 0.0)) for axis in machine.axes]
    if n >= 2:
        for a in range(3):
            if (1049 + n, a + 1) in interp.parameters.raw:
                base[a] = interp.parameters.axis_mm(1049 + n, a)
    return (base[0], base[1], base[2])


def _commanded(interp: Interpreter, values: dict) -> list[int]:
    return [a for a, letter in enumerate(interp.dialect.axes) if letter in values]


def _return_via(interp: Interpreter, name: str, values: dict, n: int) -> None:
    """G28/G30: rapid to the intermediate point (commanded axes), then to reference n (same axes)."""
    check_coordinate_command(interp, name, reference=True)
    axes = _commanded(interp, values)
    letters = interp.dialect.axes
    target = interp.resolve_target(*(values.get(letter) for letter in letters))
    for a in axes:
        interp.g28_intermediate[a] = target[a]  # stored in work coordinates, per axis (L2256)
    interp.move_linear(True, target)
    interp.comp.cancel_length_at_intermediate(interp, axes)  # the tool length vector, L3897
    reference = reference_point(interp, n)
    m = interp.out.position
    machine_target = tuple(reference[a] if a in axes else m[a] for a in range(3))
    interp.out.straight_traverse(machine_target)  # type: ignore[arg-type]
    interp.resync_program_position()
    mark_coordinate_change(interp)


def do_g28(interp: Interpreter, spec, values: dict) -> None:
    """``G28 IP_`` (L2215-L2260): via the intermediate point IP to reference position 1, commanded axes
    only, both legs at rapid."""
    _return_via(interp, "G28", values, 1)


def do_g30(interp: Interpreter, spec, values: dict) -> None:
    """``G30 [P2|P3|P4] IP_`` (L2296-L2336): like G28 to reference position 2 (default), 3 or 4."""
    p = values.get("P", 2.0)
    if p not in (2.0, 3.0, 4.0):
        raise interp.error(f"G30 P{p:g}: the reference position is P2, P3 or P4", "bad-reference")
    _return_via(interp, "G30", values, int(p))


def do_g29(interp: Interpreter, spec, values: dict) -> None:
    """``G29 IP_`` (L2262-L2294): rapid to the stored intermediate point, then to IP; in G91, IP is relative
    to the intermediate point. An axis not commanded but with an intermediate point stored returns to it
    and stays there ("the relative intermediate point in the axis doesn't have any move amount", L2270):
    the reading the manual's example X29 prints, (60, 30), against L2270's last sentence "other axes
    remain still". Axes with no intermediate point stay where they are (X28)."""
    check_coordinate_command(interp, "G29", reference=True)
    axes = _commanded(interp, values)
    letters = interp.dialect.axes
    missing = [letters[a] for a in axes if interp.g28_intermediate[a] is None]
    if missing:
        raise interp.error(f"G29 {''.join(missing)}: no intermediate point stored for that axis (G28/G30 "
                           "first)", "bad-reference", alarm=46)  # fmt: skip
    middle = tuple(interp.g28_intermediate)
    interp.move_linear(True, middle)
    s = interp.scale
    if interp.polar is None:
        base = middle if interp.incremental else (0.0, 0.0, 0.0)
        target = tuple(None if a not in axes else values[letters[a]] * s + base[a] for a in range(3))
    else:
        target = interp.resolve_target(*(values.get(letter) for letter in letters))
    interp.move_linear(True, target)
    mark_coordinate_change(interp)


#: Largest distance from the reference position that still counts as on it for G27 (mm).
REFERENCE_CHECK_MM = 0.0001


def do_g27(interp: Interpreter, spec, values: dict) -> None:
    """``G27 IP_`` (L2193-L2213): rapid to IP, then check that the commanded axes are on reference
    position 1; if not, alarm (46, the list's "ILLEGAL REFER. RETURN COMMAND")."""
    check_coordinate_command(interp, "G27", reference=True)
    axes = _commanded(interp, values)
    letters = interp.dialect.axes
    interp.move_linear(True, interp.resolve_target(*(values.get(letter) for letter in letters)))
    reference = reference_point(interp, 1)
    m = interp.out.position
    off = [letters[a] for a in axes if abs(m[a] - reference[a]) > REFERENCE_CHECK_MM]
    if off:
        where = ", ".join(f"{letters[a]} machine {m[a]:.4f} vs {reference[a]:.4f}" for a in axes)
        raise interp.error(f"G27: not on the reference position ({where})", "reference-check-failed",
                           alarm=46)  # fmt: skip


# --------------------------------------------------------------------------- G31, G60
def do_g31(interp: Interpreter, spec, values: dict) -> None:
    """``G31 IP_`` (L1383-L1455): a feed move like G01 that stops on the skip signal, then the next block
    runs from there (incremental from the break point; an absolute block moves only its own axes, L1405).
    The signal is simulated (``Interpreter.skip_signal``: program coordinate → the probe's surface per
    axis): the move stops where it first reaches one of them; with none reached (or no signal configured)
    the move completes. #5061-#5063 get the stop point (the block end without a signal, L5486), in work
    coordinates (``Interpreter.skip_position``, mm). Feed override is disabled on the move (L1398:
    override, dry run and acc/dec off unless 1940#7 SKF): the segment is flagged OVERRIDE_LOCKED. Not
    allowed with cutter compensation (alarm 36)."""
    if interp.modal.get(7, 400) != 400:
        raise interp.error("G31 in cutter compensation mode (cancel it with G40 first, L1395)",
                           "g31-in-cutter-compensation", alarm=36)  # fmt: skip
    letters = interp.dialect.axes
    target = interp.resolve_target(*(values.get(letter) for letter in letters))
    if target != (None, None, None):
        start = interp.program_position
        full = [start[a] if t is None else t for a, t in enumerate(target)]
        first = 1.0
        for letter, surface in interp.skip_signal.items():
            a = letters.index(letter)
            travel = full[a] - start[a]
            if travel and 0.0 <= (surface - start[a]) / travel <= first:
                first = (surface - start[a]) / travel
        if first < 1.0:  # the signal stops the move there: every axis at the same fraction (a straight move)
            target = tuple(start[a] + first * (full[a] - start[a]) for a in range(3))
        out = interp.out
        modes = out.modes
        out.modes = modes | SegmentMode.OVERRIDE_LOCKED | (SegmentMode.EXACT_STOP if first < 1.0 else 0)
        try:
            interp.move_linear(False, target)
        finally:
            out.modes = modes
    interp.skip_position = interp.program_position


#: Dwell at the overshoot point of G60 (L1350: "the defaulted dwell time is 1s").
G60_DWELL_S = 1.0


def do_g60(interp: Interpreter, spec, values: dict) -> None:
    """``G60 IP_`` (L1340-L1381): rapid to the end point less the overrun (P1880, per axis, in machine
    coordinates, not mirrored), dwell 1 s, then rapid in the approach direction to the end point. Axes
    with no overrun or no movement get none; with none at all it is a plain rapid."""
    letters = interp.dialect.axes
    target = interp.resolve_target(*(values.get(letter) for letter in letters))
    if target == (None, None, None):
        return
    p = interp.program_position
    full = tuple(p[a] if t is None else t for a, t in enumerate(target))
    start = interp.out.position
    end = list(interp.to_machine(full))
    if not interp._transformed:  # an omitted axis keeps its machine position (as in move_linear)
        end = [start[a] if target[a] is None else end[a] for a in range(3)]
    overshoot = list(end)
    used = False
    for a in range(3):
        overrun = interp.parameters.axis_mm(1880, a)
        if overrun and abs(end[a] - start[a]) > 1e-9:
            overshoot[a] = end[a] - overrun
            used = True
    if used:
        interp.out.straight_traverse(tuple(overshoot))  # type: ignore[arg-type]
        interp.out.dwell(G60_DWELL_S)
    interp.move_linear(True, target)



# --------------------------------------------------------------------------- chamfer and corner rounding
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
    modes: object
    armed: bool = False


def _corner_error(interp: Interpreter, message: str, code: str = "bad-corner") -> ProgramError:
    return interp.error(message, code)


def _capture(interp: Interpreter, motion: int, x, y, z, values: dict):
    """This block's move as geometry in program coordinates, without emitting it (None: no motion)."""
    was = interp._transformed
    saved = interp._program
    pending = interp._corner
    # The block starts where the waiting block ends (that one is not emitted yet).
    interp._program = pending.segment[2] if pending is not None else interp.program_position
    interp._transformed = True
    interp._capture = []
    try:
        if motion >= 2:
            interp._arc(motion, x, y, z, values)
        else:
            interp.move_linear(False, interp.resolve_target(x, y, z))
        captured = interp._capture
    finally:
        interp._capture = None
        interp._transformed = was
        interp._program = saved
    if not captured:
        return None
    kind, start, end = captured[0][:3]
    if kind == "line" and math.dist(start, end) < 1e-9:
        return None
    return captured[0]


class CoordinateChangeMark:
    """Set after G92, G52-G59, G54.1, G28-G30 or a plane change: the next block may not chamfer or round a
    corner (L1633). It rides in ``Interpreter._corner`` so the plain path pays nothing for it."""

    armed = False


def mark_coordinate_change(interp: Interpreter) -> None:
    corner = interp._corner
    if corner is None or isinstance(corner, CoordinateChangeMark):
        interp._corner = CoordinateChangeMark()
        return
    interp._corner = None
    raise interp.error(f"a coordinate system or plane change between a chamfer/corner {corner.word} block "
                       "and its next move (L1633)", "bad-corner")  # fmt: skip


def arm_corner(interp: Interpreter) -> None:
    """Called before each block while a chamfer/corner is pending: the block after it must move."""
    corner = interp._corner
    if isinstance(corner, CoordinateChangeMark):
        if corner.armed:  # the block right after the change is over
            interp._corner = None
        else:
            corner.armed = True
        return
    if corner.armed:
        interp._corner = None
        raise interp.error(f"the block after a chamfer/corner {corner.word} block (line {corner.line}) must "
                           "be a G01/G02/G03 move in the same plane (L1631)", "bad-corner")  # fmt: skip
    corner.armed = True


def finish_corner(interp: Interpreter) -> None:
    """End of program with a chamfer/corner block still waiting: it has no next move (L1631)."""
    corner = interp._corner
    interp._corner = None
    if isinstance(corner, CoordinateChangeMark):
        return
    raise interp.error(f"chamfer/corner {corner.word} in the last move block: no next move to meet (L1631)",
                       "bad-corner").located(interp.file, corner.line)  # fmt: skip


def corner_motion(interp: Interpreter, motion: int, x, y, z, values: dict) -> None:
    """A motion block while a chamfer/corner is pending, or one that carries ``,L``/``,R`` (L1597-L1646)."""
    words = [w for w in interp.dialect.corner_words if w in values]
    has_geometry = x is not None or y is not None or z is not None or (motion >= 2 and "R" in values) or (
        motion >= 2 and any(k in values for k in "IJK"))  # fmt: skip
    if isinstance(interp._corner, CoordinateChangeMark):
        if not has_geometry:
            return None  # the change's own block, or a block that does not move: the mark stays
        interp._corner = None
        if words:
            raise interp.error(f"chamfer/corner {words[0]} in the block right after a coordinate system or "
                               "plane change or a reference return (L1633)", "bad-corner")  # fmt: skip
        return interp._do_motion(None, values)
    if len(words) > 1:
        raise interp.error("a block takes either a chamfer ,L or a corner radius ,R, not both",
                           "bad-combination")  # fmt: skip
    pending = interp._corner
    if words:
        word = words[0]
        if interp.polar is not None:
            raise interp.error(f"chamfer/corner {word} in polar coordinate mode G16 (L1864)", "bad-corner")
        if motion == 0:
            raise interp.error(f"chamfer/corner {word} needs a G01/G02/G03 block", "bad-corner")
        if not has_geometry:
            raise interp.error(f"chamfer/corner {word} in a block that does not move", "bad-corner")
        if interp._restore_modes:  # G09 in this block; other group-00 codes own the axis words
            raise interp.error("G09 in a chamfer/corner block (L1646: no group-00 code but G04)",
                               "bad-corner")  # fmt: skip
        size = values[word] * interp.scale
        if size <= 0:
            raise interp.error(f"chamfer/corner {word}{values[word]:g}: the size must be positive",
                               "bad-corner")  # fmt: skip
    if not has_geometry:
        if pending is not None:
            raise interp.error(f"the block after a chamfer/corner {pending.word} block must be a G01/G02/G03 "
                               "move (L1631)", "bad-corner")  # fmt: skip
        return
    if pending is not None and motion == 0:
        raise interp.error(f"the block after a chamfer/corner {pending.word} block must be a G01/G02/G03 "
                           "move, not G00 (L1631)", "bad-corner")  # fmt: skip
    segment = _capture(interp, motion, x, y, z, values)
    if segment is None:
        if words or pending is not None:
            raise interp.error("chamfer/corner: the block does not move (zero length)", "bad-corner")
        return
    u, v, w = _PLANE_AXES[int(interp.plane)]
    if abs(segment[2][w] - segment[1][w]) > 1e-9 and (words or pending is not None):
        raise interp.error("chamfer/corner: the block moves the axis normal to the plane; chamfers and "
                           "corner rounding are in the selected plane only (L1627)",
                           "bad-corner")  # fmt: skip
    if pending is None:
        out = interp.out
        interp._corner = PendingCorner(words[0], size, segment, interp.plane, out.line, out.modes)
        return
    interp._corner = None
    if pending.plane != interp.plane:
        raise interp.error("chamfer/corner: the next block is in another plane (L1631)", "bad-corner")
    first, element, second = corner_geometry(interp, pending, segment, (u, v, w))
    line, modes = interp.out.line, interp.out.modes
    interp.out.line, interp.out.modes = pending.line, pending.modes
    try:
        for part in (first, element):
            if part is not None:
                _emit(interp, part)
    finally:
        interp.out.line, interp.out.modes = line, modes
    if words:
        if second is None:  # the corner took all of this block: nothing is left for its own ,L/,R
            raise interp.error(f"chamfer/corner {words[0]}: the previous corner {pending.word} takes all of "
                               "this block, so no corner of its own fits (L1637)", "bad-corner")  # fmt: skip
        interp._corner = PendingCorner(words[0], size, second, interp.plane, line, modes)
    elif second is not None:
        _emit(interp, second)


def _emit(interp: Interpreter, segment) -> None:
    kind, _, end, centre, sweep, feed = segment
    if kind == "line":
        interp.move_linear(False, end, feed=feed)
    else:
        interp.move_arc(end, centre, interp.plane, sweep, feed)


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
    q = (0.0,) * 3
    q = list(q)
    q[u], q[v] = point
    turned = _turn(_angle(centre, start, u, v), _angle(centre, q, u, v), sweep > 0)
    radius = math.hypot(start[u] - centre[u], start[v] - centre[v])
    return abs(turned) <= abs(sweep) + tol / radius or abs(turned) < tol / radius


def _with_point(segment, point, at_end: bool, u: int, v: int):
    """The block cut at ``point``: its new end (``at_end``) or its new start."""
    kind, start, end, centre, sweep, feed = segment
    new = list(end if at_end else start)
    new[u], new[v] = point
    new = tuple(new)
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


def corner_geometry(interp: Interpreter, pending: PendingCorner, second, axes):
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
        raise interp.error(f"chamfer/corner {pending.word}: the blocks meet in {what}, there is no corner to "
                           f"{'chamfer' if pending.word == ',L' else 'round'}", "bad-corner")  # fmt: skip
    if pending.word == ",L":
        for segment in (first, second):
            if size > _length(segment, u, v) + 1e-9:
                raise interp.error(f"chamfer ,L{size / interp.scale:g} is longer than the block "
                                   f"({_length(segment, u, v) / interp.scale:.4f}) (L1637)",
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
        raise interp.error(f"corner rounding ,R{size / interp.scale:g} does not fit the blocks (it would go "
                           "beyond a block, L1637)", "bad-corner")  # fmt: skip
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


#: Dialect action name → function(interp, spec, values); the interpreter routes them via _do_transform.
TRANSFORM_ACTIONS = {
    "g68": do_g68, "g69": do_g69, "g51": do_g51, "g50": do_g50, "g51_1": do_g51_1, "g50_1": do_g50_1,
    "g16": do_g16, "g15": do_g15, "g54_1": do_g54_1, "g10": do_g10, "g27": do_g27, "g28": do_g28,
    "g29": do_g29, "g30": do_g30, "g31": do_g31, "g60": do_g60,
}  # fmt: skip
