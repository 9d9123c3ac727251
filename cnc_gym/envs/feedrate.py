"""``cnc_gym/Feedrate-v0``: learn the feed-override knob of a CNC controller running a real G-code program."""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from cnc_gym.envs.engine import FeedrateBatch, KnobRule, RewardSpec
from cnc_gym.envs.observation import OBSERVATION_V0, ObservationLayout, markdown_table
from cnc_gym.envs.options import (
    DEFAULT_ACTION_MODE,
    DEFAULT_CONTROL_PERIOD_S,
    DEFAULT_LOOKAHEAD_MM,
    DEFAULT_LOOKAHEAD_POINTS,
    EnvNotReset,
    control_ticks,
    env_arguments,
    parse_action,
    reset_choice,
)
from cnc_gym.envs.task import RewardWeights, load_task, resolve_reward
from cnc_gym.errors import ConfigError
from cnc_gym.machine import DEFAULT_MACHINE, MachineConfig, load_machine, with_plant_backend, with_setup
from cnc_gym.motion import ActionError  # noqa: F401  (one error type for bad actions, env and controller alike)
from cnc_gym.plant import make_plant
from cnc_gym.programs import DEFAULT_DIALECT, PROGRAM_TYPES, ProgramLike, load_program
from cnc_gym.toolpath import SegmentKind, Toolpath

#: The action dtypes of :meth:`FeedrateEnv.step`'s quick path (numpy's own dtype objects: the usual arrays'
#: dtypes are these very objects).
_FLOAT32, _FLOAT64 = np.dtype(np.float32), np.dtype(np.float64)

#: Feedrate-v0's scalar observation entries, in order (the look-ahead blocks, one per
#: :data:`~cnc_gym.envs.engine.layout.LOOKAHEAD_ROWS` row, follow them); the entries are
#: :data:`OBSERVATION_V0`.
SCALAR_FEATURES = tuple(e.name for e in OBSERVATION_V0 if e.source == "signal")


def nominal_time_s(toolpath: Toolpath, machine: MachineConfig) -> float:
    """The program's time at 100 % feed with infinite acceleration: Σ length / programmed feed.

    Rapids count at the slowest axis' rapid rate (a lower bound on the rapid speed, so this never
    underestimates a rapid), dwells at their programmed time. This is ``T_nominal`` of the reward.
    """
    kind = toolpath.kind
    length = toolpath.length
    cutting = (kind == SegmentKind.LINE) | (kind == SegmentKind.ARC) | (kind == SegmentKind.NURBS)
    path_feed_mm_s = toolpath.path_feed / 60.0
    safe_feed = np.where(cutting & (path_feed_mm_s > 0), path_feed_mm_s, 1.0)
    cut_s = float(np.sum(np.where(cutting, length / safe_feed, 0.0)))
    rapid_mm_s = min(machine.axis_array("rapid_mm_min")) / 60.0
    rapid_s = float(np.sum(length[kind == SegmentKind.RAPID])) / rapid_mm_s
    dwell_s = float(np.sum(toolpath.dwell_s))
    rotary_s = 0.0
    if toolpath.rotary_axes:  # rotary-only moves: F covers the rotary travel (deg as mm), rapids at the
        alone = (length == 0) & (toolpath.rotary_travel > 0)  # slowest rotary rapid rate
        feed_mm_s = np.where(alone & cutting, toolpath.feed / 60.0, 1.0)
        rotary_s = float(np.sum(np.where(alone & cutting, toolpath.rotary_length / feed_mm_s, 0.0)))
        rates = [axis.rapid_deg_min / 60.0 for axis in machine.rotary_axes.values()]
        rapid_travel = float(np.sum(toolpath.rotary_travel[alone & (kind == SegmentKind.RAPID)]))
        if rates:
            rotary_s += rapid_travel / min(rates)
    return max(cut_s + rapid_s + dwell_s + rotary_s, 1e-3)


