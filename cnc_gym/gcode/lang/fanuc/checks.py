"""Block checks of the Fanuc family (:attr:`BlockHooks.checks <cnc_gym.gcode.dialect.BlockHooks.checks>`)
that are not a feature's own: the one-owner rule of the axis words.

Two codes of one modal group in a block are an error in the core itself (``group-conflict``: the
Fanuc family's G-per-block policy; a dialect whose controller lets the last G code win gives a
``normalise`` hook instead).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from cnc_gym.gcode.codes import CodeSpec
    from cnc_gym.gcode.dialect import BlockPlan, Seam


def axis_owners(core: Seam, plan: BlockPlan) -> CodeSpec | None:
    """At most one code of a block may take its axis words (``G92 G28 X1`` is an error)."""
    owners = [spec for spec in plan.items if spec.uses_axes]
    if len(owners) > 1 and any(letter in plan.values for letter in core.dialect.axes):
        raise core.error(f"{owners[0].name} and {owners[1].name} both use the axis words of the block",
                         "axis-word-conflict")  # fmt: skip
    return plan.axis_owner
