"""The arguments of ``cnc_gym/Feedrate-v0``: one schema, checked once, shared with the task and training
configs.

:class:`EnvArguments` declares every keyword argument of :class:`~cnc_gym.envs.feedrate.FeedrateEnv`
with its type, range and meaning (docs/env.md's argument table is written from it);
:func:`env_arguments` checks a call's arguments against it, so a bad argument is one
:class:`~cnc_gym.errors.ConfigError` line naming it. The task file (``configs/tasks``) and the training
config's ``env:`` section declare their keys with the same specs (:data:`CONTROL_PERIOD`,
:data:`PROGRAM_NAMES`, :class:`RewardWeights` …), so a value means the same and has the same range
everywhere. :func:`parse_action` is the env's check of an action (real numbers only),
:func:`reset_choice` its check of ``reset(options=...)``.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import gymnasium
import numpy as np

from cnc_gym.config import (
    MAX_TEXT,
    Choice,
    Invalid,
    Items,
    Number,
    Spec,
    Text,
    declared,
    number,
    parse_value,
    schema,
    shown,
)
from cnc_gym.envs.engine.episode import knob_of_override as compiled_knob_of_override
from cnc_gym.errors import CncGymError, ConfigError
from cnc_gym.machine import DEFAULT_MACHINE, INPUT_UNITS, PLANT_BACKENDS
from cnc_gym.motion import ActionError
from cnc_gym.motion.kernel import CONTROLLER_REVISION
from cnc_gym.programs import DEFAULT_DIALECT, PROGRAM_TYPES, ProgramLike

if TYPE_CHECKING:
    from cnc_gym.machine import MachineConfig

ACTION_MODES = ("override", "feed")
#: The contour meter's rules (cnc_gym/plant/contour.py): ``path``, the programmed path with the rapids the
#: reference has left; ``cuts``, cutting moves only (Feedrate-v0 and -v1 as registered).
CONTOUR_RULES = ("path", "cuts")
CONTOUR_RULE = Choice(choices=CONTOUR_RULES, doc="contour error against the programmed path with the rapids "
                      "the reference has left (`path`), or against cutting moves only (`cuts`, the rule "
                      "Feedrate-v0 and -v1 are registered with)")
RENDER_MODES = (None, "rgb_array")
#: Where argument errors come from, in their messages.
SOURCE = "FeedrateEnv"

#: Defaults of the arguments every env version shares (the envs' signatures and the config schemas use them).
DEFAULT_ACTION_MODE = "override"
DEFAULT_CONTROL_PERIOD_S = 0.01
DEFAULT_LOOKAHEAD_MM = 24.0
DEFAULT_LOOKAHEAD_POINTS = 8

#: Why a reward weight is bounded (every reward weight of every version).
WEIGHT_WHY = "keeps every step's reward finite, and a return within float32 precision."


@dataclass(frozen=True)
class RewardWeights:
    """Reward weights, per control step:
    ``r = -time·dt/T + progress·Δp - contour_error·min(e/tol, cap)² - violation·[e > tol]``
    (Δp: path progress in the step as a fraction of the program's length; see FeedrateEnv's docstring).
    """

    time: float = number(10.0, 0, 1e6, why=WEIGHT_WHY,
                         doc="w_time: the whole episode's time cost at nominal (100 %) speed")  # fmt: skip
    contour_error: float = number(0.05, 0, 1e6, why=WEIGHT_WHY,
                                  doc="w_error: per step, per (e_max / tol)²")  # fmt: skip
    violation: float = number(
        1.0, 0, 1e6, why=WEIGHT_WHY, doc="w_violation: per control step whose contour error exceeds tol")
    error_ratio_cap: float = number(
        10.0, 0, 1e6, low_open=True, why=WEIGHT_WHY,
        doc="c: e_max / tol is capped here so that one bad step cannot dominate a return")  # fmt: skip
    # Paid per unit of path progress; sums to exactly this over a finished episode whatever the policy,
    # so it leaves the undiscounted ranking of finishing policies unchanged but pays for progress when it
    # happens, which a discounted (γ < 1) learner needs to see that slow costs (see docs/env.md).
    progress: float = number(
        10.0, 0, 1e6, why=WEIGHT_WHY, doc="w_progress: paid over the whole path, in proportion to progress")


# Specs shared by the env's arguments, the task file and the training config's env section.
CONTROL_PERIOD = Number(
    low=0,
    high=1.0,
    low_open=True,
    unit="s",
    doc="seconds between decisions: a whole multiple of the machine's interpolation period",
    why="a decision at least every second; the step's buffers grow with it (10⁶ s needed 11 GiB).",
)
PROGRAM_NAMES = Items(
    item=Text(max_length=MAX_TEXT), single=True, max_items=1000, noun="program",
    doc="built-in program names or `.nc` paths (a single name is a list of one)")  # fmt: skip
DIALECT = Text(max_length=100, doc="controller dialect of the programs")
UNITS = Choice(choices=(None, *INPUT_UNITS),
               doc="input unit at power-on, `mm` or `inch`, for programs without G20/G21 (null: the "
                   "machine preset's `power_on_units`, else the dialect's power-on code); a program's "
                   "G20/G21 still rules")  # fmt: skip
MACHINE_NAME = Text(max_length=MAX_TEXT, doc="machine preset name or YAML path")
ACTION_MODE = Choice(choices=ACTION_MODES, doc="what the action sets: the override knob or the feed")
MAX_EPISODE_STEPS = Number(
    low=1, high=10**9, integer=True, optional=True,
    doc="step budget of an episode (null: 5 × the program's nominal time plus 1 s); `gymnasium.make` keeps "
        "this name for its TimeLimit wrapper, which can end an episode earlier but not later: to lengthen "
        "the budget, build the env class itself")  # fmt: skip


class ProgramRefs(Spec):
    """Programs given to the env: a name, path, G-code text, ``ProgramText`` or interpreted ``Program``
    (the rule of :mod:`cnc_gym.programs`), or a non-empty sequence of them."""

    def _parse(self, raw: Any) -> Any:
        refs = [raw] if isinstance(raw, PROGRAM_TYPES) else raw
        if isinstance(refs, bytes) or not isinstance(refs, list | tuple):
            raise Invalid(f"must be a program name, path or G-code text, or a list of them, got {shown(raw)}")
        if not refs:
            raise Invalid("must name at least one program")
        for ref in refs:
            if not isinstance(ref, PROGRAM_TYPES):
                raise Invalid(f"entries must be program names, paths or G-code text, got {shown(ref)}")
        return tuple(refs)

    def _allowed(self) -> str:
        return "name, path, G-code text, `ProgramText` or `Program`, or a list of them"


class MachineRef(Spec):
    """A machine: preset name, YAML path or ``MachineConfig``."""

    def _parse(self, raw: Any) -> Any:
        from cnc_gym.machine import MachineConfig

        if isinstance(raw, MachineConfig | str | os.PathLike):
            return raw
        raise Invalid(f"must be a preset name, a YAML path or a MachineConfig, got {shown(raw)}")

    def _allowed(self) -> str:
        return "preset name, YAML path or `MachineConfig`"


class SetupRef(Spec):
    """The operator's tables: None (the machine preset's ``setup`` section alone), a setup YAML path, a
    dict of its data or a ``SetupConfig`` (docs/configs.md "Setup")."""

    def _parse(self, raw: Any) -> Any:
        from cnc_gym.machine import SetupConfig, load_setup

        if raw is None:
            return None
        if isinstance(raw, str | os.PathLike | dict | SetupConfig):
            return load_setup(raw if not isinstance(raw, os.PathLike) else Path(raw))
        raise Invalid(f"must be None, a setup YAML path, a dict or a SetupConfig, got {shown(raw)}")

    def _allowed(self) -> str:
        return "null, setup YAML path, dict or `SetupConfig`"


SETUP = SetupRef(doc="the operator's work and tool offsets at power-on, on top of the machine preset's "
                     "`setup` section (null: the preset's alone); a program's G10 still changes them")


class RewardRef(Spec):
    """Reward weights: None (the default task's), a task YAML path, a dict of weights or RewardWeights
    (None is one of its values, not "optional")."""

    def _parse(self, raw: Any) -> Any:
        if raw is None or isinstance(raw, str | os.PathLike | dict | RewardWeights):
            return raw
        raise Invalid(f"must be None, a task YAML path or a dict of weights, got {shown(raw)}")

    def _allowed(self) -> str:
        return "null, task YAML path, dict of weights or `RewardWeights`"


@dataclass(frozen=True)
class EnvArguments:
    """The keyword arguments of ``cnc_gym/Feedrate-v0``, checked."""

    programs: tuple[ProgramLike, ...] | None = declared(ProgramRefs(
        optional=True, doc="programs of the episodes: built-in names, `.nc` paths, G-code text, "
                           "`ProgramText` or interpreted `Program`s (None: the default task's set)",
    ))  # fmt: skip
    dialect: str = declared(DIALECT, DEFAULT_DIALECT)
    machine: str | Path | MachineConfig = declared(MachineRef(doc="the machine"), DEFAULT_MACHINE)  # noqa: RUF009
    units: str | None = declared(UNITS)
    setup: Any = declared(SETUP)  # noqa: RUF009
    plant: str | None = declared(Choice(choices=(None, *PLANT_BACKENDS), doc="servo plant: `lti` (the exact "
                                        "linear model) or `mujoco` (masses, friction, compliance, backlash); "
                                        "null: the machine preset's `plant.backend`"))  # fmt: skip
    action_mode: str = declared(ACTION_MODE, DEFAULT_ACTION_MODE)
    control_period_s: float = declared(CONTROL_PERIOD, DEFAULT_CONTROL_PERIOD_S)
    reward: Any = declared(RewardRef(doc="reward weights (None: configs/tasks/default.yaml)"))  # noqa: RUF009
    max_episode_steps: int | None = declared(MAX_EPISODE_STEPS)
    render_mode: str | None = declared(Choice(choices=RENDER_MODES, doc="`rgb_array` draws frames"))
    lookahead_mm: float = number(
        DEFAULT_LOOKAHEAD_MM, 0, 10_000, low_open=True, unit="mm",
        doc="how far ahead the observation's look-ahead reads",
        why="the look-ahead scans the path this far every step; no machine brakes over 10 m.")  # fmt: skip
    lookahead_points: int = number(
        DEFAULT_LOOKAHEAD_POINTS, 1, 256, integer=True,
        doc="look-ahead points in the observation (4 entries each)",
        why="the observation has 9 + 4 × this entries.")  # fmt: skip
    contour_rule: str = declared(CONTOUR_RULE, "cuts")
    controller_revision: int = number(
        1, 1, CONTROLLER_REVISION, integer=True,
        doc="the simulated controller's behaviour revision: 1 as Feedrate-v0 to -v4 were published "
            "(where the override was lowered while the reference was still accelerating below the new "
            "target it overshot that target, up to about twice), 2 with that fixed (Feedrate-v5 and -v6, "
            "`cnc-gym run`, `bench`)")  # fmt: skip


def env_arguments(**kwargs: Any) -> EnvArguments:
    """The env's keyword arguments checked against :class:`EnvArguments` (one ConfigError line naming the
    first bad one)."""
    specs = schema(EnvArguments)
    unknown = sorted(set(kwargs) - set(specs))
    if unknown:
        raise ConfigError(f"{SOURCE}: unknown argument {unknown[0]} (allowed: {', '.join(specs)})")
    return EnvArguments(**{key: parse_value(specs[key], raw, SOURCE, key) for key, raw in kwargs.items()})


def control_ticks(control_period_s: float, machine: MachineConfig) -> int:
    """Interpolation periods per control step; ConfigError unless the control period is a whole multiple
    of the machine's interpolation period."""
    period = machine.controller.interpolation_period_s
    ticks = round(control_period_s / period)
    if ticks < 1 or abs(ticks * period - control_period_s) > 1e-9 * max(1.0, ticks):
        raise ConfigError(
            f"{SOURCE}: control_period_s ({control_period_s} s) must be a whole multiple of the "
            f"interpolation period ({period} s) of machine {machine.name!r}"
        )
    return int(ticks)