def observation_layout_v0(lookahead_points: int, v_ref: float, a_ref: float, max_override: float,
                          tolerance_mm: float, lookahead_mm: float) -> ObservationLayout:
    """Feedrate-v0's observation (:data:`OBSERVATION_V0`, the table in :class:`FeedrateEnv`'s docstring)
    resolved for one env's references."""
    references = {"v_ref": v_ref, "a_ref": a_ref, "tol": tolerance_mm, "H": lookahead_mm,
                  "ov_max": max_override}  # fmt: skip
    return ObservationLayout(OBSERVATION_V0, lookahead_points, references)


def reward_spec_v0(weights: RewardWeights) -> RewardSpec:
    """Feedrate-v0's reward (the formula in :class:`FeedrateEnv`'s docstring), term by term."""
    return RewardSpec((
        ("progress_delta", "linear", 0.0, weights.progress),
        ("time_fraction", "linear", 0.0, -weights.time),
        ("error_ratio", "capped_square", weights.error_ratio_cap, -weights.contour_error),
        ("violated", "linear", 0.0, -weights.violation),
    ))  # fmt: skip


class FeedrateEnv(gym.Env[np.ndarray, np.ndarray]):
    r"""Feed-rate control of a simulated CNC milling controller on real G-code.

    Each episode runs one G-code program (chosen among ``programs``) from the start to the end of the
    program. Every control step (``control_period_s``, default 10 ms = 5 interpolation periods on
    ``vmc-small``) the agent sets the feed-override knob (or, in ``"feed"`` mode, commands the feed
    directly). The controller (look-ahead, jerk-limited profile, corner and arc limits) turns the program
    into a reference position every interpolation period, the servo axes follow it, and the contour error
    (distance of the actual tool position from the programmed path, on cutting moves) is measured at every
    servo sample. The agent is rewarded for finishing sooner and penalised for contour error, and for
    every control step whose contour error exceeds the machine's tolerance.

    ## Action Space

    ``Box(-1, 1, (1,), float32)``; values outside [-1, 1] are clipped, NaN/inf or a wrong shape raise
    :class:`ActionError` (a ``ValueError``).

    | action_mode | meaning of a ∈ [-1, 1] |
    |---|---|
    | ``override`` (default) | override ``(a + 1) / 2 · max_override``: 0 … 200 % (vmc-small), a = 0 → 100 % |
    | ``feed`` | feed ``(a + 1) / 2 · max_feed_mm_min``: 0 … 15 000 mm/min on vmc-small (replaces F) |

    The controller's look-ahead and limits stay in force in both modes: the knob asks, the controller
    keeps the motion within acceleration, jerk, corner and arc limits and never breaks its braking
    envelope (so a high override cannot make the machine overshoot a stop, only cut less accurately).

    ## Observation Space

    ``Box(low, high, (9 + 4·N,), float32)`` with ``N = lookahead_points`` (default 8, so 41 entries),
    clipped to the bounds below. ``v_ref = max_feed_mm_min / 60`` (250 mm/s on vmc-small),
    ``a_ref`` = the largest axis acceleration, ``tol`` = the machine's contour tolerance, ``H`` =
    ``lookahead_mm`` (default 24 mm), ``L_k`` = 10 mm; declared once in
    :data:`cnc_gym.envs.observation.OBSERVATION_V0` (this table, the bounds, the scaling and
    :attr:`observation_structure` come from it).

    {observation_table}

    The look-ahead block describes the path, not the program, so one policy can run any program.

    ## Rewards

    Per control step of ``dt = control_period_s``, with ``e_max`` the largest contour error (mm) over the
    step's servo samples:

    .. math::

        r = - w_\text{time} \frac{dt}{T_\text{nominal}}
            + w_\text{progress} \, \Delta p
            - w_\text{error} \min\left(\frac{e_\text{max}}{tol}, c\right)^2
            - w_\text{violation} [e_\text{max} > tol]

    ``T_nominal`` is the program's time at 100 % feed (Σ length / programmed feed; see
    :func:`nominal_time_s`), so running the whole program at 100 % costs about ``w_time`` (a bit more
    because of acceleration and corners). ``Δp = p_t − p_{t−1}`` is the path progress made in the step,
    ``p = min(s / L, 1)`` with ``s`` the reference's arc length done and ``L`` the program's total
    (cutting + rapid) length; ``p = 1`` once the controller has finished. Over a finished episode the
    progress term sums to exactly ``w_progress`` whatever the policy, so the undiscounted ranking of
    policies is unchanged, while a discounted learner (γ < 1) sees faster progress as earlier reward
    (with the time term alone, a slow policy barely pays for its longer episode under discounting).
    Weights (``configs/tasks/default.yaml``): ``w_time = 10``, ``w_progress = 10``, ``w_error = 0.05``,
    ``w_violation = 1``, cap ``c = 10``. ``info["cost"] = [e_max > tol]`` is the same violation
    indicator, for constrained RL.

    ## Starting State

    The machine at its start position (the program's first point, the origin for the built-ins), at
    rest, axes settled, override 100 %. There is no randomness apart from the choice of program.

    ## Episode End

    - **Termination**: the controller has finished the program (reference at rest at the end, dwells
      done) and every axis is within the in-position width (``in_position_mm``).
    - A program without motion (nothing but modal codes, spindle or tool commands, ``M30``; or an empty
      file) terminates on the first step with reward 0 and ``cycle_time_s`` 0.
    - **Truncation**: after ``max_episode_steps`` control steps (default: 5 × ``T_nominal`` / ``dt`` plus
      one second to settle), e.g. when the knob is held at 0.

    ## Arguments

    ``programs`` (one program or a list: built-in names, paths, G-code text, ``ProgramText`` or interpreted
    ``Program``\ s, by the rule of :mod:`cnc_gym.programs`; None = the default task's set), ``dialect``,
    ``machine`` (name, YAML path or ``MachineConfig``), ``units`` (the input unit at power-on, ``"mm"`` or
    ``"inch"``, for programs without G20/G21; None: the machine preset's ``power_on_units``, else the
    dialect's; an interpreted ``Program`` keeps the unit it was read in), ``setup`` (the operator's work
    and tool offsets: a setup YAML path, a dict or a ``SetupConfig``, on top of the machine preset's
    ``setup`` section; docs/configs.md), ``action_mode``,
    ``control_period_s`` (a multiple of the interpolation period), ``reward`` (None, a task YAML path or a
    dict of weights), ``max_episode_steps``, ``render_mode`` (None or ``"rgb_array"``), ``lookahead_mm``,
    ``lookahead_points``, ``plant`` (``"lti"`` or ``"mujoco"``: the servo plant, overriding the machine
    preset's ``plant.backend``; see docs/plant.md), ``contour_rule`` (``"cuts"``, v0's meter: contour
    error against the cutting moves only; ``"path"``: against the programmed path, with the rapids the
    reference has left, so the in-position residual of a rapid → cut junction is not counted as error;
    :class:`~cnc_gym.plant.ContourErrorMeter`). ``reset(seed=..., options={"program":
    name_or_index})``: with several programs the episode's program is drawn with ``self.np_random``; the
    option picks one (a name not in the set is loaded for that episode).

    ## Info

    ``cycle_time_s``, ``contour_error_mm`` (max in this step), ``contour_error_max_mm``,
    ``contour_error_rms_mm`` (over cutting samples so far), ``tolerance_mm``, ``violations`` (control
    steps so far with ``e_max > tol``), ``violation_length_mm`` and ``violation_time_s`` (path length
    the reference advanced, and time, over the servo samples with contour error above ``tol``: these do
    not depend on the control period), ``cost``, ``line`` (source line of the current block),
    ``override`` (applied), ``feed_mm_min`` (current path speed × 60), ``path_s``, ``progress``,
    ``program``, ``steps``. At the end of an episode these are the episode's totals. A step's info is a
    dict made from the step's outputs when first used (:class:`~cnc_gym.envs.engine.batch.StepInfo`).

    ## Implementation

    A step is one compiled call (:mod:`cnc_gym.envs.engine`): the controller's periods, the servo plant,
    the contour error, the statistics, the reward and the observation, on state held in arrays. The
    observation and the reward are declared (:data:`~cnc_gym.envs.observation.OBSERVATION_V0`,
    :func:`reward_spec_v0`). The
    vector env (:class:`~cnc_gym.envs.vector.FeedrateVectorEnv`) runs N episodes in one such call.

    ## Version History

    - v0: first version. Its dynamics, reward and observation are unchanged on every preset. Programs
      that ask for corner smoothing (Syntec G05.1 Q1) now get it, because the controller honours that
      program feature (docs/motion.md §6); before, it was carried on the tool path with a warning.
      v0 is registered with ``contour_rule="cuts"`` (the meter it was published with), so its numbers
      reproduce; the benchmark runs its baselines in v0 with ``contour_rule="path"``. Feedrate-v2
      (:mod:`cnc_gym.envs.feedrate_v1`) is the version to train on.
    """

    metadata: ClassVar[dict[str, Any]] = {"render_modes": ["rgb_array"], "render_fps": 50}

    def __init__(
        self,
        programs: Sequence[ProgramLike] | ProgramLike | None = None,
        dialect: str = DEFAULT_DIALECT,
        machine: str | Path | MachineConfig = DEFAULT_MACHINE,
        action_mode: str = DEFAULT_ACTION_MODE,
        control_period_s: float = DEFAULT_CONTROL_PERIOD_S,
        reward: str | Path | dict | RewardWeights | None = None,
        max_episode_steps: int | None = None,
        render_mode: str | None = None,
        lookahead_mm: float = DEFAULT_LOOKAHEAD_MM,
        lookahead_points: int = DEFAULT_LOOKAHEAD_POINTS,
        units: str | None = None,
        plant: str | None = None,
        contour_rule: str = "cuts",
        setup: Any = None,
        controller_revision: int = 1,
    ) -> None:
        # Every argument checked once, against one schema (cnc_gym/envs/options.py).
        args = env_arguments(programs=programs, dialect=dialect, machine=machine, action_mode=action_mode,
                             control_period_s=control_period_s, reward=reward,
                             max_episode_steps=max_episode_steps, render_mode=render_mode,
                             lookahead_mm=lookahead_mm, lookahead_points=lookahead_points,
                             units=units, plant=plant, contour_rule=contour_rule, setup=setup,
                             controller_revision=controller_revision)  # fmt: skip
        self._configure(args)
        self.reward_weights = resolve_reward(args.reward)
        # Observation and reward: declared once (OBSERVATION_V0, reward_spec_v0), assembled by the
        # compiled step.
        self.layout = observation_layout_v0(self.lookahead_points, self._v_ref, self._a_ref,
                                            self.max_override, self.tolerance_mm,
                                            self.lookahead_mm)  # fmt: skip
        self._obs_spec = self.layout.kernel_spec
        self._reward_spec = reward_spec_v0(self.reward_weights)
        self.observation_space = spaces.Box(self._obs_spec.low, self._obs_spec.high, dtype=np.float32)
        #: Entry name → indices in the observation (as Gymnasium's MuJoCo envs' observation_structure).
        self.observation_structure = {name: idx.tolist() for name, idx in self.layout.structure.items()}
        self._start()

    def _configure(self, args: Any) -> None:
        """The machine, periods, references and programs of checked arguments (v0's and later versions')."""
        # (the setup rides in the machine record: every program's interpretation and cache key see it)
        self.machine: MachineConfig = with_setup(with_plant_backend(load_machine(args.machine), args.plant),
                                                 args.setup)  # fmt: skip
        self.action_mode = args.action_mode
        self.render_mode = args.render_mode
        self.dialect = args.dialect
        self.units = args.units
        self.contour_rule = args.contour_rule
        #: The simulated controller's behaviour revision (:data:`cnc_gym.motion.kernel.CONTROLLER_REVISION`).
        self.controller_revision = int(args.controller_revision)
        ctrl = self.machine.controller
        self.interpolation_period_s = ctrl.interpolation_period_s
        self.ticks_per_step = control_ticks(args.control_period_s, self.machine)
        self.control_period_s = self.ticks_per_step * ctrl.interpolation_period_s
        self.tolerance_mm = float(ctrl.contour_tolerance_mm)
        self.in_position_mm = float(ctrl.in_position_mm)
        self.max_override = float(ctrl.max_override)
        self.max_feed_mm_min = float(ctrl.max_feed_mm_min)
        self._v_ref = self.max_feed_mm_min / 60.0
        self._a_ref = max(self.machine.axis_array("max_accel_mm_s2"))
        self._max_lag_mm = self._v_ref / min(self.machine.axis_array("kv_1_s"))
        self.lookahead_mm = args.lookahead_mm
        self.lookahead_points = args.lookahead_points
        self._lookahead_horizon = args.lookahead_mm
        self._max_episode_steps_arg = args.max_episode_steps
        self._needs_reset = True  # step() before the first reset() is an error, wrapped or not

        # Programs: interpreted once (cached by cnc_gym.programs), controllers built lazily per program.
        programs = load_task("default").programs if args.programs is None else args.programs
        self._programs: list[tuple[str, Toolpath]] = [
            load_program(p, args.dialect, self.machine, units=self.units) for p in programs
        ]
        self.program_names = [name for name, _ in self._programs]
        self.action_space = spaces.Box(-1.0, 1.0, shape=(1,), dtype=np.float32)

    def _start(self) -> None:
        """The renderer and the engine, once the spaces and specs are set."""
        self._renderer = None
        self._batch = self.make_batch(1)
        self.plant = self._batch.plant
        if self.render_mode == "rgb_array":
            from cnc_gym.envs.render import EpisodeRenderer, MachineRenderer

            # Records per step; draws on render(): MuJoCo's picture of the machine on the MuJoCo plant.
            if self.machine.plant.backend == "mujoco":
                self._renderer = MachineRenderer(self.tolerance_mm, self.plant)
            else:
                self._renderer = EpisodeRenderer(self.tolerance_mm)
        self._batch.reset([0], [self.program_slot(self._batch, 0)])  # a valid state before the first reset
        self._sync()

    # ------------------------------------------------------------------------------------------ batches
    def make_batch(self, n_envs: int, parallel: bool | None = None,
                   plant: Any | None = None) -> FeedrateBatch:  # fmt: skip
        """``n_envs`` episodes of this env's task stepped together: the engine of this env (one episode)
        and of its vector env (:class:`~cnc_gym.envs.engine.batch.FeedrateBatch`). ``plant``: a plant backend
        for ``n_envs`` envs (default: the machine's ``plant.backend``, which the env's ``plant=`` sets: the
        LTI servo plant is stepped inside the compiled step, the MuJoCo plant through its methods)."""
        config = {
            "ticks_per_step": self.ticks_per_step, "tolerance_mm": self.tolerance_mm,
            "in_position_mm": self.in_position_mm, "max_override": self.max_override,
            "max_feed_mm_min": self.max_feed_mm_min, "lookahead_mm": self.lookahead_mm,
            "lookahead_points": self.lookahead_points, "feed_mode": self.action_mode == "feed",
            # The contour window reaches back over the largest possible lag (max feed / Kv).
            "window_back_mm": self._max_lag_mm, "contour_rapids_behind": self.contour_rule == "path",
            "controller_revision": self.controller_revision,
        }  # fmt: skip
        if plant is None and self.machine.plant.backend != "lti":
            plant = make_plant(self.machine, n_envs)
        return FeedrateBatch(n_envs, self.machine, config, self._obs_spec, self._reward_spec,
                             parallel=parallel, plant=plant, planner=self._planner)  # fmt: skip

    def resolve_program(self, choice: int | ProgramLike) -> tuple[str, Toolpath]:
        """A program of the set by index or name, or any other program (name, path, text…) loaded."""
        if isinstance(choice, int | np.integer) and not isinstance(choice, bool):
            if not 0 <= choice < len(self._programs):
                raise ConfigError(f"program index {choice} out of range 0..{len(self._programs) - 1}")
            return self._programs[int(choice)]
        if isinstance(choice, PROGRAM_TYPES):
            found = [p for p in self._programs if p[0] == choice]
            return found[0] if found else load_program(choice, self.dialect, self.machine, units=self.units)
        raise ConfigError(f"options['program'] must be a name, path, text or index, got {choice!r}")

    def program_slot(self, batch: FeedrateBatch, choice: int | ProgramLike) -> int:
        """The bank index of a program in ``batch`` (packed on first use with its nominal time, budget)."""
        name, toolpath = self.resolve_program(choice)
        slot = batch.find_program(name, toolpath)
        return self.pack_program(batch, name, toolpath) if slot is None else slot

    def pack_program(self, batch: FeedrateBatch, name: str, toolpath: Toolpath) -> int:
        """Pack a program into ``batch`` with its nominal time and step budget; its bank index."""
        t_nominal = nominal_time_s(toolpath, self.machine)
        budget = self._max_episode_steps_arg or (
            math.ceil(5.0 * t_nominal / self.control_period_s) + math.ceil(1.0 / self.control_period_s)
        )
        t_reward = self.reward_time_s(toolpath, t_nominal)
        return batch.add_program(name, toolpath, self.control_period_s / t_reward, int(budget),
                                 self.finish_bonus(t_nominal, int(budget)))  # fmt: skip

    #: The planner whose override the compiled step evaluates (none in v0).
    _planner: Any = None

    def finish_bonus(self, t_nominal: float, budget: int) -> float:
        """What a violation-free finish of a program pays (nothing in v0; see ``RewardSpec.finish_key``)."""
        return 0.0

    def reward_time_s(self, toolpath: Toolpath, t_nominal: float) -> float:
        """The time the reward's time term counts in (``τ = dt / this``): the program's nominal time."""
        return t_nominal

    def episode_slot(self, choice: int | ProgramLike) -> int:
        """The bank index of the episode's program (v0: the program, packed on first use)."""
        return self.program_slot(self._batch, choice)

    def draw_program(self, rng: np.random.Generator) -> int:
        """The episode's program index in the set: drawn with ``rng`` when there are several."""
        return int(rng.integers(len(self._programs))) if len(self._programs) > 1 else 0

    def _sync(self) -> None:
        """The current episode's program attributes."""
        program = self._batch.program(0)
        self.program_name: str = program.name
        self.toolpath: Toolpath = program.toolpath
        self.nominal_time_s: float = nominal_time_s(program.toolpath, self.machine)
        self.max_episode_steps: int = program.max_episode_steps

    @property
    def controller(self):
        """The controller of the current episode (a live view of the episode's state)."""
        return self._batch.controller(0)

    @property
    def meter(self):
        """The contour meter of the current program."""
        return self._batch.program(0).meter

    # ------------------------------------------------------------------------------------------ episode
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        choice = reset_choice(options)
        super().reset(seed=seed)
        if choice is None:
            choice = self.draw_program(self.np_random)
        slot = self.episode_slot(choice)  # (first: it may make the episode a batch of its own)
        self._batch.reset([0], [slot])
        self._needs_reset = False
        self._sync()
        if self._renderer is not None:
            self._renderer.start(self)
        return self._batch.observations[0].copy(), self._batch.info(0)

    # --------------------------------------------------------------------------------------------- step
    #: Whether the knob is computed from the action (v1's ``residual`` mode: :meth:`_residual_knob`).
    _residual = False

    def _parse_action(self, action: Any) -> float:
        """The knob value of an action (the step's; ActionError on a bad one)."""
        if self._needs_reset:
            raise EnvNotReset("FeedrateEnv: call reset() before step()")
        # The usual case first, at the cost of a few attribute reads: an array of shape (1,) of float32 or
        # float64 (the action space's dtype, or a policy's) holding a value in range.
        if type(action) is np.ndarray and action.shape == (1,) and (
                action.dtype is _FLOAT32 or action.dtype is _FLOAT64):  # fmt: skip
            knob = action.item()
            if not -1.0 <= knob <= 1.0:  # (NaN too)
                knob = parse_action(action)
        else:
            knob = parse_action(action)  # every other form, checked (cnc_gym/envs/options.py)
        return self._residual_knob(knob) if self._residual else knob

    def _residual_knob(self, action: float) -> float:
        """The knob of an action in [-1, 1] where :attr:`_residual` is set (none in v0)."""
        raise NotImplementedError

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        # One compiled call: controller, plant, contour error, statistics, reward, observation. The info is
        # a dict made when first used (engine.batch.StepInfo).
        result = self._batch.step_one(self._parse_action(action))
        if self._renderer is not None:
            self._renderer.record(*self._batch.last_samples(0)[:2])
        return result

    # ----------------------------------------------------------------------------------- whole episodes
    @property
    def compiled_episodes(self) -> bool:
        """Whether :meth:`run_rule` can run this env's episode: the LTI plant, stepped inside the compiled
        step; no renderer recording every step; the knob in ``override`` mode (v1's ``residual`` mode
        turns it in Python)."""
        return self._batch.fused and self._renderer is None and self.action_mode == "override"

    def run_rule(self, rule: KnobRule, max_steps: int, *, stop_time_s: float = math.inf,
                 columns: np.ndarray | None = None, rows: np.ndarray | None = None,
                 total: float = 0.0) -> tuple[int, float, int, bool, bool, dict[str, Any]]:  # fmt: skip
        """Up to ``max_steps`` steps under a deployable policy's knob rule in one compiled call
        (:meth:`FeedrateBatch.run_rule <cnc_gym.envs.engine.batch.FeedrateBatch.run_rule>`: the same steps
        as :meth:`step` with the actions the policy would give). Returns ``(steps, return, why,
        terminated, truncated, info)``: the steps run, ``total`` plus their rewards (added in order, so
        that chunks of an episode sum as one loop does), why it returned
        (:data:`~cnc_gym.envs.engine.episode.RAN` …), and the last step's flags and info. Needs
        :attr:`compiled_episodes`."""
        if self._needs_reset:
            raise EnvNotReset("FeedrateEnv: call reset() before run_rule()")
        if not self.compiled_episodes:
            raise ValueError("run_rule needs the LTI plant, no render mode and the override action mode")
        steps, total, why = self._batch.run_rule(rule, max_steps, stop_time_s=stop_time_s, columns=columns,
                                                 rows=rows, total=total)  # fmt: skip
        _, terminated, truncated, info = self._batch.outcome(0)
        return steps, total, why, terminated, truncated, info

    # ------------------------------------------------------------------------------------------ render
    def render(self) -> np.ndarray | None:
        if self.render_mode is None:
            gym.logger.warn("render() called with render_mode=None; pass render_mode='rgb_array'")
            return None
        assert self._renderer is not None  # built with render_mode "rgb_array"
        return self._renderer.draw(self)

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()


FeedrateEnv.__doc__ = (FeedrateEnv.__doc__ or "").replace(
    "{observation_table}", markdown_table(OBSERVATION_V0).replace("\n", "\n    "))
