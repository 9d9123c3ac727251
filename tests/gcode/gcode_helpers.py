"""Helpers shared by the interpreter tests (made importable by conftest.py)."""

from __future__ import annotations

import math
import os
from contextvars import ContextVar

import numpy as np
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


def compact(rows: list[dict]) -> list[tuple]:
    """Trace records as compact tuples: ("R", end) rapid, ("F", end, feed) line, ("D", seconds) dwell, ("A",
    end, centre, radius, sweep°) arc; coordinates rounded to 1 µm."""
    out: list[tuple] = []
    for r in rows:
        end = tuple(round(c, 3) + 0.0 for c in r.get("end", ()))
        if r["kind"] == "rapid":
            out.append(("R", end))
        elif r["kind"] == "line":
            out.append(("F", end, r["feed"]))
        elif r["kind"] == "dwell":
            out.append(("D", r["seconds"]))
        elif r["kind"] == "arc":
            out.append(("A", end, tuple(round(c, 3) + 0.0 for c in r["center"]), round(r["radius"], 3),
                        round(r["sweep_deg"], 3)))  # fmt: skip
        else:
            out.append((r["kind"], end))
    return out


def close(a, b, tol: float = 1e-6) -> bool:
    """Element-wise closeness of numbers or sequences."""
    if isinstance(a, int | float):
        return math.isclose(a, b, abs_tol=tol)
    return len(a) == len(b) and all(math.isclose(x, y, abs_tol=tol) for x, y in zip(a, b, strict=True))


# A property "a ProgramError or a good tool path" passes vacuously if every program is rejected: the
# properties count their outcomes (``tally``) and ``success_share`` asserts that enough ran to the end.
_SHARE: ContextVar[list[int] | None] = ContextVar("success_share", default=None)


def tally(ok: bool) -> None:
    """Count one example of the running property: ``ok`` = the program ran to a tool path."""
    counts = _SHARE.get()
    if counts is not None:
        counts[bool(ok)] += 1


def success_share(minimum: float):
    """Decorate a hypothesis property (above ``@settings``/``@given``) whose examples call :func:`tally`:
    after all examples, at least ``minimum`` of them must have run to a tool path (a regression that
    rejected every program would otherwise stay green). ``CNC_GYM_SHARE_REPORT=1 pytest -s`` prints the
    shares (the minimums are about a third of the shares measured under CI's derandomized examples)."""

    def wrap(test):
        def run() -> None:
            counts = [0, 0]
            token = _SHARE.set(counts)
            try:
                test()
            finally:
                _SHARE.reset(token)
            total = sum(counts)
            assert total > 0, "the property ran no example"
            assert counts[1] >= minimum * total, (
                f"only {counts[1]} of {total} programs ran to a tool path (at least {minimum:.0%} expected)")
            if _REPORT:
                print(f"{test.__name__}: {counts[1]} of {total} ran ({counts[1] / total:.0%})")

        for name in ("__name__", "__qualname__", "__doc__", "__module__"):
            setattr(run, name, getattr(test, name))
        return run

    return wrap


_REPORT = bool(os.environ.get("CNC_GYM_SHARE_REPORT"))


def check_outcome(text: str, **options) -> None:
    """A property's check: ``text`` ends in a one-line ProgramError with a code, or in a finite tool path
    (no NaN anywhere a number belongs); the outcome is counted for :func:`success_share`."""
    try:
        tp = interpret(text, **options)
    except ProgramError as err:
        assert err.code and "\n" not in str(err)
        tally(False)
        return
    tally(True)
    for name in ("start", "end", "radius", "sweep", "dwell_s", "length"):
        assert np.all(np.isfinite(getattr(tp, name))), name
    assert np.all(np.isfinite(tp.feed) | (tp.kind == 0) | (tp.kind == 3))  # rapids and dwells carry NaN feed
    assert np.all(np.isfinite(tp.rotary_start)) and np.all(np.isfinite(tp.rotary_end))
