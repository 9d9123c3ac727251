"""The SB3 VecEnv on the batched engine against SB3's own make_vec_env over Feedrate-v0 copies."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("stable_baselines3")

from stable_baselines3 import PPO
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.vec_env import DummyVecEnv

import cnc_gym  # noqa: F401  (registers the env)
from cnc_gym.envs.sb3 import FeedrateSB3VecEnv, StepInfo, make_sb3_vec_env
from cnc_gym.errors import ConfigError


@pytest.mark.parametrize(("env_id", "extra"), [
    ("cnc_gym/Feedrate-v0", {}),
    ("cnc_gym/Feedrate-v2", {}),
    ("cnc_gym/Feedrate-v3", {"action_mode": "residual"}),
])  # fmt: skip
def test_same_transitions_as_make_vec_env(env_id, extra):
    # Four envs on two programs with a 40-step budget: SB3's same-step resets happen mid-run. Observations,
    # rewards, dones, the info values, terminal observations and the truncation flags must all be equal
    # to DummyVecEnv over Monitor-wrapped gym.make copies seeded the same way.
    kwargs = {"programs": ["star", "circle"], "max_episode_steps": 40, **extra}
    reference = make_vec_env(env_id, n_envs=4, seed=3, env_kwargs=kwargs, vec_env_cls=DummyVecEnv)
    batched = make_sb3_vec_env(4, seed=3, env_kwargs=kwargs, env_id=env_id)
    np.testing.assert_array_equal(reference.reset(), batched.reset())
    actions = np.random.default_rng(0).uniform(-1, 1, (100, 4, 1)).astype(np.float32)
    steps_r = [reference.step(a) for a in actions]
    steps_b = [batched.step(a) for a in actions]
    ends = 0
    for t, (out_r, out_b) in enumerate(zip(steps_r, steps_b, strict=True)):
        for a, b in zip(out_r[:3], out_b[:3], strict=True):  # observations, rewards, dones
            np.testing.assert_array_equal(a, b, err_msg=f"step {t}")
        for info_r, info_b in zip(out_r[3], out_b[3], strict=True):
            keys = {k for k in info_r if k not in ("episode", "terminal_observation", "TimeLimit.truncated")}
            assert keys == set(info_b) - {"episode", "terminal_observation", "TimeLimit.truncated"}
            for key in keys:
                assert info_r[key] == info_b[key], (t, key)
            assert ("terminal_observation" in info_r) == ("terminal_observation" in info_b)
            if "terminal_observation" in info_r:
                ends += 1
                np.testing.assert_array_equal(info_r["terminal_observation"], info_b["terminal_observation"])
                assert info_r["TimeLimit.truncated"] == info_b["TimeLimit.truncated"]
                assert info_r["episode"]["l"] == info_b["episode"]["l"]
                assert info_r["episode"]["r"] == pytest.approx(float(info_b["episode"]["r"]), abs=1e-5)
    assert ends >= 8
    reference.close()
    batched.close()


def test_step_infos_read_lazily_and_copy_to_dicts():
    venv = FeedrateSB3VecEnv(2, programs=["circle"])
    venv.reset()
    *_, infos = venv.step(np.zeros((2, 1), dtype=np.float32))
    info = infos[0]
    assert isinstance(info, StepInfo) and info.get("episode") is None
    as_dict = info.copy()
    assert isinstance(as_dict, dict) and as_dict["program"] == "circle" and as_dict["steps"] == 1
    assert venv.get_attr("tolerance_mm") == [0.02, 0.02]
    assert venv.env_is_wrapped(object) == [False, False]


def test_ppo_learns_a_few_steps_on_the_batched_env():
    vec_env = make_sb3_vec_env(4, seed=0, env_kwargs={"programs": ["circle"]})
    model = PPO("MlpPolicy", vec_env, n_steps=32, batch_size=64, n_epochs=1, seed=0, device="cpu")
    model.learn(total_timesteps=256)
    vec_env.close()


def test_randomised_envs_fall_back_to_dummy_vec_env():
    venv = make_sb3_vec_env(2, seed=0, env_id="cnc_gym/Feedrate-v3",
                            env_kwargs={"programs": ["circle"], "randomize": {"enabled": True}})
    assert isinstance(venv, DummyVecEnv)
    assert venv.reset().shape == (2, 46)
    venv.close()
    with pytest.raises(ConfigError, match="randomize"):
        FeedrateSB3VecEnv(2, env_id="cnc_gym/Feedrate-v3", programs=["circle"], randomize={"enabled": True})
    with pytest.raises(ConfigError, match="unknown env id"):
        make_sb3_vec_env(2, env_id="cnc_gym/Feedrate-v99")
