"""The AZ-MC1's coordinate systems and limits (AMK AZ-MC1 programming manual §2.8, §3.1.5-§3.1.8, §3.12):

    machine (absolute) = ZPO + BPV + programmed (+ the tool offsets)

* ZPO, the zero point offset: G53 (the basic state) none, G54..G59 the table's entries 02..07
  (``AzOptions.zero_offsets``); valid from the block that selects it, moving only the axes programmed;
* BPV, the programmed datum point offset: ``G92 X… Y… Z…`` sets it (G90) or adds to it (G91), per axis;
  ``G92 X0`` withdraws it; it is added on top of the ZPO and stays until the next G92 (kept in the offset
  stack's additive slot, so a ZPO change keeps it). Its values are zero offsets: G70 does not convert them;
* software limit switches: ``G98`` (−) and ``G99`` (+) set (G90) or move (G91) the limits of the
  programmed axes, in machine coordinates; every segment is checked against the limits in force when it
  was made, arcs at their extremes too (``soft-limit``);
* ``G74``: programmable homing, axes in the order of their indices (equal indices together), index 99
  re-synchronises the interpolator to the axis (no motion).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from cnc_gym.gcode.dialects.azmc1.options import data, options
from cnc_gym.gcode.lang.fanuc import compensation

if TYPE_CHECKING:
    from cnc_gym.gcode.codes import CodeSpec
    from cnc_gym.gcode.dialect import Seam

#: G74 index that homes no axis but sets the interpolator to the axis's position (§3.1.5).
RESYNC = 99
#: G74 index that sets the axis to its modulo value or zero at the current position (§3.1.5).
MODULO = 98


def wcs(core: Seam, spec: CodeSpec, values: dict | None = None) -> None:
    """G53 (no zero offset) and G54..G59 (ZPO table entries 02..07), modal (§3.12). At power-on the table is
    loaded from ``AzOptions.zero_offsets``."""
    st = core.state
    offsets = st.offsets
    if values is None:
        table = options(core).zero_offsets
        for number in range(2, 8):
            offsets.wcs[number - 2] = [float(c) for c in table.get(number, (0.0, 0.0, 0.0))]
    entry = spec.value
    offsets.select_wcs(None if entry is None else int(entry) - 2)  # type: ignore[call-overload]
    core.resync_program_position()


def datum_offset(core: Seam, spec: CodeSpec, values: dict) -> None:
    """G92: the additive datum point offset of the programmed axes, set (G90) or added (G91), §3.1.6."""
    st = core.state
    local = st.offsets.local
    named = False
    for axis, letter in enumerate(core.dialect.axes):
        if letter in values:
            named = True
            local[axis] = local[axis] + values[letter] if st.incremental else values[letter]
    if not named:
        raise core.error("G92 needs the offset of at least one axis (G92 X0 withdraws X's)", "missing-value")
    st.offsets.update()
    core.resync_program_position()


def soft_limit(core: Seam, spec: CodeSpec, values: dict) -> None:
    """G98 (negative) / G99 (positive) software limit switches of the programmed axes, machine coordinates;
    G90 sets, G91 adds (§3.1.7, §3.1.8)."""
    st = core.state
    d = data(core)
    limits = d.low if spec.value == -1 else d.high
    named = False
    for axis, letter in enumerate(core.dialect.axes):
        if letter in values:
            named = True
            v = values[letter] * st.scale
            limits[axis] = limits[axis] + v if st.incremental else v
    if not named:
        raise core.error(f"{spec.name} needs the limit of at least one axis", "missing-value")
    for axis in range(3):
        if d.low[axis] > d.high[axis]:
            letter = core.dialect.axes[axis]
            raise core.error(f"{spec.name}: the negative limit {letter}{d.low[axis]:g} lies above the "
                             f"positive limit {letter}{d.high[axis]:g}", "soft-limit")  # fmt: skip
    epoch = (len(st.builder), tuple(d.low), tuple(d.high), st.out.line)
    if d.limit_epochs and d.limit_epochs[-1][0] == epoch[0]:
        d.limit_epochs[-1] = epoch  # no segment made under the previous limits: they never applied
    else:
        d.limit_epochs.append(epoch)


def check_soft_limits(core: Seam) -> None:
    """End of program (a finish hook): every segment within the limits in force when it was made, arcs at
    their extremes too. The first offending segment is reported at its own line. Vectorised: each point
    looks its limits up by the segment it belongs to (a G98/G99 inside a loop adds an epoch per pass)."""
    st = core.state
    d = st.dialect_data
    if d is None or not getattr(d, "limit_epochs", None):
        return
    toolpath = st.builder.build()
    starts = np.array([epoch[0] for epoch in d.limit_epochs])
    lows = np.array([epoch[1] for epoch in d.limit_epochs])
    highs = np.array([epoch[2] for epoch in d.limit_epochs])
    rows = np.arange(int(starts[0]), len(toolpath))
    first: tuple[int, int, float, str, float] | None = None
    for index, points in toolpath.extreme_points(rows):
        epoch = np.searchsorted(starts, index, side="right") - 1  # the last G98/G99 before the segment
        low, high = lows[epoch], highs[epoch]
        outside = (points < low) | (points > high)
        if not outside.any():
            continue
        k, axis = _first(outside, index)
        row = int(index[k])
        value = float(points[k, axis])
        side = "+" if value > high[k, axis] else "-"
        limit = float(high[k, axis] if side == "+" else low[k, axis])
        if first is None or row < first[0]:
            first = (row, int(axis), value, side, limit)
    if first is not None:
        row, axis, value, side, limit = first
        file, line = toolpath.source(row)
        letter = core.dialect.axes[axis]
        what = "G99 (positive)" if side == "+" else "G98 (negative)"
        raise core.error(f"software limit switch {letter}{side}: {letter}{value:.4f} (machine) is beyond the "
                         f"{what} limit {letter}{limit:g}", "soft-limit").located(file, line)  # fmt: skip


def _first(outside: np.ndarray, index: np.ndarray) -> tuple[int, int]:
    """(point, axis) of the offending point of the earliest segment."""
    hits = np.argwhere(outside)
    k, axis = hits[np.argmin(index[hits[:, 0]])]
    return int(k), int(axis)


def homing(core: Seam, spec: CodeSpec, values: dict) -> None:
    """G74: home the programmed axes, in ascending order of their indices, equal indices together, at
    rapid to the reference position (machine preset ``reference_1_mm``, else the machine zero); index 99
    sets the interpolator to the axis's position (no motion: the simulated axis is where the interpolator
    put it); index 98 (modulo or zero set) is refused by name (§3.1.5)."""
    st = core.state
    axes = core.dialect.axes
    order: dict[int, list[int]] = {}
    for axis, letter in enumerate(axes):
        if letter not in values:
            continue
        index = values[letter]
        if index != int(index) or index < 1:
            raise core.error(f"G74 {letter}{index:g}: the order index is a whole number from 1 (99: "
                             "re-synchronise)", "bad-homing")  # fmt: skip
        if index == MODULO:
            raise core.error(f"G74 {letter}98 (set to the modulo value or zero at the current position) is "
                             "not implemented: it would redefine the machine coordinates",
                             "not-implemented")  # fmt: skip
        if index != RESYNC:
            order.setdefault(int(index), []).append(axis)
    if not order:
        if not any(letter in values for letter in axes):
            raise core.error("G74 needs the axes to home with their order indices (G74 X3 Z1 Y4)",
                             "bad-homing")  # fmt: skip
        return
    compensation.before_machine_move(core)
    home = _home(core)
    for index in sorted(order):
        target = list(st.out.position)
        for axis in order[index]:
            target[axis] = home[axis]
        st.out.straight_traverse((target[0], target[1], target[2]))
    core.resync_program_position()


def _home(core: Seam) -> tuple[float, float, float]:
    machine = core.state.machine
    if machine is None:
        return (0.0, 0.0, 0.0)
    values = machine.axis_array("reference_1_mm")
    return (float(values[0]), float(values[1]), float(values[2]))


ACTIONS = {"wcs": wcs, "datum_offset": datum_offset, "soft_limit": soft_limit, "homing": homing}
