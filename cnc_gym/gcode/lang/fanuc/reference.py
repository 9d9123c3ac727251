"""Reference positions of the Fanuc family: G27 check, G28 return via an intermediate point, G29 return
from it, G30 2nd-4th reference positions, and G60 single-direction positioning.

Reference positions come from the machine preset (``AxisConfig.reference_1_mm`` … ``reference_4_mm``),
overridden for 2-4 by the parameters G10 L50 writes. Cutter compensation is suspended for these moves.

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from cnc_gym.gcode.lang.fanuc import compensation, corners, parameters
from cnc_gym.gcode.lang.fanuc.transforms import check_coordinate_command

if TYPE_CHECKING:
    from cnc_gym.gcode.codes import CodeSpec
    from cnc_gym.gcode.dialect import Seam

#: ``State.motion`` while single-direction positioning (G60) is the group-01 mode (GSK 1870#0 MDL = 1).
MODAL_POSITIONING = 60


def reference_point(core: Seam, n: int) -> tuple[float, float, float]:
    """Reference position n (1..4) in machine coordinates: the machine preset's ``reference_<n>_mm`` per
    axis (default the machine origin); P1051-P1053 written by G10 L50 override points 2-4."""
    machine = core.state.machine
    base = [0.0, 0.0, 0.0]
    if machine is not None:
        base = [float(getattr(axis, f"reference_{n}_mm", 0.0)) for axis in machine.axes]
    if n >= 2:
        for a in range(3):
            if parameters.raw(core, f"reference_{n}", a) is not None:
                base[a] = parameters.value(core, f"reference_{n}", 0.0, a)
    return (base[0], base[1], base[2])


def _commanded(core: Seam, values: dict) -> list[int]:
    return [a for a, letter in enumerate(core.dialect.axes) if letter in values]


def _return_via(core: Seam, name: str, values: dict, n: int) -> None:
    """G28/G30: rapid to the intermediate point (commanded axes), then to reference n (same axes)."""
    check_coordinate_command(core, name, reference=True)
    axes = _commanded(core, values)
    letters = core.dialect.axes
    target = core.resolve_target(*(values.get(letter) for letter in letters))
    for a in axes:
        core.state.g28_intermediate[a] = target[a]  # stored in work coordinates, per axis (§3.3.2)
    core.move_linear(True, target)
    compensation.cancel_length_at_intermediate(core, axes)  # the tool length vector, §3.5.1
    reference = reference_point(core, n)
    m = core.state.out.position
    machine_target = tuple(reference[a] if a in axes else m[a] for a in range(3))
    core.state.out.straight_traverse(machine_target)  # type: ignore[arg-type]
    core.resync_program_position()
    corners.mark_coordinate_change(core)


def _g28(core: Seam, spec, values: dict) -> None:
    """``G28 IP_`` (§3.3.2): via the intermediate point IP to reference position 1, commanded axes
    only, both legs at rapid."""
    _return_via(core, "G28", values, 1)


def _g30(core: Seam, spec, values: dict) -> None:
    """``G30 [P2|P3|P4] IP_`` (§3.3.3): like G28 to reference position 2 (default), 3 or 4."""
    p = values.get("P", 2.0)
    if p not in (2.0, 3.0, 4.0):
        raise core.error(f"G30 P{p:g}: the reference position is P2, P3 or P4", "bad-reference")
    _return_via(core, "G30", values, int(p))


def _g29(core: Seam, spec, values: dict) -> None:
    """``G29 IP_`` (§3.3.3): rapid to the stored intermediate point, then to IP; in G91, IP is relative
    to the intermediate point. An axis not commanded but with an intermediate point stored returns to it
    and stays there ("the relative intermediate point in the axis doesn't have any move amount", §3.3.3):
    the reading the manual's example X29 prints, (60, 30), against §3.3.3's last sentence "other axes
    remain still". Axes with no intermediate point stay where they are (X28)."""
    check_coordinate_command(core, "G29", reference=True)
    axes = _commanded(core, values)
    letters = core.dialect.axes
    missing = [letters[a] for a in axes if core.state.g28_intermediate[a] is None]
    if missing:
        raise core.error(f"G29 {''.join(missing)}: no intermediate point stored for that axis (G28/G30 "
                         "first)", "bad-reference", alarm="bad-reference/no-intermediate")  # fmt: skip
    stored = core.state.g28_intermediate
    middle = (stored[0], stored[1], stored[2])
    core.move_linear(True, middle)
    s = core.state.scale
    if core.state.polar is None:
        base = middle if core.state.incremental else (0.0, 0.0, 0.0)
        each = [None if a not in axes else values[letters[a]] * s + base[a] for a in range(3)]
        target = (each[0], each[1], each[2])
    else:
        target = core.resolve_target(*(values.get(letter) for letter in letters))
    core.move_linear(True, target)
    corners.mark_coordinate_change(core)


