"""The single env's info (:class:`~cnc_gym.envs.engine.batch.StepInfo`): a dict made when first used, which
behaves as the plain dict it replaces wherever a user reads, copies, stores or changes it."""

from __future__ import annotations

import copy
import json
import pickle

import gymnasium as gym
import numpy as np
import pytest

import cnc_gym  # noqa: F401  (registers the ids)
from cnc_gym.envs.engine.batch import StepInfo


@pytest.fixture(scope="module")
def env() -> gym.Env:
    env = gym.make("cnc_gym/Feedrate-v4", programs=["circle"])
    env.reset(seed=3)
    for _ in range(2):  # (Gymnasium's checker reads the first steps' infos)
        env.step(np.array([0.0], dtype=np.float32))
    return env


def step(env: gym.Env, knob: float = 0.4) -> tuple[StepInfo, dict]:
    """A step's info, unused, and the plain dict that the step's outputs made before infos were lazy."""
    *_, terminated, truncated, info = env.step(np.array([knob], dtype=np.float32))
    batch = env.unwrapped._batch  # type: ignore[attr-defined]
    out = batch._out_rows[0].tolist()
    want = dict(zip(batch.info_keys, out[3:], strict=False))
    for key in ("violations", "line", "steps"):
        want[key] = int(want[key])
    want["program"] = "circle"
    assert isinstance(info, StepInfo) and info._outputs is not None  # (not made yet)
    if terminated or truncated:
        env.reset()
    return info, want


def test_step_infos_equal_the_dicts_they_replace(env):
    for k in range(40):
        info, want = step(env, 0.9 if k % 2 else -0.2)
        assert isinstance(info, dict)
        assert repr(info) == repr(want)  # keys in order, values with their types
        assert info == want and want == info
        assert not info != want  # noqa: SIM202  (__ne__ too)


@pytest.mark.parametrize("use", [
    lambda i: dict(i), lambda i: {**i}, lambda i: list(i), lambda i: list(i.items()),
    lambda i: list(i.values()), lambda i: len(i), lambda i: i["progress"], lambda i: i.get("progress"),
    lambda i: "steps" in i,
    lambda i: repr(i), lambda i: str(i), lambda i: json.loads(json.dumps(i)), lambda i: i.copy(),
    lambda i: copy.copy(i), lambda i: copy.deepcopy(i), lambda i: pickle.loads(pickle.dumps(i)),
    lambda i: list(reversed(i)), lambda i: i | {}, lambda i: {} | i, lambda i: sorted(i),
])  # fmt: skip
def test_every_way_of_reading_sees_every_entry(env, use):
    info, want = step(env)
    assert use(info) == use(want)


def test_changes_keep_the_other_entries(env):
    info, want = step(env)
    info["episode"] = {"r": 1.0}  # as SB3's Monitor and Gymnasium's RecordEpisodeStatistics do
    want["episode"] = {"r": 1.0}
    assert info == want and list(info) == list(want)
    info, want = step(env)
    assert info.pop("cost") == want.pop("cost") and info == want
    info, want = step(env)
    assert info.setdefault("new", 1) == 1 and "new" in info and len(info) == len(want) + 1
    info, want = step(env)
    info.update(extra=2)
    assert info == {**want, "extra": 2}
    info, _ = step(env)
    info.clear()
    assert info == {} and len(info) == 0


def test_two_unused_infos_compare_by_their_entries(env):
    a, want_a = step(env)
    b, want_b = step(env)
    assert (a == b) == (want_a == want_b)
    assert a | b == want_a | want_b


def test_infos_are_snapshots(env):
    # A stored info keeps its step's values after later steps (it holds a copy of the outputs).
    info, want = step(env)
    for _ in range(5):
        env.step(np.array([0.5], dtype=np.float32))
    assert info == want


def test_made_like_a_dict_it_is_a_dict():
    info = StepInfo(a=1, b=2)
    assert info == {"a": 1, "b": 2} and list(info) == ["a", "b"] and repr(info) == "{'a': 1, 'b': 2}"
    assert StepInfo.fromkeys(["x"], 0) == {"x": 0}


def test_checkers_and_wrappers_take_it():
    from gymnasium.utils.env_checker import check_env

    env = gym.make("cnc_gym/Feedrate-v4", programs=["circle"])
    check_env(env.unwrapped, skip_render_check=True)
    stats = gym.wrappers.RecordEpisodeStatistics(gym.make("cnc_gym/Feedrate-v4", programs=["circle"],
                                                          max_episode_steps=20))  # fmt: skip
    stats.reset(seed=0)
    for _ in range(20):
        *_, terminated, truncated, info = stats.step(np.array([0.0], dtype=np.float32))
        if terminated or truncated:
            break
    assert "episode" in info and info["steps"] == 20
