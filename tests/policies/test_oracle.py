"""The oracle planner as a policy: within tolerance and faster than every constant override that is."""

from __future__ import annotations

import gymnasium
import numpy as np
import pytest

import cnc_gym  # noqa: F401  (registers the env)
from cnc_gym.policies import ConstantOverride, OraclePlanner
from cnc_gym.runner import record_run

OVERRIDES = np.round(np.arange(1, 21) * 0.1, 1)  # 10 %, 20 %, … 200 %

# A corner-rich part that starts cutting at the origin (no rapid before the first cut): zig-zag teeth
# (turns of ±53° and 127°), two 90° corners and a closing move; F3000.
ZIGZAG = """(zigzag: sharp corners only)
G90 G17 G21
G01 X10 Y5 F3000
X20 Y0
X30 Y5
X40 Y0
X40 Y10
X0 Y10
X0 Y0
M30
"""


def _constant_verdict(env, override: float, time_to_beat: float, allowed_violations: int) -> str:
    """'violates', 'slower' or 'FASTER' for one constant override against the classical run.

    'violates': more violations than the classical run had. A constant override that gets there, or is
    still cutting when the classical run has finished, cannot beat it, so the episode stops there (that
    keeps the slow overrides cheap).
    """
    policy = ConstantOverride(override)
    observation, info = env.reset(seed=0)
    policy.reset(env)
    while True:
        observation, _, terminated, truncated, info = env.step(policy.act(observation, info))
        if info["violations"] > allowed_violations:
            return "violates"
        if truncated:  # cut off by the env's step budget: not finished, so not faster
            return "slower"
        if terminated:
            return "FASTER" if info["cycle_time_s"] < time_to_beat else "slower"
        if info["cycle_time_s"] >= time_to_beat:
            return "slower"


@pytest.mark.parametrize(
    "program", [ZIGZAG, "star", "pocket", "freeform"], ids=["zigzag", "star", "pocket", "freeform"]
)
def test_oracle_beats_every_compliant_constant_override(program):
    env = gymnasium.make("cnc_gym/Feedrate-v0", programs=[program], machine="vmc-small")
    classical = record_run(env, OraclePlanner(), record=False)
    assert classical.finished
    # Within tolerance: no violation at all. (The controller waits in position at the rapid's end, so the
    # plunge that follows an approach rapid starts from a settled servo; no step is left that no feed avoids.)
    assert classical.violations == 0
    careful = record_run(env, ConstantOverride(0.1), record=False)
    # Faster than every constant override 10 %…200 % that stays as compliant.
    verdicts = {
        float(x): _constant_verdict(env, float(x), classical.cycle_time_s, 0)
        for x in OVERRIDES
    }
    assert "FASTER" not in verdicts.values(), verdicts
    # The comparison is not empty: some constant overrides are as compliant (and slower) ...
    assert "slower" in verdicts.values(), verdicts
    # ... and the planner is not merely careful: it beats the slowest compliant one by a wide margin.
    assert classical.cycle_time_s < 0.75 * careful.cycle_time_s
    env.close()


def test_oracle_uses_override_above_100_percent_where_geometry_allows():
    env = gymnasium.make("cnc_gym/Feedrate-v0", programs=["star"], machine="vmc-small")
    result = record_run(env, OraclePlanner())
    assert result.override.max() > 1.2
    assert result.override.min() < 1.0
    env.close()


def test_planning_shows_a_bar_when_asked_and_nothing_otherwise(capsys):
    env = gymnasium.make("cnc_gym/Feedrate-v0", programs=["circle"], machine="vmc-small")
    env.reset(seed=0)
    OraclePlanner(progress=True).reset(env)
    assert "oracle: planning circle" in capsys.readouterr().err
    env.reset(seed=0)
    OraclePlanner().reset(env)  # progress=None: a bar only when stderr is a terminal (not under pytest)
    assert capsys.readouterr().err == ""
    env.close()
