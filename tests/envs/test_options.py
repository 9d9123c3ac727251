"""The env's arguments, reset options and actions: one schema, checked once, one clean line per mistake."""

from __future__ import annotations

import dataclasses
import tracemalloc

import gymnasium
import numpy as np
import pytest

from cnc_gym.envs.feedrate import FeedrateEnv
from cnc_gym.envs.options import EnvArguments, EnvNotReset, env_arguments, parse_action
from cnc_gym.errors import CncGymError, ConfigError
from cnc_gym.machine import ControllerConfig, MachineConfig, load_machine
from cnc_gym.motion import ActionError


@pytest.fixture(scope="module")
def env():
    return FeedrateEnv(programs=["circle"])


def make(**kwargs):
    return FeedrateEnv(**{"programs": ["circle"], **kwargs})


@pytest.mark.parametrize(
    ("kwargs", "fragment"),
    [
        ({"control_period_s": 1e6}, "control_period_s must be in (0, 1] s, got 1000000.0"),
        ({"control_period_s": 1e308}, "control_period_s must be in (0, 1] s"),
        ({"control_period_s": float("nan")}, "control_period_s must be finite"),
        ({"control_period_s": "0.01"}, "control_period_s must be a number"),
        ({"control_period_s": True}, "control_period_s must be a number"),
        ({"programs": 5}, "programs must be a program name, path or G-code text, or a list of them, got 5"),
        ({"programs": ["circle", 5]}, "programs entries must be program names"),
        ({"programs": b"circle"}, "programs must be a program name"),
        ({"machine": None}, "machine must be a preset name, a YAML path or a MachineConfig, got None"),
        ({"machine": 3.5}, "machine must be a preset name"),
        ({"dialect": 7}, "dialect must be a string"),
        ({"reward": 5}, "reward must be None, a task YAML path or a dict of weights"),
        ({"reward": {"time": float("inf")}}, "reward.time must be finite"),
        ({"max_episode_steps": 10**12}, "max_episode_steps must be an integer in [1, 1000000000]"),
        ({"lookahead_points": 10**6}, "lookahead_points must be an integer in [1, 256]"),
        ({"lookahead_points": np.float64(8.5)}, "lookahead_points must be an integer"),
        ({"lookahead_mm": 1e300}, "lookahead_mm must be in (0, 10000] mm"),
        ({"render_mode": "human"}, "render_mode must be one of null, rgb_array"),
        ({"units": "cm"}, "units must be one of null, mm, inch, got 'cm'"),
    ],
)
def test_bad_arguments_are_one_config_error_line(kwargs, fragment):
    tracemalloc.start()  # refused before anything large is built: memory, not wall time (a busy machine)
    try:
        with pytest.raises(ConfigError) as err:
            make(**kwargs)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    message = str(err.value)
    assert peak < 64 * 2**20, f"{peak / 2**20:.0f} MB at the peak"
    assert message.startswith("FeedrateEnv: ") and "\n" not in message, message
    assert fragment in message, message


def test_numpy_scalars_are_numbers_and_checked_once():
    # Issue 8: lookahead_points=np.int64(8) was rejected by a second check with another rule.
    env = make(lookahead_points=np.int64(8), lookahead_mm=np.float32(24.0), control_period_s=np.float64(0.01),
               max_episode_steps=np.int32(500))  # fmt: skip
    assert env.lookahead_points == 8 and isinstance(env.lookahead_points, int)
    assert env.observation_space.shape == (41,)
    assert env.ticks_per_step == 5


def test_every_argument_of_the_env_is_in_the_schema():
    import inspect

    params = set(inspect.signature(FeedrateEnv.__init__).parameters) - {"self"}
    assert params == {f.name for f in dataclasses.fields(EnvArguments)}
    with pytest.raises(ConfigError, match="unknown argument speed"):
        env_arguments(speed=1)


@pytest.mark.parametrize("version", ["v0", "v1"])
def test_the_env_signature_defaults_are_the_schema_defaults(version):
    import inspect

    from cnc_gym.envs.feedrate_v1 import EnvArgumentsV1, FeedrateEnvV1

    env, schema = {"v0": (FeedrateEnv, EnvArguments), "v1": (FeedrateEnvV1, EnvArgumentsV1)}[version]
    defaults = {name: p.default for name, p in inspect.signature(env.__init__).parameters.items()
                if name != "self"}  # fmt: skip
    declared = {f.name: f.default for f in dataclasses.fields(schema) if f.default is not dataclasses.MISSING}
    assert {name: defaults[name] for name in declared} == declared


def test_a_bad_machine_config_object_is_refused_by_key():
    machine = MachineConfig(name="py", controller=ControllerConfig(post_filter_s=1e6), source="<python>")
    with pytest.raises(ConfigError, match=r"^<python>: controller\.post_filter_s must be in \[0, 0\.5\] s"):
        make(machine=machine)


