"""scripts/fuzz.py: a short fuzzing run on every CI run, a long one behind the ``slow`` marker.

Every program must end in ``ok`` or ``error:CODE``: a crash, a program past the time or memory bound, or a
console command that disagrees with ``interpret`` fails the test and names the program's outcome class.
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]


def _fuzz_module():
    spec = importlib.util.spec_from_file_location("cnc_gym_fuzz", REPO / "scripts" / "fuzz.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses resolve their module's annotations through sys.modules
    spec.loader.exec_module(module)
    return module


fuzz = _fuzz_module()


def _check(report, programs: int) -> None:
    bad = [(index, outcome, detail) for index, _, outcome, detail, _ in report.bad]
    assert not bad, f"seed {report.seed}: {bad}"
    assert report.tried == programs and set(report.classes()) <= {"ok", "error"}
    # The generator reaches past the reader: a good share of programs run to the end, and many kinds of
    # error are met (a generator that only made syntax errors would pass the check above vacuously).
    assert report.outcomes["ok"] >= programs // 10
    assert len([o for o in report.outcomes if o.startswith("error:")]) >= 10


def test_a_short_fuzzing_run_finds_nothing():
    report = fuzz.fuzz(seed=0, programs_budget=80, time_limit=4.0, cli_every=40)
    _check(report, 80)
    assert report.cli_checked >= 2


def test_the_generator_is_deterministic_and_covers_both_kinds():
    first = [text for _, (_, text) in zip(range(40), fuzz.programs(7), strict=False)]
    again = [text for _, (_, text) in zip(range(40), fuzz.programs(7), strict=False)]
    kinds = {kind for _, (kind, _) in zip(range(40), fuzz.programs(7), strict=False)}
    assert first == again and kinds == {"grammar", "mutated"}


def test_the_classifier_names_every_outcome():
    assert fuzz._classify("G01 X1 F100\n", 5.0)[0] == "ok"
    assert fuzz._classify("G01 X1.2.3\n", 5.0)[0] == "error:bad-number"
    assert fuzz._classify("#1=0\nWHILE[#1LT1]DO1\nEND1\n", 0.4)[0] == "error:time-budget"
    assert fuzz.check_cli("G01 X1.2.3\n", "error:bad-number", 5.0) == ""
    assert fuzz.check_cli("G01 X1 F100\n", "error:missing-feed", 5.0).startswith("exit 0")


def test_every_built_dialect_takes_its_turn_and_finds_nothing():
    """The Fanuc-family grammar through every built dialect: a dialect whose reader or hooks crash on
    some input fails here, not only GSK 25i."""
    from cnc_gym.gcode import DIALECT_MODULES

    built = tuple(sorted(name for name, module in DIALECT_MODULES.items() if module))
    programs = 20 * len(built)
    report = fuzz.fuzz(seed=3, programs_budget=programs, time_limit=4.0, cli_every=0, dialects=built)
    bad = [(index, outcome, detail) for index, _, outcome, detail, _ in report.bad]
    assert not bad, f"seed {report.seed}: {bad}"
    assert dict(report.by_dialect) == {name: 20 for name in built}


@pytest.mark.slow
def test_a_long_fuzzing_run_finds_nothing():
    report = fuzz.fuzz(seed=1, programs_budget=5000, time_limit=10.0, cli_every=250)
    _check(report, 5000)
