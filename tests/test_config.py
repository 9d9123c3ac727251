"""The config schema and the bounded YAML reader: every reproducer of a bad config is one clean line.

Each bad file must give one ConfigError whose text names the file (and the key, where there is one), with
no traceback, no warning, and quickly: the reader's bounds hold before anything large is built.
"""

from __future__ import annotations

import dataclasses
import importlib.util
import math
import tracemalloc
import warnings
from pathlib import Path

import pytest

import cnc_gym.config as config_module
from cnc_gym.config import (
    MAX_CONFIG_BYTES,
    MAX_NESTING,
    MAX_NODES,
    Items,
    Number,
    Section,
    Spec,
    markdown_table,
    parse_yaml,
    read_yaml,  # fmt: skip
    schema,
)
from cnc_gym.envs.task import load_task
from cnc_gym.errors import ConfigError
from cnc_gym.machine import AxisConfig, ControllerConfig, MachineConfig, RotaryAxisConfig, load_machine

REPO = Path(__file__).resolve().parents[1]


def one_line_error(path: Path, load=load_machine, max_nodes: int | None = None) -> str:
    """The ConfigError of loading ``path``: one line, naming the file, no warning, and with bounded work:
    at most ``max_nodes`` YAML values composed (counted, not timed: a timed test fails on a busy machine)
    and at most 64 MB of Python memory at the peak."""
    composed = 0
    compose = config_module._config_loader().compose_node

    def counting(self, parent, index):
        nonlocal composed
        composed += 1
        return compose(self, parent, index)

    tracemalloc.start()
    try:
        with warnings.catch_warnings(), pytest.MonkeyPatch.context() as patch:
            warnings.simplefilter("error")  # numpy overflow warnings and the like fail the test
            patch.setattr(config_module._config_loader(), "compose_node", counting)
            with pytest.raises(ConfigError) as err:
                load(path)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 64 * 2**20, f"{peak / 2**20:.0f} MB at the peak"
    if max_nodes is not None:
        assert composed <= max_nodes, f"{composed} values composed before the refusal"
    message = str(err.value)
    assert "\n" not in message and "Traceback" not in message, message
    assert message.startswith(str(path)), message
    assert len(message) < 500, message
    return message


def write(tmp_path: Path, content: str | bytes, name: str = "m.yaml") -> Path:
    path = tmp_path / name
    if isinstance(content, bytes):
        path.write_bytes(content)
    else:
        path.write_text(content)
    return path


# ------------------------------------------------------------------------------------ the YAML reader
@pytest.mark.parametrize(
    ("content", "fragment"),
    [
        ("a: " + "[" * 5000 + "]" * 5000 + "\n", f"nested deeper than {MAX_NESTING} levels"),
        ("".join("  " * i + f"k{i}:\n" for i in range(60)) + "  " * 60 + "v\n", "nested deeper"),
        ("a: &a [*a]\n", "an alias refers to a node that contains it"),
        ("name: x\nname: y\n", "duplicate key 'name'"),
        ("a: " + "9" * 5000 + "\n", "number literal is too long"),
        ("name: !!python/object/apply:os.system ['echo hacked']\n", "invalid YAML"),
        ("name: a\x00b\n", "invalid YAML"),
        ("description: \x1b[2J\n", "invalid YAML"),
        ("a: [1, 2\n", "invalid YAML"),
    ],
)
def test_malformed_yaml_is_one_line(tmp_path, content, fragment):
    message = one_line_error(write(tmp_path, content))
    assert fragment in message
    assert "\x1b" not in message and "\x00" not in message


def test_an_alias_bomb_is_refused_before_it_expands(tmp_path):
    # Nine levels of nine-fold aliases: 9^9 ≈ 387 million strings once expanded (842 MB before).
    lines = ["a0: &a0 [x, x, x, x, x, x, x, x, x]"]
    lines += [f"a{i}: &a{i} [{', '.join([f'*a{i - 1}'] * 9)}]" for i in range(1, 9)]
    lines += ["name: bomb", "description: *a8"]
    message = one_line_error(write(tmp_path, "\n".join(lines) + "\n"), max_nodes=200)
    assert "values once aliases are expanded" in message


def test_a_file_larger_than_the_cap_is_refused_unread(tmp_path):
    message = one_line_error(write(tmp_path, "# " + "x" * MAX_CONFIG_BYTES + "\n"))
    assert "larger than" in message


