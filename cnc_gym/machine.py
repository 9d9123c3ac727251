"""Machine presets: the controller's and the servo axes' parameters, loaded from YAML.

A preset is a YAML file under ``configs/machines/`` (or any path). It is read with ``yaml.safe_load`` and
validated into frozen dataclasses; unknown keys, wrong types and out-of-range values are
:class:`~cnc_gym.errors.ConfigError` naming the file and the key. Parameter names say what they mean;
the GSK 25i parameter number is given beside each where its parameter manual has one.

Layout of a preset file::

    name: vmc-small
    description: ...
    controller: {interpolation_period_s: 0.002, lookahead_blocks: 32, ...}   # ControllerConfig fields
    axis_defaults: {rapid_mm_min: 30000, kv_1_s: 40, ...}                     # AxisConfig fields
    axes: {x: {kv_1_s: 40}, y: {kv_1_s: 38}, z: {...}}                        # per-axis overrides
    rotary_axes: {b: {rapid_deg_min: 3600, ...}}                              # optional A/B/C axes

Rotary axes (``RotaryAxisConfig``) are optional: a machine without them rejects A/B/C words by name. The
controller times their moves and keeps their speed, acceleration and jerk within limits; the plant
simulates the three linear axes only (contour error is the tool's XYZ error, see docs/motion.md).

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from cnc_gym.config import check_keys, configs_dir, read_yaml
from cnc_gym.errors import ConfigError
from cnc_gym.frozen import FrozenDict

__all__ = ["AxisConfig", "ControllerConfig", "MachineConfig", "RotaryAxisConfig", "configs_dir",
           "load_machine", "machine_names"]  # fmt: skip

AXIS_NAMES = ("x", "y", "z")
ROTARY_NAMES = ("a", "b", "c")


@dataclass(frozen=True)
class AxisConfig:
    """One linear axis: kinematic limits used by the controller and servo parameters used by the plant."""

    rapid_mm_min: float = 30000.0  # P1226 rapid traverse rate
    max_feed_mm_min: float = 15000.0  # P1225 per-axis cutting-feed clamp
    max_accel_mm_s2: float = 5000.0  # cutting acceleration; GSK: 2·P1225/(2·P1480+P1481)
    max_jerk_mm_s3: float = 50000.0  # cutting jerk; GSK: 2·A/P1481
    rapid_accel_mm_s2: float = 5000.0  # GSK: 2·P1226/(2·P1410+P1411)
    rapid_jerk_mm_s3: float = 50000.0  # GSK: 2·A_rapid/P1411
    corner_step_mm_min: float = 1000.0  # P1227 largest velocity step of this axis at a block junction
    kv_1_s: float = 40.0  # position-loop gain Kv
    feedforward: float = 0.0  # velocity feed-forward fraction, 0..1
    velocity_loop_hz: float = 0.0  # velocity-loop bandwidth; 0 = ideal (pure P position loop)
    velocity_loop_damping: float = 0.7
    min_position_mm: float = -1e6  # travel limits (stored stroke check 1); generous by default
    max_position_mm: float = 1e6
    # Reference positions in machine coordinates: 1 for G28/G27, 2-4 for G30 P2-P4 (GSK P1051-P1053).
    reference_1_mm: float = 0.0
    reference_2_mm: float = 0.0
    reference_3_mm: float = 0.0
    reference_4_mm: float = 0.0


@dataclass(frozen=True)
class RotaryAxisConfig:
    """One rotary axis (A, B or C), in degrees: the limits the controller keeps while timing its moves.

    The GSK 25i treats a rotary axis's degrees like millimetres in the feed (§3.2.2): in a block that
    moves linear and rotary axes together, F is the rate along the composite vector
    √(ΔX² + ΔY² + ΔZ² + ΔB²) with degrees counted as mm; a rotary-only G01 runs at F deg/min.
    """

    rapid_deg_min: float = 3600.0  # P1226 rapid traverse rate of the axis
    max_feed_deg_min: float = 3600.0  # P1225 per-axis cutting-feed clamp
    max_accel_deg_s2: float = 1800.0
    max_jerk_deg_s3: float = 18000.0
    rapid_accel_deg_s2: float = 1800.0
    rapid_jerk_deg_s3: float = 18000.0
    corner_step_deg_min: float = 1000.0  # P1227 largest velocity step at a block junction
    reference_1_deg: float = 0.0  # G28 reference position (machine coordinate)


class RotaryAxes(FrozenDict):
    """Rotary axes by letter: a read-only, hashable mapping (machines are cache keys)."""


@dataclass(frozen=True)
class ControllerConfig:
    """Path-level controller parameters."""

    interpolation_period_s: float = 0.002  # P9121 (2 ms)
    lookahead_blocks: int = 32  # P1409 look-ahead planning window
    max_feed_mm_min: float = 15000.0  # P1224 composite cutting-feed clamp (after override)
    max_override: float = 2.0  # feed-override knob range 0..200 %
    override_slew_per_s: float = 10.0  # how fast the applied override follows the knob (1/s)
    max_centripetal_accel_mm_s2: float = 5000.0  # P1442 arc acceleration limit
    chord_tolerance_mm: float = 0.001  # P1472 arc control accuracy at the interpolation period
    min_arc_feed_mm_min: float = 0.0  # P1505 floor on the arc speed limit
    post_filter_s: float = 0.0  # post-interpolation acc/dec filter (moving average), 0 = none
    in_position_mm: float = 0.01  # in-position width for exact stop and program end
    contour_tolerance_mm: float = 0.05  # contour error above this counts as a violation


@dataclass(frozen=True)
class MachineConfig:
    name: str
    description: str = ""
    controller: ControllerConfig = field(default_factory=ControllerConfig)
    axes: tuple[AxisConfig, AxisConfig, AxisConfig] = (AxisConfig(), AxisConfig(), AxisConfig())
    source: str = "<defaults>"
    #: Rotary axes by upper-case letter, in A, B, C order (empty: a 3-axis machine).
    rotary_axes: RotaryAxes = field(default_factory=RotaryAxes)

    def __post_init__(self) -> None:
        if not isinstance(self.rotary_axes, RotaryAxes):
            object.__setattr__(self, "rotary_axes", RotaryAxes(self.rotary_axes))

    @property
    def rotary_letters(self) -> str:
        """The rotary axes' letters, e.g. ``"B"`` (``""`` on a 3-axis machine)."""
        return "".join(self.rotary_axes)

    def axis_array(self, name: str) -> tuple[float, float, float]:
        """One AxisConfig field for X, Y, Z, e.g. ``machine.axis_array("kv_1_s")``."""
        return tuple(float(getattr(axis, name)) for axis in self.axes)  # type: ignore[return-value]


