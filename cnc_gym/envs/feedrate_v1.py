"""``cnc_gym/Feedrate-v1`` and ``-v2``: the feed-rate task with a return that ranks like the benchmark's score
(v2: with the programmed-path contour meter)."""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from gymnasium import spaces

from cnc_gym.config import Choice, Number, declared, number, parse_value, schema, section, spec_of
from cnc_gym.envs.engine import RewardSpec
from cnc_gym.envs.engine.layout import F_SIGNAL, SIG_PLANNER_OVERRIDE
from cnc_gym.envs.feedrate import FeedrateEnv
from cnc_gym.envs.observation import OBSERVATION_V1, ObservationLayout, markdown_table
from cnc_gym.envs.options import (
    ACTION_MODES,
    CONTROL_PERIOD,
    DEFAULT_ACTION_MODE,
    DEFAULT_CONTROL_PERIOD_S,
    DEFAULT_LOOKAHEAD_MM,
    DEFAULT_LOOKAHEAD_POINTS,
    DIALECT,
    MAX_EPISODE_STEPS,
    RENDER_MODES,
    WEIGHT_WHY,
    EnvArguments,
    MachineRef,
)
from cnc_gym.envs.planner_prior import PlannerPrior
from cnc_gym.envs.randomization import DomainRandomization, MachineDraw, draw_machine
from cnc_gym.errors import ConfigError
from cnc_gym.machine import DEFAULT_MACHINE, MachineConfig
from cnc_gym.plant import make_plant
from cnc_gym.programs import DEFAULT_DIALECT, ProgramLike
from cnc_gym.toolpath import Toolpath

#: Action modes of v1: v0's two, and ``residual`` (the agent scales the deployable planner's knob).
ACTION_MODES_V1 = (*ACTION_MODES, "residual")
#: Where v1's argument errors come from, in their messages.
SOURCE_V1 = "FeedrateEnv-v1"


@dataclass(frozen=True)
class RankingReward:
    """Weights of Feedrate-v1's reward (the class docstring of :class:`FeedrateEnvV1`). Any values in range
    keep the ranking rules: time and finish weights are positive, the others non-negative."""

    time: float = number(1.0, 0, 1e6, low_open=True, why=WEIGHT_WHY,
                         doc="w_time: the episode's time cost per nominal time (> 0: faster ranks higher)")
    progress: float = number(1.0, 0, 1e6, why=WEIGHT_WHY,
                             doc="w_progress: paid over the whole path, in proportion to progress")
    violation: float = number(10.0, 0, 1e6, why=WEIGHT_WHY,
                              doc="w_violation: per mm of path cut with contour error over tolerance")
    finish: float = number(1.0, 0, 1e6, low_open=True, why=WEIGHT_WHY,
                           doc="w_finish: paid, with the step budget's time, on a violation-free finish")


@dataclass(frozen=True)
class RelativeReward:
    """Weights of Feedrate-v6's reward (the ``relative`` rule; the class docstring of
    :class:`FeedrateEnvV1`): no finish bonus, so a violation-free episode's return is its time alone, per
    the deployable planner's scheduled time; feasibility is the cost's budget of 0
    (:data:`COST_BUDGET_MM`)."""

    time: float = number(1.0, 0, 1e6, low_open=True, why=WEIGHT_WHY,
                         doc="w_time: the episode's time cost per the planner's scheduled time (> 0: faster "
                         "ranks higher)")
    progress: float = number(1.0, 0, 1e6, low_open=True, why=WEIGHT_WHY,
                             doc="w_progress: paid over the whole path, in proportion to progress (> 0: a "
                             "finish outranks a truncation)")
    violation: float = number(10.0, 0, 1e6, why=WEIGHT_WHY,
                              doc="w_violation: per mm of path cut with contour error over tolerance (the "
                              "constraint's cost is that length, `info[\"cost\"]`)")


#: Each reward rule's weights record (:data:`REWARD_RULES`).
REWARD_RECORDS: dict[str, type] = {"ranking": RankingReward, "relative": RelativeReward}


#: The per-mm violation cost's budget of the constrained formulation (``info["cost"]``, summed over an
#: episode, is the episode's violation length in mm); the benchmark's feasibility is a budget of 0.
COST_BUDGET_MM = 0.0


