"""FeedrateVectorEnv: the same transitions as gymnasium's SyncVectorEnv over FeedrateEnv copies."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

from cnc_gym.envs.feedrate import FeedrateEnv
from cnc_gym.envs.vector import FeedrateVectorEnv, FeedrateVectorEnvV1
from cnc_gym.errors import ConfigError


def _same_episodes(native: gym.vector.VectorEnv, sync: gym.vector.SyncVectorEnv, *, seed: int, steps: int,
                   rng: np.random.Generator, low: float, high: float) -> int:  # fmt: skip
    """Step both with the same random actions from ``reset(seed)``: every observation, reward, flag and info
    entry equal, bit for bit. Returns the number of episode ends seen."""
    obs_n, info_n = native.reset(seed=seed)
    obs_s, info_s = sync.reset(seed=seed)
    np.testing.assert_array_equal(obs_n, obs_s)
    np.testing.assert_array_equal(info_n["program"], info_s["program"])
    ends = 0
    for _ in range(steps):
        actions = rng.uniform(low, high, (native.num_envs, 1)).astype(np.float32)
        out_n = native.step(actions)
        out_s = sync.step(actions)
        for a, b in zip(out_n[:4], out_s[:4], strict=True):
            np.testing.assert_array_equal(a, b)
        assert set(out_n[4]) == set(out_s[4])
        for key, value in out_s[4].items():
            np.testing.assert_array_equal(out_n[4][key], value, err_msg=key)
        ends += int(np.sum(out_n[2] | out_n[3]))
    return ends


def test_matches_sync_vector_env_through_episode_ends():
    # Four copies over two programs with a 30-step budget, so that truncations and next-step autoresets
    # happen mid-run; random actions. Every observation, reward, flag and info entry must equal
    # SyncVectorEnv's (which is Gymnasium's reference implementation of the same semantics).
    kwargs = {"programs": ["star", "circle"], "max_episode_steps": 30}
    native = FeedrateVectorEnv(4, **kwargs)
    sync = gym.vector.SyncVectorEnv([lambda: FeedrateEnv(**kwargs)] * 4)
    assert native.observation_space == sync.observation_space
    assert native.action_space == sync.action_space
    ends = _same_episodes(native, sync, seed=7, steps=75, rng=np.random.default_rng(0), low=-1.0, high=1.0)
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


@pytest.mark.parametrize(("env_id", "kwargs"), [
    ("cnc_gym/Feedrate-v1", {}),
    ("cnc_gym/Feedrate-v2", {"action_mode": "feed"}),
    ("cnc_gym/Feedrate-v3", {}),
    ("cnc_gym/Feedrate-v3", {"action_mode": "residual"}),
    ("cnc_gym/Feedrate-v1", {"action_mode": "residual", "residual_range": 4.0}),
    ("cnc_gym/Feedrate-v6", {"action_mode": "residual", "reward": {"time": 2.0}}),
])  # fmt: skip
def test_every_id_has_a_vector_entry_point_with_the_single_envs_numbers(env_id, kwargs):
    # gymnasium.make_vec through the id's vector entry point against SyncVectorEnv over gymnasium.make
    # copies: every observation, reward, flag and info entry (the reward terms, the finish bonus and the
    # planner's override included) bit for bit, through truncations and next-step autoresets.
    import cnc_gym  # noqa: F401  (registers the ids)

    kwargs = {"programs": ["star", "circle"], "max_episode_steps": 30, **kwargs}
    native = gym.make_vec(env_id, 3, vectorization_mode="vector_entry_point", **kwargs)
    sync = gym.vector.SyncVectorEnv([lambda: gym.make(env_id, **kwargs)] * 3)
    assert isinstance(native, FeedrateVectorEnvV1)
    assert native.single_observation_space == sync.single_observation_space
    ends = _same_episodes(native, sync, seed=11, steps=70, rng=np.random.default_rng(), low=-1.2, high=1.2)
    assert ends >= 6
    native.close()
    sync.close()


def test_randomised_envs_get_sync_vector_env_from_the_entry_point():
    import cnc_gym  # noqa: F401
    from cnc_gym.envs.vector import make_vector_env_v1

    envs = gym.make_vec("cnc_gym/Feedrate-v2", 2, vectorization_mode="vector_entry_point",
                        programs=["circle"], randomize={"enabled": True, "machines": 2})  # fmt: skip
    assert isinstance(envs, gym.vector.SyncVectorEnv)
    envs.reset(seed=0)
    obs, *_ = envs.step(np.zeros((2, 1), dtype=np.float32))
    assert obs.shape == (2, 46)
    envs.close()
    with pytest.raises(ConfigError, match="randomize"):
        FeedrateVectorEnvV1(2, programs=["circle"], randomize={"enabled": True})
    with pytest.raises(ConfigError, match="num_envs"):
        make_vector_env_v1(0, programs=["circle"])


def test_every_registered_id_is_listed_and_has_a_vector_entry_point():
    import cnc_gym

    registered = sorted(name for name in gym.registry if name.startswith("cnc_gym/"))
    assert registered == sorted(cnc_gym.ENV_IDS)
    for name in registered:
        assert gym.spec(name).vector_entry_point is not None, name
