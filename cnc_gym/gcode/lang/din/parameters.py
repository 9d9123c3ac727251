"""The DIN family's variable model: global R parameters (AMK AZ-MC1 programming manual §8 "Parameters").

``R<n>`` are REAL (double) parameters, global to the main program and every subroutine (data passes to a
subroutine through them: there are no argument lists, §7). They start at 0 (the manual gives no initial
value). ``P<n>`` reads indirectly: the parameter whose number R<n> holds.

The store is a ``list`` subclass so that a compiled expression reads ``R12`` as ``store[12]``, a plain list
index, on the interpreter's hot path (``expressions.py``). A dialect's store subclass adds the data its
functions read (the AZ-MC1's tool table: ``TLOC[n]`` …) through :meth:`data_function` and
:meth:`procedure`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from cnc_gym.errors import ProgramError
from cnc_gym.gcode.lang.din.expressions import MAX_PARAMETER

if TYPE_CHECKING:
    from cnc_gym.gcode.dialect import Dialect


class ParameterStore(list):
    """R0..R9999 (see the module docstring); ``system`` is the core's system-variable slot (unused)."""

    __slots__ = ("dialect", "system")

    def __init__(self, dialect: Dialect | None = None) -> None:
        super().__init__([0.0] * (MAX_PARAMETER + 1))
        self.dialect = dialect
        self.system: Any = None

    @staticmethod
    def number(value: float | None, what: str = "R") -> int:
        """A computed parameter number: a whole number 0..MAX_PARAMETER, else ``bad-parameter``."""
        if value is None or value != value:
            raise ProgramError(f"{what}[…]: the parameter number is not a number", code="bad-parameter")
        n = round(value)
        if abs(value - n) > 1e-9 or not 0 <= n <= MAX_PARAMETER:
            raise ProgramError(f"{what}[{value:g}]: parameter numbers are whole numbers 0..{MAX_PARAMETER}",
                               code="bad-parameter")  # fmt: skip
        return n

    def read(self, number: float | None) -> float:
        return self[self.number(number)]

    def write(self, number: float | None, value: float | None) -> None:
        if value is None or value - value != 0.0:
            raise ProgramError(f"R{number}: the value is not finite", code="math-error")
        self[self.number(number)] = float(value)

    def data_function(self, name: str, argument: float) -> float:
        """A function the dialect answers from its run data (the base store has none)."""
        raise ProgramError(f"{name}[…] has no data on this controller", code="unknown-function")

    def procedure(self, name: str, argument: float) -> None:
        """A write command standing alone in its block (``TRESDEL[n]``); the base store has none."""
        raise ProgramError(f"{name}[…] has no meaning on this controller", code="unknown-function")
