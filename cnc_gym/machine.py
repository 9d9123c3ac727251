"""Machine presets: the controller's and the servo axes' parameters, loaded from YAML.

A preset is a YAML file under ``configs/machines/`` (or any path). It is read with the bounded safe
loader of :mod:`cnc_gym.config` and validated into frozen dataclasses (machines are cache keys: hashable,
read-only). Every key is declared once below with its type, range, unit and meaning (the docs' key
tables in docs/configs.md are written from these declarations); unknown keys, wrong types and
out-of-range values are one :class:`~cnc_gym.errors.ConfigError` line naming the file and the key.
Parameter names say what they mean; the GSK 25i parameter number is given beside each where the manual
has one (GSK 25i parameter manual).

Layout of a preset file::

    name: vmc-small
    description: ...
    power_on_units: inch                                                      # optional: mm or inch
    controller: {interpolation_period_s: 0.002, lookahead_blocks: 32, ...}   # ControllerConfig fields
    axis_defaults: {rapid_mm_min: 30000, kv_1_s: 40, ...}                     # AxisConfig fields
    axes: {x: {kv_1_s: 40}, y: {kv_1_s: 38}, z: {...}}                        # per-axis overrides
    rotary_axes: {b: {rapid_deg_min: 3600, ...}}                              # optional A/B/C axes
    plant: {backend: mujoco, timestep_s: 0.0005, axes: {x: {load_mass_kg: 150, ...}, ...}}  # optional
    setup: {work_offsets: {G54: [100, 50, -200]}, tools: {1: {length_mm: 120, radius_mm: 5}}}  # optional

Rotary axes (``RotaryAxisConfig``) are optional: a machine without them rejects A/B/C words by name. The
controller times their moves and keeps their speed, acceleration and jerk within limits; the plant
simulates the three linear axes only (contour error is the tool's XYZ error, see docs/motion.md).

The ``plant`` section (``PlantConfig``) picks the servo backend: ``lti`` (the default: the exact linear
model of :mod:`cnc_gym.plant.servo`) or ``mujoco`` (:mod:`cnc_gym.plant.mujoco`: the same loops driving
masses with friction, compliance and backlash, in SI units). The LTI backend reads only ``backend``.

The ranges are physical: wide enough for any real machine, narrow enough that the simulation stays
finite, fast and small (a tiny rate would make an episode last hours of simulated time, a huge filter
or look-ahead window would need gigabytes). Each range's reason is in its declaration.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import re
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from cnc_gym.config import (
    Invalid,
    Items,
    Number,
    Section,
    Text,
    check_keys,
    check_object,
    choice,
    configs_dir,
    flag,
    from_mapping,
    mapping,
    number,
    read_yaml,
    schema,
    section,
    shown,
    table,
    text,
)
from cnc_gym.defaults import DEFAULT_MACHINE, INCH_MM, INPUT_UNITS
from cnc_gym.errors import ConfigError
from cnc_gym.frozen import FrozenDict

__all__ = ["DEFAULT_MACHINE", "INPUT_UNITS", "AxisConfig", "AxisMechanicsConfig", "ControllerConfig",
           "MachineConfig", "MachineFunctionsConfig", "PlantConfig", "RotaryAxisConfig", "SetupConfig",
           "ToolSetup", "check_machine", "configs_dir", "load_machine", "load_setup", "machine_names",
           "merge_setups", "with_setup"]  # fmt: skip

AXIS_NAMES = ("x", "y", "z")
ROTARY_NAMES = ("a", "b", "c")

# Ranges shared by the keys of one kind, each with its reason (one place to change a kind's range).
_RATE_WHY = ("100 mm/min is below any machine's rapid rate or feed clamp (slower rates make an episode "
             "last hours of simulated time); 1 000 m/min is far above the fastest machines (about 200).")
_ACCEL_WHY = ("0.0001 g to 100 g: real axes reach about 0.1-5 g; values far outside make the planner's "
              "arithmetic overflow.")  # fmt: skip
_JERK_WHY = "real axes run at 10^3-10^7 mm/s³; values far outside make the planner's arithmetic overflow."
_TRAVEL_WHY = "±1 km: any machine's travel, and positions stay exact in double precision."


_ROTARY_WHY = "as the linear axes', degrees counting as mm (the GSK rotary feed rule)."


def _rate(default: float, doc: str, unit: str = "mm/min", why: str = _RATE_WHY) -> Any:
    return number(default, 100, 1e6, unit=unit, doc=doc, why=why)


def _accel(default: float, doc: str, unit: str = "mm/s²", why: str = _ACCEL_WHY) -> Any:
    return number(default, 1, 1e6, unit=unit, doc=doc, why=why)


def _jerk(default: float, doc: str, unit: str = "mm/s³", why: str = _JERK_WHY) -> Any:
    return number(default, 10, 1e9, unit=unit, doc=doc, why=why)


def _position(default: float, doc: str, unit: str = "mm", why: str = _TRAVEL_WHY) -> Any:
    return number(default, -1e6, 1e6, unit=unit, doc=doc, why=why)


def _corner_step(default: float, unit: str = "mm/min") -> Any:
    return number(default, 0, 1e6, unit=unit, doc="largest velocity step of this axis at a block junction "
                  "(P1227)", why="0 stops at every corner; the upper end as the rates'.")  # fmt: skip


@dataclass(frozen=True)
class AxisConfig:
    """One linear axis: kinematic limits used by the controller and servo parameters used by the plant."""

    rapid_mm_min: float = _rate(30000.0, "rapid traverse rate (P1226)")
    max_feed_mm_min: float = _rate(15000.0, "per-axis cutting-feed clamp (P1225)")
    max_accel_mm_s2: float = _accel(5000.0, "cutting acceleration; GSK: 2·P1225/(2·P1480 + P1481)")
    max_jerk_mm_s3: float = _jerk(50000.0, "cutting jerk; GSK: 2·A/P1481")
    rapid_accel_mm_s2: float = _accel(5000.0, "rapid acceleration; GSK: 2·P1226/(2·P1410 + P1411)")
    rapid_jerk_mm_s3: float = _jerk(50000.0, "rapid jerk; GSK: 2·A_rapid/P1411")
    corner_step_mm_min: float = _corner_step(1000.0)
    kv_1_s: float = number(40.0, 1, 2000, unit="1/s", doc="position-loop gain Kv",
                           why="real drives run at 10-500 1/s.")  # fmt: skip
    feedforward: float = number(0.0, 0, 1, doc="velocity feed-forward fraction")
    velocity_loop_hz: float = number(
        0.0, 1, 5000, off=0, unit="Hz", doc="velocity-loop bandwidth; 0 = ideal (a pure P position loop)",
        why="real velocity loops have 50-2000 Hz; with a velocity loop, Kv must stay below "
            "2·damping·2π·velocity_loop_hz (Routh-Hurwitz) or the loop is unstable.")  # fmt: skip
    velocity_loop_damping: float = number(
        0.7, 0.05, 5, doc="velocity-loop damping ratio ζ",
        why="real loops are tuned to 0.3-1.5; extreme values break the plant's discretisation.")  # fmt: skip
    min_position_mm: float = _position(-1e6, "travel limit − (stored stroke check 1)")
    max_position_mm: float = _position(1e6, "travel limit + (stored stroke check 1)")
    reference_1_mm: float = _position(0.0, "reference position 1 (G28/G27), machine coordinates")
    reference_2_mm: float = _position(0.0, "reference position 2 (G30 P2; GSK P1051)")
    reference_3_mm: float = _position(0.0, "reference position 3 (G30 P3; GSK P1052)")
    reference_4_mm: float = _position(0.0, "reference position 4 (G30 P4; GSK P1053)")

    def config_problems(self) -> Iterator[tuple[str, str]]:
        """Rules across keys: ``(key, problem)``."""
        if self.min_position_mm >= self.max_position_mm:
            yield "min_position_mm", f"must be below max_position_mm ({self.max_position_mm:g})"
        if self.velocity_loop_hz > 0:
            # s³ + 2ζωn s² + ωn² s + ωn² Kv is stable iff Kv < 2ζωn.
            bound = 2.0 * self.velocity_loop_damping * 2.0 * math.pi * self.velocity_loop_hz
            if self.kv_1_s >= bound:
                yield "kv_1_s", (f"makes the servo loop unstable: with a velocity loop it must be below "
                                 f"2·damping·2π·velocity_loop_hz = {bound:.4g} 1/s, "
                                 f"got {self.kv_1_s:g}")  # fmt: skip


@dataclass(frozen=True)
class RotaryAxisConfig:
    """One rotary axis (A, B or C), in degrees: the limits the controller keeps while timing its moves.

    The GSK 25i treats a rotary axis's degrees like millimetres in the feed (GSK 25i programming manual
    §3.2.2, G01 with rotary axes): in a block that moves linear and rotary axes together, F is the rate
    along the composite vector √(ΔX² + ΔY² + ΔZ² + ΔB²) with degrees counted as mm; a rotary-only G01
    runs at F deg/min.
    """

    rapid_deg_min: float = _rate(3600.0, "rapid traverse rate (P1226)", "deg/min", _ROTARY_WHY)
    max_feed_deg_min: float = _rate(3600.0, "cutting-feed clamp (P1225)", "deg/min", _ROTARY_WHY)
    max_accel_deg_s2: float = _accel(1800.0, "cutting acceleration", "deg/s²", _ROTARY_WHY)
    max_jerk_deg_s3: float = _jerk(18000.0, "cutting jerk", "deg/s³", _ROTARY_WHY)
    rapid_accel_deg_s2: float = _accel(1800.0, "rapid acceleration", "deg/s²", _ROTARY_WHY)
    rapid_jerk_deg_s3: float = _jerk(18000.0, "rapid jerk", "deg/s³", _ROTARY_WHY)
    corner_step_deg_min: float = _corner_step(1000.0, "deg/min")
    reference_1_deg: float = _position(0.0, "G28 reference position (machine coordinate)", "deg", _ROTARY_WHY)


class RotaryAxes(FrozenDict):
    """Rotary axes by letter: a read-only, hashable mapping (machines are cache keys)."""


@dataclass(frozen=True)
class ControllerConfig:
    """Path-level controller parameters."""

    interpolation_period_s: float = number(
        0.002, 1e-4, 0.02, unit="s", doc="interpolation period (P9121)",
        why="real controllers interpolate every 0.1-8 ms; the simulation takes one step per period "
            "(1e-7 s would take minutes per second of motion), and beyond 20 ms a 15 m/min feed moves "
            "5 mm between references.")  # fmt: skip
    lookahead_blocks: int = number(
        32, 0, 5000, integer=True, doc="look-ahead window in motion blocks (P1409); 0 or 1: every block "
        "ends at rest", why="current controllers look ahead at most a few thousand blocks; the planner's "
        "memory and work per period grow with the window.")  # fmt: skip
    max_feed_mm_min: float = _rate(15000.0, "composite cutting-feed clamp after override (P1224)")
    max_override: float = number(
        2.0, 0.1, 10, doc="feed-override knob range: 2.0 = 0 … 200 %",
        why="real knobs end at 120-254 %; up to 10× for experiments.")  # fmt: skip
    override_slew_per_s: float = number(
        10.0, 0.01, 10000, unit="1/s", doc="how fast the applied override follows the knob",
        why="from 100 s for the whole range to a step within one period.")  # fmt: skip
    max_centripetal_accel_mm_s2: float = _accel(5000.0, "arc acceleration limit (P1442)")
    chord_tolerance_mm: float = number(
        0.001, 1e-6, 1, unit="mm", doc="arc control accuracy at the interpolation period (P1472)",
        why="1 nm (finer than any scale) to 1 mm.")  # fmt: skip
    min_arc_feed_mm_min: float = number(0.0, 0, 1e6, unit="mm/min", why="up to max_feed_mm_min.",
                                        doc="floor on the arc speed limit (P1505)")  # fmt: skip
    post_filter_s: float = number(
        0.0, 0, 0.5, unit="s", doc="post-interpolation acc/dec filter (moving average); 0 = none",
        why="real after-interpolation filters are 0-0.5 s; the plant keeps one reference sample per "
            "interpolation period of the window (1e6 s needed 22 GB).")  # fmt: skip
    in_position_mm: float = number(0.01, 1e-6, 10, unit="mm", why="1 nm to 10 mm.",
                                   doc="in-position width at exact stops and the end (P1471)")  # fmt: skip
    contour_tolerance_mm: float = number(0.05, 1e-6, 10, unit="mm", why="1 nm to 10 mm.",
                                         doc="contour error above this counts as a violation")  # fmt: skip

    corner_smoothing_tolerance_mm: float = number(
        0.0, 1e-6, 10, off=0, unit="mm", doc="corner smoothing of short line segments in continuous mode: "
        "the largest deviation of the blend from the programmed corner (GSK P1401#1 EFL on, tolerance "
        "P1473); 0 = off (EFL = 0)", why="1 nm to 10 mm.")  # fmt: skip
    corner_smoothing_min_angle_deg: float = number(
        150.0, 60, 180, unit="deg", doc="smooth only corners whose included angle is at least this (P1495; "
        "180° = collinear)", why="GSK allows 120-180°; below 60° a blend within a small tolerance crawls "
        "round a near-reversal.")  # fmt: skip
    corner_smoothing_max_segment_mm: float = number(
        0.0, 1e-3, 1e6, off=0, unit="mm", doc="smooth only junctions of lines at most this long (the "
        "\"small segment\" condition); 0 = any length", why="1 µm to the travel range.")  # fmt: skip
    corner_rule: str = choice(
        "step", ("step", "jerk"), doc="how fast a junction where the tangent or the curvature changes may be "
        "passed: `step`: GSK's per-axis velocity step (P1227, the axes' `corner_step_mm_min`) only, which "
        "deliberately allows a step of the axis velocities within one interpolation period (its finite-"
        "difference jerk is far above the axes' jerk); `jerk`: also the jerk-limited corner rule, so that "
        "the 2 ms finite-difference jerk of the reference stays within the axes' jerk (and the path-norm "
        "jerk) at junctions too: a speed limit per junction, a stop where the acceleration alone would "
        "exceed it, and a lower jerk around the junctions passed (docs/motion.md §7)")  # fmt: skip
    path_max_accel_mm_s2: float = number(
        0.0, 1, 1e6, off=0, unit="mm/s²", doc="limit on the norm of the path acceleration vector "
        "(tangential and centripetal together); 0 = only the per-axis limits", why=_ACCEL_WHY)  # fmt: skip
    path_max_jerk_mm_s3: float = number(
        0.0, 10, 1e9, off=0, unit="mm/s³", doc="limit on the norm of the path jerk vector; 0 = only the "
        "per-axis limits", why=_JERK_WHY)  # fmt: skip

    def config_problems(self) -> Iterator[tuple[str, str]]:
        """Rules across keys: ``(key, problem)``."""
        if self.min_arc_feed_mm_min > self.max_feed_mm_min:
            yield "min_arc_feed_mm_min", f"must not exceed max_feed_mm_min ({self.max_feed_mm_min:g})"


#: The servo backends a preset's ``plant.backend`` (and ``plant=`` / ``--plant``) may name.
PLANT_BACKENDS = ("lti", "mujoco")
_MASS_WHY = "10 g to 100 t: any feed axis's moving parts; the loop gains are tuned to the mass."


@dataclass(frozen=True)
class AxisMechanicsConfig:
    """The mechanics of one feed axis for the MuJoCo plant, in SI units (the LTI plant ignores them).

    The motor side (rotor, coupling, ball screw) and the load side (table, saddle or head) are two bodies
    joined by the screw's axial spring-damper, with an optional dead band (backlash) in between; with
    ``coupling_stiffness_n_um: 0`` the axis is rigid (one body). The drive's velocity loop is tuned to the
    axis's whole moving mass (what the commissioning engineer's autotuning measures), so masses change
    the loop's disturbance rejection, not its reference response.
    """

    load_mass_kg: float = number(200.0, 0.01, 1e5, unit="kg", why=_MASS_WHY,
                                 doc="mass of the axis's own moving body: X the table (with workpiece), "
                                     "Y the saddle (it also carries the table), Z the head")  # fmt: skip
    motor_mass_kg: float = number(100.0, 0.01, 1e5, unit="kg", why=_MASS_WHY,
                                  doc="motor-side inertia as a mass along the axis: (rotor + coupling + "
                                      "screw inertia)·(2π/lead)²")  # fmt: skip
    viscous_damping_n_s_m: float = number(0.0, 0, 1e7, unit="N·s/m",
                                          doc="viscous friction of the load's guideways",
                                          why="0 to far above any lubricated guideway.")  # fmt: skip
    coulomb_friction_n: float = number(
        0.0, 0, 1e5, unit="N", doc="Coulomb (dry) friction of the load's guideways (MuJoCo frictionloss)",
        why="0 to 100 kN: rolling guides have 10-200 N, box ways some kN.")  # fmt: skip
    coupling_stiffness_n_um: float = number(
        0.0, 1, 1e6, off=0, unit="N/µm",
        doc="axial stiffness between motor and load (screw, nut, bearings, as datasheets quote it); "
            "0 = rigid", why="ball-screw drives have 50-1000 N/µm.")  # fmt: skip
    coupling_damping_n_s_m: float = number(0.0, 0, 1e7, unit="N·s/m", why="0 to far above any drive train.",
                                           doc="damping of the motor-load coupling")  # fmt: skip
    backlash_mm: float = number(0.0, 0, 1, unit="mm", why="worn screws reach 0.1 mm.",
                                doc="dead band of the coupling (lost motion at a reversal); needs a "
                                    "coupling stiffness")  # fmt: skip
    position_feedback: str = choice("motor", ("motor", "load"), doc="where the position loop measures: "
                                    "`motor` (rotary encoder, semi-closed loop) or `load` (linear scale, "
                                    "full-closed loop)")  # fmt: skip
    velocity_integral_time_s: float = number(
        0.0, 1e-4, 10, off=0, unit="s",
        doc="reset time Tn of a PI velocity loop; 0 = P velocity loop (as the LTI plant)",
        why="drives use 1-100 ms; the loop must stay stable (checked when the plant is built).")  # fmt: skip

    def config_problems(self) -> Iterator[tuple[str, str]]:
        """Rules across keys: ``(key, problem)``."""
        if self.backlash_mm > 0 and self.coupling_stiffness_n_um == 0:
            yield "backlash_mm", "needs coupling_stiffness_n_um > 0 (a dead band sits between two bodies)"


@dataclass(frozen=True)
class PlantAxes:
    """The mechanics of X, Y and Z."""

    x: AxisMechanicsConfig = section(AxisMechanicsConfig, doc="X: the table")  # noqa: RUF009
    y: AxisMechanicsConfig = section(AxisMechanicsConfig, doc="Y: the saddle, carrying the table")  # noqa: RUF009
    z: AxisMechanicsConfig = section(AxisMechanicsConfig, doc="Z: the head")  # noqa: RUF009

    def axis(self, index: int) -> AxisMechanicsConfig:
        return (self.x, self.y, self.z)[index]


@dataclass(frozen=True)
class PlantConfig:
    """Which servo plant turns the reference into motion, and (MuJoCo) the machine's mechanics."""

    backend: str = choice("lti", PLANT_BACKENDS, doc="`lti`: the exact linear servo model (fast); `mujoco`: "
                          "the same loops driving masses with friction, compliance and backlash")  # fmt: skip
    timestep_s: float = number(
        0.0005, 1e-5, 0.02, unit="s",
        doc="MuJoCo physics timestep: at most the interpolation period and a whole fraction of it",
        why="10 µs resolves a 2 kHz resonance; the step's cost grows as 1/timestep.")  # fmt: skip
    axes: PlantAxes = section(PlantAxes, doc="per-axis mechanics (see below)")  # noqa: RUF009