#: Largest distance from the reference position that still counts as on it for G27 (mm).
REFERENCE_CHECK_MM = 0.0001


def _g27(core: Seam, spec, values: dict) -> None:
    """``G27 IP_`` (§3.3.1): rapid to IP, then check that the commanded axes are on reference
    position 1; if not, ``reference-check-failed`` (GSK alarm 46, the list's "ILLEGAL REFER. RETURN
    COMMAND")."""
    check_coordinate_command(core, "G27", reference=True)
    axes = _commanded(core, values)
    letters = core.dialect.axes
    core.move_linear(True, core.resolve_target(*(values.get(letter) for letter in letters)))
    reference = reference_point(core, 1)
    m = core.state.out.position
    off = [letters[a] for a in axes if abs(m[a] - reference[a]) > REFERENCE_CHECK_MM]
    if off:
        where = ", ".join(f"{letters[a]} machine {m[a]:.4f} vs {reference[a]:.4f}" for a in axes)
        raise core.error(f"G27: not on the reference position ({where})", "reference-check-failed")


#: Dwell at the overshoot point of G60 (§3.2.7: "the defaulted dwell time is 1s").
G60_DWELL_S = 1.0


def _g60(core: Seam, spec, values: dict) -> None:
    """``G60 IP_`` (§3.2.7): rapid to the end point less the overrun (P1880, per axis, in machine
    coordinates, not mirrored), dwell 1 s, then rapid in the approach direction to the end point. Axes
    with no overrun or no movement get none; with none at all it is a plain rapid."""
    letters = core.dialect.axes
    target = core.resolve_target(*(values.get(letter) for letter in letters))
    if target == (None, None, None):
        return
    p = core.program_position
    full = (p[0] if target[0] is None else target[0], p[1] if target[1] is None else target[1],
            p[2] if target[2] is None else target[2])  # fmt: skip
    start = core.state.out.position
    end = list(core.to_machine(full))
    if not core.state.transformed:  # an omitted axis keeps its machine position (as in move_linear)
        end = [start[a] if target[a] is None else end[a] for a in range(3)]
    overshoot = list(end)
    used = False
    for a in range(3):
        overrun = parameters.value(core, "positioning_overrun", 0.0, a)
        if overrun and abs(end[a] - start[a]) > 1e-9:
            overshoot[a] = end[a] - overrun
            used = True
    if used:
        core.state.out.straight_traverse(tuple(overshoot))  # type: ignore[arg-type]
        core.state.out.dwell(G60_DWELL_S)
    core.move_linear(True, target)


def _reference_move(move):
    """The action of a reference-position code: compensation is suspended for its moves; as a group-01
    mode (G60 with 1870#0 MDL = 1) it becomes the modal motion of axis-only blocks."""

    def action(core: Seam, spec: CodeSpec, values: dict) -> None:
        compensation.before_machine_move(core)  # cutter compensation is suspended for the reference moves
        if spec.group == 1:  # G60 modal (1870#0 MDL = 1): axis-only blocks position like G60
            st = core.state
            st.motion = MODAL_POSITIONING
            st.motion_key = core.dialect.roles.modal_positioning  # type: ignore[assignment]
        move(core, spec, values)

    action.__name__ = action.__qualname__ = move.__name__.lstrip("_")
    action.__doc__ = move.__doc__
    return action


reference_check = _reference_move(_g27)
reference_return = _reference_move(_g28)
reference_return_from = _reference_move(_g29)
reference_return_n = _reference_move(_g30)
single_direction = _reference_move(_g60)

ACTIONS = {
    "reference_check": reference_check, "reference_return": reference_return,
    "reference_return_from": reference_return_from, "reference_return_n": reference_return_n,
    "single_direction": single_direction,
}  # fmt: skip
