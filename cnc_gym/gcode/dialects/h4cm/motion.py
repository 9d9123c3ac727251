"""The H4C-M's motion codes where they differ from the Fanuc family (HUST H4C-M manual §3.5 G02/G03, §3.7
G04, §3.11-§3.13 G28/G29/G30):

* **G04 X** dwells X seconds, 0-8000 s; X without a decimal point counts 0.001 s (``G4 X1`` is 1 ms, the
  least-increment rule). There is no P form.
* **Arcs**: the family's I/J/K and R rules, with the H4C-M's own: an R arc may not sweep -10°…+10° or
  179°…181° ("do not use R"), so R full circles are refused; every arc block opens the arc mode that only a
  G00/G01 block closes (``blocks.py``, ERROR 25).
* **G28/G30** move the named axes (all if none) straight to the 1st/2nd reference point; the values of
  the words only select axes. **G29** returns the named axes (all if none) to where they were before the
  last G28/G30. Both at rapid, no intermediate point.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from cnc_gym.gcode.dialects.h4cm import blocks
from cnc_gym.gcode.dialects.h4cm.options import data
from cnc_gym.gcode.lang.fanuc import arcs, corners
from cnc_gym.gcode.lang.fanuc.least_units import is_whole, whole_count
from cnc_gym.gcode.lang.fanuc.reference import reference_point
from cnc_gym.toolpath import PLANE_AXES

if TYPE_CHECKING:
    from cnc_gym.gcode.codes import CodeSpec
    from cnc_gym.gcode.dialect import Seam

#: §2.2.5: G04 0-8000 s; X without a decimal point counts 0.001 s (§2.3.5's least increment).
MAX_DWELL_S = 8000.0
DWELL_UNIT_S = 0.001
#: §3.5: "Do not use R for sweeps of -10°…+10° or 179°…181°".
R_FORBIDDEN = ((0.0, 10.0), (179.0, 181.0), (350.0, 360.0))


def dwell(core: Seam, spec: CodeSpec, values: dict) -> None:
    """``G04 X_``: dwell X seconds (module docstring)."""
    for letter in "YZ":
        if letter in values:
            raise core.error(f"address {letter} has no meaning with G04 (the dwell is X seconds)",
                             "unused-word")
    if "X" not in values:
        raise core.error("G04 needs X (the dwell in seconds)", "missing-value")
    # X in seconds, never converted by G20; without a point a count of 1 ms (the 4/3 format's 0.001).
    seconds = whole_count(core, "X", values["X"]) * DWELL_UNIT_S if is_whole(core, "X") else values["X"]
    if not 0.0 <= seconds <= MAX_DWELL_S:
        raise core.error(f"G04 X{seconds:g}: the dwell is 0-{MAX_DWELL_S:g} s", "bad-dwell")
    core.state.out.dwell(seconds)


def r_sweep_deg(core: Seam, x, y, z, r: float) -> float | None:
    """The sweep (degrees, 0-360) of an R arc from the program position to the block's end point; None when
    R is too small for the chord (the family's arc rule names that)."""
    here = core.program_position
    target = core.resolve_target(x, y, z)
    end = [here[a] if t is None else t for a, t in enumerate(target)]
    u, v, _ = PLANE_AXES[core.state.plane]
    chord = math.hypot(end[u] - here[u], end[v] - here[v])
    radius = abs(r) * core.state.scale
    if radius == 0.0:
        return 0.0
    if chord > 2.0 * radius + core.dialect.arc_radius_tolerance_mm:
        return None
    minor = math.degrees(2.0 * math.asin(min(1.0, chord / (2.0 * radius))))
    return minor if r > 0 else 360.0 - minor


def arc(core: Seam, motion: int, x, y, z, values: dict) -> None:
    """G02/G03: the H4C-M's R rule, then the family's arc; the arc mode opens (module docstring)."""
    name = "G02" if motion == 2 else "G03"
    if "R" in values:
        sweep = r_sweep_deg(core, x, y, z, values["R"])
        for low, high in R_FORBIDDEN:
            if sweep is not None and low <= sweep <= high:
                raise core.error(f"{name} R{values['R']:g} sweeps {sweep:.1f}°: an R arc may not sweep "
                                 "-10°…+10° "
                                 "or 179°…181° (HUST H4C-M manual §3.5); give the centre with I/J/K",
                                 "arc-r-sweep")  # fmt: skip
    arcs.arc(core, motion, x, y, z, values)
    blocks.open_arc(core)


def reference(core: Seam, spec: CodeSpec, values: dict) -> None:
    """``G28 [X Y Z]`` / ``G30 [X Y Z]``: the named axes (all if none) at rapid straight to reference point 1
    (G28) or 2 (G30), machine coordinates (the preset's ``reference_1_mm``/``reference_2_mm``)."""
    st = core.state
    letters = core.dialect.axes
    axes = [a for a, letter in enumerate(letters) if letter in values] or [0, 1, 2]
    here = core.program_position
    memory = data(core).before_reference
    for a in range(3):
        memory[a] = here[a] if a in axes else None
    point = reference_point(core, int(spec.value))  # type: ignore[call-overload]
    m = st.out.position
    st.out.straight_traverse(tuple(point[a] if a in axes else m[a] for a in range(3)))  # type: ignore[arg-type]
    core.resync_program_position()
    corners.mark_coordinate_change(core)


def reference_back(core: Seam, spec: CodeSpec, values: dict) -> None:
    """``G29 [X Y Z]``: the named axes (all if none) at rapid back to where they were before the last
    G28/G30 (the values only select axes)."""
    letters = core.dialect.axes
    named = [a for a, letter in enumerate(letters) if letter in values]
    memory = data(core).before_reference
    axes = named or [a for a in range(3) if memory[a] is not None]
    missing = [letters[a] for a in axes if memory[a] is None]
    if missing or not axes:
        raise core.error(f"G29 {''.join(missing)}: no position stored before a G28/G30 for that axis",
                         "bad-reference")  # fmt: skip
    target = tuple(memory[a] if a in axes else None for a in range(3))
    core.move_linear(True, target)  # type: ignore[arg-type]
    corners.mark_coordinate_change(core)


ACTIONS = {"hust_dwell": dwell, "hust_reference": reference, "hust_reference_back": reference_back}