def test_a_long_flat_list_is_refused_early(tmp_path):
    message = one_line_error(write(tmp_path, "a: [" + "1," * 100_000 + "]\n"), max_nodes=MAX_NODES + 2)
    assert "more than" in message and "values" in message


def test_non_utf8_is_one_line(tmp_path):
    message = one_line_error(write(tmp_path, b"name: caf\xe9\n"))
    assert "not UTF-8" in message and "0xe9" in message


def test_yaml_12_exponent_floats_are_numbers():
    assert parse_yaml("a: 1e-3\nb: 2E6\nc: -1.5e+2\nd: 1e\ne: '1e5'\n", "t") == {
        "a": 0.001, "b": 2e6, "c": -150.0, "d": "1e", "e": "1e5"}  # fmt: skip


def test_a_directory_or_missing_file_is_one_line(tmp_path):
    for path in (tmp_path, tmp_path / "absent.yaml"):
        with pytest.raises(ConfigError, match="cannot read"):
            read_yaml(path, "machine config")


# -------------------------------------------------------------------------------- machine reproducers
@pytest.mark.parametrize(
    ("content", "fragment"),
    [
        ("controller: {post_filter_s: 1.0e6}\n", "controller.post_filter_s must be in [0, 0.5] s"),
        ("controller: {lookahead_blocks: 2147483648}\n", "controller.lookahead_blocks must be an integer in"),
        ("controller: {lookahead_blocks: 1e29}\n", "controller.lookahead_blocks must be an integer in"),
        ("axis_defaults: {velocity_loop_damping: 1e300}\n", "axis_defaults.velocity_loop_damping must be in"),
        ("axis_defaults: {rapid_mm_min: 1e-300}\n", "axis_defaults.rapid_mm_min must be in [100, 1e6]"),
        ("axes: {z: {rapid_mm_min: 50}}\n", "axes.z.rapid_mm_min must be in"),
        ("controller: {interpolation_period_s: 1e-7}\n", "controller.interpolation_period_s must be in"),
        ("controller: {interpolation_period_s: 1.0}\n", "controller.interpolation_period_s must be in"),
        ("controller: {max_feed_mm_min: 1e300}\n", "controller.max_feed_mm_min must be in"),
        ("axis_defaults: {max_jerk_mm_s3: 1e300}\n", "axis_defaults.max_jerk_mm_s3 must be in"),
        ("axis_defaults: {kv_1_s: .inf}\n", "axis_defaults.kv_1_s must be finite"),
        ("rotary_axes: {b: {rapid_deg_min: 1e-300}}\n", "rotary_axes.b.rapid_deg_min must be in"),
        ("axes: {x: 5}\n", "'axes.x' must be a mapping, got 5"),
        ("axes: {x: [1, 2]}\n", "'axes.x' must be a mapping"),
        ("controller: [1, 2]\n", "'controller' must be a mapping"),
        ("rotary_axes: {b: 7}\n", "'rotary_axes.b' must be a mapping"),
        ("axis_defaults: 3\n", "'axis_defaults' must be a mapping"),
        ("- 1\n", "the config must be a mapping"),
        ("", "got an empty file"),
        ("axes: {y: {kv_1_s: 600, velocity_loop_hz: 60}}\n", "axes.y.kv_1_s makes the servo loop unstable"),
        ("controller: {min_arc_feed_mm_min: 20000}\n", "min_arc_feed_mm_min must not exceed max_feed_mm_min"),
        ("{1: 2}\n", "unknown key 1"),
        ("name: " + "n" * 300 + "\n", "name must be at most 200 characters long"),
    ],
)
def test_machine_reproducers_are_one_line(tmp_path, content, fragment):
    message = one_line_error(write(tmp_path, content))
    assert fragment in message, message


def test_a_machine_built_in_python_keeps_the_same_rules():
    bad_axis = dataclasses.replace(AxisConfig(), rapid_mm_min=1e-300)
    machine = MachineConfig(name="py", axes=(AxisConfig(), bad_axis, AxisConfig()), source="<python>")
    with pytest.raises(ConfigError, match=r"^<python>: axes.y.rapid_mm_min must be in \[100, 1e6\]"):
        load_machine(machine)
    fast = ControllerConfig(interpolation_period_s=1e-7)
    slow = MachineConfig(name="py", controller=fast, source="<python>")
    with pytest.raises(ConfigError, match=r"controller\.interpolation_period_s"):
        load_machine(slow)
    with pytest.raises(ConfigError, match="must be a preset name"):
        load_machine(None)  # type: ignore[arg-type]
    assert load_machine(load_machine("gsk25i")) == load_machine("gsk25i")


