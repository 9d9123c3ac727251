"""The README tour runs as printed and prints what it shows (``scripts/readme_tour.py``).

The quick commands (``cnc-gym trace``/``run``, the Python block) run on every ``make test``; ``make demo``
and the training commands under ``pytest -m slow``. ``make test`` itself is never run from here.
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def load_tour():
    spec = importlib.util.spec_from_file_location("readme_tour", ROOT / "scripts" / "readme_tour.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up there
    spec.loader.exec_module(module)
    return module


tour = load_tour()
README = (ROOT / "README.md").read_text(encoding="utf-8")


def test_the_readme_shows_commands_to_check():
    commands = tour.commands(README)
    texts = [c.text for c in commands]
    assert any(t.startswith(".venv/bin/cnc-gym trace examples/") for t in texts)
    assert any(t.startswith(".venv/bin/cnc-gym run ") for t in texts)
    assert "make demo" in texts and "make test" in texts
    assert all(c.shown for c in commands if "cnc-gym" in c.text)  # every cnc-gym command shows its output
    assert tour.python_blocks(README)
    assert tour.unmarked_commands(README) == []


def test_the_quick_commands_run_as_printed():
    problems = tour.check(README, slow=False)
    assert problems == [], "\n".join(problems)


@pytest.mark.slow
def test_the_slow_commands_run_as_printed():
    problems = tour.check(README, slow=True)
    assert problems == [], "\n".join(problems)


def test_shown_output_matching():
    actual = ["a", "b", "c", "d"]
    assert tour.matches(["a", "b", "c", "d"], actual)
    assert tour.matches(["a", "..."], actual)
    assert tour.matches(["...", "c", "d"], actual)
    assert tour.matches(["a", "...", "d"], actual)
    assert tour.matches(["...", "b", "c", "..."], actual)
    assert not tour.matches(["a", "c", "..."], actual)  # literal lines are consecutive
    assert not tour.matches(["a", "b"], actual)  # without "...", the whole output
    assert not tour.matches(["...", "x", "..."], actual)


def test_long_floats_match_to_a_relative_1e9_and_everything_else_exactly():
    shown = '{"contour_error_max_mm": 0.02317565598902111, "cycle_time_s": 8.28, "violations": 3}'
    other_cpu = '{"contour_error_max_mm": 0.02317565598902335, "cycle_time_s": 8.28, "violations": 3}'
    assert tour.matches([shown], [other_cpu])
    assert not tour.matches([shown], [other_cpu.replace("0.023175655989", "0.023175755989")])  # 4e-6 relative
    assert not tour.matches([shown], [other_cpu.replace("8.28", "8.29")])  # short numbers: exactly
    assert not tour.matches([shown], [other_cpu.replace("violations", "violation")])
    assert not tour.matches(["x 1.2345678901234"], ["x 1.2345678901234 y"])
    assert tour.matches(["...", "star 0.1234567890123", "..."], ["a", "star 0.1234567890124", "b"])


def test_commands_and_their_output_are_parsed_with_exit_statuses():
    text = ("x\n```\n$ echo hi\nhi\n$ false  # exit status 1\n```\n"
            "```python\nprint(1)\n```\n```\nmake demo\n```\n")
    commands = tour.commands(text)
    assert [(c.line, c.text, c.shown, c.status) for c in commands] == [
        (3, "echo hi", ["hi"], 0),
        (5, "false  # exit status 1", [], 1),
    ]
    assert tour.unmarked_commands(text) == ["make demo"]
    assert [b.lines for b in tour.python_blocks(text)] == [["print(1)"]]