# ------------------------------------------------------------------------------------------- the setup
_OFFSET_WHY = ("±1 km: any machine's travel; each dialect's own offset limits (GSK 25i ±999.999 mm geometry, "
               "±99.999 mm wear …) are checked when a program runs.")  # fmt: skip
_WORK_OFFSET_KEY = re.compile(r"G0*(5[4-9])(?:\.([1-9]))?(?:P0*([0-9]{1,4}))?|EXT")
#: The work offset keys a setup may name (the docs' wording).
WORK_OFFSET_KEYS = ("`G54`…`G59`, `G54.1 P1`…`G54.1 P300` (the dialect's extended systems), "
                    "`G59.1`…`G59.9` (Syntec), `EXT` (the external offset, G10 L2 P0)")  # fmt: skip


def work_offset_key(raw: Any) -> str:
    """A setup's work offset key in its canonical spelling (``"g54.1p05"`` → ``"G54.1 P5"``, ``"G54.1"`` →
    ``"G54.1 P1"``), or :class:`~cnc_gym.config.Invalid`. Whether the dialect has the system is checked when
    a program runs (:func:`cnc_gym.gcode.setup.apply_setup`)."""
    text_ = raw.replace(" ", "").upper() if isinstance(raw, str) else None
    match = _WORK_OFFSET_KEY.fullmatch(text_) if text_ else None
    if match is None:
        raise Invalid(f"is not a work coordinate system ({WORK_OFFSET_KEYS.replace('`', '')})")
    if text_ == "EXT":
        return "EXT"
    code, sub, p = match.groups()
    if sub is None:
        if p is not None:
            raise Invalid("is not a work coordinate system: P goes with G54.1 (G54.1 P5)")
        return f"G{code}"
    if code == "54" and sub == "1":
        number_ = int(p or 1)
        if not 1 <= number_ <= 300:
            raise Invalid(f"is not a work coordinate system: G54.1 P{number_} is outside P1…P300")
        return f"G54.1 P{number_}"
    if p is not None:
        raise Invalid(f"is not a work coordinate system: G{code}.{sub} takes no P")
    return f"G{code}.{sub}"


