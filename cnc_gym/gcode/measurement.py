"""G37 automatic tool length measurement (manual L4692-L4783) with a simulated measuring instrument.

``G90 G37 Z_`` (H given in an earlier block) moves the tool at rapid toward the measurement position M,
changes to the measurement feed (P2651) a distance r (P2652) before it, and moves on until the
instrument's approach-end signal. The signal must come within ±e (P2653) of M: while the tool is still
more than e short of M ("B to C") or not by e past it ("point F") it is alarm 80. The tool stops at the
signal; the offset of the current H number changes by (signal coordinate − M) (L4731).

The simulation has no instrument, so :class:`ToolMeasurement` says where its signal comes: per H number,
the work coordinate of the measured axis at which the tool tip meets it (the manual's example: H01 reaches
the instrument at Z198 when G37 Z200 was commanded, so the offset falls by 2.0). An H number it does not
list reaches it exactly at M: the offset is right and does not change.

Choices where the manual is silent (docs/gcode.md):
* the offset memory has a geometry and a wear value per number (memory C), so — per note 3 (L4745) —
  the H *wear* value is changed;
* the change is written to the offset memory only; a G43/G44 vector already in force keeps its value
  until H or G43/G44 is given again (the next block uses the vector in force, as with G10);
* one axis word (X, Y or Z), absolute: G37 in G91, with two axes, in cutter compensation, or under
  G68/G51/G51.1 is an error rather than a guess;
* P2652 and P2653 are lengths in the least increment (0.0001 mm) when written by ``G10 L50`` (R takes
  no decimal point); standard 1000 mm/min, 0, 0 (so only a signal exactly at M passes).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from cnc_gym.errors import ConfigError
from cnc_gym.toolpath import SegmentMode

if TYPE_CHECKING:
    from cnc_gym.gcode.interpreter import Interpreter

#: Parameter numbers (GSK parameter volume): measurement feed, deceleration distance r, signal band e.
P_FEED, P_DECEL, P_BAND = 2651, 2652, 2653
ALARM = 80


@dataclass(frozen=True)
class ToolMeasurement:
    """The simulated measuring instrument and the G37 parameters.

    ``signal_at``: H number → work coordinate (mm) of the measured axis where the approach-end signal
    comes; numbers not listed signal at the commanded measurement position.
    ``feed_mm_min`` (P2651), ``decel_mm`` (r, P2652), ``band_mm`` (e, P2653): the machine tool
    builder's settings; ``G10 L50`` in the program overrides them.
    """

    signal_at: Mapping[int, float] = field(default_factory=dict)
    feed_mm_min: float = 1000.0
    decel_mm: float = 0.0
    band_mm: float = 0.0

    def __post_init__(self) -> None:
        for name in ("feed_mm_min", "decel_mm", "band_mm"):
            value = getattr(self, name)
            if not isinstance(value, int | float) or value != value or value < 0:
                raise ConfigError(f"ToolMeasurement.{name} must be a non-negative number, got {value!r}")
        if self.feed_mm_min <= 0:
            raise ConfigError("ToolMeasurement.feed_mm_min must be positive")
        for number, coordinate in dict(self.signal_at).items():
            if not isinstance(number, int) or not 1 <= number <= 256:
                raise ConfigError(f"ToolMeasurement.signal_at: H numbers are 1..256, got {number!r}")
            if not isinstance(coordinate, int | float) or coordinate != coordinate:
                raise ConfigError(f"ToolMeasurement.signal_at[{number}] must be a number, got {coordinate!r}")

    @classmethod
    def coerce(cls, value: ToolMeasurement | Mapping | None) -> ToolMeasurement:
        """``None`` (standard settings), a ToolMeasurement, or ``{"signal_at": {1: 198.0}, …}``."""
        if value is None:
            return cls()
        if isinstance(value, cls):
            return value
        if isinstance(value, Mapping):
            unknown = set(value) - {"signal_at", "feed_mm_min", "decel_mm", "band_mm"}
            if unknown:
                raise ConfigError(f"tool_measurement: unknown keys {sorted(unknown)}")
            return cls(**value)
        raise ConfigError(f"tool_measurement must be a ToolMeasurement or a mapping, "
                          f"got {type(value).__name__}")  # fmt: skip


def skip_signal_surfaces(value: Mapping | None, axes: str) -> dict[str, float]:
    """G31's simulated skip signal: ``{"X": 60.0}`` — the probe signals when the tool reaches X60
    (program coordinates, mm); the first surface a G31 move reaches stops it. None: no signal."""
    if value is None:
        return {}
    if not isinstance(value, Mapping):
        raise ConfigError(f"skip_signal must be a mapping of axis → coordinate, got {type(value).__name__}")
    surfaces = {}
    for letter, coordinate in value.items():
        if letter not in axes:
            raise ConfigError(f"skip_signal: {letter!r} is not an axis ({', '.join(axes)})")
        number = isinstance(coordinate, int | float) and not isinstance(coordinate, bool)
        if not number or coordinate != coordinate:
            raise ConfigError(f"skip_signal[{letter!r}] must be a number, got {coordinate!r}")
        surfaces[letter] = float(coordinate)
    return surfaces


def _parameter(interp: Interpreter, number: int, default: float, unit: float) -> float:
    raw = interp.parameters.raw.get((number, 0))
    return default if raw is None else raw * unit


def do_g37(interp: Interpreter, spec, values: dict) -> None:
    """``G90 G37 IP_``: measure, move to the signal point, correct the H offset (module docstring)."""
    letters = [letter for letter in interp.dialect.axes if letter in values]
    if "H" in values:
        raise interp.error("G37: specify H in an earlier block, not in the G37 block (L4741)",
                           "g37-h-in-block", alarm=ALARM)  # fmt: skip
    if len(letters) != 1:
        raise interp.error(f"G37 takes one axis word (X, Y or Z), got {len(letters) or 'none'}",
                           "g37-axis")  # fmt: skip
    if interp.incremental:
        raise interp.error("G37 is an absolute command (G90 G37 IP_, L4708)", "g37-incremental")
    if interp.comp.side:
        raise interp.error("G37 in cutter compensation mode: cancel it with G40 first", "bad-combination")
    if interp.chain.active or interp.polar is not None:
        raise interp.error("G37 under coordinate rotation, scaling, mirror or polar input is not supported",
                           "bad-combination")  # fmt: skip
    number = interp.comp.h_number
    if number == 0:
        raise interp.error("G37 needs a tool length offset number: give H in an earlier block", "g37-no-h",
                           alarm=ALARM)  # fmt: skip
    settings: ToolMeasurement = interp.tool_measurement
    feed = _parameter(interp, P_FEED, settings.feed_mm_min, 1.0)
    decel = _parameter(interp, P_DECEL, settings.decel_mm, 0.0001)
    band = _parameter(interp, P_BAND, settings.band_mm, 0.0001)

    letter = letters[0]
    axis = interp.dialect.axes.index(letter)
    origin = interp.offsets.origin[axis]
    start = interp.out.position[axis] - origin  # work coordinates along the measured axis
    target = values[letter] * interp.scale  # the measurement position M
    if abs(target - start) < 1e-9:
        raise interp.error(f"G37 starts at the measurement position {letter}{target:g}: nothing to approach",
                           "g37-signal", alarm=ALARM)  # fmt: skip
    direction = 1.0 if target > start else -1.0
    signal = float(settings.signal_at.get(number, target))
    # Along the approach: distance from the start to the signal, to the feed change (B), to M − e (C) and
    # to M + e (F).
    to_signal = (signal - start) * direction
    to_b = max((target - start) * direction - decel, 0.0)
    to_c = (target - start) * direction - band
    to_f = (target - start) * direction + band
    unit = interp.scale
    if to_signal < to_b or to_signal < to_c:
        where = "during the rapid approach" if to_signal < to_b else "before the permitted band (B to C)"
        raise interp.error(f"G37: the approach-end signal came {where}: {letter}{signal / unit:g} vs "
                           f"{letter}{target / unit:g} ± {band / unit:g}", "g37-signal",
                           alarm=ALARM)  # fmt: skip
    if to_signal > to_f:
        raise interp.error(f"G37: no approach-end signal by {letter}{(start + direction * to_f) / unit:g} "
                           f"({letter}{target / unit:g} + {band / unit:g})", "g37-signal",
                           alarm=ALARM)  # fmt: skip
    _move(interp, axis, origin, start, to_b, signal, feed)
    # Offset = current + (measured coordinate − commanded coordinate) (L4731): the H wear value (memory C).
    interp.tool_offsets.set("H", number, interp.tool_offsets.get("H", number, wear=True) + (signal - target),
                            wear=True, error=lambda message, code: interp.error(message, code))  # fmt: skip
    interp.resync_program_position()


def _move(interp: Interpreter, axis: int, origin: float, start: float, to_b: float, end: float,
          feed: float) -> None:  # fmt: skip
    """Rapid from the start to B, then the measurement feed to ``end`` (work coordinates) with a stop."""
    out = interp.out
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