def machine_names() -> list[str]:
    return sorted(p.stem for p in (configs_dir() / "machines").glob("*.yaml"))


def load_machine(name_or_path: str | Path = "vmc-small") -> MachineConfig:
    """Load a preset by name (``vmc-small``, ``gsk25i``, ``p-loop-30`` …) or from a YAML path."""
    if isinstance(name_or_path, MachineConfig):
        return name_or_path
    path = Path(name_or_path)
    if path.suffix not in (".yaml", ".yml"):
        path = configs_dir() / "machines" / f"{name_or_path}.yaml"
        if not path.exists():
            raise ConfigError(f"unknown machine {name_or_path!r}; presets: {', '.join(machine_names())}")
    data = read_yaml(path, "machine config")
    return machine_from_dict(data, source=str(path))


def machine_from_dict(data: Any, source: str = "<dict>") -> MachineConfig:
    if not isinstance(data, dict):
        raise ConfigError(f"{source}: a machine config must be a mapping")
    keys = {"name", "description", "controller", "axis_defaults", "axes", "rotary_axes"}
    check_keys(data, keys, source, "")
    controller = _build(ControllerConfig, data.get("controller", {}), source, "controller")
    defaults = data.get("axis_defaults", {}) or {}
    axes_data = data.get("axes", {}) or {}
    if not isinstance(axes_data, dict):
        raise ConfigError(f"{source}: 'axes' must be a mapping of x/y/z")
    check_keys(axes_data, set(AXIS_NAMES), source, "axes")
    _build(AxisConfig, defaults, source, "axis_defaults")  # validate defaults on their own
    axes = tuple(
        _build(AxisConfig, {**defaults, **(axes_data.get(n) or {})}, source, f"axes.{n}") for n in AXIS_NAMES
    )
    rotary_data = data.get("rotary_axes", {}) or {}
    if not isinstance(rotary_data, dict):
        raise ConfigError(f"{source}: 'rotary_axes' must be a mapping of a/b/c")
    check_keys(rotary_data, set(ROTARY_NAMES), source, "rotary_axes")
    rotary = {n.upper(): _build(RotaryAxisConfig, rotary_data[n] or {}, source, f"rotary_axes.{n}")
              for n in ROTARY_NAMES if n in rotary_data}  # fmt: skip
    name = data.get("name", Path(source).stem)
    if not isinstance(name, str):
        raise ConfigError(f"{source}: 'name' must be a string")
    return MachineConfig(name=name, description=str(data.get("description", "")), controller=controller,
                         axes=axes, source=source, rotary_axes=rotary)  # type: ignore[arg-type]  # fmt: skip


