"""scripts/bench_macros.py runs, and its executed-block formulas match the interpreter's own count."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

from cnc_gym.errors import ProgramError
from cnc_gym.gcode import interpret

_PATH = Path(__file__).resolve().parents[4] / "scripts" / "bench_macros.py"


@pytest.fixture(scope="module")
def bench():
    spec = importlib.util.spec_from_file_location("bench_macros", _PATH)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("name", ["loop_program", "calls_program"])
def test_block_formula_is_exact(bench, name):
    # max_blocks = the formula runs; one less stops with too-many-blocks.
    text, blocks = getattr(bench, name)(120)
    tp = interpret(text, max_blocks=blocks)
    assert len(tp) >= 100
    with pytest.raises(ProgramError) as info:
        interpret(text, max_blocks=blocks - 1)
    assert info.value.code == "too-many-blocks"


def test_bench_runs(bench, capsys):
    assert bench.main(["--moves", "300", "--repeats", "1"]) == 0
    out = capsys.readouterr().out
    assert "loop" in out and "calls" in out and "baseline" in out
