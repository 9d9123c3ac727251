"""The score rule, confidence intervals, and violation metrics that do not depend on the control period."""

from __future__ import annotations

import math

import gymnasium
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import cnc_gym  # noqa: F401
from cnc_gym.benchmark.metrics import episode_score, format_table, is_feasible, mean_ci, summarize


def test_score_rule():
    assert episode_score(True, 0.0, 2.0) == 0.5
    assert episode_score(False, 0.0, 2.0) == 0.0  # truncated
    assert episode_score(True, 0.01, 1.1) == 0.0  # violating
    assert episode_score(True, None, 1.0) == 0.0  # unknown violations: not feasible
    assert not is_feasible(True, 1e-9)


@given(ratio_a=st.floats(1.0, 1e6), ratio_b=st.floats(1.0, 1e6), finished=st.booleans(),
       length=st.floats(0.0, 1e3, exclude_min=True))  # fmt: skip
def test_an_infeasible_episode_never_outranks_a_feasible_one(ratio_a, ratio_b, finished, length):
    feasible = episode_score(True, 0.0, ratio_a)
    assert feasible > 0
    assert episode_score(finished, length, ratio_b) < feasible  # violating, whatever its speed
    assert episode_score(False, 0.0, ratio_b) < feasible  # truncated


def test_mean_ci_is_the_student_t_interval():
    mean, half = mean_ci([1.0, 2.0, 3.0])
    assert mean == 2.0
    assert half == pytest.approx(4.302652729911275 * 1.0 / math.sqrt(3))  # t(0.975, 2) · s/√n
    assert mean_ci([5.0]) == (5.0, None)


def _record(policy, program, seed, score, family="f", feasible=True, ratio=2.0, length=0.0):
    return {"policy": policy, "program": program, "seed": seed, "score": score, "family": family,
            "feasible": feasible, "finished": True, "time_ratio": ratio, "violation_length_mm": length,
            "cut_length_mm": 100.0, "reference": False}  # fmt: skip


def test_summary_is_a_mean_over_programs_per_seed_then_over_seeds():
    records = [_record("p", "a", 0, 0.5), _record("p", "b", 0, 0.0, feasible=False, length=2.0),
               _record("p", "a", 1, 0.5), _record("p", "b", 1, 0.5)]  # fmt: skip
    (row,) = [r for r in summarize(records) if r["family"] == "all"]
    assert row["score"] == pytest.approx((25.0 + 50.0) / 2)
    assert row["score_ci95"] == pytest.approx(12.706204736174707 * 17.67766952966369 / math.sqrt(2))
    assert row["feasible_share"] == 0.75
    assert row["violation_rate"] == pytest.approx(2.0 / 400.0)
    assert "p" in format_table(summarize(records))


def test_violation_length_does_not_depend_on_the_control_period():
    lengths, times, steps = [], [], []
    for period in (0.002, 0.01, 0.02):
        env = gymnasium.make("cnc_gym/Feedrate-v0", programs=["star"], control_period_s=period)
        env.reset(seed=0)
        action = np.array([0.5], dtype=np.float32)  # 150 %: violates at the corners
        while True:
            _, _, terminated, truncated, info = env.step(action)
            if terminated or truncated:
                break
        lengths.append(info["violation_length_mm"])
        times.append(info["violation_time_s"])
        steps.append(info["violations"])
        env.close()
    assert lengths[0] > 0.5
    assert lengths == pytest.approx([lengths[0]] * 3, rel=1e-9)
    assert times == pytest.approx([times[0]] * 3, rel=1e-9)
    assert len(set(steps)) == 3  # the per-step count does depend on it
