"""Machine presets: every preset loads with its documented values; bad files give one clear ConfigError."""

from __future__ import annotations

import textwrap
from pathlib import Path

import pytest

from cnc_gym.errors import CncGymError, ConfigError
from cnc_gym.machine import MachineConfig, load_machine, machine_from_dict, machine_names


def write(tmp_path: Path, text: str, name: str = "m.yaml") -> Path:
    path = tmp_path / name
    path.write_text(textwrap.dedent(text))
    return path


def test_required_presets_exist_and_load():
    names = machine_names()
    for required in ("vmc-small", "gsk25i", "p-loop-30"):
        assert required in names
    for name in names:
        machine = load_machine(name)
        assert isinstance(machine, MachineConfig)
        assert machine.name == name  # the file's name: matches its preset name
        assert machine.source.endswith(f"{name}.yaml")


def test_default_preset_is_vmc_small():
    assert load_machine().name == "vmc-small"


def test_p_loop_30_is_the_textbook_case():
    machine = load_machine("p-loop-30")
    assert machine.axis_array("kv_1_s") == (30.0, 30.0, 30.0)
    assert machine.axis_array("feedforward") == (0.0, 0.0, 0.0)
    assert machine.axis_array("velocity_loop_hz") == (0.0, 0.0, 0.0)
    assert machine.controller.post_filter_s == 0.0
    # "limits as vmc-small"
    vmc = load_machine("vmc-small")
    for field in ("rapid_mm_min", "max_feed_mm_min", "max_accel_mm_s2", "max_jerk_mm_s3"):
        assert machine.axis_array(field) == vmc.axis_array(field)


def test_gsk25i_values_follow_the_manual_formulas():
    machine = load_machine("gsk25i")
    ctrl = machine.controller
    assert ctrl.interpolation_period_s == 0.002  # P9121
    assert ctrl.lookahead_blocks == 10  # P1409
    assert ctrl.max_feed_mm_min == 4000  # P1224
    assert ctrl.max_centripetal_accel_mm_s2 == 500  # P1442 = 0.5 m/s²
    assert ctrl.chord_tolerance_mm == 0.001  # P1472
    assert ctrl.min_arc_feed_mm_min == 200  # P1505
    axis = machine.axes[0]
    assert axis.max_feed_mm_min == 4000  # P1225
    assert axis.corner_step_mm_min == 1000  # P1227
    # A = 2·V/(2·T1 + T2), J = 2·A/T2 with V = 4000 mm/min = 66.667 mm/s, T1 = T2 = 16 ms.
    accel = 2 * (4000 / 60) / (2 * 0.016 + 0.016)
    assert axis.max_accel_mm_s2 == pytest.approx(accel, rel=1e-5)
    assert axis.max_jerk_mm_s3 == pytest.approx(2 * accel / 0.016, rel=1e-5)
    # Rapid: T1 = T2 = 100 ms on the chosen P1226.
    rapid_accel = 2 * (axis.rapid_mm_min / 60) / 0.3
    assert axis.rapid_accel_mm_s2 == pytest.approx(rapid_accel, rel=1e-5)
    assert axis.rapid_jerk_mm_s3 == pytest.approx(2 * rapid_accel / 0.1, rel=1e-5)
    assert machine.axis_array("kv_1_s") == (245.0, 245.0, 245.0)  # P4209
    assert machine.axis_array("feedforward") == (0.0, 0.0, 0.0)  # P4210 = 0 %


def test_per_axis_overrides_and_loading_by_path(tmp_path):
    path = write(tmp_path, """
        name: custom
        axis_defaults: {kv_1_s: 25}
        axes:
          y: {kv_1_s: 27.5}
        """)  # fmt: skip
    machine = load_machine(path)
    assert machine.axis_array("kv_1_s") == (25.0, 27.5, 25.0)
    assert machine.source == str(path)


@pytest.mark.parametrize(
    ("text", "expected_key"),
    [
        ("name: x\nspeed: 3\n", "speed"),
        ("controller: {interpolation_period: 0.002}\n", "controller.interpolation_period"),
        ("axis_defaults: {kv: 30}\n", "axis_defaults.kv"),
        ("axes: {x: {kv_1_s: 30, stiffness: 1}}\n", "axes.x.stiffness"),
        ("axes: {a: {kv_1_s: 30}}\n", "axes.a"),
    ],
)
def test_unknown_keys_are_named(tmp_path, text, expected_key):
    path = write(tmp_path, text)
    with pytest.raises(ConfigError) as info:
        load_machine(path)
    message = str(info.value)
    assert str(path) in message
    assert f"unknown key {expected_key}" in message