def tool_number(raw: Any) -> int:
    """A setup's tool (offset) number: an integer 1…9999, or :class:`~cnc_gym.config.Invalid`."""
    if isinstance(raw, bool) or not isinstance(raw, int) or not 1 <= raw <= 9999:
        raise Invalid("is not an offset number (an integer 1…9999)")
    return raw


@dataclass(frozen=True)
class ToolSetup:
    """One offset number of the operator's tool table: what an H word (length) and a D word (radius) of
    that number read, geometry plus wear."""

    length_mm: float = number(0.0, -1e4, 1e4, unit="mm", why=_OFFSET_WHY.replace("1 km", "10 m"),
                              doc="tool length offset: H geometry (the AZ-MC1's D record length, the H4C-M's "
                                  "group Z offset)")  # fmt: skip
    radius_mm: float = number(0.0, -1e4, 1e4, unit="mm", why=_OFFSET_WHY.replace("1 km", "10 m"),
                              doc="cutter radius: D geometry (the AZ-MC1's D record radius, the H4C-M's "
                                  "group R)")  # fmt: skip
    length_wear_mm: float = number(0.0, -1e4, 1e4, unit="mm", doc="tool length wear (added to the length)",
                                   why=_OFFSET_WHY.replace("1 km", "10 m"))  # fmt: skip
    radius_wear_mm: float = number(0.0, -1e4, 1e4, unit="mm", doc="cutter radius wear (added to the radius)",
                                   why=_OFFSET_WHY.replace("1 km", "10 m"))  # fmt: skip


