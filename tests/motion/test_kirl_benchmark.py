"""The KIRL benchmark (issue: a benchmark to beat): on the kirl-planar-v1 suite the classical controller
meets KIRL's limits in a cycle within 1.10× the TOPP-RA-with-FIR reference (scripts/bench_kirl.py)."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

from cnc_gym.benchmark.suites import check_suite, load_suite
from cnc_gym.gcode import interpret
from cnc_gym.machine import load_machine

SCRIPT = Path(__file__).resolve().parents[2] / "scripts" / "bench_kirl.py"


def bench():
    spec = importlib.util.spec_from_file_location("bench_kirl", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_suite_is_reproducible_and_holds_kirl_outlines():
    suite = load_suite("kirl-planar-v1")
    assert check_suite("kirl-planar-v1") == []
    assert {e.family for e in suite.entries} == {"kirl"}
    b = bench()
    machine = load_machine(suite.machine)
    for entry in suite.programs("test"):
        points, _ = b.outline(interpret(entry.text(), dialect=suite.dialect, machine=machine))
        assert 230 <= len(points) - 1 <= 260
        assert points[0] == pytest.approx(points[-1])  # closed


def test_classical_controller_meets_every_limit_within_1_10_of_the_reference():
    b = bench()
    suite = load_suite("kirl-planar-v1")
    machine = load_machine(suite.machine)
    entry = suite.programs("test")[0]
    tp = interpret(entry.text(), dialect=suite.dialect, machine=machine)
    ours = b.controller_run(tp, machine)
    ref = b.reference_run(b.outline(tp)[0])
    assert ours["v"] <= b.V_MAX * (1 + 1e-6)
    assert ours["a"] <= b.A_MAX * (1 + 1e-3)  # finite differences of float positions
    assert ours["j"] <= b.J_MAX * (1 + 1e-3)
    assert ours["deviation_mm"] <= b.DEVIATION
    assert ours["cycle_s"] <= 1.10 * ref["cycle_s"]
    # the reference is itself within the limits (FIR jerk, deviation)
    assert ref["a"] <= b.A_MAX and ref["j"] <= b.J_MAX and ref["deviation_mm"] <= b.DEVIATION