@pytest.mark.parametrize(
    ("text", "fragment"),
    [
        ("controller: {lookahead_blocks: many}\n", "controller.lookahead_blocks must be an integer"),
        ("controller: {lookahead_blocks: 2.5}\n", "controller.lookahead_blocks must be an integer"),
        ("axis_defaults: {kv_1_s: true}\n", "axis_defaults.kv_1_s must be a number"),
        ("axis_defaults: {kv_1_s: [30]}\n", "axis_defaults.kv_1_s must be a number"),
        ("axes: {z: {max_accel_mm_s2: '3000'}}\n", "axes.z.max_accel_mm_s2 must be a number"),
        ("axis_defaults: {kv_1_s: .nan}\n", "axis_defaults.kv_1_s must be finite"),
        ("axis_defaults: {kv_1_s: -30}\n", "axis_defaults.kv_1_s must be in [1, 2000] 1/s, got -30"),
        ("controller: {post_filter_s: -0.01}\n", "controller.post_filter_s must be in [0, 0.5] s"),
        ("axes: {y: {kv_1_s: 0}}\n", "axes.y.kv_1_s must be in [1, 2000] 1/s, got 0"),
        ("controller: {interpolation_period_s: 0}\n", "controller.interpolation_period_s must be in [0.0001"),
        ("axis_defaults: {feedforward: 1.5}\n", "axis_defaults.feedforward must be in [0, 1], got 1.5"),
        ("axis_defaults: {min_position_mm: 10, max_position_mm: 5}\n", "min_position_mm must be below"),
        ("controller: 3\n", "'controller' must be a mapping"),
        ("axes: [x, y]\n", "'axes' must be a mapping"),
        ("name: 7\n", "name must be a string, got 7"),
        ("- a list\n", "must be a mapping"),
        ("", "must be a mapping"),
    ],
)
def test_bad_values_are_config_errors_naming_file_and_key(tmp_path, text, fragment):
    path = write(tmp_path, text)
    with pytest.raises(ConfigError) as info:
        load_machine(path)
    message = str(info.value)
    assert message.startswith(f"{path}: "), message
    assert fragment in message, message


def test_negative_travel_limits_are_allowed(tmp_path):
    path = write(tmp_path, "axis_defaults: {min_position_mm: -500, max_position_mm: -10}\n")
    assert load_machine(path).axes[2].min_position_mm == -500


def test_bad_yaml_is_a_config_error(tmp_path):
    path = write(tmp_path, "controller: {interpolation_period_s: 0.002\naxes: [\n")
    with pytest.raises(ConfigError) as info:
        load_machine(path)
    assert str(path) in str(info.value)
    assert "invalid YAML" in str(info.value)


def test_yaml_tags_cannot_build_python_objects(tmp_path):
    # safe_load refuses python/* tags: the file is reported, nothing is executed.
    path = write(tmp_path, "name: !!python/object/apply:os.system ['echo hacked']\n")
    with pytest.raises(ConfigError, match="invalid YAML"):
        load_machine(path)


def test_missing_file_and_unknown_preset(tmp_path):
    missing = tmp_path / "absent.yaml"
    with pytest.raises(ConfigError) as info:
        load_machine(missing)
    assert str(missing) in str(info.value)
    assert "cannot read" in str(info.value)
    with pytest.raises(ConfigError) as info:
        load_machine("no-such-machine")
    assert "no-such-machine" in str(info.value)
    assert "vmc-small" in str(info.value)  # lists the presets there are


def test_config_error_is_a_project_error():
    with pytest.raises(CncGymError):
        machine_from_dict({"bogus": 1}, source="inline")


def test_machines_with_rotary_axes_stay_hashable_and_read_only():
    # Machines key caches (programs, the classical planner) and travel to vector-env workers by pickle.
    import pickle

    from cnc_gym.machine import RotaryAxisConfig

    machine = load_machine("gsk25i")
    assert machine.rotary_letters == "B"
    assert hash(machine) == hash(load_machine("gsk25i"))
    assert pickle.loads(pickle.dumps(machine)) == machine
    with pytest.raises(TypeError):
        machine.rotary_axes["C"] = RotaryAxisConfig()
    # a plain dict given to the constructor is frozen too
    built = MachineConfig(name="m", rotary_axes={"A": RotaryAxisConfig()})
    assert hash(built) and built.rotary_letters == "A"
