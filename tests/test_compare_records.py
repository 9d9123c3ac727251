"""scripts/compare_records.py: a policy against a baseline, program by program, from bench records."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "scripts"))

from compare_records import compare  # noqa: E402


def _rec(policy: str, program: str, seed: int, cycle: float, feasible: bool = True,
         machine: str = "m") -> dict:  # fmt: skip
    return {"policy": policy, "program": program, "seed": seed, "cycle_time_s": cycle, "feasible": feasible,
            "machine": machine, "track": "nominal", "reference": False, "score": 0.5, "suite": "s",
            "split": "test"}  # fmt: skip


RECORDS = [
    _rec("classical", "a", 0, 10.0), _rec("classical", "b", 0, 10.0), _rec("classical", "c", 0, 10.0, False),
    *[_rec("agent", "a", s, 9.0) for s in range(3)],  # faster
    *[_rec("agent", "b", s, 10.5 if s == 0 else 10.0) for s in range(3)],  # slower on the mean over seeds
    *[_rec("agent", "c", s, 8.0, s != 1) for s in range(3)],  # violates where the baseline did too
    _rec("agent", "d", 0, 1.0),  # no baseline run: not compared
    _rec("classical", "a", 0, 20.0, machine="other"), _rec("agent", "a", 0, 20.0, False, machine="other"),
]  # fmt: skip


def test_counts_and_failures_per_machine():
    mine, other = compare(RECORDS, "agent", "classical")
    user = compare([{**r, "suite": "user"} for r in RECORDS[:6]], "agent", "classical")
    assert [r["programs_from"] for r in user] == ["user"] and mine["programs_from"] == "s/test"
    assert (mine["machine"], mine["programs"], mine["faster"], mine["slower"]) == ("m", 3, 2, 1)
    assert mine["failures"] == ["b slower (1.017 ×)"]  # c's violation is not added: classical violates too
    assert mine["mean_time_s"] == pytest.approx((9.0 + 30.5 / 3 + 8.0) / 3)
    assert mine["baseline_time_s"] == pytest.approx(10.0)
    assert other["failures"] == ["a adds a violation (1 of 1 seeds)"]
    assert other["faster"] == other["slower"] == 0


def test_the_script_prints_a_markdown_row_per_machine(tmp_path):
    path = tmp_path / "records.jsonl"
    path.write_text("".join(json.dumps(r) + "\n" for r in RECORDS))
    command = [sys.executable, "scripts/compare_records.py", str(path), "--policy", "agent", "--markdown"]
    result = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert len(lines) == 4 and "b slower" in lines[2]
    assert lines[2].startswith("| s/test | `m` | nominal | 3 |")
    missing = subprocess.run([*command[:3], "--policy", "nobody"], cwd=ROOT, capture_output=True, text=True,
                             timeout=120)  # fmt: skip
    assert missing.returncode == 1 and "no programs with both 'nobody'" in missing.stderr
    bad = tmp_path / "bad.jsonl"
    bad.write_text('{"x": 1}\n')
    broken = subprocess.run([*command[:2], str(bad), "--policy", "agent"], cwd=ROOT, capture_output=True,
                            text=True, timeout=120)  # fmt: skip
    assert broken.returncode == 2 and broken.stderr.strip() == f"{bad}:1: not a cnc-gym bench record"