def reset_choice(options: Any) -> int | ProgramLike | None:
    """The program that ``reset(options=...)`` asks for (None: draw one); ConfigError on a bad option."""
    if options is None:
        return None
    if not isinstance(options, dict):
        raise ConfigError(f"reset: options must be a dict, got {shown(options)}")
    unknown = sorted(shown(key, 40) for key in options if key != "program")
    if unknown:
        raise ConfigError(f"reset: unknown option {unknown[0]} (allowed: program)")
    choice = options.get("program")
    if choice is None or isinstance(choice, PROGRAM_TYPES):
        return choice
    if isinstance(choice, int | np.integer) and not isinstance(choice, bool | np.timedelta64):
        return int(choice)
    raise ConfigError(f"reset: options['program'] must be a name, path, text or index, got {shown(choice)}")


class EnvNotReset(CncGymError, gymnasium.error.ResetNeeded):
    """``step()`` before the first ``reset()`` (the same error Gymnasium's order wrapper raises)."""


def knob_of_override(override: float, max_override: float) -> float:
    """The knob value in [-1, 1] that asks for ``override``: the action ``a`` with override
    ``(a + 1)/2 · max_override``, rounded to the action space's float32 and clipped (the compiled
    :func:`~cnc_gym.envs.engine.episode.knob_of_override`, which the baselines' compiled episodes round
    with too)."""
    return compiled_knob_of_override(float(override), float(max_override))


