"""docs/benchmark.md: its leaderboard is what scripts/leaderboard.py makes of the committed records, and its
suite table matches the manifest."""

from __future__ import annotations

import re
import subprocess
import sys
from collections import Counter
from pathlib import Path

import pytest

from cnc_gym.benchmark.leaderboard import leaderboard_rows, render_markdown, replace_between_markers
from cnc_gym.benchmark.runner import read_jsonl
from cnc_gym.benchmark.suites import load_suite
from cnc_gym.errors import CncGymError

ROOT = Path(__file__).resolve().parents[2]
DOC = ROOT / "docs" / "benchmark.md"
RECORDS = sorted((ROOT / "docs" / "results").glob("*.jsonl"))


def test_the_leaderboard_is_generated_from_the_committed_records():
    assert RECORDS, "docs/results holds the bench records the leaderboard comes from"
    result = subprocess.run([sys.executable, "scripts/leaderboard.py",
                             *(str(p.relative_to(ROOT)) for p in RECORDS), "--check"],
                            cwd=ROOT, capture_output=True, text=True)  # fmt: skip
    assert result.returncode == 0, result.stderr
    records = read_jsonl(RECORDS)
    table = render_markdown(records, [str(p.relative_to(ROOT)) for p in RECORDS])
    assert table in DOC.read_text()
    # The baselines are all there, each named with its commit.
    assert {"classical", "oracle", "bound"} <= {r["policy"] for r in records}
    assert all(r["commit"] in table for r in records)


def test_the_suite_table_matches_the_manifest():
    suite = load_suite()
    counts = Counter((e.family, e.split) for e in suite.entries)
    text = DOC.read_text()
    for family in {e.family for e in suite.entries}:
        row = re.search(rf"^\| `{family}` \|.*\| (\d+) \| (\d+) \| (\d+) \|$", text, re.M)
        assert row, family
        expected = tuple(counts[(family, split)] for split in ("train", "val", "test"))
        assert tuple(int(x) for x in row.groups()) == expected


def _rec(policy, score, **kw):
    base = {"suite": "s", "suite_sha256": "h", "split": "test", "machine": "m", "program": "p", "seed": 0,
            "family": "f", "feasible": score > 0, "finished": True, "time_ratio": 2.0, "commit": "c",
            "violation_length_mm": 0.0, "reference": policy == "bound", "score": score}  # fmt: skip
    return {**base, "policy": policy, **kw}


def test_only_the_best_constant_is_shown_and_new_policies_join():
    rows = leaderboard_rows([_rec("constant:0.5", 0.2), _rec("constant:1.0", 0.3), _rec("classical", 0.4),
                             _rec("ppo-seed0.zip", 0.5), _rec("bound", 1.0)])  # fmt: skip
    names = [r["policy"] for r in rows]
    assert names == ["ppo-seed0.zip", "classical", "constant:1.0 (best of 2 constants)", "bound"]
    assert rows[0]["kind"] == "learned / user policy"


def test_records_of_different_suites_do_not_mix():
    with pytest.raises(CncGymError, match="one suite, split, machine"):
        leaderboard_rows([_rec("classical", 0.4), _rec("oracle", 0.5, split="val")])


@pytest.mark.parametrize("key", ["record_version", "bound_version"])
def test_records_of_different_metric_or_bound_versions_do_not_mix(key):
    # Records made before the programmed-path meter and bound version 2 carry no record_version (or 1):
    # their numbers mean something else, so they never share a table with today's.
    new = _rec("classical", 0.4, record_version=2, bound_version=2)
    old = _rec("oracle", 0.5, record_version=2, bound_version=2)
    old.pop(key)
    with pytest.raises(CncGymError, match=f"several values of '{key}'.*record version and bound version"):
        leaderboard_rows([new, old])
    assert leaderboard_rows([new, {**old, key: 2}])


def test_markers_are_required():
    with pytest.raises(CncGymError, match="markers"):
        replace_between_markers("no markers here", "table")
