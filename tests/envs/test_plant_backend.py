"""The env's plant backend: chosen by the preset, overridden by ``plant=`` and ``--plant``; the MuJoCo
plant gives results of the same structure, and its picture falls back to matplotlib without GL."""

from __future__ import annotations

import json
import warnings

import gymnasium as gym
import numpy as np
import pytest

import cnc_gym  # noqa: F401  (registers the env ids)
from cnc_gym.cli import main
from cnc_gym.errors import ConfigError
from cnc_gym.plant import ServoPlant
from cnc_gym.plant.mujoco import MujocoPlant


def run_to_end(env, knob: float = 0.0, limit: int = 5000):
    obs, info = env.reset(seed=0)
    for _ in range(limit):
        obs, reward, terminated, truncated, info = env.step(np.array([knob], dtype=np.float32))
        if terminated or truncated:
            return obs, reward, terminated, truncated, info
    raise AssertionError("episode did not end")


@pytest.mark.parametrize(
    ("machine", "plant", "expected"),
    [("vmc-small", None, ServoPlant), ("vmc-small-mujoco", None, MujocoPlant),
     ("vmc-small-mujoco", "lti", ServoPlant), ("vmc-small", "mujoco", MujocoPlant)],
)  # fmt: skip
def test_the_preset_picks_the_plant_and_plant_overrides_it(machine, plant, expected):
    env = gym.make("cnc_gym/Feedrate-v0", programs=["circle"], machine=machine, plant=plant)
    assert isinstance(env.unwrapped.plant, expected)
    assert env.unwrapped.machine.plant.backend == ("lti" if expected is ServoPlant else "mujoco")
    env.close()


def test_a_bad_plant_is_one_config_error():
    with pytest.raises(ConfigError, match="plant must be one of null, lti, mujoco, got 'bullet'"):
        gym.make("cnc_gym/Feedrate-v0", programs=["circle"], plant="bullet")


def test_mujoco_episode_has_the_lti_episode_structure_and_mechanics_cost_accuracy():
    results = {}
    for plant in ("lti", "mujoco"):
        env = gym.make("cnc_gym/Feedrate-v0", programs=["circle"], machine="vmc-small-mujoco", plant=plant)
        obs, reward, terminated, _, info = run_to_end(env)
        assert terminated and env.observation_space.contains(obs) and np.isfinite(reward)
        results[plant] = info
        env.close()
    lti, mj = results["lti"], results["mujoco"]
    assert set(lti) == set(mj)
    assert {type(v) for v in lti.values()} == {type(v) for v in mj.values()}
    # The same program and knob: the same path at the same speed, so cycle times within settling time;
    # friction and backlash make the MuJoCo machine's contour error larger, not smaller.
    assert abs(mj["cycle_time_s"] - lti["cycle_time_s"]) < 0.5
    assert mj["contour_error_max_mm"] > lti["contour_error_max_mm"]


def test_rgb_array_without_gl_warns_once_and_draws_with_matplotlib(monkeypatch):
    monkeypatch.setenv("MUJOCO_GL", "disable")
    env = gym.make("cnc_gym/Feedrate-v0", programs=["circle"], machine="vmc-small-mujoco",
                   render_mode="rgb_array")  # fmt: skip
    env.reset(seed=0)
    for _ in range(20):
        env.step(np.array([0.0], dtype=np.float32))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        first = env.render()
        second = env.render()
    assert sum("no off-screen OpenGL" in str(w.message) for w in caught) == 1
    assert first.ndim == 3 and first.shape[2] == 3 and first.shape == second.shape
    env.close()


def test_rgb_array_draws_the_machine_where_gl_is_available():
    from cnc_gym.plant.mujoco_render import open_gl_context

    context, reason = open_gl_context(32, 32)
    if context is None:
        pytest.skip(f"no off-screen OpenGL here: {reason}")
    context.free()
    env = gym.make("cnc_gym/Feedrate-v0", programs=["circle"], machine="vmc-small-mujoco",
                   render_mode="rgb_array")  # fmt: skip
    env.reset(seed=0)
    for _ in range(50):
        env.step(np.array([0.0], dtype=np.float32))
    image = env.render()
    env.close()
    assert image.shape == (480, 640, 3) and image.std() > 10


def test_cli_run_takes_plant(capsys):
    argv = ["run", "circle", "--machine", "vmc-small", "--plant", "mujoco", "--json", "--no-progress"]
    assert main(argv) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["finished"] and summary["contour_error_max_mm"] > 0
    assert main(["run", "circle", "--plant", "bullet", "--no-progress"]) == 2
    out, err = capsys.readouterr()
    assert out == "" and len(err.strip().splitlines()) == 1 and "plant" in err


def test_bench_records_name_the_plant(tmp_path, capsys):
    program = tmp_path / "line.nc"
    program.write_text("G90 G00 X0 Y0 Z1\nG01 Z0 F600\nG01 X20 F3000\nM30\n")
    out = tmp_path / "records.jsonl"
    argv = ["bench", "--programs", str(program), "--policy", "constant:1.0", "--plant", "mujoco",
            "--json", str(out), "--no-progress"]  # fmt: skip
    assert main(argv) == 0
    records = [json.loads(line) for line in out.read_text().splitlines()]
    assert records and {r["plant"] for r in records} == {"mujoco"}


def test_vector_env_on_the_mujoco_plant_steps_each_env_as_a_single_env():
    from cnc_gym.envs.vector import FeedrateVectorEnv

    knobs = np.linspace(-0.5, 0.8, 60)
    vector = FeedrateVectorEnv(2, programs=["circle"], machine="vmc-small-mujoco")
    assert isinstance(vector.batch.plant, MujocoPlant) and vector.batch.plant.n_envs == 2
    vector.reset(seed=0)
    rewards = []
    for knob in knobs:
        _, reward, _, _, _ = vector.step(np.array([[knob], [0.3]], dtype=np.float32))
        rewards.append(reward)
    vector.close()
    single = gym.make("cnc_gym/Feedrate-v0", programs=["circle"], machine="vmc-small-mujoco")
    single.reset(seed=0)
    alone = [single.step(np.array([knob], dtype=np.float32))[1] for knob in knobs]
    single.close()
    np.testing.assert_allclose(np.array(rewards)[:, 0], alone, rtol=1e-9, atol=1e-12)


def test_mujoco_that_cannot_load_is_one_config_error(monkeypatch):
    import sys

    from cnc_gym.machine import load_machine
    from cnc_gym.plant import make_plant

    monkeypatch.setitem(sys.modules, "cnc_gym.plant.mujoco", None)  # as if MuJoCo were not installed
    with pytest.raises(ConfigError, match="the MuJoCo plant cannot be loaded"):
        make_plant(load_machine("vmc-small-mujoco"))