@dataclass(frozen=True)
class SetupConfig:
    """The operator's tables as the control holds them when the program starts: the work offsets and the
    tool offsets. A program's G10 still changes them while it runs (docs/configs.md "Setup")."""

    units: str = choice("mm", INPUT_UNITS, doc="unit of every length in this setup: `mm` or `inch`")
    work_offsets: Mapping[str, tuple[float, float, float]] = table(
        work_offset_key, WORK_OFFSET_KEYS,
        Items(item=Number(low=-1e6, high=1e6, unit="mm"), min_items=3, max_items=3,
              noun="values of [x, y, z]"),
        doc="work coordinate system → its origin `[x, y, z]` in machine coordinates",
        why=_OFFSET_WHY)  # fmt: skip
    tools: Mapping[int, ToolSetup] = table(
        tool_number, "offset numbers 1…9999", Section(of=ToolSetup),
        doc="offset number → `length_mm`, `radius_mm` and their wear (the H and D words of that number read "
            "them)")  # fmt: skip
    source: str = "<defaults>"
    #: Where the tables sit in ``source``: "" (a setup file) or ``"setup."`` (a preset's section).
    where: str = ""

    @property
    def empty(self) -> bool:
        return not self.work_offsets and not self.tools

    def in_mm(self) -> SetupConfig:
        """The same tables with every length in mm."""
        if self.units == "mm":
            return self
        k = INCH_MM
        offsets = FrozenDict({key: tuple(c * k for c in xyz) for key, xyz in self.work_offsets.items()})
        tools = FrozenDict({n: ToolSetup(*(getattr(t, f.name) * k for f in dataclasses.fields(ToolSetup)))
                            for n, t in self.tools.items()})  # fmt: skip
        return SetupConfig("mm", offsets, tools, self.source, self.where)


