"""scripts/reward_signal.py: the signal a reward gives, on one program."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "scripts"))

import reward_signal


def test_rescaled_return_is_the_closed_form():
    episode = reward_signal.EpisodeReturn(total=0.0, discounted=0.0, bonus=0.0, bonus_discounted=0.0,
                                          feasible=True, cycle_time_s=2.0, time_s=4.0, relative=True,
                                          steps=[(-0.1, 0.3), (-0.1, 0.2)])  # fmt: skip
    # Time counted per 2 s instead of 4 s doubles the time terms: (0.3 − 0.2) + 0.5 · (0.2 − 0.2).
    assert episode.rescaled(2.0, 0.5) == pytest.approx(0.1 + 0.5 * 0.0, abs=1e-12)
    assert episode.rescaled(4.0, 1.0) == pytest.approx(0.3, abs=1e-12)


def test_one_program_v5_pays_a_bonus_v6_none(tmp_path, capsys):
    out = tmp_path / "signal.json"
    assert reward_signal.main(["--limit", "1", "--json", str(out)]) == 0
    data = json.loads(out.read_text())
    v5, v6 = data["summary"]["cnc_gym/Feedrate-v5"], data["summary"]["cnc_gym/Feedrate-v6"]
    assert v5["bonus"] > 1.0 and v6["bonus"] == 0.0
    # The same two episodes in both (only the reward differs): the same feasibility.
    row = data["rows"][0]
    assert row["cnc_gym/Feedrate-v5"]["planner_feasible"] == row["cnc_gym/Feedrate-v6"]["planner_feasible"]
    assert "cnc_gym/Feedrate-v6 (simulated)" in row
    table = capsys.readouterr().out
    assert "time per the planner's simulated cycle time" in table and "oracle" in table
