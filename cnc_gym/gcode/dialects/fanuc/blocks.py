"""Block rules of the ``fanuc`` dialect that differ from the GSK 25i's (docs/fanuc.md).

**G00/G01 with a reference return.** Fanuc 0i and Haas controls accept ``G00 G28 G91 Z0`` — the
safe-start line many CAM posts and hand-written programs begin with: G28 takes the axis words and the
motion code in the same block only sets the modal motion for the blocks after it. The GSK 25i allows one
owner of the axis words per block and refuses it (``axis-word-conflict``).
"""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from cnc_gym.gcode.codes import CodeSpec
    from cnc_gym.gcode.dialect import BlockPlan, Seam

#: Codes that may share their block with G00/G01 (the motion code then only sets the mode).
REFERENCE_ACTIONS = frozenset({"reference_check", "reference_return", "reference_return_from",
                               "reference_return_n"})  # fmt: skip


def motion_with_reference_return(core: Seam, plan: BlockPlan) -> CodeSpec | None:
    """G00/G01 in the block of G27-G30: the motion code sets the modal motion only (block check)."""
    owner, motion = plan.axis_owner, plan.motion
    if owner is None or motion is None or owner.action not in REFERENCE_ACTIONS or motion.value not in (0, 1):
        return owner
    index = plan.items.index(motion)
    plan.items[index] = replace(motion, action="motion_mode")
    plan.motion = None
    return owner