def load_setup(setup: str | Path | Mapping | SetupConfig) -> SetupConfig:
    """A setup from a YAML file's path, a mapping of its data, or a :class:`SetupConfig` (checked); every
    problem is one ConfigError line naming the file and the key."""
    if isinstance(setup, SetupConfig):
        check_object(setup, setup.source)
        return setup
    if isinstance(setup, str | Path):
        data = read_yaml(setup, "setup file")
        return from_mapping(SetupConfig, data, str(setup), "", {"source": str(setup)})
    if isinstance(setup, Mapping):
        return from_mapping(SetupConfig, dict(setup), "setup", "", {"source": "setup"})  # (its own messages)
    raise ConfigError(f"setup must be a YAML path, a mapping or a SetupConfig, got {type(setup).__name__}")


def merge_setups(base: SetupConfig, override: SetupConfig | None) -> SetupConfig:
    """``base``'s tables with ``override``'s entries on top (a key in both: ``override``'s), in mm."""
    if override is None or override.empty:
        return base
    if base.empty:
        return override
    a, b = base.in_mm(), override.in_mm()
    offsets, tools = FrozenDict({**a.work_offsets, **b.work_offsets}), FrozenDict({**a.tools, **b.tools})
    return SetupConfig("mm", offsets, tools, f"{base.source} + {override.source}")


