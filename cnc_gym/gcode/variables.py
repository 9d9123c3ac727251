"""The macro variable store: #0 (always null), locals #1-#33, commons #100-#199 and #500-#999.

One level of locals for now; G65/G66 calls (a later issue) push and pop levels with :meth:`push_locals` /
:meth:`pop_locals`. System variables (#1000 and up) are recognised by the dialect's ranges and rejected
by name until they are built, never read as 0.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from cnc_gym.gcode.dialect import Dialect


class VariableStore:
    """Numbered macro variables. A missing key is null (``None``)."""

    def __init__(self, dialect: Dialect) -> None:
        self.dialect = dialect
        self.locals: dict[int, float] = {}
        self.commons: dict[int, float] = {}
        self._local_stack: list[dict[int, float]] = []

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
        index = self._index(number)
        kind = self._kind(index)
        if kind == "local":
            return self.locals.get(index)
        if kind == "common":
            return self.commons.get(index)
        if kind == "null":
            return None
        raise self.dialect.error(f"system variable #{index} is not implemented yet", "not-implemented")

    def write(self, number: float | None, value: float | None) -> None:
        index = self._index(number)
        kind = self._kind(index)
        if kind == "null":
            raise self.dialect.error("#0 is always null and cannot be assigned", "bad-variable")
        if kind == "system":
            raise self.dialect.error(f"system variable #{index} is not implemented yet", "not-implemented")
        store = self.locals if kind == "local" else self.commons
        if value is None:
            store.pop(index, None)
        else:
            if not math.isfinite(value):
                raise self.dialect.error(f"#{index}: value out of range", "overflow")
            store[index] = float(value)

    def push_locals(self, values: dict[int, float]) -> None:
        self._local_stack.append(self.locals)
        self.locals = dict(values)

    def pop_locals(self) -> None:
        self.locals = self._local_stack.pop()
