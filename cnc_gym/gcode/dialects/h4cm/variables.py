"""The H4C-M's variables (HUST H4C-M manual §3.41): #1-#9999, integers kept at power-off, no null, no locals.

"All variables … must be integer": a value is a count of least increments when a length word uses it
(``G01 U#12``) and a plain integer elsewhere. A variable never written reads 0 (the memory holds numbers,
not a null mark). The range is ±9 999 999 (the 4/3 format's ±9999.999); beyond it the controller stops
("system operation will result in error"): ``overflow``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from cnc_gym.gcode.dialects.h4cm.reader import MAX_INTEGER

if TYPE_CHECKING:
    from cnc_gym.gcode.dialect import Dialect


class HustVariables:
    """#1-#9999 as integers (module docstring). ``system`` is unused: the H4C-M has no system variables in
    the program's reach (#10000 and up are read-only and undocumented)."""

    def __init__(self, dialect: Dialect) -> None:
        self.dialect = dialect
        self.system: Any = None
        self.values: dict[int, int] = {}
        self._low, self._high = dialect.variables[0]

    def _index(self, number: float | None) -> int:
        if number is None or number != int(number) or not self._low <= number <= self._high:
            shown = "null" if number is None else f"#{number:g}"
            raise self.dialect.error(f"variable {shown} does not exist (#{self._low}-#{self._high})",
                                     "bad-variable")  # fmt: skip
        return int(number)

    def read(self, number: float | None) -> float:
        return float(self.values.get(self._index(number), 0))

    def write(self, number: float | None, value: float | None) -> None:
        index = self._index(number)
        if value is None:
            value = 0
        whole = int(value)  # "results < 1 are discarded": truncation toward zero
        if abs(whole) > MAX_INTEGER:
            raise self.dialect.error(f"#{index} = {whole}: beyond ±{MAX_INTEGER} (4/3 format: ±9999.999)",
                                     "overflow")  # fmt: skip
        self.values[index] = whole

    def clear(self) -> None:
        """G10 P2002: all variables back to 0."""
        self.values.clear()
