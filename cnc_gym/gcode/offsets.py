"""Tool offset memory: H (tool length) and D (cutter radius / tool position) tables, geometry and wear.

GSK 25i (§3.5.1, §3.5.2, §3.5.5):

* numbers 0..256; number 0 (H00, D00) is always 0 and cannot be set;
* each number has a geometry and a wear value; the offset in use is their sum;
* ``G10 L10 P_ R_`` H geometry, ``L11`` H wear, ``L12`` D geometry, ``L13`` D wear; G90 sets, G91 adds;
  geometry within ±999.999 mm, wear within ±99.999 mm (inch: ±99.9999 / ±9.9999 in) else alarm 32;
* D holds a radius or a diameter by parameter 2601#7 (ODI). The manual's printed standard setting is
  "diameter" but every worked example treats D as a radius (§3.5.2, where the text and the examples disagree);
  we follow the examples: ``d_is_diameter=False`` by default, a switch for the other reading.

Values are stored in mm. The macro system variables (#2001-#2400, #10001-#13400) read and write the same
tables through :meth:`ToolOffsets.get` / :meth:`ToolOffsets.set`; ``G10 L10-L13`` through
:func:`apply_g10`.

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass

from cnc_gym.errors import ProgramError

#: G10 L number → (table letter, wear?)
G10_TABLES: dict[int, tuple[str, bool]] = {
    10: ("H", False),
    11: ("H", True),
    12: ("D", False),
    13: ("D", True),
}

ErrorFactory = Callable[[str, str], ProgramError]


def _plain_error(message: str, code: str) -> ProgramError:
    return ProgramError(message, code=code)


@dataclass
class ToolOffsets:
    """H and D offset tables (geometry + wear, mm) of one program run.

    ``count``: highest offset number (GSK: 256). ``geometry_limit_mm`` / ``wear_limit_mm``: largest
    magnitude G10 or a system variable may store (GSK: 999.999 / 99.999 mm). ``d_is_diameter``: D values
    are diameters (2601#7 ODI's printed standard), halved when used as a compensation radius.
    """

    count: int = 256
    geometry_limit_mm: float = 999.999
    wear_limit_mm: float = 99.999
    d_is_diameter: bool = False

    def __post_init__(self) -> None:
        n = self.count + 1
        self.tables: dict[tuple[str, bool], list[float]] = {
            (letter, wear): [0.0] * n for letter in "HD" for wear in (False, True)
        }

    # ------------------------------------------------------------------ reading
    def get(self, letter: str, number: int, *, wear: bool = False) -> float:
        """Stored geometry (or wear) value of H/D ``number``, mm; number 0 is always 0."""
        return self.tables[(letter, wear)][self._index(letter, number, _plain_error)]

    def length(self, number: int) -> float:
        """Tool length offset of H``number`` in use: geometry + wear, mm (H00 = 0)."""
        return self.tables[("H", False)][number] + self.tables[("H", True)][number]

    def radius(self, number: int) -> float:
        """Cutter compensation radius of D``number``: geometry + wear, halved if D holds diameters."""
        value = self.tables[("D", False)][number] + self.tables[("D", True)][number]
        return value / 2.0 if self.d_is_diameter else value

    def position_offset(self, number: int) -> float:
        """G45-G48 amount of D``number`` (the D value as stored: geometry + wear, never halved)."""
        return self.tables[("D", False)][number] + self.tables[("D", True)][number]

    # ------------------------------------------------------------------ writing
    def set(self, letter: str, number: float, value_mm: float, *, wear: bool = False,
            incremental: bool = False, error: ErrorFactory = _plain_error) -> None:  # fmt: skip
        """Store H/D ``number`` (geometry or wear); ``incremental`` adds to the stored value (G91).

        Errors (from ``error(message, code)``): ``bad-offset-number`` for 0 or beyond ``count``,
        ``bad-offset-value`` for a non-finite value or one beyond the geometry/wear limit.
        """
        index = self._index(letter, number, error)
        if index == 0:
            raise error(f"{letter}00 is always 0 and cannot be set", "bad-offset-number")
        table = self.tables[(letter, wear)]
        new = table[index] + value_mm if incremental else value_mm
        limit = self.wear_limit_mm if wear else self.geometry_limit_mm
        if not math.isfinite(new) or abs(new) > limit + 1e-9:
            kind = "wear" if wear else "geometry"
            raise error(
                f"{letter}{index:02d} {kind} value {new:g} mm is beyond ±{limit:g} mm", "bad-offset-value"
            )
        table[index] = float(new)

    def _index(self, letter: str, number: float, error: ErrorFactory) -> int:
        if letter not in "HD" or len(letter) != 1:
            raise ValueError(f"tool offset table {letter!r} (H or D)")
        if number != int(number) or not 0 <= number <= self.count:
            raise error(f"{letter}{number:g}: offset numbers are 0..{self.count}", "bad-offset-number")
        return int(number)

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_mapping(cls, values: Mapping | ToolOffsets | None, **kw) -> ToolOffsets:
        """Initial offsets for :func:`cnc_gym.gcode.interpret`'s ``tool_offsets=``.

        Accepts a :class:`ToolOffsets` (copied), ``None`` (all zero), or a mapping
        ``{"H": {1: 20.0}, "D": {7: 5.0}, "H_wear": {...}, "D_wear": {...}}`` (mm). Bad keys or values
        raise :class:`~cnc_gym.errors.ConfigError`.
        """
        from cnc_gym.errors import ConfigError

        if isinstance(values, ToolOffsets):
            copy = cls(values.count, values.geometry_limit_mm, values.wear_limit_mm, values.d_is_diameter)
            copy.tables = {key: list(table) for key, table in values.tables.items()}
            return copy
        offsets = cls(**kw)
        if values is None:
            return offsets
        if not isinstance(values, Mapping):
            raise ConfigError(
                f"tool_offsets must be a mapping like {{'H': {{1: 20.0}}}}, got {type(values).__name__}"
            )
        names = {"H": ("H", False), "D": ("D", False), "H_wear": ("H", True), "D_wear": ("D", True)}

        def config_error(message: str, code: str) -> ProgramError:
            raise ConfigError(f"tool_offsets: {message}")

        for key, table in values.items():
            if key not in names or not isinstance(table, Mapping):
                raise ConfigError(f"tool_offsets: key {key!r} must be one of {sorted(names)} with a "
                                  "{number: mm} mapping")  # fmt: skip
            letter, wear = names[key]
            for number, value in table.items():
                if isinstance(number, bool) or not isinstance(number, int):
                    raise ConfigError(f"tool_offsets[{key!r}]: offset number {number!r} is not an integer")
                if isinstance(value, bool) or not isinstance(value, int | float):
                    raise ConfigError(f"tool_offsets[{key!r}][{number}]: {value!r} is not a number of mm")
                offsets.set(letter, number, float(value), wear=wear, error=config_error)
        return offsets


def apply_g10(offsets: ToolOffsets, kind: int, number: float | None, value_mm: float | None, *,
              incremental: bool, error: ErrorFactory) -> None:  # fmt: skip
    """``G10 L10..L13 P<number> R<value>``: write one tool offset (G90 sets, G91 adds; §3.5.5).

    ``value_mm`` is R already converted to mm. A missing P is ``bad-g10``; a missing R is
    ``missing-value``; range errors as :meth:`ToolOffsets.set`.
    """
    letter, wear = G10_TABLES[kind]
    if number is None:
        raise error(f"G10 L{kind} needs P (the offset number 1..{offsets.count})", "bad-g10")
    if value_mm is None:
        raise error(f"G10 L{kind} needs R (the offset value)", "missing-value")
    offsets.set(letter, number, value_mm, wear=wear, incremental=incremental, error=error)
