"""The H4C-M's interpolation modes (HUST H4C-M manual §3.4 "CNC and Master/Slave mode", MCM #93):

* **CNC mode** (#93 = 0, the default): "the servo motor will decelerate to a complete stop at the end of
  the first block, then … accelerate to the feed-rate on the next block": every segment carries the
  exact-stop mode (set with the run's H4C-M state, ``options.data``); F is the vector feed (Examples 2
  and 3 of §3.4; Example 1's per-axis comments are shifted a line and contradict them).
* **Master/slave mode** (#93 = 1, 2, 3: X, Y or Z master): no stop between blocks, and **F is the master
  axis's speed**; the slaves follow in proportion, so the vector feed of a G01 block is F·|Δ|/|Δmaster|.
  A block in which the master does not move runs at F ("the feed-rate of the slave axis will be used").
  G00 in this mode scales the rapid from the master axis's traverse rate; the simulated controller's rapid
  clamps each axis to its own rate and keeps the direction instead (the same when one axis limits).
* **Non-stop mode** (#93 = 256): no stop between blocks, F the vector feed.

The acc/dec filter (#166, #167, #222) and the arc feed cap 85·√(1000·R) are the machine's: the preset
``configs/machines/h4cm.yaml`` carries them.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from cnc_gym.gcode.dialects.h4cm.options import options
from cnc_gym.gcode.lang.fanuc.motion import motion as family_motion

if TYPE_CHECKING:
    from cnc_gym.gcode.codes import CodeSpec
    from cnc_gym.gcode.dialect import Seam


def motion(core: Seam, spec: CodeSpec | None = None, values: dict | None = None) -> None:
    """G00-G03 or an axis-only block: in master/slave mode a G01's F is the master axis's speed."""
    master = options(core).interpolation_mode
    st = core.state
    mode = spec.value if spec is not None and spec.value is not None else st.motion
    if not 1 <= master <= 3 or mode != 1 or values is None or st.feed is None:
        family_motion(core, spec, values)
        return
    target = core.resolve_target(values.get("X"), values.get("Y"), values.get("Z"))
    here = core.program_position
    delta = [0.0 if t is None else t - here[a] for a, t in enumerate(target)]
    along_master = abs(delta[master - 1])
    feed = st.feed
    if along_master > 0.0:
        st.feed = feed * math.hypot(*delta) / along_master
    try:
        family_motion(core, spec, values)
    finally:
        st.feed = feed


ACTIONS = {"motion": motion}
