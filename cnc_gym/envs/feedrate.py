"""``cnc_gym/Feedrate-v0``: learn the feed-override knob of a CNC controller running a real G-code program."""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from numba import njit

from cnc_gym.envs.options import EnvNotReset, control_ticks, env_arguments, parse_action, reset_choice
from cnc_gym.envs.task import RewardWeights, load_task, resolve_reward
from cnc_gym.errors import ConfigError
from cnc_gym.machine import MachineConfig, load_machine, with_plant_backend
from cnc_gym.motion import ActionError  # noqa: F401  (one error type for bad actions, env and controller alike)
from cnc_gym.motion import kernel as _kernel
from cnc_gym.programs import PROGRAM_TYPES, ProgramLike, load_program
from cnc_gym.toolpath import SegmentKind, Toolpath

# Columns of the controller's rows (Controller.advance_rows) the step reads.
_O_X, _O_Z1, _O_SEG, _O_S = _kernel.O_X, _kernel.O_Z + 1, _kernel.O_SEG, _kernel.O_S

#: Scalar observation entries, in order (the look-ahead block follows them).
SCALAR_FEATURES = (
    "speed",
    "accel",
    "override",
    "knob",
    "following_error",
    "contour_error_step",
    "contour_error_now",
    "progress",
    "distance_to_stop",
)
#: Per-point look-ahead entries; each is a block of ``lookahead_points`` values.
LOOKAHEAD_FEATURES = ("speed_limit", "curvature", "turn_angle", "programmed_feed")

# Normalisation constants (documented in the class docstring).
_CURVATURE_LENGTH_MM = 10.0  # curvature κ is observed as κL/(1 + κL): R 50 mm → 0.17, R 1 mm → 0.91
_FOLLOWING_ERROR_REF_MM = 1.0


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


@njit(cache=True, nogil=True)
def _error_statistics(error, reference, actual):
    """``(max, sum of squares, last)`` of a step's contour errors and the last sample's following error
    ‖reference − actual‖."""
    e_max = 0.0
    sum_sq = 0.0
    for e in error:
        sum_sq += e * e
        if e > e_max:
            e_max = e
    dx = reference[-1, 0] - actual[-1, 0]
    dy = reference[-1, 1] - actual[-1, 1]
    dz = reference[-1, 2] - actual[-1, 2]
    return e_max, sum_sq, error[-1], math.sqrt(dx * dx + dy * dy + dz * dz)


