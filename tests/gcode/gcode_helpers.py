"""Helpers shared by the interpreter tests (made importable by conftest.py)."""

from __future__ import annotations

import math

import pytest

from cnc_gym.errors import ProgramError
from cnc_gym.gcode import interpret


def records(text: str, **kw) -> list[dict]:
    """Interpret ``text`` and return the trace records (the ``cnc-gym trace`` shape)."""
    return interpret(text, **kw).to_records()


def moves(text: str, **kw) -> list[dict]:
    """Trace records without dwells."""
    return [r for r in records(text, **kw) if r["kind"] != "dwell"]


def program_error(text: str, **kw) -> ProgramError:
    with pytest.raises(ProgramError) as info:
        interpret(text, **kw)
    return info.value


def close(a, b, tol: float = 1e-6) -> bool:
    """Element-wise closeness of numbers or sequences."""
    if isinstance(a, int | float):
        return math.isclose(a, b, abs_tol=tol)
    return len(a) == len(b) and all(math.isclose(x, y, abs_tol=tol) for x, y in zip(a, b, strict=True))
