"""FeedrateVectorEnv: the same transitions as gymnasium's SyncVectorEnv over FeedrateEnv copies."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

from cnc_gym.envs.feedrate import FeedrateEnv
from cnc_gym.envs.vector import FeedrateVectorEnv
from cnc_gym.errors import ConfigError


def test_matches_sync_vector_env_through_episode_ends():
    # Four copies over two programs with a 30-step budget, so that truncations and next-step autoresets
    # happen mid-run; random actions. Every observation, reward, flag and info entry must equal
    # SyncVectorEnv's (which is Gymnasium's reference implementation of the same semantics).
    kwargs = {"programs": ["star", "circle"], "max_episode_steps": 30}
    native = FeedrateVectorEnv(4, **kwargs)
    sync = gym.vector.SyncVectorEnv([lambda: FeedrateEnv(**kwargs)] * 4)
    assert native.observation_space == sync.observation_space
    assert native.action_space == sync.action_space
    obs_n, info_n = native.reset(seed=7)
    obs_s, info_s = sync.reset(seed=7)
    np.testing.assert_array_equal(obs_n, obs_s)
    np.testing.assert_array_equal(info_n["program"], info_s["program"])
    rng = np.random.default_rng(0)
    ends = 0
    for _ in range(75):
        actions = rng.uniform(-1, 1, (4, 1)).astype(np.float32)
        out_n = native.step(actions)
        out_s = sync.step(actions)
        for a, b in zip(out_n[:4], out_s[:4], strict=True):
            np.testing.assert_array_equal(a, b)
        for key, value in out_s[4].items():
            np.testing.assert_array_equal(out_n[4][key], value, err_msg=key)
        assert set(out_n[4]) == set(out_s[4])
        ends += int(np.sum(out_n[2] | out_n[3]))
    assert ends >= 8  # two 30-step truncations per copy
    native.close()
    sync.close()


def test_bad_arguments():
    with pytest.raises(ConfigError, match="num_envs"):
        FeedrateVectorEnv(0, programs=["circle"])
    with pytest.raises(ConfigError, match="render"):
        FeedrateVectorEnv(2, programs=["circle"], render_mode="rgb_array")
    envs = FeedrateVectorEnv(2, programs=["circle"])
    envs.reset(seed=0)
    with pytest.raises(ValueError, match="shape"):
        envs.step(np.zeros((3, 1), dtype=np.float32))