def _build(cls, data: Any, source: str, where: str):
    if not isinstance(data, dict):
        raise ConfigError(f"{source}: '{where}' must be a mapping")
    fields = {f.name: f for f in dataclasses.fields(cls)}
    check_keys(data, set(fields), source, where)
    values = {}
    for key, raw in data.items():
        want = type(getattr(cls(), key))
        if isinstance(raw, bool) or not isinstance(raw, int | float):
            raise ConfigError(f"{source}: {where}.{key} must be a number, got {raw!r}")
        if want is int and not float(raw).is_integer():
            raise ConfigError(f"{source}: {where}.{key} must be an integer, got {raw!r}")
        value = want(raw)
        if not math.isfinite(value):
            raise ConfigError(f"{source}: {where}.{key} must be finite")
        if value < 0 and not key.startswith(("min_position", "max_position", "reference_")):
            raise ConfigError(f"{source}: {where}.{key} must not be negative, got {raw!r}")
        values[key] = value
    obj = cls(**values)
    _check_ranges(obj, source, where)
    return obj


def _check_ranges(obj, source: str, where: str) -> None:
    positive = {
        "interpolation_period_s", "lookahead_blocks", "max_feed_mm_min", "max_override",
        "override_slew_per_s", "max_centripetal_accel_mm_s2", "chord_tolerance_mm", "in_position_mm",
        "contour_tolerance_mm", "rapid_mm_min", "max_accel_mm_s2", "max_jerk_mm_s3", "rapid_accel_mm_s2",
        "rapid_jerk_mm_s3", "kv_1_s", "rapid_deg_min", "max_feed_deg_min", "max_accel_deg_s2",
        "max_jerk_deg_s3", "rapid_accel_deg_s2", "rapid_jerk_deg_s3",
    }  # fmt: skip
    for f in dataclasses.fields(obj):
        if f.name in positive and getattr(obj, f.name) <= 0:
            raise ConfigError(f"{source}: {where}.{f.name} must be positive")
    if isinstance(obj, AxisConfig):
        if obj.feedforward > 1:
            raise ConfigError(f"{source}: {where}.feedforward must be within 0..1")
        if obj.min_position_mm >= obj.max_position_mm:
            raise ConfigError(f"{source}: {where}: min_position_mm must be below max_position_mm")
