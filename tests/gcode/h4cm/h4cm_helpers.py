"""Helpers of the H4C-M tests: run a program with ``dialect="h4cm"`` and read its tool path compactly."""

from __future__ import annotations

import math

import pytest

from cnc_gym.errors import ProgramError
from cnc_gym.gcode import interpret


def run(text: str, **kw):
    """``interpret`` with ``dialect="h4cm"`` unless another (a variant with other options) is given."""
    kw.setdefault("dialect", "h4cm")
    return interpret(text, **kw)


def path(text: str, **kw) -> list[tuple]:
    """Rows as tuples: ("R", end) rapid, ("F", end, feed) line, ("D", seconds) dwell, ("A", end, centre,
    radius, sweep°) arc; coordinates rounded to 1 µm."""
    out = []
    for r in run(text, **kw).to_records():
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


def ends(text: str, **kw) -> list[tuple]:
    """The end points of the moves (no dwells), rounded to 1 µm."""
    return [row[1] for row in path(text, **kw) if row[0] != "D"]


def error(text: str, **kw) -> ProgramError:
    with pytest.raises(ProgramError) as info:
        run(text, **kw)
    return info.value


def close(a, b, tol: float = 1e-3) -> bool:
    return all(math.isclose(x, y, abs_tol=tol) for x, y in zip(a, b, strict=True))
