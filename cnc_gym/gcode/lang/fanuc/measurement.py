"""G37 automatic tool length measurement (manual §3.5.6) with a simulated measuring instrument.

``G90 G37 Z_`` (H given in an earlier block) moves the tool at rapid toward the measurement position M,
changes to the measurement feed (P2651) a distance r (P2652) before it, and moves on until the
instrument's approach-end signal. The signal must come within ±e (P2653) of M: while the tool is still
more than e short of M ("B to C") or not by e past it ("point F") it is alarm 80. The tool stops at the
signal; the offset of the current H number changes by (signal coordinate − M) (§3.5.6).

The simulation has no instrument, so :class:`ToolMeasurement` says where its signal comes: per H number,
the work coordinate of the measured axis at which the tool tip meets it (the manual's example: H01 reaches
the instrument at Z198 when G37 Z200 was commanded, so the offset falls by 2.0). An H number it does not
list reaches it exactly at M: the offset is right and does not change.

Choices where the manual is silent (docs/gcode.md):
* the offset memory has a geometry and a wear value per number (memory C), so — per note 3 (§3.5.6) —
  the H *wear* value is changed;
* the change is written to the offset memory only; a G43/G44 vector already in force keeps its value
  until H or G43/G44 is given again (the next block uses the vector in force, as with G10);
* one axis word (X, Y or Z), absolute: G37 in G91, with two axes, in cutter compensation, or under
  G68/G51/G51.1 is an error rather than a guess;
* P2652 and P2653 are lengths in the least increment (0.0001 mm) when written by ``G10 L50`` (R takes
  no decimal point); standard 1000 mm/min, 0, 0 (so only a signal exactly at M passes).

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from cnc_gym.gcode.lang.fanuc import compensation, parameters
from cnc_gym.toolpath import SegmentMode

if TYPE_CHECKING:
    from cnc_gym.gcode.codes import CodeSpec
    from cnc_gym.gcode.dialect import Seam
    from cnc_gym.gcode.settings import ToolMeasurement



def _g37(core: Seam, spec: CodeSpec, values: dict) -> None:
    """``G90 G37 IP_``: measure, move to the signal point, correct the H offset (module docstring)."""
    letters = [letter for letter in core.dialect.axes if letter in values]
    if "H" in values:
        raise core.error("G37: specify H in an earlier block, not in the G37 block (GSK 25i §3.5.6)",
                         "g37-h-in-block")  # fmt: skip
    if len(letters) != 1:
        raise core.error(f"G37 takes one axis word (X, Y or Z), got {len(letters) or 'none'}",
                         "g37-axis")  # fmt: skip
    if core.state.incremental:
        raise core.error("G37 is an absolute command (G90 G37 IP_, GSK 25i §3.5.6)", "g37-incremental")
    if core.state.comp.side:
        raise core.error("G37 in cutter compensation mode: cancel it with G40 first", "bad-combination")
    if core.state.chain.active or core.state.polar is not None:
        raise core.error("G37 under coordinate rotation, scaling, mirror or polar input is not supported",
                         "bad-combination")  # fmt: skip
    number = core.state.comp.h_number
    if number == 0:
        raise core.error("G37 needs a tool length offset number: give H in an earlier block", "g37-no-h")
    settings: ToolMeasurement = core.state.tool_measurement
    feed = parameters.value(core, "measure_feed", settings.feed_mm_min)
    decel = parameters.value(core, "measure_decel", settings.decel_mm)
    band = parameters.value(core, "measure_band", settings.band_mm)

    letter = letters[0]
    axis = core.dialect.axes.index(letter)
    origin = core.state.offsets.origin[axis]
    start = core.state.out.position[axis] - origin  # work coordinates along the measured axis
    target = values[letter] * core.state.scale  # the measurement position M
    if abs(target - start) < 1e-9:
        raise core.error(f"G37 starts at the measurement position {letter}{target:g}: nothing to approach",
                         "g37-signal")  # fmt: skip
    direction = 1.0 if target > start else -1.0
    signal = float(settings.signal_at.get(number, target))
    # Along the approach: distance from the start to the signal, to the feed change (B), to M − e (C) and
    # to M + e (F).
    to_signal = (signal - start) * direction
    to_b = max((target - start) * direction - decel, 0.0)
    to_c = (target - start) * direction - band
    to_f = (target - start) * direction + band
    unit = core.state.scale
    if to_signal < to_b or to_signal < to_c:
        where = "during the rapid approach" if to_signal < to_b else "before the permitted band (B to C)"
        raise core.error(f"G37: the approach-end signal came {where}: {letter}{signal / unit:g} vs "
                         f"{letter}{target / unit:g} ± {band / unit:g}", "g37-signal")  # fmt: skip
    if to_signal > to_f:
        raise core.error(f"G37: no approach-end signal by {letter}{(start + direction * to_f) / unit:g} "
                         f"({letter}{target / unit:g} + {band / unit:g})", "g37-signal")  # fmt: skip
    _move(core, axis, origin, start, to_b, signal, feed)
    # Offset = current + (measured coordinate − commanded coordinate) (§3.5.6): the H wear value (memory C).
    offsets = core.state.comp.offsets
    offsets.set("H", number, offsets.get("H", number, wear=True) + (signal - target), wear=True,
                error=lambda message, code: core.error(message, code))  # fmt: skip
    core.resync_program_position()


def _move(core: Seam, axis: int, origin: float, start: float, to_b: float, end: float,
          feed: float) -> None:  # fmt: skip
    """Rapid from the start to B, then the measurement feed to ``end`` (work coordinates) with a stop."""
    out = core.state.out
    direction = 1.0 if end > start else -1.0
    if to_b > 0:
        point = list(out.position)
        point[axis] = origin + start + direction * to_b
        out.straight_traverse(tuple(point))  # type: ignore[arg-type]
    point = list(out.position)
    point[axis] = origin + end
    modes = out.modes
    out.modes = modes | SegmentMode.EXACT_STOP  # the signal stops the axis
    out.straight_feed(tuple(point), feed)  # type: ignore[arg-type]
    out.modes = modes


def tool_length_measure(core: Seam, spec: CodeSpec, values: dict) -> None:
    """G37 (module docstring); cutter compensation is suspended for its moves."""
    compensation.before_machine_move(core)
    _g37(core, spec, values)


ACTIONS = {"tool_length_measure": tool_length_measure}