@njit(cache=True, nogil=True)
def _assemble_observation(raw, speed_limit, curvature, turn_angle, feed, scale, low, high):
    """The observation: ``raw`` scalars (9) then the four look-ahead blocks, times ``scale``, clipped.

    Curvature κ enters as κL/(1 + κL) (L = _CURVATURE_LENGTH_MM); NaN from upstream becomes 0 (a NaN
    would poison a policy).
    """
    n = speed_limit.shape[0]
    base = raw.shape[0]
    obs = np.empty(base + 4 * n, dtype=np.float32)
    for i in range(base + 4 * n):
        if i < base:
            x = raw[i]
        elif i < base + n:
            x = speed_limit[i - base]
        elif i < base + 2 * n:
            kl = curvature[i - base - n] * _CURVATURE_LENGTH_MM
            x = kl / (kl + 1.0)
        elif i < base + 3 * n:
            x = turn_angle[i - base - 2 * n]
        else:
            x = feed[i - base - 3 * n]
        x *= scale[i]
        if x != x:
            x = 0.0
        obs[i] = min(max(x, low[i]), high[i])
    return obs


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
    ``lookahead_mm`` (default 24 mm), ``L_k`` = 10 mm.

    | index | observation | formula | range |
    |---|---|---|---|
    | 0 | path speed | ``v / v_ref`` | [0, 2] |
    | 1 | path acceleration | ``a / a_ref`` | [-2, 2] |
    | 2 | applied override | ``override / max_override`` | [0, 1] |
    | 3 | last action (knob) | ``a`` | [-1, 1] |
    | 4 | following error | ``‖reference − actual‖ / 1 mm`` | [0, 5] |
    | 5 | contour error, max over the last step | ``e_max / tol`` | [0, 5] |
    | 6 | contour error, last servo sample | ``e / tol`` | [0, 5] |
    | 7 | progress | ``s / L`` (path length done) | [0, 1] |
    | 8 | distance to the next stop | ``min(d_stop / H, 1)`` | [0, 1] |
    | 9 … 8+N | speed limit ahead | controller's limit at N points over the next H mm, ``/ v_ref`` | [0, 2] |
    | 9+N … 8+2N | curvature ahead | ``κ L_k / (1 + κ L_k)`` | [0, 1] |
    | 9+2N … 8+3N | turning angle ahead | ``θ / π``, the largest junction turn in each bin | [0, 1] |
    | 9+3N … 8+4N | programmed feed ahead | ``F / 60 / v_ref`` | [0, 2] |

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
    dialect's; an interpreted ``Program`` keeps the unit it was read in), ``action_mode``,
    ``control_period_s`` (a multiple of the interpolation period), ``reward`` (None, a task YAML path or a
    dict of weights), ``max_episode_steps``, ``render_mode`` (None or ``"rgb_array"``), ``lookahead_mm``,
    ``lookahead_points``, ``plant`` (``"lti"`` or ``"mujoco"``: the servo plant, overriding the machine
    preset's ``plant.backend``; see docs/plant.md). ``reset(seed=..., options={"program":
    name_or_index})``: with several programs the episode's program is drawn with ``self.np_random``; the
    option picks one (a name not in the set is loaded for that episode).

    ## Info

    ``cycle_time_s``, ``contour_error_mm`` (max in this step), ``contour_error_max_mm``,
    ``contour_error_rms_mm`` (over cutting samples so far), ``tolerance_mm``, ``violations`` (control
    steps so far with ``e_max > tol``), ``violation_length_mm`` and ``violation_time_s`` (path length
    the reference advanced, and time, over the servo samples with contour error above ``tol``: these do
    not depend on the control period), ``cost``, ``line`` (source line of the current block),
    ``override`` (applied), ``feed_mm_min`` (current path speed × 60), ``path_s``, ``progress``,
    ``program``, ``steps``. At the end of an episode these are the episode's totals.

    ## Version History

    - v0: first version.
    """

    metadata: ClassVar[dict[str, Any]] = {"render_modes": ["rgb_array"], "render_fps": 50}

    def __init__(
        self,
        programs: Sequence[ProgramLike] | ProgramLike | None = None,
        dialect: str = "gsk25i",
        machine: str | Path | MachineConfig = "vmc-small",
        action_mode: str = "override",
        control_period_s: float = 0.01,
        reward: str | Path | dict | RewardWeights | None = None,
        max_episode_steps: int | None = None,
        render_mode: str | None = None,
        lookahead_mm: float = 24.0,
        lookahead_points: int = 8,
        units: str | None = None,
        plant: str | None = None,
    ) -> None:
        from cnc_gym.motion import Controller
        from cnc_gym.plant import ContourErrorMeter, make_plant

        self._controller_cls = Controller
        self._meter_cls = ContourErrorMeter
        # Every argument checked once, against one schema (cnc_gym/envs/options.py).
        args = env_arguments(programs=programs, dialect=dialect, machine=machine, action_mode=action_mode,
                             control_period_s=control_period_s, reward=reward,
                             max_episode_steps=max_episode_steps, render_mode=render_mode,
                             lookahead_mm=lookahead_mm, lookahead_points=lookahead_points,
                             units=units, plant=plant)  # fmt: skip
        self.machine: MachineConfig = with_plant_backend(load_machine(args.machine), args.plant)
        self.action_mode = args.action_mode
        self.render_mode = args.render_mode
        self.dialect = args.dialect
        self.units = args.units
        self.reward_weights = resolve_reward(args.reward)
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
            load_program(p, dialect, self.machine, units=self.units) for p in programs
        ]
        self._episode_cache: dict[str, dict[str, Any]] = {}
        self.program_names = [name for name, _ in self._programs]

        self.plant = make_plant(self.machine, n_envs=1)  # the preset's backend, or plant=

        # Spaces.
        self.action_space = spaces.Box(-1.0, 1.0, shape=(1,), dtype=np.float32)
        n = self.lookahead_points
        low = np.array([0, -2, 0, -1, 0, 0, 0, 0, 0] + [0] * (4 * n), dtype=np.float32)
        high = np.array([2, 2, 1, 1, 5, 5, 5, 1, 1] + [2] * n + [1] * n + [1] * n + [2] * n, dtype=np.float32)
        self.observation_space = spaces.Box(low, high, dtype=np.float32)
        self._raw = np.zeros(len(SCALAR_FEATURES))
        base = len(SCALAR_FEATURES)
        self._la_blocks = [slice(base + i * n, base + (i + 1) * n) for i in range(len(LOOKAHEAD_FEATURES))]
        scale = np.ones(len(low))
        tol = self.tolerance_mm
        scale[:9] = [1 / self._v_ref, 1 / self._a_ref, 1 / self.max_override, 1.0,
                     1 / _FOLLOWING_ERROR_REF_MM, 1 / tol, 1 / tol, 1.0, 1 / self.lookahead_mm]  # fmt: skip
        scale[self._la_blocks[0]] = 1 / self._v_ref
        scale[self._la_blocks[2]] = 1 / math.pi
        scale[self._la_blocks[3]] = 1 / self._v_ref
        self._obs_scale = scale  # entry 7 (progress) is set per program: 1 / path length
        self._obs_low, self._obs_high = low.astype(np.float64), high.astype(np.float64)

        # Per-tick buffers for the settle phase after the controller has finished.
        self._settle_reference = np.zeros((self.ticks_per_step, 3))
        self._renderer = None
        if render_mode == "rgb_array":
            from cnc_gym.envs.render import EpisodeRenderer, MachineRenderer

            # Records per step; draws on render(): MuJoCo's picture of the machine on the MuJoCo plant.
            if self.machine.plant.backend == "mujoco":
                self._renderer = MachineRenderer(self.tolerance_mm, self.plant)
            else:
                self._renderer = EpisodeRenderer(self.tolerance_mm)
        self._select(0)
        self._reset_stats()

    # ------------------------------------------------------------------------------------------ episode
    def _episode_objects(self, name: str, toolpath: Toolpath) -> dict[str, Any]:
        """Controller, meter and nominal time of a program (built once, reused by every reset)."""
        key = f"{name}:{id(toolpath)}"
        objects = self._episode_cache.get(key)
        if objects is None:
            t_nominal = nominal_time_s(toolpath, self.machine)
            budget = self._max_episode_steps_arg or (
                math.ceil(5.0 * t_nominal / self.control_period_s) + math.ceil(1.0 / self.control_period_s)
            )
            kind = toolpath.kind
            objects = {
                "controller": self._controller_cls(toolpath, self.machine),
                # The window reaches back over the largest possible lag (max feed / Kv) so that on
                # short-segment programs the actual point is never measured against the wrong segment.
                "meter": self._meter_cls(toolpath, window_back_mm=self._max_lag_mm),
                "nominal_time_s": t_nominal,
                "max_episode_steps": int(budget),
                "cutting": (kind == SegmentKind.LINE)
                | (kind == SegmentKind.ARC)
                | (kind == SegmentKind.NURBS),
                "start": toolpath.start[0].copy() if len(toolpath) else np.zeros(3),
                "lines": [int(x) for x in toolpath.line],
            }
            self._episode_cache[key] = objects
        return objects

    def _select(self, index_or_name: int | str) -> None:
        if isinstance(index_or_name, int | np.integer) and not isinstance(index_or_name, bool):
            if not 0 <= index_or_name < len(self._programs):
                raise ConfigError(f"program index {index_or_name} out of range 0..{len(self._programs) - 1}")
            name, toolpath = self._programs[int(index_or_name)]
        elif isinstance(index_or_name, PROGRAM_TYPES):
            found = [p for p in self._programs if p[0] == index_or_name]
            name, toolpath = found[0] if found else load_program(index_or_name, self.dialect, self.machine,
                                                                 units=self.units)  # fmt: skip
        else:
            raise ConfigError(
                f"options['program'] must be a name, path, text or index, got {index_or_name!r}"
            )
        objects = self._episode_objects(name, toolpath)
        self.program_name: str = name
        self.toolpath: Toolpath = toolpath
        self.controller = objects["controller"]
        self.meter = objects["meter"]
        self.nominal_time_s: float = objects["nominal_time_s"]
        self.max_episode_steps: int = objects["max_episode_steps"]
        self._cutting_segments: np.ndarray = objects["cutting"]
        self._start = objects["start"]
        self._total_length = max(toolpath.total_length, 1e-9)
        self._source_lines: list[int] = objects["lines"]
        self._obs_scale[7] = 1.0 / self._total_length
        self._time_reward = self.reward_weights.time * self.control_period_s / self.nominal_time_s

    def _reset_stats(self) -> None:
        self._steps = 0
        self._ticks = 0
        self._error_max_mm = 0.0
        self._error_sq_sum = 0.0
        self._error_samples = 0
        self._violations = 0
        self._violation_length_mm = 0.0
        self._violation_time_s = 0.0
        self._last_path_s = self.controller.path_s
        self._knob = 0.0
        self._last_segment = 0
        self._last_reference = self._start
        self._last_error_step = 0.0
        self._last_error_now = 0.0
        self._following_error_mm = 0.0
        self._progress = 0.0
        if self._renderer is not None:
            self._renderer.clear()

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        choice = reset_choice(options)
        super().reset(seed=seed)
        self._needs_reset = False
        if choice is None:
            choice = int(self.np_random.integers(len(self._programs))) if len(self._programs) > 1 else 0
        self._select(choice)
        self.controller.reset()
        self.meter.reset()
        self.plant.reset(self._start[None, :])
        self._reset_stats()
        self._progress = self._path_progress()
        if self._renderer is not None:
            self._renderer.start(self)
        return self._observe(), self._info(0.0, 0.0)

    # --------------------------------------------------------------------------------------------- step
    def _parse_action(self, action: Any) -> float:
        if self._needs_reset:
            raise EnvNotReset("FeedrateEnv: call reset() before step()")
        if type(action) is np.ndarray and action.shape == (1,) and action.dtype.kind == "f":  # usual case
            knob = float(action[0])
            if math.isfinite(knob):
                return min(max(knob, -1.0), 1.0)
        return parse_action(action)  # every other form, checked (cnc_gym/envs/options.py)

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        knob = self._parse_action(action)
        self._knob = knob
        if not len(self.toolpath):  # a program without motion (only M30, or empty): done at once, in 0 s
            self._steps += 1
            return self._observe(), 0.0, True, False, self._info(0.0, 0.0)
        controller = self.controller
        n = self.ticks_per_step
        if not controller.finished:
            # The kernel's rows, not a MotionChunk: the step needs only positions and segments.
            if self.action_mode == "override":
                rows = controller.advance_rows(n, override=(knob + 1.0) * 0.5 * self.max_override)
            else:
                rows = controller.advance_rows(n, feed_mm_min=(knob + 1.0) * 0.5 * self.max_feed_mm_min)
            reference = rows[:, _O_X:_O_Z1]
            segment = rows[:, _O_SEG].astype(np.int64)
            path_s = rows[:, _O_S]
            if len(reference) < n:  # the program ended inside this step: hold the end point
                reference = np.concatenate((reference, np.repeat(reference[-1:], n - len(reference), axis=0)))
                segment = np.concatenate((segment, np.repeat(segment[-1:], n - len(segment))))
                path_s = np.concatenate((path_s, np.repeat(path_s[-1:], n - len(path_s))))
            self._last_segment = int(segment[-1])
            self._last_reference = reference[-1]
        else:  # settling at the end: the reference rests at the last point
            reference = self._settle_reference
            reference[:] = self._last_reference
            segment = np.full(n, self._last_segment)
            path_s = None
        actual = self.plant.step(reference[None])[0]
        # In-position check (P1471), sampled once per control step: the controller holds the reference on
        # an exact stop, a rapid end or start, or the program end until the servo is settled there.
        if controller.waiting_in_position and self.plant.settled(self.in_position_mm)[0]:
            controller.release_in_position()
        # The reference only moves forward, so equal first and last segments mean one segment for the whole
        # step: the meter's scalar-hint path (same window, same result) skips the per-sample bookkeeping.
        first_segment = int(segment[0])
        one_segment = first_segment == int(segment[-1])
        error = self.meter.measure(actual, first_segment if one_segment else segment)
        self._ticks += n
        self._steps += 1

        e_max, sum_sq, e_now, self._following_error_mm = _error_statistics(error, reference, actual)
        # The meter returns 0 where the reference is on a rapid or dwell, so the sum of squares over all
        # samples is the sum over cutting samples; only the count needs the cutting mask.
        if one_segment:
            n_cut = n if self._cutting_segments[first_segment] else 0
        else:
            n_cut = int(np.count_nonzero(self._cutting_segments[segment]))
        if n_cut:
            self._error_sq_sum += sum_sq
            self._error_samples += n_cut
        if e_max > self._error_max_mm:
            self._error_max_mm = e_max
        violated = e_max > self.tolerance_mm
        self._violations += violated
        if violated:  # per servo sample: the reference's path advance and time while over tolerance
            over = error > self.tolerance_mm
            if path_s is not None:
                advance = np.diff(path_s, prepend=self._last_path_s)
                self._violation_length_mm += float(np.sum(advance[over]))
            self._violation_time_s += int(np.count_nonzero(over)) * self.interpolation_period_s
        if path_s is not None:
            self._last_path_s = float(path_s[-1])
        self._last_error_step = e_max
        self._last_error_now = e_now

        w = self.reward_weights
        ratio = min(e_max / self.tolerance_mm, w.error_ratio_cap)
        finished = controller.finished
        progress = 1.0 if finished else min(controller.path_s / self._total_length, 1.0)  # _path_progress
        reward = (
            w.progress * (progress - self._progress)
            - self._time_reward
            - w.contour_error * ratio * ratio
            - (w.violation if violated else 0.0)
        )
        self._progress = progress

        terminated = finished and bool(self.plant.settled(self.in_position_mm)[0])
        truncated = (not terminated) and self._steps >= self.max_episode_steps
        if self._renderer is not None:
            self._renderer.record(actual, error)
        return self._observe(), reward, terminated, truncated, self._info(e_max, 1.0 if violated else 0.0)

    def _path_progress(self) -> float:
        """``p = min(s / L, 1)``, and exactly 1 once the controller has finished the program."""
        if self.controller.finished:
            return 1.0
        return min(self.controller.path_s / self._total_length, 1.0)

    # ------------------------------------------------------------------------------------ observations
    def _observe(self) -> np.ndarray:
        # The nine scalars into a preallocated buffer; one compiled call scales, clips and appends the
        # look-ahead blocks (one numpy ufunc each cost more than the whole call).
        raw = self._raw
        controller = self.controller
        # (speed limit, curvature, turn angle, feed, [distance to stop]) rows; arguments checked in __init__
        ahead = controller.lookahead_rows(self._lookahead_horizon, self.lookahead_points)
        raw[0] = controller.speed
        raw[1] = controller.accel
        raw[2] = controller.override_applied
        raw[3] = self._knob
        raw[4] = self._following_error_mm
        raw[5] = self._last_error_step
        raw[6] = self._last_error_now
        raw[7] = controller.path_s
        raw[8] = ahead[4, 0]
        return _assemble_observation(raw, ahead[0], ahead[1], ahead[2], ahead[3], self._obs_scale,
                                     self._obs_low, self._obs_high)  # fmt: skip

    def _info(self, step_error_mm: float, cost: float) -> dict[str, Any]:
        controller = self.controller
        segment = min(max(controller.segment_index, 0), len(self._source_lines) - 1)
        rms = math.sqrt(self._error_sq_sum / self._error_samples) if self._error_samples else 0.0
        path_s = controller.path_s
        return {
            "cycle_time_s": self._ticks * self.interpolation_period_s,
            "contour_error_mm": step_error_mm,
            "contour_error_max_mm": self._error_max_mm,
            "contour_error_rms_mm": rms,
            "tolerance_mm": self.tolerance_mm,
            "violations": self._violations,
            "violation_length_mm": self._violation_length_mm,
            "violation_time_s": self._violation_time_s,
            "cost": cost,
            "line": self._source_lines[segment] if self._source_lines else 0,
            "override": controller.override_applied,
            "feed_mm_min": controller.speed * 60.0,
            "path_s": path_s,
            "progress": self._progress,
            "program": self.program_name,
            "steps": self._steps,
        }

    # ------------------------------------------------------------------------------------------ render
    def render(self) -> np.ndarray | None:
        if self.render_mode is None:
            gym.logger.warn("render() called with render_mode=None; pass render_mode='rgb_array'")
            return None
        return self._renderer.draw(self)

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