MACHINE_V1 = MachineRef(doc="the machine (of every episode, or the centre of the randomisation)")
RESIDUAL_RANGE = Number(low=1, high=10, low_open=True, doc="residual mode: the override is the planner's "
                        "× residual_range^a", why="a factor above 1; 10 spans 0.1 to 10 times the "
                        "planner's override.")  # fmt: skip
PLANNER_VERSION_V1 = Number(low=1, high=3, integer=True, doc="the deployable planner's version behind the "
                            "`planner_override` entry and the residual mode: 1 (v1, v2; frozen), 2 (v3; "
                            "frozen), 3 (v4)",
                            why="the planner versions there are (motion.planner.PLANNERS).")  # fmt: skip
ACTION_MODE_V1 = Choice(choices=ACTION_MODES_V1, doc="what the action sets: the override knob, the feed, or "
                        "a factor on the deployable planner's override")
#: The reward's rules (:data:`REWARD_RECORDS`): what the time term counts in
#: (:meth:`FeedrateEnvV1.reward_time_s`) and what a violation-free finish pays (:meth:`~.finish_bonus`).
REWARD_RULES = tuple(REWARD_RECORDS)
REWARD_RULE = Choice(choices=REWARD_RULES, doc="the reward's rule: `ranking` (v1 to v5): time per nominal "
                     "time, and a violation-free finish pays w_time·N_max·τ + w_finish, so that it outranks "
                     "every violating or truncated episode; `relative` (v6): time per the deployable "
                     "planner's scheduled time, no finish bonus, feasibility the cost's zero "
                     "budget")  # fmt: skip


@dataclass(frozen=True)
class EnvArgumentsV1:
    """The keyword arguments of ``cnc_gym/Feedrate-v1``, checked."""

    programs: tuple[ProgramLike, ...] | None = declared(spec_of(EnvArguments, "programs"))
    dialect: str = declared(DIALECT, DEFAULT_DIALECT)
    machine: str | Path | MachineConfig = declared(MACHINE_V1, DEFAULT_MACHINE)  # noqa: RUF009
    action_mode: str = declared(ACTION_MODE_V1, DEFAULT_ACTION_MODE)
    control_period_s: float = declared(CONTROL_PERIOD, DEFAULT_CONTROL_PERIOD_S)
    reward: RankingReward | RelativeReward | None = section(  # noqa: RUF009
        RankingReward, optional=True, doc="reward weights: `RankingReward`'s under the `ranking` rule, "
        "`RelativeReward`'s (no `finish`) under `relative` (null: the defaults)")
    randomize: DomainRandomization | None = section(  # noqa: RUF009
        DomainRandomization, optional=True, doc="domain randomisation (null: off)")
    residual_range: float = declared(RESIDUAL_RANGE, 2.0)
    max_episode_steps: int | None = declared(MAX_EPISODE_STEPS)
    render_mode: str | None = declared(Choice(choices=RENDER_MODES, doc="`rgb_array` draws frames"))
    lookahead_mm: float = declared(spec_of(EnvArguments, "lookahead_mm"), DEFAULT_LOOKAHEAD_MM)
    lookahead_points: int = declared(spec_of(EnvArguments, "lookahead_points"), DEFAULT_LOOKAHEAD_POINTS)
    units: str | None = declared(spec_of(EnvArguments, "units"))
    setup: Any = declared(spec_of(EnvArguments, "setup"))  # noqa: RUF009
    plant: str | None = declared(spec_of(EnvArguments, "plant"))
    contour_rule: str = declared(spec_of(EnvArguments, "contour_rule"), "cuts")
    planner_version: int = declared(PLANNER_VERSION_V1, 1)
    controller_revision: int = declared(spec_of(EnvArguments, "controller_revision"), 1)
    reward_rule: str = declared(REWARD_RULE, "ranking")