def m_code_number(raw: Any) -> int:
    """An M code number of a preset's ``machine_functions.m_codes``: an integer 0…999."""
    if isinstance(raw, bool) or not isinstance(raw, int) or not 0 <= raw <= 999:
        raise Invalid("is not an M code number (an integer 0…999)")
    return raw


@dataclass(frozen=True)
class MachineFunctionsConfig:
    """The M codes the machine builder added: the control hands them to the machine (no motion of the
    program; the block waits for the machine's answer at rest)."""

    m_codes: Mapping[int, str] = table(
        m_code_number, "M code numbers 0…999", Text(max_length=200),
        doc="M code → what it does on this machine: run as a machine function (a 0 s stop, listed on "
            "the tool path) in every dialect, unless the dialect gives the code a meaning of its "
            "own")  # fmt: skip
    strict: bool = flag(False, doc="refuse an M code that is neither the dialect's own nor in `m_codes` "
                                   "(and, for `fanuc`, not on its list of usual machine codes); false: "
                                   "`fanuc` runs it as a machine function with a note")  # fmt: skip


@dataclass(frozen=True)
class MachineConfig:
    name: str = text("", doc="the preset's name (default: the file's name)")
    description: str = text("", max_length=4096, doc="one paragraph for people")
    #: The input unit in force at power-on (a controller parameter, as Fanuc's 0001#2 INI): an inch
    #: machine reads a program without G20/G21 in inches. A program's own G20/G21 still rules; the
    #: ``units=`` argument (``--units``) rules over this key.
    power_on_units: str | None = choice(None, (None, *INPUT_UNITS), doc="input unit at power-on, `mm` or "
                                        "`inch` (null: the dialect's power-on code: G21, Syntec G71); a "
                                        "program's G20/G21 still rules")  # fmt: skip
    #: Calculator-type input (Fanuc 3401#0 DPI = 1): a number without a decimal point is in mm, inch or
    #: seconds where the dialect would read least input increments (``--calculator-input`` sets it).
    calculator_input: bool = flag(False, doc="calculator-type input (Fanuc parameter 3401#0 DPI = 1): `X10` "
                                  "is 10 mm, not 10 least input increments, in the dialects that have the "
                                  "setting (`fanuc`); false: the dialect's standard reading")  # fmt: skip
    controller: ControllerConfig = section(ControllerConfig, doc="path-level controller parameters")  # noqa: RUF009
    axes: tuple[AxisConfig, AxisConfig, AxisConfig] = (AxisConfig(), AxisConfig(), AxisConfig())
    source: str = "<defaults>"
    #: Rotary axes by upper-case letter, in A, B, C order (empty: a 3-axis machine).
    rotary_axes: RotaryAxes = field(default_factory=RotaryAxes)
    plant: PlantConfig = section(PlantConfig, doc="servo backend and mechanics (see below)")  # noqa: RUF009
    setup: SetupConfig = section(SetupConfig, doc="the operator's tables at power-on: work offsets and tool "  # noqa: RUF009
                                 "offsets (see below); `--setup FILE` adds to them")  # fmt: skip
    machine_functions: MachineFunctionsConfig = section(  # noqa: RUF009
        MachineFunctionsConfig, doc="the machine builder's M codes (see below)")

    def __post_init__(self) -> None:
        if not isinstance(self.rotary_axes, RotaryAxes):
            object.__setattr__(self, "rotary_axes", RotaryAxes(self.rotary_axes))

    @property
    def rotary_letters(self) -> str:
        """The rotary axes' letters, e.g. ``"B"`` (``""`` on a 3-axis machine)."""
        return "".join(self.rotary_axes)

    def config_problems(self) -> Iterator[tuple[str, str]]:
        """Rules across sections: ``(key, problem)``."""
        period, step = self.controller.interpolation_period_s, self.plant.timestep_s
        substeps = period / step
        if step > period * (1 + 1e-9) or abs(substeps - round(substeps)) > 1e-6 * substeps:
            yield "plant.timestep_s", (f"must be the interpolation period ({period:g} s) divided by a whole "
                                       f"number, got {step:g}")  # fmt: skip

    def axis_array(self, name: str) -> tuple[float, float, float]:
        """One AxisConfig field for X, Y, Z, e.g. ``machine.axis_array("kv_1_s")``."""
        return tuple(float(getattr(axis, name)) for axis in self.axes)  # type: ignore[return-value]


