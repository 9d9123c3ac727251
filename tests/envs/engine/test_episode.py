"""Whole episodes in compiled code: the same episode as the Python loop, bit for bit.

Each test runs an episode both ways in this process (the Python loop, :func:`cnc_gym.rollout.play`, and
the compiled driver, :func:`cnc_gym.rollout.play_compiled`) and compares the two: the same CPU runs both,
so exact equality is the claim (never a comparison with stored numbers).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cnc_gym.envs.engine import KnobRule
from cnc_gym.envs.engine.episode import ENDED, RAN, STOPPED
from cnc_gym.motion import ActionError
from cnc_gym.policies import ClassicalPlanner, ConstantOverride
from cnc_gym.rollout import compiled_rule, play, play_compiled, policy_env
from tests.envs.engine.random_gcode import random_gcode

# Exact stops, dwells, arcs, rapids (the built-ins), a program without motion, a one-move program.
PROGRAMS = ["star", "circle", "pocket", "M30\n", "G90 G01 X5 Y3 F1200\nM30\n"]


def _episode(policy, programs, *, compiled: bool, env_id: str | None = None, chunk_steps: int = 2048,
             stop_time_s: float | None = None, **settings):  # fmt: skip
    env = policy_env(policy, programs=programs, env_id=env_id, machine="vmc-small", **settings)
    try:
        observation, info = env.reset(seed=0)
        policy.reset(env)
        if not compiled:
            def stop(steps, reward, terminated, truncated, info):
                over = stop_time_s is not None and info["cycle_time_s"] >= stop_time_s - 1e-9
                return over and not terminated

            return play(env, policy, observation, info, stop)
        rule = compiled_rule(env, policy)
        assert rule is not None
        return play_compiled(env, rule, chunk_steps=chunk_steps, stop_time_s=stop_time_s)
    finally:
        env.close()


def _same(a, b) -> None:
    assert a.info == b.info  # every info value, exactly (the same CPU ran both)
    assert (a.total_return, a.steps, a.terminated, a.truncated, a.stopped) == (
        b.total_return, b.steps, b.terminated, b.truncated, b.stopped)  # fmt: skip


@pytest.mark.parametrize("program", PROGRAMS)
@pytest.mark.parametrize("make", [lambda: ConstantOverride(1.0), lambda: ConstantOverride(0.35),
                                  lambda: ConstantOverride(2.0), ClassicalPlanner],
                         ids=["constant:1", "constant:0.35", "constant:2", "classical"])  # fmt: skip
def test_a_compiled_episode_is_the_python_loops(program, make):
    _same(_episode(make(), [program], compiled=False), _episode(make(), [program], compiled=True))


@pytest.mark.parametrize("env_id", ["cnc_gym/Feedrate-v2", "cnc_gym/Feedrate-v4"])
def test_a_compiled_episode_is_the_python_loops_in_later_versions(env_id):
    # (their reward terms, finish bonus and planner entry ride in the info: all compared)
    for make in (lambda: ConstantOverride(0.8), ClassicalPlanner):
        _same(_episode(make(), ["star"], compiled=False, env_id=env_id),
              _episode(make(), ["star"], compiled=True, env_id=env_id))  # fmt: skip


def test_chunks_do_not_change_the_episode():
    whole = _episode(ClassicalPlanner(), ["circle"], compiled=True)
    assert whole.steps > 50
    for chunk in (1, 7, 50):
        _same(whole, _episode(ClassicalPlanner(), ["circle"], compiled=True, chunk_steps=chunk))


def test_the_step_budget_truncates_alike():
    a = _episode(ConstantOverride(0.0), ["star"], compiled=False)  # the knob at 0: no progress
    _same(a, _episode(ConstantOverride(0.0), ["star"], compiled=True))
    assert a.truncated and not a.terminated


@pytest.mark.parametrize("stop_time_s", [0.05, 0.333, 1e9])
def test_a_stop_time_stops_alike(stop_time_s):
    a = _episode(ConstantOverride(0.5), ["star"], compiled=False, stop_time_s=stop_time_s)
    _same(a, _episode(ConstantOverride(0.5), ["star"], compiled=True, stop_time_s=stop_time_s))
    assert a.stopped == (stop_time_s < 1e9)


@settings(max_examples=8, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), override=st.floats(0.05, 2.0))
def test_random_programs_and_knobs(seed, override):
    program = random_gcode(np.random.default_rng(seed), 12)
    for make in (lambda: ConstantOverride(override), ClassicalPlanner):
        _same(_episode(make(), [program], compiled=False), _episode(make(), [program], compiled=True))


def test_the_driver_returns_why_it_stopped():
    env = policy_env(ConstantOverride(1.0), programs=["star"], machine="vmc-small").unwrapped
    env.reset(seed=0)
    columns = np.array([0, 12], dtype=np.int64)  # cycle_time_s, path_s
    rows = np.full((10, 2), np.nan)
    steps, _, why, terminated, truncated, info = env.run_rule(KnobRule.hold(0.0), 10, columns=columns,
                                                              rows=rows)  # fmt: skip
    assert (steps, why, terminated, truncated) == (10, RAN, False, False)
    assert rows[-1, 0] == info["cycle_time_s"] and rows[-1, 1] == info["path_s"]
    assert np.all(np.diff(rows[:, 0]) > 0)
    steps, _, why, *_ = env.run_rule(KnobRule.hold(0.0), 10, stop_time_s=0.12)
    assert why == STOPPED and steps == 2
    steps, _, why, terminated, *_ = env.run_rule(KnobRule.hold(0.0), 10**7)
    assert why == ENDED and terminated


def test_a_schedule_that_is_not_a_number_is_the_envs_action_error():
    env = policy_env(ConstantOverride(1.0), programs=["star"], machine="vmc-small")
    env.reset(seed=0)
    rule = KnobRule.follow(np.array([[0.0, math.nan]]), 0.03, 0.0, 2.0)
    with pytest.raises(ActionError, match="finite"):
        play_compiled(env, rule)
    with pytest.raises(ActionError, match="finite"):  # what the Python loop does with that knob
        env.step(np.array([math.nan], dtype=np.float32))


def test_a_schedule_table_must_have_rows_of_two():
    with pytest.raises(ValueError, match="rows"):
        KnobRule.follow(np.zeros((0, 2)), 0.03, 0.0, 2.0)
    with pytest.raises(ValueError, match="rows"):
        KnobRule.follow(np.zeros(4), 0.03, 0.0, 2.0)