def env_arguments_v1(**kwargs: Any) -> EnvArgumentsV1:
    """v1's keyword arguments checked against :class:`EnvArgumentsV1` (one ConfigError line)."""
    specs = schema(EnvArgumentsV1)
    unknown = sorted(set(kwargs) - set(specs))
    if unknown:
        raise ConfigError(f"{SOURCE_V1}: unknown argument {unknown[0]} (allowed: {', '.join(specs)})")
    values = {key: parse_value(specs[key], raw, SOURCE_V1, key) for key, raw in kwargs.items()
              if key != "reward"}  # fmt: skip
    if "reward" in kwargs:  # read into the weights record of the rule it belongs to
        record = REWARD_RECORDS[values.get("reward_rule", "ranking")]
        values["reward"] = parse_value(dataclasses.replace(specs["reward"], of=record), kwargs["reward"],
                                       SOURCE_V1, "reward")  # fmt: skip
    return EnvArgumentsV1(**values)


def reward_spec_v1(weights: RankingReward | RelativeReward) -> RewardSpec:
    """Feedrate-v1's reward, term by term, with the finish bonus under the ``ranking`` rule
    (:meth:`FeedrateEnvV1.finish_bonus`) and none under the ``relative`` rule (``weights`` a
    :class:`RelativeReward`); the terms and the bonus are in the info, and the cost is the step's violation
    length."""
    ranking = isinstance(weights, RankingReward)
    return RewardSpec((
        ("time_fraction", "linear", 0.0, -weights.time),
        ("progress_delta", "linear", 0.0, weights.progress),
        ("violation_length", "linear", 0.0, -weights.violation),
    ), term_keys=("reward_time", "reward_progress", "reward_violation"),
        finish_key="reward_finish" if ranking else None, cost="violation_length")  # fmt: skip


def scaled_feed(toolpath: Toolpath, factor: float) -> Toolpath:
    """``toolpath`` with every programmed feed × ``factor`` (the controller's clamps still apply)."""
    if factor == 1.0:
        return toolpath
    return dataclasses.replace(toolpath, feed=toolpath.feed * factor)


