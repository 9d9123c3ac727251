"""scripts/bench_env_memory.py: a fresh child process's peak resident set, phase by phase."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "scripts"))

import bench_env_memory as bench  # noqa: E402


def _check_phases(result: dict, names: list[str]) -> None:
    assert [name for name, _ in result["phases"]] == names
    peaks = [peak for _, peak in result["phases"]]
    assert all(peak > 0 for peak in peaks)
    assert peaks == sorted(peaks)  # a peak never falls
    if sys.platform.startswith("linux"):
        assert set(result["end"]) == {"RssFile", "RssAnon"}
        # What is resident at the end is about the last peak (read just after it: reading allocates a little).
        assert sum(result["end"].values()) <= peaks[-1] + 1.0


def test_pendulum_child_reports_every_phase_and_loads_no_numba():
    result = bench.run_child(bench.PENDULUM_ID, 5)
    _check_phases(result, ["python", "import numpy", "import gymnasium", "import the env's module",
                           "gymnasium.make", "reset + 5 steps"])  # fmt: skip
    assert "scipy" not in result["loaded"]


def test_numba_floor_child_loads_one_function_from_the_cache():
    result = bench.run_child(bench.NUMBA_FLOOR, 0)
    _check_phases(result, ["python", "import numpy", "import numba", "import gymnasium",
                           "one function from numba's cache"])  # fmt: skip
    # numba readies its target on the first call: the largest phase after numba's own import.
    peaks = dict(result["phases"])
    assert peaks["one function from numba's cache"] > peaks["import gymnasium"]


def test_table_lists_each_phase_with_its_increase():
    result = {"id": "x", "repeats": 3, "phases": {"python": 10.0, "import numpy": 25.5},
              "end": {"RssFile": 12.0, "RssAnon": 13.0}, "loaded": []}  # fmt: skip
    lines = bench.table([result]).splitlines()
    assert lines[0].startswith("x: peak resident set")
    assert lines[1].split() == ["python", "10.0", "+10.0"]
    assert lines[2].split() == ["import", "numpy", "25.5", "+15.5"]
    assert "12.0 file-backed, 13.0 anonymous" in lines[3]
    assert lines[4].endswith("loaded: none")


@pytest.mark.slow
@pytest.mark.parametrize("floor_first", [False, True])
def test_env_child_reports_every_phase(floor_first):
    result = bench.run_child("cnc_gym/Feedrate-v0", 5, floor_first)
    floor = ["one function from numba's cache"] if floor_first else []
    _check_phases(result, ["python", "import numpy", "import numba", "import gymnasium", *floor,
                           "import cnc_gym", "import the env's module", "gymnasium.make",
                           "reset + 5 steps"])  # fmt: skip