def test_step_before_reset_is_an_error_on_the_unwrapped_env():
    env = make()
    with pytest.raises(EnvNotReset) as err:
        env.step(np.zeros(1, dtype=np.float32))
    assert isinstance(err.value, CncGymError) and isinstance(err.value, gymnasium.error.ResetNeeded)
    assert "reset()" in str(err.value)
    env.reset(seed=0)
    env.step(np.zeros(1, dtype=np.float32))


@pytest.mark.parametrize(
    "action",
    ["0.5", b"0.5", np.array(["0.5"]), 0.5 + 0j, np.array([0.5 + 0j]), np.datetime64("2024-01-01"),
     np.array([1], dtype="datetime64[s]"), np.timedelta64(1, "s"), True, np.bool_(False), np.array([True]),
     object(), [object()], {"a": 1}, None, [[0.5, 0.5]], float("nan"), -float("inf"), np.array([np.nan])],
)  # fmt: skip
def test_only_real_numbers_are_actions(env, action):
    env.reset(seed=0)
    with pytest.raises(ActionError) as err:
        env.step(action)
    assert "action" in str(err.value) and "\n" not in str(err.value)


@pytest.mark.parametrize(
    ("action", "knob"),
    [(10**400, 1.0), (-(10**400), -1.0), (np.int64(3), 1.0), (np.array([2], dtype=np.uint8), 1.0),
     (0.25, 0.25), ([0.25], 0.25), (np.float16(-0.5), -0.5), (np.array([[0.5]]).reshape(1), 0.5)],
)  # fmt: skip
def test_real_numbers_of_any_size_are_clipped(env, action, knob):
    assert parse_action(action) == knob
    env.reset(seed=0)
    env.step(action)  # env.step(10**400) was an OverflowError


@pytest.mark.parametrize(
    ("options", "fragment"),
    [([("program", 1)], "options must be a dict"), ({"toolpath": "circle"}, "unknown option 'toolpath'"),
     ({"program": 1.5}, "options['program'] must be a name, path, text or index"),
     ({"program": True}, "options['program'] must be")],
)  # fmt: skip
def test_bad_reset_options_are_one_line(env, options, fragment):
    with pytest.raises(ConfigError) as err:
        env.reset(options=options)
    assert fragment in str(err.value) and "\n" not in str(err.value)


def test_reset_takes_a_numpy_index(env):
    assert env.reset(options={"program": np.int64(0)})[1]["program"] == "circle"


def test_a_task_file_and_the_env_share_the_control_period_rule(tmp_path):
    from cnc_gym.envs.task import load_task

    path = tmp_path / "task.yaml"
    path.write_text("control_period_s: 1e6\n")
    with pytest.raises(ConfigError) as from_file:
        load_task(path)
    with pytest.raises(ConfigError) as from_argument:
        make(control_period_s=1e6)
    rule = "control_period_s must be in (0, 1] s, got 1000000.0"
    assert rule in str(from_file.value) and rule in str(from_argument.value)


def test_the_control_period_must_be_a_multiple_of_the_machines_period():
    with pytest.raises(ConfigError, match="whole multiple of the interpolation period"):
        make(control_period_s=0.003)
    assert make(machine=load_machine("gsk25i"), control_period_s=0.02).ticks_per_step == 10


def test_units_sets_the_power_on_unit_of_the_programs():
    # A program without G20/G21: X1. is 1 inch with units="inch" (also for a program picked at reset),
    # 1 mm by default; the preset's power_on_units is the default of the argument; G21 in the text rules.
    from cnc_gym.envs.vector import FeedrateVectorEnv
    from cnc_gym.machine import machine_from_dict

    text = "G00 X0 Y0\nG01 X1. F20.\n"

    def end_x(env):
        return float(env.toolpath.end[-1][0])

    inch = make(programs=[text], units="inch")
    inch.reset(seed=0)
    assert end_x(inch) == pytest.approx(25.4)
    inch.reset(options={"program": "G01 X2. F20.\n"})  # loaded at reset, in the same unit
    assert end_x(inch) == pytest.approx(50.8)
    default = make(programs=[text])
    default.reset(seed=0)
    assert end_x(default) == pytest.approx(1.0)
    preset = machine_from_dict({"power_on_units": "inch"}, source="inch.yaml")
    by_preset = make(programs=[text], machine=preset)
    by_preset.reset(seed=0)
    assert end_x(by_preset) == pytest.approx(25.4)
    metric = make(programs=["G21\n" + text], units="inch")
    metric.reset(seed=0)
    assert end_x(metric) == pytest.approx(1.0)
    vector = FeedrateVectorEnv(2, programs=[text], units="inch")
    vector.reset(seed=0)
    assert all(end_x(vector.batch.program(e)) == pytest.approx(25.4) for e in range(vector.num_envs))
