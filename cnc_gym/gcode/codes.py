"""The vocabulary of a dialect's code tables: one G or M code (:class:`CodeSpec`), one address's number
format (:class:`AddressRule`), and the table key of a code number.

G and M codes are keyed by ``round(number * 10)`` so decimal codes fit: G01 → 10, G54.1 → 541, G06.2 → 62.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass


def gkey(number: float) -> int:
    """Table key of a G/M code number: tenths, so G54.1 and G06.2 are exact integers."""
    return round(number * 10)


def code_name(letter: str, key: int) -> str:
    """``G01``, ``G54.1``, ``M30`` from a table key."""
    whole, tenth = divmod(key, 10)
    return f"{letter}{whole:02d}" + (f".{tenth}" if tenth else "")


def round_to(x: float, step: float) -> float:
    """Round half away from zero to a multiple of ``step`` (an address's least input increment). An infinite
    or NaN ``x`` (a literal of 400 digits reads as infinity) comes back as it is, for the caller's range check
    to refuse."""
    if not math.isfinite(x):
        return x
    n = math.floor(abs(x) / step + 0.5 + 1e-9)
    return math.copysign(n * step, x) if n else 0.0


@dataclass(frozen=True)
class AddressRule:
    """Number format of one address: range, whether a decimal point is allowed, unit class.

    ``unit``: ``length`` (mm or inch by G20/G21; truncated to the least input increment), ``feed``
    (mm/min or inch/min), ``integer`` (a whole number: N, O, T, M, S, L, H, D), ``plain`` (a bare real).
    """

    low: float
    high: float
    unit: str = "plain"
    point_allowed: bool = True
    alarm: int | None = None  # alarm raised when the value is out of range


@dataclass(frozen=True)
class CodeSpec:
    """One G or M code of a dialect (or a word such as F that carries an action).

    ``action`` names the callable in the dialect's action registry (:attr:`Dialect.actions
    <cnc_gym.gcode.dialect.Dialect.actions>`) that carries the code out (``motion``, ``plane``, ``units``,
    ``dwell``, ``cycle`` …) and ``value`` is that action's argument (the plane, the motion kind, the cycle
    kind …). ``step`` places it in the dialect's order of execution. ``group`` is the modal group
    (0 = one-shot). ``uses_axes`` marks one-shot codes whose block's axis words belong to them rather than
    to the modal motion (G04 X, G10, G52, G92). ``words`` are the extra addresses the code gives a meaning
    to. ``implemented`` False: the code exists on the controller but this interpreter rejects it by name.
    ``address_rules``: number formats this code gives its own words, in place of the dialect's address
    rules (the L of a pocket cycle is a step-over length, ``L2.5``, where M98's L is a count). The reader
    applies them to blocks that name the code; G06.2's modal blocks re-read theirs.
    """

    name: str
    group: int
    action: str
    value: object = None
    step: str = "record"
    uses_axes: bool = False
    words: str = ""
    implemented: bool = True
    note: str = ""
    address_rules: Mapping[str, AddressRule] | None = None