# ----------------------------------------------------------------------------------- task reproducers
@pytest.mark.parametrize(
    ("content", "fragment"),
    [
        ("control_period_s: 1.0e6\n", "control_period_s must be in (0, 1] s"),
        ("control_period_s: 1e308\n", "control_period_s must be in (0, 1] s"),
        ("programs: []\n", "programs must name at least one program"),
        ("programs: [circle, 5]\n", "programs entry 2 must be a string"),
        ("reward: {time: .nan}\n", "reward.time must be finite"),
        ("reward: {error_ratio_cap: 0}\n", "reward.error_ratio_cap must be in (0, 1e6]"),
        ("reward: 3\n", "'reward' must be a mapping"),
        ("action_mode: velocity\n", "action_mode must be one of override, feed"),
    ],
)
def test_task_reproducers_are_one_line(tmp_path, content, fragment):
    message = one_line_error(write(tmp_path, content), load=load_task)
    assert fragment in message, message


# ---------------------------------------------------------------------------------------- the schemas
def _all_schemas() -> list[type]:
    from cnc_gym.envs.options import EnvArguments
    from cnc_gym.envs.task import TaskConfig
    from cnc_gym_agents.training import TrainConfig

    found, todo = [], [MachineConfig, AxisConfig, RotaryAxisConfig, TaskConfig, TrainConfig, EnvArguments]
    while todo:
        cls = todo.pop()
        if cls in found:
            continue
        found.append(cls)
        todo += [spec.of for spec in schema(cls).values() if isinstance(spec, Section) and spec.of]
    return found


def test_every_key_is_documented_and_every_number_bounded():
    for cls in _all_schemas():
        for key, spec in schema(cls).items():
            assert spec.doc, f"{cls.__name__}.{key} has no doc"
            numbers = [spec] if isinstance(spec, Number) else [spec.item] if isinstance(spec, Items) else []
            for number in numbers:
                if isinstance(number, Number):
                    assert math.isfinite(number.low) and math.isfinite(number.high), f"{cls.__name__}.{key}"


def test_defaults_keep_their_own_rules():
    # A schema whose default breaks its own range would make every file without the key fail.
    for cls in _all_schemas():
        instance = cls()
        for key, spec in schema(cls).items():
            if not isinstance(spec, Section):
                spec.parse(getattr(instance, key))


def test_the_docs_tables_are_written_from_the_schemas():
    path = REPO / "scripts" / "config_docs.py"
    module_spec = importlib.util.spec_from_file_location("config_docs", path)
    module = importlib.util.module_from_spec(module_spec)
    module_spec.loader.exec_module(module)
    covered = {cls for cls, _ in module.TABLES.values()}
    assert set(_all_schemas()) <= covered, "a config section has no docs table (scripts/config_docs.py)"
    assert module.main(["--check"]) == 0, "docs tables are stale: run .venv/bin/python scripts/config_docs.py"


def test_markdown_table_lists_every_key_with_its_range():
    table = markdown_table(ControllerConfig, "controller.")
    for key in schema(ControllerConfig):
        assert f"`controller.{key}`" in table
    assert "in [0.0001, 0.02] s" in table


def test_a_spec_without_range_reads_anything():
    assert Spec().parse([1, "x"]) == [1, "x"]


def test_read_yaml_parses_a_text_once_and_hands_every_caller_its_own_copy(tmp_path):
    import cnc_gym.config as config

    path = tmp_path / "preset.yaml"
    path.write_text("axes:\n  x: {kv: 40}\nname: a\n")
    config._parse_yaml_cached.cache_clear()
    first = read_yaml(path, "machine config")
    first["axes"]["x"]["kv"] = 1  # a caller changing what it got
    second = read_yaml(path, "machine config")
    assert second == {"axes": {"x": {"kv": 40}}, "name": "a"}
    assert config._parse_yaml_cached.cache_info().hits == 1
    path.write_text("axes:\n  x: {kv: 45}\nname: a\n")  # a changed file is read anew
    assert read_yaml(path, "machine config")["axes"]["x"]["kv"] == 45
    path.write_text("axes: [\n")  # and a broken one fails every time
    for _ in range(2):
        with pytest.raises(ConfigError, match="invalid YAML"):
            read_yaml(path, "machine config")