def parse_action(action: Any) -> float:
    """The knob value in [-1, 1] of an action: one real number, as a scalar or an array of shape (1,).

    Out-of-range values are clipped (a Python integer of any size included); NaN, infinity, strings,
    booleans, complex numbers, dates, objects and wrong shapes are an :class:`ActionError` line.
    """
    if isinstance(action, bool | np.bool_):
        raise ActionError(f"action must be a real number, got {shown(action)}")
    if type(action) is int:  # exact, so 10**400 clips to 1 instead of overflowing a float
        return float(min(max(action, -1), 1))
    if isinstance(action, str | bytes):
        raise ActionError(f"action must be a real number, got {shown(action)}")
    try:
        value = np.asarray(action)
    except Exception:  # an object numpy cannot even look at
        value = None
    if value is None or value.dtype.kind not in "fiu":
        kind = "" if value is None else f" (dtype {value.dtype})"
        raise ActionError(f"action must be a real number or an array of shape (1,), got {shown(action)}"
                          f"{kind}")  # fmt: skip
    if value.size != 1 or value.ndim > 1:
        raise ActionError(f"action must have shape (1,), got shape {value.shape}")
    knob = float(value.reshape(()))
    if not math.isfinite(knob):
        raise ActionError(f"action must be finite, got {knob}")
    return min(max(knob, -1.0), 1.0)
