"""The H4C-M's coordinate and data-setting codes (HUST H4C-M manual §3.9 G10, §3.15 G50/G51, §3.17
G68/G69):

* **G10 X Y Z** (no P) makes the tool's current position the given coordinates of the work system in
  force and writes the offset into that system (a G92 that persists: "the recommended method").
* **G10 … P1nn** (nn = 01-40, a tool group): X/Y/Z *set* the group's offsets, U/V/W *set* its wear,
  I/J/K *add* to its wear; R sets the group's radius (the R column of the offset page). The Z offset is
  the G43/G44 length (H nn), R + R wear the G41/G42 radius (D nn); the X/Y columns are kept but move
  nothing (the manual gives them no use on the mill).
* **G10 P100-P2002** system functions: P200 L sets the part-counter limit, P201 clears the counter, P2002
  clears #1-#9999. The others concern the machine's set-up, not the program's path (P100 in-position
  data, P510 baud rate, P600 flash burning, P800 G01 acc/dec time, P1000 factory parameters,
  P2000/P2001 program memory): refused by name (docs/h4cm.md).
* **G68 / G69** toggle the mirror of X / Y about the program origin ("reverse the sign of X coordinates";
  issuing it again restores it). Arcs reverse direction when one axis is mirrored.
* **G51 I J K** scales X, Y, Z by I, J, K (0.01-100; an axis not named keeps 1) about the position where
  G51 is given; G50 cancels.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from cnc_gym.gcode.canonical import scaling_stage
from cnc_gym.gcode.dialects.h4cm.options import data
from cnc_gym.gcode.lang.fanuc import corners

if TYPE_CHECKING:
    from cnc_gym.gcode.codes import CodeSpec
    from cnc_gym.gcode.dialect import Seam

#: Tool groups (§3.9.2: 40 sets of X, Y, Z, R offsets and wear).
TOOL_GROUPS = 40
#: G10 system functions the simulated machine does not have, with what they do on the controller.
SYSTEM_REFUSED = {
    100: "sets the in-position data of the servo (the machine preset's in_position_mm)",
    510: "sets the RS232 baud rate",
    600: "burns programs, parameters, ladder or system data into flash memory",
    800: "sets the G01 acc/dec time constant (MCM #167: the machine preset's post_filter_s)",
    1000: "resets every MCM parameter to the factory value",
    2000: "clears the current program from the controller's memory",
    2001: "clears all programs from the controller's memory",
}
MAX_COUNTER = 9_999_999
SCALE_RANGE = (0.01, 100.0)


def g10(core: Seam, spec: CodeSpec, values: dict) -> None:
    """``G10`` in its HUST forms (module docstring)."""
    if "P" not in values:
        return _work_origin(core, values)
    p = values["P"]
    if p != int(p):
        raise core.error(f"G10 P{p:g}: P is a whole number (P1nn tool groups, P100-P2002 functions)",
                         "bad-g10")
    p = int(p)
    if 101 <= p <= 100 + TOOL_GROUPS:
        return _tool_group(core, p - 100, values)
    _only(core, values, "PL", f"G10 P{p}")
    if p in SYSTEM_REFUSED:
        raise core.error(f"G10 P{p} {SYSTEM_REFUSED[p]}: a set-up function of the controller the simulation "
                         "does not have", "not-implemented")  # fmt: skip
    d = data(core)
    if p == 200:
        limit = values.get("L")
        if limit is None or limit != int(limit) or not 0 <= limit <= MAX_COUNTER:
            raise core.error(f"G10 P200 needs L, the part-counter limit 0-{MAX_COUNTER} (0: none)", "bad-g10")
        d.counter_limit = int(limit)
    elif p == 201:
        d.parts = 0
    elif p == 2002:
        clear = getattr(core.state.variables, "clear", None)
        if clear is not None:
            clear()
    else:
        raise core.error(f"G10 P{p}: no such data setting (P1nn tool groups 01-40, P100, P200, P201, P510, "
                         "P600, P800, P1000, P2000-P2002)", "bad-g10")  # fmt: skip


def _only(core: Seam, values: dict, letters: str, what: str) -> None:
    for letter in values:
        if letter not in letters:
            raise core.error(f"address {letter} has no meaning with {what}", "unused-word")


def _work_origin(core: Seam, values: dict) -> None:
    """``G10 X Y Z``: the current position becomes (X, Y, Z) of the work system in force."""
    _only(core, values, core.dialect.axes, "G10 without P (the work-origin setting)")
    st = core.state
    if st.chain.active:
        raise core.error("G10 X Y Z with mirror or scaling in force: cancel them first (G68/G69, G50)",
                         "bad-g10")  # fmt: skip
    offsets = st.offsets
    # H4C-M always has a work system in force (G54..G59 select one; only a DIN G53 selects none).
    assert offsets.active_wcs is not None
    entry = offsets.wcs[offsets.active_wcs]
    machine = st.out.position
    for axis, letter in enumerate(core.dialect.axes):
        if letter in values:
            entry[axis] = machine[axis] - values[letter] * st.scale - offsets.tool_length[axis]
    offsets.update()
    core.resync_program_position()
    corners.mark_coordinate_change(core)


def _tool_group(core: Seam, group: int, values: dict) -> None:
    """``G10 X Y Z / U V W / I J K [R] P1nn``: set offsets, set wear, add wear of tool group nn."""
    _only(core, values, "XYZUVWIJKRP", f"G10 P1{group:02d}")
    st = core.state
    s = st.scale
    offsets = st.comp.offsets
    xy = data(core).xy_offsets.setdefault(group, {"X": 0.0, "Y": 0.0, "X_wear": 0.0, "Y_wear": 0.0})
    for letters, wear, add in (("XYZ", False, False), ("UVW", True, False), ("IJK", True, True)):
        for axis, letter in enumerate(letters):
            if letter not in values:
                continue
            mm = values[letter] * s
            if axis == 2:
                offsets.set("H", group, mm, wear=wear, incremental=add, error=core.error)
            else:
                key = "XY"[axis] + ("_wear" if wear else "")
                xy[key] = xy[key] + mm if add else mm
    if "R" in values:
        offsets.set("D", group, values["R"] * s, error=core.error)


def mirror(core: Seam, spec: CodeSpec, values: dict) -> None:
    """G68 (``spec.value`` 0: X) / G69 (1: Y): toggle the mirror of that axis about the program origin."""
    _only(core, values, "", spec.name)
    st = core.state
    flags = data(core).mirror
    axis = int(spec.value)  # type: ignore[call-overload]
    flags[axis] = not flags[axis]
    if any(flags):
        factors = (-1.0 if flags[0] else 1.0, -1.0 if flags[1] else 1.0, 1.0)
        st.chain.set("mirror", scaling_stage(spec.name, (0.0, 0.0, 0.0), factors))
    else:
        st.chain.set("mirror", None)
    core.set_transform_state()
    core.resync_program_position()
    corners.mark_coordinate_change(core)


def scaling(core: Seam, spec: CodeSpec, values: dict) -> None:
    """``G51 I J K``: scale about the current position (module docstring)."""
    factors = []
    for letter in "IJK":
        factor = values.get(letter, 1.0)
        if not SCALE_RANGE[0] <= factor <= SCALE_RANGE[1]:
            low, high = SCALE_RANGE
            raise core.error(f"G51 {letter}{factor:g}: a scale factor is {low:g}-{high:g}",
                             "bad-scale-factor")  # fmt: skip
        factors.append(factor)
    if not any(letter in values for letter in "IJK"):
        raise core.error("G51 needs I, J or K (the X, Y, Z scale factors)", "missing-value")
    st = core.state
    centre = core.program_position
    st.chain.set("scaling", scaling_stage("G51", centre, (factors[0], factors[1], factors[2])))
    core.set_transform_state()


def scaling_cancel(core: Seam, spec: CodeSpec, values: dict | None = None) -> None:
    """G50: scaling off; the tool's position is the start of the next move."""
    st = core.state
    if st.chain.stages["scaling"] is None:
        return
    st.chain.set("scaling", None)
    core.resync_program_position()
    core.set_transform_state()


ACTIONS = {"hust_g10": g10, "hust_mirror": mirror, "hust_scaling": scaling,
           "hust_scaling_cancel": scaling_cancel}  # fmt: skip
