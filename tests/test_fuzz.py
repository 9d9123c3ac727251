"""scripts/fuzz.py: short fuzzing runs on every CI run (about 300 programs), long ones marked ``slow``.

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
    report = fuzz.fuzz(seed=0, programs_budget=80, time_limit=4.0, cli_every=40,
                       mix={"grammar": 1, "mutated": 1})  # fmt: skip
    _check(report, 80)
    assert report.cli_checked >= 2


def test_the_generator_is_deterministic_and_covers_every_kind():
    first = [text for _, (_, text) in zip(range(60), fuzz.programs(7), strict=False)]
    again = [fuzz.program_at(7, index)[1] for index in range(60)]
    kinds = {kind for _, (kind, _) in zip(range(60), fuzz.programs(7), strict=False)}
    assert first == again and kinds == set(fuzz.DEFAULT_MIX)


def test_the_targets_put_every_character_class_and_every_address_letter_behind_a_semicolon_too():
    import random

    rng = random.Random(5)
    texts = [fuzz.character_program(rng) for _ in range(400)]
    unicode_digits = fuzz.CHARACTER_CLASSES["unicode-digit"]
    assert sum(";" in t for t in texts) > 100 and any(c in t for t in texts for c in unicode_digits)
    words = [fuzz.address_program(rng) for _ in range(2000)]
    assert all(any(f"{letter}" in t.upper() for t in words) for letter in "ABCDEFGHIJKLMNOPQRSTUVWXYZ")
    assert sum(";" in t for t in words) > 300 and any("e3" in t.lower() for t in words)


def test_batches_and_workers_change_no_count():
    """The report is a function of the seed and the programs: one worker in batches of 7 and two workers in
    batches of 5 count the same outcomes."""
    runs = [fuzz.fuzz(seed=4, programs_budget=40, time_limit=4.0, cli_every=0, workers=w, batch=b,
                      dialects=("gsk25i", "h4cm")) for w, b in ((1, 7), (2, 5))]  # fmt: skip
    assert runs[0].outcomes == runs[1].outcomes and runs[0].tried == runs[1].tried == 40
    assert runs[0].by_dialect_class == runs[1].by_dialect_class


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
    report = fuzz.fuzz(seed=3, programs_budget=programs, time_limit=4.0, cli_every=0, dialects=built,
                       batch=10)  # fmt: skip
    bad = [(index, outcome, detail) for index, _, outcome, detail, _ in report.bad]
    assert not bad, f"seed {report.seed}: {bad}"
    assert dict(report.by_dialect) == {name: 20 for name in built}


@pytest.mark.slow
def test_a_long_fuzzing_run_finds_nothing():
    report = fuzz.fuzz(seed=1, programs_budget=5000, time_limit=10.0, cli_every=250,
                       mix={"grammar": 1, "mutated": 1})  # fmt: skip
    _check(report, 5000)


@pytest.mark.slow
def test_a_long_targeted_run_over_every_dialect_finds_nothing():
    from cnc_gym.gcode import DIALECT_MODULES

    built = tuple(sorted(name for name, module in DIALECT_MODULES.items() if module))
    report = fuzz.fuzz(seed=2, programs_budget=10_000, time_limit=10.0, cli_every=1000, dialects=built)
    bad = [(index, outcome, detail) for index, _, outcome, detail, _ in report.bad]
    assert not bad, f"seed {report.seed}: {bad}"


def test_an_unregistered_code_is_a_finding(monkeypatch):
    # Outside the test suite's strict mode nothing stops an unregistered code at run time: the fuzzer
    # reports one as a crash (here: every code, with the registry emptied).
    from cnc_gym import error_codes

    assert fuzz._classify("G01 X F100\n", 4.0)[0] == "error:missing-value"
    monkeypatch.setattr(error_codes, "_STRICT", False)
    monkeypatch.setattr(error_codes, "CODES", frozenset())
    assert fuzz._classify("G01 X F100\n", 4.0)[0] == "crash:unregistered-code"
