"""The H4C-M's block rules (HUST H4C-M manual §2.3.6 notes for edition, §3.1, §3.5 arcs, §3.40 radius
compensation): the word normaliser and the block checks.

**Normaliser** (runs before a block's codes are looked up):

* **one G code per block, the last one wins**: "If several G-codes are accidentally specified in a block,
  only the last G-code specified is effective" (§3.1: ``G00 G1 X10.000`` runs G01);
* **U, V, W are incremental X, Y, Z** in G90 (§2.2.4, §3.18); under G91 they are ignored ("rendered
  ineffective": no motion on that axis); with both X and U in one block U wins (§2.3.6). G10 keeps its U/V/W
  (tool wear, ``coordinates.py``);
* a groove block's T and D are its type and tool radius, not a tool or an offset group (taken off the
  words for ``grooves.py``);
* **D is a compensation group 1-16, D0 is D1** (§3.40).

**Checks** (on blocks that take the core's general path):

* **an arc mode must be closed by a G00/G01 block** ("G02, G03 command block must be followed by a G00 or
  G01 command block … Otherwise, Error 25", §3.5): after an arc, a block that moves without naming G00 or
  G01 (an axis-only block, another G02/G03) is ERROR 25;
* **radius compensation** (§3.40): G41/G42 start only in a G00/G01 block; no direct G41↔G42 change and no
  D change while it is on (G40 first); G40 not in an arc block; not in canned cycles; G28/G30/G31 need it
  cancelled first.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from cnc_gym.gcode.dialects.h4cm.options import data

if TYPE_CHECKING:
    from cnc_gym.gcode.codes import CodeSpec
    from cnc_gym.gcode.dialect import BlockPlan, Seam

_G10 = 10.0
_GROOVES = (22.0, 23.0, 24.0, 25.0)
_INCREMENTAL = (("U", 0, "X"), ("V", 1, "Y"), ("W", 2, "Z"))
#: Compensation groups G41/G42 may name (§3.40 "D: Tool group number (1~16)").
MAX_D = 16
#: Flag in ``State.general_path`` while an arc block waits for its G00/G01.
ARC_OPEN = "h4cm-arc"
_NEED_COMP_OFF = ("hust_reference", "skip", "hust_groove", "hust_pattern")


def normalise(core: Seam, gs, ms, values: dict) -> tuple:
    """The block normaliser (module docstring)."""
    if core.state.dialect_data is None:
        data(core)  # the first block: the run's H4C-M state, and the interpolation mode's stop rule
    if gs is not None and len(gs) > 1:
        gs = [gs[-1]]
    g = gs[0] if gs is not None else None
    if g in _GROOVES:
        if "T" in values or "D" in values:
            values = dict(values)
            data(core).groove_words = {k: values.pop(k) for k in "TD" if k in values}
        return gs, ms, values
    if g != _G10 and ("U" in values or "V" in values or "W" in values):
        values = dict(values)
        st = core.state
        here = core.program_position
        # The distance mode of this block: its own G90/G91 (the block's only G code) or the one in force.
        incremental = st.incremental if g not in (90.0, 91.0) else g == 91.0
        for letter, axis, absolute in _INCREMENTAL:
            if letter in values:
                step = values.pop(letter)
                if not incremental:
                    values[absolute] = here[axis] / st.scale + step
    if "D" in values and g not in _GROOVES:
        d = values["D"]
        if d != int(d) or not 0 <= d <= MAX_D:
            raise core.error(f"D{d:g}: the compensation group is 1-{MAX_D} (D0 is D1)", "bad-offset-number")
        if d == 0:
            d = 1.0
            values = {**values, "D": d}
        comp = core.state.comp
        if comp.side and d != comp.d_number:
            raise core.error(f"D{d:g} while compensation with D{comp.d_number} is on: cancel with G40 before "
                             "changing D (§3.40)", "comp-d-change")  # fmt: skip
    return gs, ms, values


def check_block(core: Seam, plan: BlockPlan) -> CodeSpec | None:
    """The arc-mode and radius-compensation rules (module docstring). (Block check.)"""
    st = core.state
    motion = plan.motion
    roles = core.dialect.roles
    cutter = plan.by_group.get(roles.cutter_group)  # type: ignore[arg-type]
    comp = st.comp
    arc_here = (motion.value in (2, 3)) if motion is not None else st.motion in (2, 3)
    if cutter is not None:
        if cutter.value != 0 and arc_here:
            raise core.error(f"{cutter.name} in an arc block: radius compensation starts in a G00/G01 block "
                             "(§3.40)", "comp-arc-startup")  # fmt: skip
        if cutter.value == 0 and comp.side and arc_here and motion is not None:
            raise core.error("G40 in an arc block: cancel in a G00/G01 block (§3.40)", "comp-arc-startup")
        if cutter.value != 0 and comp.side and cutter.value != comp.side:
            raise core.error(f"{cutter.name} while {'G41' if comp.side > 0 else 'G42'} is on: "
                             "cancel with "
                             "G40 before changing sides (§3.40)", "comp-switch")  # fmt: skip
    if comp.side:
        cycle = plan.by_group.get(roles.cycle_group)  # type: ignore[arg-type]
        if cycle is not None and cycle.action == "cycle":
            raise core.error(f"{cycle.name} with radius compensation on: cancel with G40 first (§3.40: no "
                             "compensation in canned cycles)", "comp-not-cancelled")  # fmt: skip
        for spec in plan.items:
            if spec.action in _NEED_COMP_OFF:
                raise core.error(f"{spec.name} with radius compensation on: cancel with G40 first (§3.11, "
                                 "§3.14, §3.40)", "comp-not-cancelled")  # fmt: skip
    d = st.dialect_data
    if d is not None and d.arc_open:
        moves = motion is not None or (plan.axis_owner is None and st.modal_item is None
                                       and any(a in plan.values for a in core.dialect.axes))  # fmt: skip
        if moves:
            if motion is None or motion.value not in (0, 1):
                name = motion.name if motion is not None else "an axis-only block"
                raise core.error(f"{name} after an arc: an arc block must be followed by a G00 or G01 block "
                                 "(HUST H4C-M manual §3.5)", "arc-mode")  # fmt: skip
            d.arc_open = False
            st.general_path.discard(ARC_OPEN)
    return plan.axis_owner


def open_arc(core: Seam) -> None:
    """An arc block ran: the next moving block must name G00 or G01."""
    data(core).arc_open = True
    core.state.general_path.add(ARC_OPEN)
