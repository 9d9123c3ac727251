"""The macro variable store: #0 (always null), locals #1-#33, commons #100-#199 and #500-#999, and the
system variables (#1000 and up) through :class:`~cnc_gym.gcode.lang.fanuc.sysvars.SystemVariables`.

Locals are one set per macro call level (§3.7.7): G65, G66 and G/M-code macro calls push a fresh set
(:meth:`VariableStore.push_locals`), M99 pops it; M98 and M/T-code subprogram calls share the caller's set.

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Protocol

if TYPE_CHECKING:
    from cnc_gym.gcode.dialect import Dialect


#: Largest magnitude a variable holds (§3.7.7 "Max ±10^47"; §3.7.2's ±999999 would refuse ordinary
#: values such as a feed of 1 000 000 mm/min, so the limitations table is followed).
MAX_VALUE = 1e47


class SystemVariableSource(Protocol):
    """What the store needs from the system-variable table (lang/fanuc/sysvars.py)."""

    def read(self, index: int) -> float | None: ...

    def write(self, index: int, value: float | None) -> None: ...

    def count_part(self) -> None: ...


class VariableStore:
    """Numbered macro variables. A missing key is null (``None``).

    ``system``: the system-variable table; without one (the store alone, in tests) system variables are
    rejected by name, never read as 0.
    """

    def __init__(self, dialect: Dialect, system: SystemVariableSource | None = None) -> None:
        self.dialect = dialect
        self.system = system
        self.locals: dict[int, float] = {}
        self.commons: dict[int, float] = {}
        self._local_stack: list[dict[int, float]] = []
        # Exact (first, last) ranges of locals and commons, for the fast path of read/write.
        ranges = dialect.variables
        self._local_range = next(((lo, hi) for lo, hi in ranges if hi <= 33), (1, 0))
        self._common_ranges = tuple((lo, hi) for lo, hi in ranges if hi > 33)

    @property
    def level(self) -> int:
        """The local-variable level: 0 in the main program, +1 per macro call (§3.7.6)."""
        return len(self._local_stack)

    def _index(self, value: float | None) -> int:
        if value is None:
            raise self.dialect.error("variable number is null", "bad-variable")
        index = math.floor(abs(value) + 0.5) * (1 if value >= 0 else -1)
        if abs(value - index) > 1e-9:
            raise self.dialect.error(f"variable number #{value:g} is not an integer", "bad-variable")
        return index

    def _kind(self, index: int) -> str:
        if index == 0:
            return "null"
        for low, high in self.dialect.variables:
            if low <= index <= high:
                return "local" if high <= 33 else "common"
        for low, high in self.dialect.system_variables:
            if low <= index <= high:
                return "system"
        raise self.dialect.error(f"variable #{index} does not exist", "bad-variable")

    def read(self, number: float | None) -> float | None:
        # Fast path: an exact local or common number (dict keys are ints; 5.0 finds key 5).
        if number is not None:
            lo, hi = self._local_range
            if lo <= number <= hi and number == int(number):
                return self.locals.get(number)  # type: ignore[call-overload]
            for lo, hi in self._common_ranges:
                if lo <= number <= hi and number == int(number):
                    return self.commons.get(number)  # type: ignore[call-overload]
        index = self._index(number)
        kind = self._kind(index)
        if kind == "local":
            return self.locals.get(index)
        if kind == "common":
            return self.commons.get(index)
        if kind == "null":
            return None
        if self.system is None:
            raise self.dialect.error(f"system variable #{index} is not available here", "not-implemented")
        return self.system.read(index)

    def write(self, number: float | None, value: float | None) -> None:
        index = self._index(number)
        kind = self._kind(index)
        if kind == "null":
            raise self.dialect.error("#0 is always null and cannot be assigned", "bad-variable")
        if value is not None and not abs(value) <= MAX_VALUE:  # also NaN
            raise self.dialect.error(f"#{index}: {value:g} is beyond ±1e47 (GSK 25i §3.7.7)", "overflow")
        if kind == "system":
            if self.system is None:
                raise self.dialect.error(f"system variable #{index} is not available here", "not-implemented")
            self.system.write(index, value)
            return
        store = self.locals if kind == "local" else self.commons
        if value is None:
            store.pop(index, None)
        else:
            store[index] = float(value)

    def push_locals(self, values: dict[int, float]) -> None:
        """A new local level holding ``values`` (the call's arguments); the rest is null."""
        self._local_stack.append(self.locals)
        self.locals = dict(values)

    def pop_locals(self) -> None:
        self.locals = self._local_stack.pop()
