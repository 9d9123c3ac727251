"""The H4C-M's canned cycles and hole patterns (HUST H4C-M manual §3.19-§3.28 G80-G89, §3.33-§3.37
G34-G37).

**G81-G89** run the Fanuc family's modal cycle (``lang/fanuc/cycles.py``) with the H4C-M's differences:

* there is no G73, G74, G76, G84, G87 or G88 (G84 is in the manual's contents only: refused by name);
* the cycle always returns to the initial level (the start point S; G98 is the only return mode);
* G86 bores with a spindle stop at the bottom and retracts **at feed** (the cycle table's "G01 out");
* under G91, **R and Z are both increments from the start point S** (the initial level), not Z from R;
* G83's clearance d is MCM #282 (2.000 mm): feed Q, rapid up to R, rapid down to d above the depth cut,
  feed Q + d, … (the family's G83 steps);
* K is the number of times the block drills; K0 stores the cycle without drilling (the patterns' "drilling
  resource").

**G34-G37** position at rapid over each hole of a pattern and drill it with the stored cycle; without a
stored cycle they only position ("the canned cycle can only do the positioning without drillings"):

* ``G34 X Y I(radius) J(first angle) K(holes)``: a bolt circle, K holes 360°/K apart counter-clockwise;
* ``G35 X Y I(spacing) J(angle) K(holes)``: K holes on a line at angle J, the first at (X, Y);
* ``G36 X Y I(radius) J(first angle) P(angle step) K(holes)``: K holes on an arc;
* ``G37 X Y I(ΔX) P(holes per row) J(ΔY) K(rows)``: a grid, row by row, each row back the way the last
  came (zig-zag). The figures are lost; these are the readings the worked examples support.

Angles are degrees; J, P as angles and K, P as counts are read as plain numbers (``J45`` is 45°).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from cnc_gym.gcode.dialect import CycleKind
from cnc_gym.gcode.lang.fanuc import cycles as family
from cnc_gym.gcode.lang.fanuc.cycles import _at, cycle_block, drilling_axes, emit, limit

if TYPE_CHECKING:
    from cnc_gym.gcode.codes import CodeSpec
    from cnc_gym.gcode.dialect import Hole, Seam

Point = tuple[float, float]
MAX_HOLES = 9999


def bore_spindle_stop(core: Seam, h: Hole) -> list:
    """G86 boring (H4C-M): 1. rapid to R; 2. feed to Z; 3. spindle stop; 4. feed back to R; 5. rapid to
    the initial level; 6. spindle restarts in its programmed direction."""
    hole, w = h.hole, h.w
    return [("rapid", _at(hole, w, h.r_level)), ("feed", _at(hole, w, h.bottom), h.feed, False),
            ("spindle", 0),
            ("feed", _at(hole, w, h.r_level), h.feed, False), ("rapid", _at(hole, w, h.initial)),
            ("spindle", h.spindle)]  # fmt: skip


CYCLES = {**{k: family.CYCLES[k] for k in ("drill", "drill_dwell", "peck_deep", "bore", "bore_dwell")},
          "hust_bore_spindle_stop": CycleKind("hust_bore_spindle_stop", bore_spindle_stop)}  # fmt: skip


def cycle(core: Seam, spec: CodeSpec, values: dict) -> None:
    """A cycle block: under G91 the Z word is measured from the initial level, not from R (module
    docstring); then the family's modal cycle."""
    st = core.state
    w = drilling_axes(core)[2]
    letter = core.dialect.axes[w]
    if st.incremental and letter in values:
        state = st.cycle
        initial = core.program_position[w] if state.spec is None else state.initial
        r_level = values["R"] * st.scale + initial if "R" in values else state.r
        if r_level is None:
            raise core.error(f"{spec.name} under G91 needs R with the first Z (both measured from the start "
                             "point)", "cycle-missing-data")  # fmt: skip
        # The family adds R to a G91 Z (Z from R): give it the distance from R that lands on initial + Z.
        values = {**values, letter: values[letter] + (initial - r_level) / st.scale}
    family.cycle(core, spec, values)


def _polar(centre: Point, radius: float, degrees: list[float]) -> list[Point]:
    return [(centre[0] + radius * math.cos(math.radians(a)), centre[1] + radius * math.sin(math.radians(a)))
            for a in degrees]  # fmt: skip


def pattern_holes(code: int, origin: Point, values: dict, scale: float) -> list[Point]:
    """The holes of G34-G37 (module docstring), program mm."""
    i = values["I"] * scale
    if code == 34:
        n = int(values["K"])
        return _polar(origin, i, [values["J"] + k * 360.0 / n for k in range(n)])
    if code == 35:
        c, s = math.cos(math.radians(values["J"])), math.sin(math.radians(values["J"]))
        return [(origin[0] + k * i * c, origin[1] + k * i * s) for k in range(int(values["K"]))]
    if code == 36:
        return _polar(origin, i, [values["J"] + k * values["P"] for k in range(int(values["K"]))])
    dy = values["J"] * scale
    holes: list[Point] = []
    for row in range(int(values["K"])):
        columns = range(int(values["P"])) if row % 2 == 0 else range(int(values["P"]) - 1, -1, -1)
        holes.extend((origin[0] + col * i, origin[1] + row * dy) for col in columns)
    return holes


def hole_pattern(core: Seam, spec: CodeSpec, values: dict) -> None:
    """G34-G37 (``spec.value`` the G number; module docstring)."""
    code = int(spec.value)  # type: ignore[call-overload]
    needs = "IJK" if code in (34, 35) else "IJPK"
    for letter in needs:
        if letter not in values:
            raise core.error(f"{spec.name} needs {letter}", "cycle-argument")
    counts = "K" if code != 37 else "PK"
    for letter in counts:
        n = values[letter]
        if n != int(n) or not 1 <= n <= MAX_HOLES:
            raise core.error(f"{spec.name} {letter}{n:g}: a number of holes is 1-{MAX_HOLES}",
                             "cycle-argument")
    if code in (34, 36) and values["I"] <= 0:
        raise core.error(f"{spec.name} I{values['I']:g}: the radius must be positive", "cycle-argument")
    if code == 37:
        limit(core, values["P"] * values["K"], f"{spec.name} holes (P x K)")
    st = core.state
    here = core.program_position
    target = core.resolve_target(values.get("X"), values.get("Y"), None)
    origin = (here[0] if target[0] is None else target[0], here[1] if target[1] is None else target[1])
    holes = pattern_holes(code, origin, values, st.scale)
    if st.cycle.spec is None:
        for x, y in holes:  # no drilling cycle stored: positioning only
            emit(core, [("rapid", (x, y, None))])
        return
    for hole in holes:
        cycle_block(core, None, {}, hole_xy=hole, holes=len(holes))


ACTIONS = {"cycle": cycle, "hust_pattern": hole_pattern}
