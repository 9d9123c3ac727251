"""The JSON Lines writer of ``cnc-gym trace`` is the records through json.dumps, character for character."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from cnc_gym.errors import CncGymError
from cnc_gym.gcode import interpret
from cnc_gym.machine import load_machine
from cnc_gym.programs import BUILTIN_PROGRAMS, load_program
from cnc_gym.toolpath import Plane, SegmentMode, ToolpathBuilder
from cnc_gym.toolpath.nurbs import NurbsCurve
from cnc_gym.toolpath.records import _r, rounded, toolpath_jsonl


def reference_text(tp) -> str:
    return "".join(json.dumps(record) + "\n" for record in tp.to_records())


@pytest.mark.parametrize("name", BUILTIN_PROGRAMS)
def test_builtins(name):
    _, tp = load_program(name)
    assert toolpath_jsonl(tp) == reference_text(tp)


def test_random_rows_of_every_kind_mode_and_awkward_number():
    # Values that print differently (1e-05, -0.0, ties at the 6th decimal, large coordinates), every
    # mode flag, rows from a second file, NURBS rows: the writer takes each row either
    # way and the text must not change.
    rng = np.random.default_rng(4)
    awkward = [0.0, -0.0, 1e-5, -1e-7, 0.1234565, 2.5e-6, 123456.7890125, 1e-4, 0.5, 1 / 3, -2 / 3]
    builder = ToolpathBuilder(files=("main.nc", "sub.nc"))
    here = np.zeros(3)

    def point():
        return tuple(float(rng.choice(awkward)) if rng.random() < 0.3 else float(x)
                     for x in rng.normal(0, 50, 3))  # fmt: skip

    for number in range(400):
        choice = number % 6
        modes = SegmentMode(int(rng.integers(0, 32))) if rng.random() < 0.3 else SegmentMode.NONE
        extra = {"line": number + 1, "modes": modes, "file_index": int(rng.random() < 0.1)}
        there = point()
        if choice == 0:
            builder.rapid(tuple(here), there, **extra)
        elif choice in (1, 2):
            builder.line(tuple(here), there, feed=float(rng.choice([1200.0, 1e-5, 333.3333335])), **extra)
        elif choice == 3:
            plane = Plane(int(rng.integers(0, 3)))
            builder.arc(tuple(here), there, point(), plane, float(rng.uniform(-7, 7)), feed=600.0, **extra)
        elif choice == 4:
            builder.dwell(tuple(here), float(rng.choice([0.5, 1e-5, 0.0])), **extra)
            there = tuple(here)
        else:
            ctrl = np.vstack((here, rng.normal(0, 5, (3, 3)) + here))
            curve = NurbsCurve(ctrl, np.ones(4), np.array([0, 0, 0, 0, 1, 1, 1, 1.0]), order=4)
            builder.nurbs(curve, feed=900.0, **extra)
            there = tuple(ctrl[-1])
        here = np.array(there)
    tp = builder.build()
    assert toolpath_jsonl(tp) == reference_text(tp)
    # A number that is not finite has no JSON form: one error naming the line, nothing printed.
    builder.line(tuple(here), (1.0, 2.0, 3.0), feed=math.inf, line=999)
    with pytest.raises(CncGymError, match=r"^line 999: the tool path holds a number that is not finite"):
        toolpath_jsonl(builder.build())


def test_rotary_axes_and_interpreted_programs():
    rotary = interpret("G01 X1 F100\nG91 G01 X1 B45\nG90 G00 B0\n", machine=load_machine("gsk25i"))
    assert toolpath_jsonl(rotary) == reference_text(rotary)
    text = ("G90 G21 G17\nG00 X10 Y0 Z5\nG09 G01 Z0 F1200\nG02 X0 Y10 I-10 J0 F3000\n"
            "G03 X-10 Y0 Z-2 R10\nG04 X0.25\nG18 G02 X0 Z-2 I5 K0\nM30\n")  # fmt: skip
    tp = interpret(text)
    assert toolpath_jsonl(tp) == reference_text(tp)
    smoothed = interpret("G5.1 Q1 E0.01\nG01 X1. F100\nG02 X3. R1.\nG5.1 Q0\nG01 X4.\n", dialect="syntec")
    assert smoothed.smoothing_tolerance_mm.any()
    assert toolpath_jsonl(smoothed) == reference_text(smoothed)
    empty = interpret("G90\nM30\n")
    assert toolpath_jsonl(empty) == reference_text(empty)


def _same_numbers(values) -> bool:
    expected = [repr(_r(x)) for x in np.asarray(values, dtype=float).tolist()]
    return [repr(x) for x in rounded(np.asarray(values, dtype=float))] == expected


@given(st.floats(allow_nan=False, allow_infinity=False))
def test_vectorised_rounding_is_pythons_round(x):
    assert _same_numbers([x, -x, x * 1e6, x / 1e6])


def test_vectorised_rounding_on_ties_near_ties_and_every_scale():
    # Exact ties at the 6th decimal (k/128: 7812.5e-6), values a hair either side of a tie, and values from
    # 1e-9 to 1e20 (past 2**52 / 1e6 the scaled product is no longer exact and Python's round decides).
    rng = np.random.default_rng(7)
    ties = np.arange(-4000, 4000) / 128.0
    near = (np.round(rng.normal(0, 100, 4000) * 1e6) + 0.5) / 1e6
    values = [ties, near, np.nextafter(near, np.inf), np.nextafter(near, -np.inf)]
    values += [rng.normal(0, scale, 2000) for scale in 10.0 ** np.arange(-9, 21)]
    assert _same_numbers(np.concatenate(values))