#: Keys of a preset file besides MachineConfig's own: per-axis sections merged into ``axes``.
_AXIS_SECTIONS = ("axis_defaults", "axes", "rotary_axes")


def machine_names() -> list[str]:
    return sorted(p.stem for p in (configs_dir() / "machines").glob("*.yaml"))


def load_machine(name_or_path: str | Path | MachineConfig = DEFAULT_MACHINE) -> MachineConfig:
    """Load a preset by name (``vmc-small``, ``gsk25i``, ``p-loop-30`` …) or from a YAML path; a
    ``MachineConfig`` built in Python is checked against the same schema and returned."""
    if isinstance(name_or_path, MachineConfig):
        return check_machine(name_or_path)
    if not isinstance(name_or_path, str | Path):
        raise ConfigError(f"machine must be a preset name, a YAML path or a MachineConfig, "
                          f"got {type(name_or_path).__name__}")  # fmt: skip
    path = Path(name_or_path)
    if path.suffix not in (".yaml", ".yml"):
        path = configs_dir() / "machines" / f"{name_or_path}.yaml"
        if not str(name_or_path) or not path.is_file():
            presets = ", ".join(machine_names())
            raise ConfigError(f"unknown machine {shown(str(name_or_path))}; presets: {presets}")
    data = read_yaml(path, "machine config")
    return machine_from_dict(data, source=str(path))


