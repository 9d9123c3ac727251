"""Coordinate systems of the Fanuc family: G54-G59 and G54.1 Pn work systems, G52 local system, G92
floating system, G10 data input (L2/L20 work offsets; L10-L13 tool offsets and L50 parameters hand over).

machine = program + G52 local + work origin; work origin = the G92 floating origin while one is set, else
external offset (G10 L2 P0) + the active work system's offset (``canonical.OffsetStack``). Offsets are
stored in mm: switching G20/G21 does not rescale them. docs/gcode.md "Coordinates and offsets".

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from cnc_gym.gcode.lang.fanuc import corners, parameters
from cnc_gym.gcode.lang.fanuc.transforms import check_coordinate_command
from cnc_gym.gcode.offsets import apply_g10

if TYPE_CHECKING:
    from cnc_gym.gcode.codes import CodeSpec
    from cnc_gym.gcode.dialect import Seam

EXTRA_WCS = 48  # G54.1 P1..P48 (§3.2.20)


def wcs(core: Seam, spec: CodeSpec, values: dict | None = None) -> None:
    """G54-G59: work coordinate system ``spec.value`` (1..6); drops a G92 floating system."""
    st = core.state
    number = spec.value
    if not isinstance(number, int) or not 1 <= number <= st.offsets.n_standard_wcs:
        raise ValueError(f"dialect {core.dialect.name}: {spec.name} selects work coordinate system "
                         f"{number!r}, not 1..{st.offsets.n_standard_wcs}")  # fmt: skip
    if st.chain.active:
        check_coordinate_command(core, spec.name)
    st.offsets.select_wcs(number - 1)
    st.extra_wcs = 0
    core.resync_program_position()
    if values is not None:  # not at power-on
        corners.mark_coordinate_change(core)


def wcs_extra(core: Seam, spec: CodeSpec, values: dict) -> None:
    """``G54.1 Pn``: additional work coordinate system n = 1..48; no P = P1 (§3.2.20). A P in the
    block belongs to G54.1 alone (§3.2.20: ``G54.1 G04 P1000`` is an error); ``spec.value`` holds the table
    keys of the codes whose P would collide."""
    st = core.state
    check_coordinate_command(core, "G54.1")
    collide = spec.value or frozenset()
    for word in st.block_words:  # (letter, digits) or (letter, value, text); text None = expression
        text = word[-1]
        if word[0] == "G" and text is not None and round(float(text) * 10) in collide:  # type: ignore[operator]
            raise core.error(f"in a G54.1 block P is the work offset number; G{text} cannot use it "
                             "(GSK 25i §3.2.20)", "bad-combination")  # fmt: skip
    number = values.get("P", 1.0)
    if number != int(number) or not 1 <= number <= EXTRA_WCS:
        raise core.error(f"G54.1 P{number:g}: additional work coordinate systems are P1..P{EXTRA_WCS}",
                         "bad-offset-number")  # fmt: skip
    st.offsets.select_wcs(st.offsets.n_standard_wcs + int(number) - 1)
    st.extra_wcs = int(number)
    core.resync_program_position()
    corners.mark_coordinate_change(core)


def local_origin(core: Seam, spec: CodeSpec, values: dict) -> None:
    """G52 IP_: local origin at IP in the current work system; IP0 cancels per axis (§3.2.14).
    The values are a setting, absolute whatever G90/G91 (docs/gcode.md)."""
    st = core.state
    if st.chain.active:
        check_coordinate_command(core, "G52", local=True)
    for axis, letter in enumerate(core.dialect.axes):
        if letter in values:
            st.offsets.local[axis] = values[letter] * st.scale
    st.offsets.update()
    core.resync_program_position()
    corners.mark_coordinate_change(core)


def floating_origin(core: Seam, spec: CodeSpec, values: dict) -> None:
    """G92 IP_: the current position gets coordinates IP in a floating system (§3.2.13)."""
    st = core.state
    if st.chain.active:
        check_coordinate_command(core, "G92")
    position = st.out.position
    for axis, letter in enumerate(core.dialect.axes):
        if letter in values:
            st.offsets.set_floating(axis, position[axis], values[letter] * st.scale)
    for axis, letter in enumerate(st.rotary_axes):  # degrees: G20/G21 do not scale them
        if letter in values:
            st.rotary_origin[axis] = st.out.rotary[axis] - values[letter]
    st.offsets.update()
    core.resync_program_position()
    corners.mark_coordinate_change(core)


def data_input(core: Seam, spec: CodeSpec, values: dict) -> None:
    """``G10 L2 Pp IP_`` (p = 0 external, 1..6 G54..G59), ``G10 L20 Pn IP_`` (G54.1 P1..P48), ``G10
    L10..L13 Pn R_`` (tool offsets, offsets.py), ``G10 L50`` (parameter input mode until G11). For L2 and
    L20 G90 sets and G91 adds (§3.2.10, §3.2.20)."""
    st = core.state
    if "L" not in values:
        raise core.error("G10 needs an L word (L2/L20 work offsets, L10-L13 tool offsets, L50 parameters)",
                         "missing-value")  # fmt: skip
    kind = int(values["L"])
    if kind in (10, 11, 12, 13):
        return _tool_offset(core, kind, values)
    if kind == 50:
        return parameters.open_input(core, values)
    if kind not in (2, 20):
        raise core.error(f"G10 L{kind} does not exist (L2, L10-L13, L20, L50)", "bad-g10")
    if "R" in values:
        raise core.error(f"address R has no meaning with G10 L{kind}", "unused-word")
    top = 6 if kind == 2 else EXTRA_WCS
    what = "0..6 (0 = external offset, 1..6 = G54..G59)" if kind == 2 else f"1..{EXTRA_WCS} (G54.1 P1..P48)"
    if "P" not in values:
        raise core.error(f"G10 L{kind} needs P{what}", "bad-g10")
    text = core.word_text("P")
    p = values["P"]
    low = 0 if kind == 2 else 1
    if (text is not None and "." in text) or p != int(p) or not low <= p <= top:
        raise core.error(f"G10 L{kind} P{text or p:}: P must be {what}", "bad-g10")
    offsets = st.offsets
    if kind == 2:
        target = offsets.external if p == 0 else offsets.wcs[int(p) - 1]
    else:
        target = offsets.wcs[offsets.n_standard_wcs + int(p) - 1]
    for axis, letter in enumerate(core.dialect.axes):
        if letter in values:
            mm = values[letter] * st.scale
            target[axis] = target[axis] + mm if st.incremental else mm
    offsets.update()
    core.resync_program_position()


def _tool_offset(core: Seam, kind: int, values: dict) -> None:
    """G10 L10-L13 P R: written to the tool offset memory (offsets.apply_g10)."""
    st = core.state
    for letter in core.dialect.axes:
        if letter in values:
            raise core.error(f"address {letter} has no meaning with G10 L{kind} (P number, R value)",
                             "unused-word")  # fmt: skip
    value = values.get("R")
    apply_g10(st.comp.offsets, kind, values.get("P"), None if value is None else value * st.scale,
              incremental=st.incremental, error=core.error)  # fmt: skip


ACTIONS = {
    "wcs": wcs, "wcs_extra": wcs_extra, "local_origin": local_origin, "floating_origin": floating_origin,
    "data_input": data_input,
}  # fmt: skip
