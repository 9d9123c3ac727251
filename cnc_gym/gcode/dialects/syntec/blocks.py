"""Syntec 8.20's block rules: the word normaliser and the block checks (Syntec 8.20 mill programming manual,
the sections named beside each rule).

**Words a code takes for itself.** Some codes give a word-with-an-action its own meaning in their block:
``M98 H_`` is a sequence number (§M98), not a length offset; ``G92 S_`` the spindle limit (§G96/G97), not
a speed; ``G37``/``G37.1 D_ F_`` the probe over-travel and measuring feed (§G37), not a cutter offset or
the modal feed. The normaliser takes them off the block before its words run and leaves them for the
code (``SyntecData``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from cnc_gym.gcode.dialects.syntec.options import data

if TYPE_CHECKING:
    from cnc_gym.gcode.codes import CodeSpec
    from cnc_gym.gcode.dialect import BlockPlan, Seam

#: M codes allowed in G05 mode: the program's end (§G05 conditions 1 and 3).
HSHP_M_CODES = (30.0, 99.0)
_MEASURING = (37.0, 37.1)


def normalise(core: Seam, gs, ms, values: dict) -> tuple:
    """The block normaliser (module docstring); M codes other than M30/M99 in G05 mode are refused."""
    if gs is None and ms is None:
        return gs, ms, values
    if ms is not None:
        d = core.state.dialect_data
        if d is not None and d.hshp is not None and any(m not in HSHP_M_CODES for m in ms):
            bad = next(m for m in ms if m not in HSHP_M_CODES)
            raise core.error(f"M{bad:02g} in high-speed, high-precision mode G05: M codes are invalid there "
                             "(end the mode with G05 P0 first; only M30/M99 end the program in it)",
                             "hshp-m-code")  # fmt: skip
        if 98.0 in ms and "H" in values:
            values = dict(values)
            data(core).call_label = values.pop("H")
    if gs is not None:
        if 92.0 in gs and "S" in values:
            values = dict(values)
            data(core).clamp_word = values.pop("S")
        if any(g in _MEASURING for g in gs) and ("D" in values or "F" in values):
            values = dict(values)
            data(core).measure_words = {k: values.pop(k) for k in "DF" if k in values}
    return gs, ms, values


def check_block(core: Seam, plan: BlockPlan) -> CodeSpec | None:
    """A hole pattern and a canned-cycle code in one block (the pattern uses the cycle in force); G40/G41/G42
    with G02/G03 (§G40/G41/G42 note 3: "only with G00 and G01 in the same block"). (Block check.)"""
    roles = core.dialect.roles
    cycle_spec = plan.by_group.get(roles.cycle_group)  # type: ignore[arg-type]
    pattern = next((spec for spec in plan.items if spec.action == "hole_pattern"), None)
    if pattern is not None and cycle_spec is not None:
        raise core.error(f"{pattern.name} and {cycle_spec.name} in one block: store the cycle with "
                         f"{cycle_spec.name} … K0 first, then {pattern.name}", "cycle-conflict")  # fmt: skip
    cutter = plan.by_group.get(roles.cutter_group)  # type: ignore[arg-type]
    if cutter is not None and plan.motion is not None and plan.motion.value in (2, 3):
        raise core.error(f"{cutter.name} cannot share a block with {plan.motion.name}: cutter compensation "
                         "starts, changes and ends on G00/G01 blocks only", "comp-arc-startup")  # fmt: skip
    return plan.axis_owner
