"""The one rollout: the env a policy runs in, the episode loop and its record."""

from __future__ import annotations

import gymnasium
import numpy as np
import pytest

import cnc_gym  # noqa: F401  (registers the env ids)
from cnc_gym.rollout import CONTOUR_RULE, DEFAULT_ENV_ID, Episode, Policy, play, policy_env, run_episode


class _Knob:
    """A constant knob that counts its calls."""

    name = "knob"

    def __init__(self, action: float = 0.0) -> None:
        self.action = np.array([action], dtype=np.float32)
        self.resets = 0
        self.acts = 0

    def reset(self, env) -> None:
        self.resets += 1

    def act(self, observation, info):
        self.acts += 1
        return self.action


class _Named(_Knob):
    """A policy that names its env, as a trained model does."""

    env_id = "cnc_gym/Feedrate-v1"
    env_kwargs = {"action_mode": "residual", "residual_range": 3.0}  # noqa: RUF012


def test_a_policy_without_an_env_of_its_own_runs_in_v0_with_the_path_meter():
    env = policy_env(_Knob(), programs=["circle"], machine="vmc-small")
    try:
        assert env.spec.id == DEFAULT_ENV_ID == "cnc_gym/Feedrate-v0"
        assert env.unwrapped.contour_rule == CONTOUR_RULE == "path"  # v0's own meter is "cuts"
        assert env.unwrapped.machine.name == "vmc-small"
    finally:
        env.close()


def test_a_policy_that_names_its_env_runs_there_with_its_settings():
    env = policy_env(_Named(), programs=["star"], plant="lti")
    try:
        assert env.spec.id == "cnc_gym/Feedrate-v1"
        base = env.unwrapped
        assert base.action_mode == "residual" and base.residual_range == 3.0
        assert base.contour_rule == "path"
    finally:
        env.close()
    # contour_rule=None keeps the env id's own meter.
    env = policy_env(_Named(), programs=["star"], contour_rule=None)
    assert env.unwrapped.contour_rule == "cuts"
    env.close()


def test_run_episode_is_reset_then_the_loop_and_counts_what_the_env_gave():
    env = gymnasium.make("cnc_gym/Feedrate-v0", programs=["circle"])
    policy = _Knob(0.0)
    episode = run_episode(env, policy, seed=0)
    assert isinstance(episode, Episode) and policy.resets == 1 and policy.acts == episode.steps
    assert episode.finished and episode.terminated and not episode.truncated and not episode.stopped
    # The same episode stepped by hand.
    env.reset(seed=0)
    total, steps, info = 0.0, 0, {}
    done = False
    while not done:
        _, reward, terminated, truncated, info = env.step(np.array([0.0], dtype=np.float32))
        total += float(reward)
        steps += 1
        done = terminated or truncated
    assert (episode.steps, episode.total_return) == (steps, total)
    assert episode.info["cycle_time_s"] == info["cycle_time_s"]
    env.close()


def test_the_step_hook_sees_every_step_and_can_stop_the_episode():
    env = gymnasium.make("cnc_gym/Feedrate-v0", programs=["star"])
    seen = []

    def hook(steps, reward, terminated, truncated, info):
        seen.append((steps, info["path_s"]))
        return steps == 25

    observation, info = env.reset(seed=0)
    episode = play(env, _Knob(), observation, info, hook)
    assert episode.stopped and not episode.finished and episode.steps == 25
    assert [s for s, _ in seen] == list(range(1, 26))
    assert episode.info["path_s"] == seen[-1][1]
    env.close()


def test_a_step_budget_ends_the_episode_truncated():
    env = gymnasium.make("cnc_gym/Feedrate-v0", programs=["star"], max_episode_steps=30)
    episode = run_episode(env, _Knob(-1.0), seed=0)  # override 0: the program never ends
    assert episode.truncated and not episode.finished and not episode.stopped and episode.steps == 30
    env.close()


@pytest.mark.parametrize("spec", ["constant:1.0", "classical"])
def test_the_baselines_are_policies(spec):
    from cnc_gym.policies import make_policy

    assert isinstance(make_policy(spec), Policy)


def test_the_compiling_notice_is_said_once_per_process_and_only_when_it_compiles(monkeypatch):
    import io

    from cnc_gym import rollout
    from cnc_gym.envs.engine import batch

    log = io.StringIO()
    monkeypatch.setattr(rollout, "_announced", False)
    monkeypatch.setattr(batch, "step_needs_compiling", lambda parallel=False: False)
    assert not rollout.announce_compiling(log)
    monkeypatch.setattr(batch, "step_needs_compiling", lambda parallel=False: True)
    assert rollout.announce_compiling(log)
    assert not rollout.announce_compiling(log)
    assert log.getvalue().count("compiling the simulator (first run only") == 1


def test_the_readme_check_knows_the_notice():
    # scripts/readme_tour.py leaves the first run's notice out of the shown output it compares.
    import sys
    from pathlib import Path

    from cnc_gym.rollout import COMPILING_NOTICE

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "scripts"))
    import readme_tour

    assert COMPILING_NOTICE.format(30).startswith(readme_tour.COMPILING_PREFIX)


# ------------------------------------------------------------------------------- compiled episodes
def test_the_baselines_run_compiled_and_other_policies_in_python():
    from cnc_gym.envs.engine import KnobRule
    from cnc_gym.policies import ClassicalPlanner, ConstantOverride
    from cnc_gym.rollout import compiled_rule, step_by_step

    for policy in (ConstantOverride(0.7), ClassicalPlanner()):
        env = policy_env(policy, programs=["star"], machine="vmc-small")
        env.reset(seed=0)
        policy.reset(env)
        rule = compiled_rule(env, policy)
        assert isinstance(rule, KnobRule)
        with step_by_step():
            assert compiled_rule(env, policy) is None
        # A wrapper that may act on every step (here the step budget's) keeps the Python loop.
        assert compiled_rule(gymnasium.wrappers.TimeLimit(env, 10), policy) is None
        env.close()
    knob = ConstantOverride(0.7)
    assert compiled_rule(policy_env(knob, programs=["star"]), _Knob()) is None  # not a DeployablePolicy
    # A render mode records every step in Python; so does the MuJoCo plant (not the compiled step).
    env = policy_env(knob, programs=["star"], render_mode="rgb_array")
    env.reset(seed=0)
    knob.reset(env)
    assert compiled_rule(env, knob) is None
    env.close()


def test_a_subclass_that_acts_its_own_way_runs_in_python():
    from cnc_gym.policies import ClassicalPlanner, ConstantOverride

    class Wobbly(ConstantOverride):
        def act(self, observation, info):
            return -super().act(observation, info)

    class Late(ClassicalPlanner):
        def act(self, observation, info):
            return super().act(observation, info)

    for policy in (Wobbly(0.5), Late()):
        env = policy_env(policy, programs=["star"])
        env.reset(seed=0)
        policy.reset(env)
        assert policy.knob_rule() is None
        env.close()
    assert ClassicalPlanner().knob_rule() is None  # before its reset: no schedule