def machine_from_dict(data: Any, source: str = "<dict>") -> MachineConfig:
    """Build and check a machine from the data of a preset file (see the module docstring's layout)."""
    data = mapping(data, source, "")
    check_keys(data, set(schema(MachineConfig)) | set(_AXIS_SECTIONS), source)
    defaults = mapping(data.get("axis_defaults"), source, "axis_defaults")
    from_mapping(AxisConfig, defaults, source, "axis_defaults")  # checked on their own first
    axes_data = mapping(data.get("axes"), source, "axes")
    check_keys(axes_data, AXIS_NAMES, source, "axes")
    axes = tuple(
        from_mapping(AxisConfig, {**defaults, **mapping(axes_data.get(n), source, where)}, source, where)
        for n, where in ((n, f"axes.{n}") for n in AXIS_NAMES)
    )
    rotary_data = mapping(data.get("rotary_axes"), source, "rotary_axes")
    check_keys(rotary_data, ROTARY_NAMES, source, "rotary_axes")
    rotary = RotaryAxes({n.upper(): from_mapping(RotaryAxisConfig, rotary_data[n], source, f"rotary_axes.{n}")
                         for n in ROTARY_NAMES if n in rotary_data})  # fmt: skip
    own = {key: value for key, value in data.items() if key not in _AXIS_SECTIONS}
    own.setdefault("name", Path(source).stem)
    built = {"axes": axes, "rotary_axes": rotary, "source": source}
    machine = from_mapping(MachineConfig, own, source, "", built)
    if not machine.setup.empty:  # the setup's errors at run time name the preset
        machine = dataclasses.replace(machine, setup=dataclasses.replace(machine.setup, source=source,
                                                                         where="setup."))
    return machine


def with_setup(machine: MachineConfig, setup: str | Path | Mapping | SetupConfig | None) -> MachineConfig:
    """``machine`` with ``setup`` (a setup file, its data or a SetupConfig) on top of its preset's ``setup``
    section (an entry in both: the file's); None: ``machine`` as it is."""
    if setup is None:
        return machine
    return dataclasses.replace(machine, setup=merge_setups(machine.setup, load_setup(setup)))


def machine_with_options(machine: str | Path | MachineConfig, setup: str | Path | None,
                         calculator_input: bool) -> MachineConfig:
    """The machine preset ``machine`` with a setup file on top of its own and calculator-type input on, as
    the command line gives them (``--setup``, ``--calculator-input``): the record ``run`` and ``bench``
    pass along."""
    loaded = with_setup(machine if isinstance(machine, MachineConfig) else load_machine(machine), setup)
    return dataclasses.replace(loaded, calculator_input=True) if calculator_input else loaded


def with_plant_backend(machine: MachineConfig, backend: str | None) -> MachineConfig:
    """``machine`` with ``plant.backend`` set to ``backend`` (None: as it is), e.g. for the env's
    ``plant=`` and the CLI's ``--plant``; a name not in :data:`PLANT_BACKENDS` is a ConfigError."""
    if backend is None or backend == machine.plant.backend:
        return machine
    if backend not in PLANT_BACKENDS:
        raise ConfigError(f"plant must be one of {', '.join(PLANT_BACKENDS)}, got {shown(backend)}")
    return dataclasses.replace(machine, plant=dataclasses.replace(machine.plant, backend=backend))


def check_machine(machine: MachineConfig) -> MachineConfig:
    """``machine`` if it keeps every rule a preset file must keep (same messages), else ConfigError."""
    if not isinstance(machine, MachineConfig):
        raise ConfigError(f"machine must be a MachineConfig, got {type(machine).__name__}")
    try:
        hash(machine)
    except TypeError:
        raise ConfigError(f"{machine.source}: a MachineConfig must be hashable (axes a tuple)") from None
    return _check_machine(machine)


@functools.lru_cache(maxsize=64)
def _check_machine(machine: MachineConfig) -> MachineConfig:
    source = machine.source
    check_object(machine, source)
    if len(machine.axes) != len(AXIS_NAMES) or not all(isinstance(a, AxisConfig) for a in machine.axes):
        raise ConfigError(f"{source}: axes must be three AxisConfig (X, Y, Z)")
    for name, axis in zip(AXIS_NAMES, machine.axes, strict=True):
        check_object(axis, source, f"axes.{name}")
    for letter, axis in machine.rotary_axes.items():
        if letter not in "ABC" or not isinstance(axis, RotaryAxisConfig):
            raise ConfigError(f"{source}: rotary_axes must map A, B or C to a RotaryAxisConfig")
        check_object(axis, source, f"rotary_axes.{letter.lower()}")
    return machine
