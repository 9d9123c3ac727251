"""The batch (:class:`~cnc_gym.envs.engine.batch.FeedrateBatch`): which step it takes, the vector env's
batched step against reference envs one by one, partial resets, bad actions, copies and pickles.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from random_gcode import random_gcode
from reference_step import ReferenceEnv

from cnc_gym.envs.feedrate import FeedrateEnv
from cnc_gym.envs.feedrate_v1 import FeedrateEnvV1
from cnc_gym.envs.vector import FeedrateVectorEnv


def test_reference_env_takes_the_modular_step():
    assert FeedrateEnv(programs=["circle"])._batch.fused
    assert not ReferenceEnv(programs=["circle"])._batch.fused


@pytest.mark.parametrize("parallel", [False, True])
def test_vector_env_same_as_reference_envs_one_by_one(parallel):
    # Six envs over three random programs and a built-in with a short budget: truncations, terminations
    # and next-step autoresets happen mid-run in different envs. The batched env (serial, or in numba's
    # threads) must equal Gymnasium's SyncVectorEnv over reference envs, infos included.
    rng = np.random.default_rng(11)
    programs = [random_gcode(rng, 6) for _ in range(3)] + ["star"]
    kwargs = {"programs": programs, "max_episode_steps": 60}
    batched = FeedrateVectorEnv(6, parallel=parallel, **kwargs)
    assert batched.batch.parallel == parallel
    sync = gym.vector.SyncVectorEnv([lambda: ReferenceEnv(**kwargs)] * 6)
    obs_b, info_b = batched.reset(seed=5)
    obs_s, info_s = sync.reset(seed=5)
    np.testing.assert_array_equal(obs_b, obs_s)
    for key, value in info_s.items():
        np.testing.assert_array_equal(info_b[key], value, err_msg=key)
    ends = 0
    for t in range(200):
        actions = rng.uniform(-1, 1, (6, 1)).astype(np.float32)
        out_b, out_s = batched.step(actions), sync.step(actions)
        for a, b in zip(out_b[:4], out_s[:4], strict=True):
            np.testing.assert_array_equal(a, b, err_msg=f"step {t}")
        assert set(out_b[4]) == set(out_s[4])
        for key, value in out_s[4].items():
            np.testing.assert_array_equal(out_b[4][key], value, err_msg=f"step {t}: {key}")
        ends += int(np.sum(out_b[2] | out_b[3]))
    assert ends >= 12


def test_resetting_some_envs_leaves_the_others_as_they_are():
    envs = FeedrateVectorEnv(3, programs=["star", "circle"])
    envs.reset(seed=0)
    for _ in range(20):
        envs.step(np.full((3, 1), 0.5, dtype=np.float32))
    before_f, before_i = envs.batch.state_f.copy(), envs.batch.state_i.copy()
    envs.reset_envs([1], [None], [{"program": "circle"}])
    np.testing.assert_array_equal(envs.batch.state_f[[0, 2]], before_f[[0, 2]])
    np.testing.assert_array_equal(envs.batch.state_i[[0, 2]], before_i[[0, 2]])
    info = envs.batch.info(1)
    assert info["program"] == "circle" and info["steps"] == 0 and info["cycle_time_s"] == 0.0


def test_vector_env_rejects_bad_actions_and_steps_before_reset():
    envs = FeedrateVectorEnv(2, programs=["circle"])
    with pytest.raises(gym.error.ResetNeeded):
        envs.step(np.zeros((2, 1), dtype=np.float32))
    envs.reset(seed=0)
    with pytest.raises(ValueError, match="finite"):
        envs.step(np.array([[0.0], [np.nan]]))
    with pytest.raises(ValueError, match="shape"):
        envs.step(np.zeros((3, 1)))


@pytest.mark.parametrize("env_class", [FeedrateEnv, ReferenceEnv])
def test_a_copied_or_pickled_env_steps_like_the_env(env_class):
    # The oracle planner simulates on copy.deepcopy of the env: the copy's compiled call, state views and
    # controllers must be its own, and the original must run on untouched.
    import copy
    import pickle

    env = env_class(programs=["star", "circle"])
    env.reset(seed=3)
    rng = np.random.default_rng(3)
    for _ in range(40):
        env.step(rng.uniform(-1, 1, 1).astype(np.float32))
    copies = [copy.deepcopy(env), pickle.loads(pickle.dumps(env))]
    ends = 0
    for t in range(1500):
        action = rng.uniform(-1, 1, 1).astype(np.float32)
        out = env.step(action)
        for other in copies:
            out_c = other.step(action)
            np.testing.assert_array_equal(out[0], out_c[0], err_msg=f"step {t}")
            assert out[1:] == out_c[1:], f"step {t}"
        if out[2] or out[3]:
            ends += 1
            first = env.reset()
            for other in copies:
                assert other.reset()[1] == first[1]
    assert ends >= 1


def test_v1_copied_env_steps_like_the_env():
    # The planner's tables and the v1 outputs travel with a copy of the env.
    import copy

    env = FeedrateEnvV1(programs=["star"], action_mode="residual")
    env.reset(seed=0)
    for _ in range(30):
        env.step(np.zeros(1, dtype=np.float32))
    other = copy.deepcopy(env)
    for t in range(200):
        action = np.array([0.3 * np.sin(t / 7)], dtype=np.float32)
        out, out_c = env.step(action), other.step(action)
        np.testing.assert_array_equal(out[0], out_c[0])
        assert repr(out[1:]) == repr(out_c[1:])