class FeedrateEnvV1(FeedrateEnv):
    r"""Feed-rate control on real G-code, with a return that ranks policies like the benchmark's score.

    The same machine, controller, servo plant and contour meter as ``cnc_gym/Feedrate-v0`` (one compiled
    step, :mod:`cnc_gym.envs.engine`); what changes is what the agent is paid for, what it sees, and what
    it may be trained on.

    ## Action Space

    ``Box(-1, 1, (1,), float32)``; values outside [-1, 1] are clipped, NaN/inf or a wrong shape raise
    :class:`ActionError`.

    | action_mode | meaning of a ∈ [-1, 1] |
    |---|---|
    | ``override`` (default) | override ``(a + 1) / 2 · max_override`` (v0's knob) |
    | ``feed`` | feed ``(a + 1) / 2 · max_feed_mm_min`` (replaces F) |
    | ``residual`` | override ``clip(ov_plan · ρ^a, 0, max_override)``, ``ρ = residual_range`` (default 2) |

    ``ov_plan`` is the deployable planner's override (the benchmark's ``classical`` baseline, which knows
    the program and the machine, never the env's dynamics): a = 0 is exactly the planner, a = ±1 twice
    or half its override.

    ## Observation Space

    ``Box(low, high, (14 + 4·N,), float32)`` with ``N = lookahead_points`` (default 8: 46 entries),
    declared once in :data:`cnc_gym.envs.observation.OBSERVATION_V1` (this table, the bounds, the scaling
    and :attr:`observation_structure` come from it). ``v_ref = max_feed_mm_min / 60``, ``a_ref`` the
    preset's largest axis acceleration, ``tol`` the contour tolerance, ``H = lookahead_mm``,
    ``ov_max = max_override``. Nothing identifies a position in a particular program.

    {observation_table}

    ## Rewards

    Per control step of ``dt``, with ``τ = dt / T_nominal`` (:func:`~cnc_gym.envs.feedrate.nominal_time_s`),
    ``Δp`` the path progress in the step (a fraction of the program's length) and ``ℓ`` the path length
    (mm) the reference advanced over the step's servo samples with contour error above ``tol``:

    .. math::

        r = - w_\text{{time}} τ + w_\text{{progress}} Δp - w_\text{{violation}} ℓ
            + [\text{{finished with no violation}}] (w_\text{{time}} N_\text{{max}} τ + w_\text{{finish}})

    The last term is paid once, on the step that finishes the program, when the episode's violation
    length is 0 (``N_max`` = the step budget). The undiscounted return of an episode of ``n`` steps is
    ``w_progress·p − w_time·n·τ − w_violation·L_viol`` plus the bonus, so on one program:

    - a finished, violation-free episode always has a higher return than one with violations or one that
      is truncated (the bonus exceeds any time difference, since ``n ≤ N_max``);
    - among violation-free episodes, the faster one wins (``−w_time·n·τ``);
    - error inside the tolerance costs nothing (the score does not penalise it either);
    - ``ℓ`` and the time are measured per path length and per second: the control period changes neither.

    This is the benchmark's primary score's order (docs/benchmark.md); ``tests/envs/test_feedrate_v1.py``
    checks it on episodes of known outcome. Weights (:class:`RankingReward`): ``w_time = 1``,
    ``w_progress = 1``, ``w_violation = 10`` per mm, ``w_finish = 1``. The terms are in ``info``
    (``reward_time``, ``reward_progress``, ``reward_violation``, ``reward_finish``).

    **v6** (``reward_rule="relative"``): the same terms with ``τ = dt / T_plan``, ``T_plan`` the deployable
    planner's scheduled time of the program on the episode's machine plus its dwells
    (:meth:`reward_time_s`), and no finish bonus. Violation-free finishes rank by time as above, every
    finish outranks a truncation, and a policy at the planner's pace earns about ``w_progress − w_time`` on
    every program, so the time a policy saves is most of the return's spread; feasibility is the cost's
    budget of 0, not part of the return's order. Weights: :class:`RelativeReward` (no ``w_finish``, no
    ``reward_finish`` in the info).

    **Cost** (constrained RL, Safety-Gymnasium's convention): ``info["cost"] = ℓ``, the step's violation
    length in mm, so an episode's cost is its ``violation_length_mm``; the budget is
    ``COST_BUDGET_MM = 0`` (the benchmark's feasibility); ``agents/training.py``'s PPO-Lagrangian takes it
    as ``cost_limit`` (0 in ``configs/train/ppo-lagrangian-residual-v6.yaml``).

    ## Starting State

    As v0: the machine at rest at the program's start, override 100 %. With ``randomize`` enabled, each
    reset also draws the episode's machine (Kv level and axis mismatch, feed-forward, acceleration
    limits) and a feed scale (:mod:`cnc_gym.envs.randomization`) with the env's generator.

    ## Episode End

    As v0: termination when the program has finished and the axes are in position; truncation after the
    step budget (5 × ``T_nominal`` / ``dt`` plus one second, or ``max_episode_steps``).

    ## Arguments

    v0's (``programs``, ``dialect``, ``machine``, ``control_period_s``, ``max_episode_steps``,
    ``render_mode``, ``lookahead_mm``, ``lookahead_points``, ``units``, ``setup``, ``plant``,
    ``contour_rule``: ``"cuts"`` for v1, ``"path"`` for v2 and v3), and ``action_mode``
    (with ``residual``),
    ``reward`` (:class:`RankingReward` or a dict of its weights), ``randomize``
    (:class:`~cnc_gym.envs.randomization.DomainRandomization` or a dict; None: off, as in the benchmark),
    ``residual_range``, ``planner_version`` (the deployable planner behind ``planner_override`` and the
    ``residual`` mode: 1 for v1 and v2, 2 for v3, 3 for v4; :data:`cnc_gym.motion.planner.PLANNERS`).
    ``reset(seed=..., options={{"program": ...}})`` as v0.

    ## Info

    v0's keys (``cost`` is now the violation length of the step, mm), the reward terms, and
    ``planner_override`` (the planner's override for the next step).

    ## Version History

    - v6: v5 with the ``relative`` reward rule (above): time per the planner's scheduled time, no finish
      bonus. Dynamics, observation, action and cost are v5's. The version to train on with a reward.
    - v5: v4 on the controller's revision 2 (no overshoot where the override is lowered during an
      acceleration). Observation, reward and planner are v4's.
    - v4: v3 with the live deployable planner, version 3 (``planner_version=3``): the ``planner_override``
      observation entry and info key, and the knob the ``residual`` mode scales, are the ``classical``
      baseline's of today (faster than version 2 at the same feasibility: docs/benchmark.md). Dynamics,
      reward and the other entries are v2's.
    - v3: v2 with the deployable planner version 2 (``planner_version=2``, now frozen bit for bit), which
      holds the contour tolerance on the test split of ``cnc-bench-v1``. Dynamics, reward and the other
      entries are v2's. v1 and v2 keep planner version 1, frozen bit for bit, so that their published
      results and the models trained on them reproduce.
    - v2: v1 with the programmed-path contour meter (``contour_rule="path"``): the rapids the reference
      has left are part of the path the tool is measured against, so the in-position residual at a
      rapid → cut junction (about 4 µm on vmc-small, at every cut that follows a rapid) is no longer
      contour error; everywhere else the error, and so the reward, cost and observation, are v1's.
      Dynamics unchanged (docs/plant.md, "Contour error at a rapid → cut
      junction").
    - v1: reward that ranks like the benchmark's score (violations per path length, finish bonus, no
      penalty inside the tolerance); observation without program position, with the machine's parameters
      and the deployable planner's override; ``residual`` action mode; domain randomisation. Registered
      with ``contour_rule="cuts"`` (the meter it was published with). The models in docs/results/models
      were trained on v1.
    - v0: first version (kept as it was; docs/env.md).
    """

    def __init__(
        self,
        programs: Sequence[ProgramLike] | ProgramLike | None = None,
        dialect: str = DEFAULT_DIALECT,
        machine: str | Path | MachineConfig = DEFAULT_MACHINE,
        action_mode: str = DEFAULT_ACTION_MODE,
        control_period_s: float = DEFAULT_CONTROL_PERIOD_S,
        reward: dict | RankingReward | None = None,
        randomize: dict | DomainRandomization | None = None,
        residual_range: float = 2.0,
        max_episode_steps: int | None = None,
        render_mode: str | None = None,
        lookahead_mm: float = DEFAULT_LOOKAHEAD_MM,
        lookahead_points: int = DEFAULT_LOOKAHEAD_POINTS,
        units: str | None = None,
        plant: str | None = None,
        contour_rule: str = "cuts",
        setup: Any = None,
        planner_version: int = 1,
        controller_revision: int = 1,
        reward_rule: str = "ranking",
    ) -> None:
        args = env_arguments_v1(programs=programs, dialect=dialect, machine=machine, action_mode=action_mode,
                                control_period_s=control_period_s, reward=reward, randomize=randomize,
                                residual_range=residual_range, max_episode_steps=max_episode_steps,
                                render_mode=render_mode, lookahead_mm=lookahead_mm,
                                lookahead_points=lookahead_points, units=units, plant=plant,
                                contour_rule=contour_rule, setup=setup,
                                planner_version=planner_version,
                                controller_revision=controller_revision,
                                reward_rule=reward_rule)  # fmt: skip
        self._configure(args)
        self.base_machine = self.machine
        self.reward_rule = args.reward_rule
        weights = args.reward or REWARD_RECORDS[self.reward_rule]()
        self.reward_weights: RankingReward | RelativeReward = weights
        self.randomize = args.randomize or DomainRandomization()
        self.residual_range = float(args.residual_range)
        self._residual = self.action_mode == "residual"
        if self.randomize.enabled:
            problem = self.randomize.stability_problem(self.machine)
            if problem:
                raise ConfigError(f"{SOURCE_V1}: randomize: {problem}")
            # The contour window reaches back over the largest lag any draw can have.
            lowest = min(self.machine.axis_array("kv_1_s")) * self.randomize.kv_scale[0] * (
                1.0 - self.randomize.kv_mismatch[1])  # fmt: skip
            self._max_lag_mm = self._v_ref / lowest
        self.layout = ObservationLayout(OBSERVATION_V1, self.lookahead_points, {
            "v_ref": self._v_ref, "a_ref": self._a_ref, "tol": self.tolerance_mm, "H": self.lookahead_mm,
            "ov_max": self.max_override})  # fmt: skip
        self._obs_spec = self.layout.kernel_spec
        self._reward_spec = reward_spec_v1(self.reward_weights)
        self.observation_space = spaces.Box(self.layout.low, self.layout.high, dtype=np.float32)
        #: Entry name → indices in the observation (as Gymnasium's MuJoCo envs' observation_structure).
        self.observation_structure = {name: idx.tolist() for name, idx in self.layout.structure.items()}
        self.planner_version = int(args.planner_version)
        self._planner = PlannerPrior(self.control_period_s, self.max_override, self.planner_version)
        #: The current episode's machine draw and feed scale (None and 1 without randomisation).
        self.episode_draw: MachineDraw | None = None
        self.feed_scale = 1.0
        self._pool: list[tuple[MachineDraw, Any] | None] = [None] * self.randomize.machines
        self._start()

    def finish_bonus(self, t_nominal: float, budget: int) -> float:
        """The finish bonus of a program (the class docstring): ``w_time · N_max · τ + w_finish`` under the
        ``ranking`` rule, none under the ``relative`` rule."""
        w = self.reward_weights
        if not isinstance(w, RankingReward):  # the relative rule's record (REWARD_RECORDS)
            return 0.0
        return w.time * budget * self.control_period_s / max(t_nominal, 1e-12) + w.finish

    def reward_time_s(self, toolpath: Toolpath, t_nominal: float) -> float:
        """The time the reward's time term counts in (the class docstring): ``T_nominal`` under the
        ``ranking`` rule; under ``relative`` ``T_plan``, the deployable planner's scheduled time of the
        program on the episode's machine (as it plans: :meth:`plan_on`) plus its dwells, never below a
        tenth of ``T_nominal``. The schedule is the one the planner entries and ``residual`` mode use
        (planned once, recalled when the program is packed)."""
        if isinstance(self.reward_weights, RankingReward):  # the ranking rule's record (REWARD_RECORDS)
            return t_nominal
        schedule = self._planner.schedule(toolpath, self.machine, None)
        return max(schedule.time_s + float(np.sum(toolpath.dwell_s)), 0.1 * t_nominal)

    @property
    def planner_override(self) -> float:
        """The deployable planner's override for the next step (``info["planner_override"]``)."""
        return float(self._batch.state_f[0, F_SIGNAL + SIG_PLANNER_OVERRIDE])

    # ------------------------------------------------------------------------------------------ episode
    def episode_slot(self, choice: int | ProgramLike) -> int:
        """The bank index of the episode's program; with randomisation, the episode's machine is drawn
        and the program packed on it with a feed scale of its own."""
        if self.randomize.enabled:
            name, toolpath = self.resolve_program(choice)
            k = int(self.np_random.integers(len(self._pool)))
            if self._pool[k] is None:
                draw = draw_machine(self.base_machine, self.randomize, self.np_random)
                self._pool[k] = (draw, make_plant(draw.machine, n_envs=1))
            self.episode_draw, plant = self._pool[k]  # type: ignore[misc]
            self.feed_scale = float(self.np_random.uniform(*self.randomize.feed_scale))
            self.machine = self.episode_draw.machine
            # The episode's engine: the machine's plant, the program packed with its controller tables.
            self._batch = self.make_batch(1, plant=plant)
            self.plant = plant
            return self.pack_program(self._batch, name, scaled_feed(toolpath, self.feed_scale))
        return self.program_slot(self._batch, choice)

    def plan_on(self, machine: MachineConfig | None) -> None:
        """The deployable planner behind the planner entries and ``residual`` mode plans with ``machine``
        from the next reset on (None: with the env's own). The benchmark's tracks whose plant differs from
        the machine's parameter table give it the nominal machine, as they give the ``classical`` policy.
        The engine is rebuilt (its programs were packed with the old schedules): call it before a reset."""
        if machine is not self._planner.nominal_machine:
            self._planner.nominal_machine = machine
            self._start()

    # --------------------------------------------------------------------------------------------- step
    def _residual_knob(self, action: float) -> float:
        """``residual`` mode: the knob asking for the planner's override × ``residual_range^a``."""
        override = min(max(self.planner_override * self.residual_range**action, 0.0), self.max_override)
        return self._planner.knob(override)


FeedrateEnvV1.__doc__ = (FeedrateEnvV1.__doc__ or "").replace(
    "{observation_table}", markdown_table().replace("\n", "\n    ")).replace("{{", "{").replace("}}", "}")


__all__ = ["ACTION_MODES_V1", "COST_BUDGET_MM", "REWARD_RECORDS", "REWARD_RULES", "EnvArgumentsV1",
           "FeedrateEnvV1", "RankingReward", "RelativeReward", "env_arguments_v1", "reward_spec_v1",
           "scaled_feed"]
