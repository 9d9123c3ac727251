"""Helpers of the H4C-M tests: the shared interpreter-test helpers (gcode_helpers) with ``dialect="h4cm"``."""

from __future__ import annotations

from gcode_helpers import close as close_to
from gcode_helpers import compact, program_error

from cnc_gym.errors import ProgramError
from cnc_gym.gcode import interpret


def run(text: str, **kw):
    """``interpret`` with ``dialect="h4cm"`` unless another (a variant with other options) is given."""
    kw.setdefault("dialect", "h4cm")
    return interpret(text, **kw)


def path(text: str, **kw) -> list[tuple]:
    """The tool path as compact rows (gcode_helpers.compact): ("R", end), ("F", end, feed), ("D", seconds),
    ("A", end, centre, radius, sweep°)."""
    return compact(run(text, **kw).to_records())


def ends(text: str, **kw) -> list[tuple]:
    """The end points of the moves (no dwells), rounded to 1 µm."""
    return [row[1] for row in path(text, **kw) if row[0] != "D"]


def error(text: str, **kw) -> ProgramError:
    """The ProgramError the program ends in (``dialect="h4cm"`` unless given)."""
    kw.setdefault("dialect", "h4cm")
    return program_error(text, **kw)


def close(a, b, tol: float = 1e-3) -> bool:
    """Closeness to 1 µm (the paths' rounding)."""
    return close_to(a, b, tol)
