"""docs/training.md: its result table is what scripts/leaderboard.py makes of the committed bench records."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
DOC = ROOT / "docs" / "training.md"
#: The test-split records the tables are made of (every track): the baselines' and the trained agents'.
RECORDS = sorted(str(p.relative_to(ROOT)) for p in (ROOT / "docs" / "results").glob("*.jsonl"))
#: The trained agents' records: the PPO-Lagrangian agent's and the distilled students' on every track (the
#: chosen configuration's, ``distill-floor``, and the previous choice's).
AGENTS = ["docs/results/cnc-bench-v1-test-learned.jsonl", "docs/results/cnc-bench-v1-test-distill.jsonl",
          "docs/results/cnc-bench-v1-test-distill-perturbed.jsonl",
          "docs/results/cnc-bench-v1-test-distill-mujoco.jsonl",
          "docs/results/cnc-bench-v1-test-distill-floor.jsonl",
          "docs/results/cnc-bench-v1-test-distill-floor-perturbed.jsonl",
          "docs/results/cnc-bench-v1-test-distill-floor-mujoco.jsonl"]  # fmt: skip


def test_the_result_table_is_generated_from_the_committed_records():
    command = [sys.executable, "scripts/leaderboard.py", *RECORDS, "--doc", str(DOC), "--check"]
    result = subprocess.run(command, cwd=ROOT, capture_output=True, text=True)
    assert result.returncode == 0, result.stderr


@pytest.mark.parametrize("path", AGENTS)
def test_the_agents_were_benched_with_three_training_seeds_on_a_committed_tree(path):
    from cnc_gym.benchmark.runner import read_jsonl

    assert path in RECORDS
    records = read_jsonl([ROOT / path])
    assert {r["split"] for r in records} == {"test"}
    for policy in {r["policy"] for r in records}:
        mine = [r for r in records if r["policy"] == policy]
        assert "{seed}" in policy and sorted({r["seed"] for r in mine}) == [0, 1, 2]
        assert len(mine) == 3 * 70
        assert all(not r["commit"].endswith("+dirty") for r in mine)
        assert (ROOT / policy.replace("{seed}", "0")).is_file()


def _records(folder: str) -> list[str]:
    return sorted(str(p.relative_to(ROOT)) for p in (ROOT / "docs" / "results" / folder).glob("*.jsonl"))


@pytest.mark.parametrize("val", [
    ["docs/results/val/ppo-lagrangian-residual-narrow.jsonl"],  # today's records
    [f"docs/results/val/record-v1/{name}.jsonl"  # how the variant was chosen (record version 1)
     for name in ("ppo-residual", "ppo-lagrangian-residual", "ppo-lagrangian-residual-narrow")],
    _records("val/distill"),
    ["docs/results/val/distill/baselines.jsonl", "docs/results/val/ppo-lagrangian-residual-v6.jsonl"],
    _records("val/perturbed"),
])  # fmt: skip
def test_the_val_tables_are_the_scripts_output(val):
    command = [sys.executable, "scripts/leaderboard.py", *val, "--print"]
    result = subprocess.run(command, cwd=ROOT, capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    assert result.stdout in DOC.read_text()


def test_todays_records_do_not_mix_with_record_version_1():
    command = [sys.executable, "scripts/leaderboard.py", "--print",
               "docs/results/val/ppo-lagrangian-residual-narrow.jsonl",
               "docs/results/val/record-v1/ppo-residual.jsonl"]  # fmt: skip
    result = subprocess.run(command, cwd=ROOT, capture_output=True, text=True)
    assert result.returncode != 0 and "record_version" in result.stderr


def test_the_generalisation_table_is_the_scripts_output():
    records = _records("generalisation")
    assert len(records) == 4  # three machines and the real programs
    command = [sys.executable, "scripts/compare_records.py", *records, "--policy",
               "docs/results/models/distill-floor-residual-s{seed}.zip", "--markdown"]  # fmt: skip
    result = subprocess.run(command, cwd=ROOT, capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    assert result.stdout in DOC.read_text()
