"""SB3 training helpers: the validated training config and the PPO / PPO-Lagrangian training loop.

``scripts/train.py`` and ``scripts/evaluate.py`` are thin entry points over these. A config is YAML read
with the bounded safe loader of :mod:`cnc_gym.config`; every key is declared below with its type and
range (docs/configs.md's key tables are written from these declarations), and the ``env:`` keys share
their specs with the envs' own arguments (:mod:`cnc_gym.envs.options`, :mod:`cnc_gym.envs.feedrate_v1`,
:mod:`cnc_gym.envs.randomization`). Unknown keys, wrong types, out-of-range values and keys that do not
belong to the chosen env version are one :class:`~cnc_gym.errors.ConfigError` line naming the file and
the key. See ``configs/train/``.

Programs may be named one by one (built-in names, ``.nc`` paths) or as a split of a benchmark suite,
``suite:<name>/<split>`` (e.g. ``suite:cnc-bench-v1/train``); a suite's ``test`` split is refused, so a
training config cannot train on the programs the result is reported on.
"""

from __future__ import annotations

import dataclasses
import tempfile
import time
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

from cnc_gym import ENV_IDS as REGISTERED_ENV_IDS
from cnc_gym.config import (
    Choice,
    Number,
    check_object,
    configs_dir,
    declared,
    flag,
    from_mapping,
    items,
    number,
    parse_value,
    parse_yaml,
    read_yaml,
    section,
    shown,
    spec_of,
    text,
)
from cnc_gym.envs.feedrate_v1 import ACTION_MODE_V1, RESIDUAL_RANGE, RankingReward, RelativeReward
from cnc_gym.envs.options import (
    CONTROL_PERIOD,
    DEFAULT_ACTION_MODE,
    DEFAULT_CONTROL_PERIOD_S,
    DIALECT,
    MACHINE_NAME,
    MAX_EPISODE_STEPS,
    PROGRAM_NAMES,
    RewardWeights,
)
from cnc_gym.envs.randomization import DomainRandomization
from cnc_gym.errors import CncGymError, ConfigError
from cnc_gym.machine import DEFAULT_MACHINE
from cnc_gym.policies.shield import PlannerShield
from cnc_gym.programs import DEFAULT_DIALECT

#: The env versions a training config may name: every id cnc_gym registers (v4: the live planner).
ENV_IDS = REGISTERED_ENV_IDS
#: A program entry naming a whole split of a benchmark suite.
SUITE_PREFIX = "suite:"
#: Keyword arguments a trained model records (plain JSON in its zip), so that ``cnc-gym bench`` and
#: ``cnc-gym run`` rebuild the env it acts in: what fixes the meaning of its observation and action.
POLICY_ENV_KEYS = ("action_mode", "control_period_s", "residual_range", "lookahead_mm", "lookahead_points")

#: Most samples in one PPO rollout (n_steps × n_envs): about 200 MB of buffers with this env's observation.
MAX_ROLLOUT = 2**20


@dataclass
class EnvSettings:
    """The env trained on: its id and keyword arguments (and, by default, evaluation's)."""

    id: str = declared(Choice(choices=ENV_IDS, doc="the env version"), "cnc_gym/Feedrate-v0")
    programs: list[str] = declared(  # noqa: RUF009
        dataclasses.replace(PROGRAM_NAMES, doc="built-in program names, `.nc` paths, or a suite split "
                            "`suite:<name>/<split>` (train or val)", as_tuple=False),
        default_factory=lambda: ["star", "pocket", "freeform"],
    )
    dialect: str = declared(DIALECT, DEFAULT_DIALECT)
    machine: str = declared(MACHINE_NAME, DEFAULT_MACHINE)
    action_mode: str = declared(dataclasses.replace(ACTION_MODE_V1, doc="what the action sets (`residual`: "
                                                    "Feedrate-v1 to -v6)"), DEFAULT_ACTION_MODE)  # fmt: skip
    control_period_s: float = declared(CONTROL_PERIOD, DEFAULT_CONTROL_PERIOD_S)
    reward: RewardWeights | None = section(  # noqa: RUF009
        RewardWeights, optional=True, doc="Feedrate-v0's reward weights (null: configs/tasks/default.yaml)")
    reward_v1: RankingReward | None = section(  # noqa: RUF009
        RankingReward, optional=True, doc="Feedrate-v1 to -v5's reward weights (null: their defaults)")
    reward_v6: RelativeReward | None = section(  # noqa: RUF009
        RelativeReward, optional=True, doc="Feedrate-v6's reward weights (null: its defaults)")
    randomize: DomainRandomization | None = section(  # noqa: RUF009
        DomainRandomization, optional=True, doc="Feedrate-v1's domain randomisation (null: off)")
    residual_range: float = declared(RESIDUAL_RANGE, 2.0)
    max_episode_steps: int | None = declared(MAX_EPISODE_STEPS)

    def config_problems(self) -> Iterator[tuple[str, str]]:
        """Rules across keys: ``(key, problem)``."""
        if self.id == "cnc_gym/Feedrate-v0":
            if self.action_mode == "residual":
                yield "action_mode", "residual needs id: cnc_gym/Feedrate-v6 (or -v1 to -v5)"
            for key in ("reward_v1", "reward_v6", "randomize"):
                if getattr(self, key) is not None:
                    yield key, "belongs to cnc_gym/Feedrate-v1 to -v6 (set id: cnc_gym/Feedrate-v6)"
        elif self.reward is not None:
            yield "reward", "holds Feedrate-v0's weights; v1 to v5 take reward_v1, v6 reward_v6"
        elif self.id == "cnc_gym/Feedrate-v6" and self.reward_v1 is not None:
            yield "reward_v1", "holds Feedrate-v1 to -v5's weights; v6's (no finish bonus) are reward_v6"
        elif self.id != "cnc_gym/Feedrate-v6" and self.reward_v6 is not None:
            yield "reward_v6", f"holds Feedrate-v6's weights; those of {self.id} are reward_v1"
        for program in self.programs:
            if program.startswith(SUITE_PREFIX):
                problem = _suite_problem(program)
                if problem:
                    yield "programs", problem

    def program_list(self) -> list[str]:
        """The programs, a suite split expanded into its files."""
        out: list[str] = []
        for program in self.programs:
            if program.startswith(SUITE_PREFIX):
                from cnc_gym.benchmark.suites import load_suite

                name, split = program.removeprefix(SUITE_PREFIX).split("/")
                out += [str(p) for p in load_suite(name).paths(split)]
            else:
                out.append(program)
        return out

    def make_kwargs(self) -> dict[str, Any]:
        kwargs: dict[str, Any] = {"programs": self.program_list(), "dialect": self.dialect,
                                  "machine": self.machine, "action_mode": self.action_mode,
                                  "control_period_s": self.control_period_s}  # fmt: skip
        if self.reward is not None:
            kwargs["reward"] = dataclasses.asdict(self.reward)
        if self.id != "cnc_gym/Feedrate-v0":
            kwargs["residual_range"] = self.residual_range
            if self.reward_v1 is not None:
                kwargs["reward"] = dataclasses.asdict(self.reward_v1)
            if self.reward_v6 is not None:
                kwargs["reward"] = dataclasses.asdict(self.reward_v6)
            if self.randomize is not None:
                kwargs["randomize"] = dataclasses.asdict(self.randomize)
        if self.max_episode_steps is not None:
            kwargs["max_episode_steps"] = self.max_episode_steps
        return kwargs

    def policy_env(self) -> dict[str, Any]:
        """What a trained model records of its env (:data:`POLICY_ENV_KEYS`): plain JSON."""
        kwargs = self.make_kwargs()
        return {"id": self.id, "kwargs": {k: kwargs[k] for k in POLICY_ENV_KEYS if k in kwargs}}


def _suite_problem(program: str) -> str | None:
    """Why ``suite:<name>/<split>`` cannot be trained on, or None."""
    from cnc_gym.benchmark.suites import suite_names

    spec = program.removeprefix(SUITE_PREFIX)
    if spec.count("/") != 1:
        return f"{program!r}: a suite split is written suite:<name>/<split>, e.g. suite:cnc-bench-v1/train"
    name, split = spec.split("/")
    if name not in suite_names():
        return f"{program!r}: unknown suite {name!r} (suites: {', '.join(suite_names())})"
    if split not in ("train", "val"):
        return (f"{program!r}: train on the train split (or val); the test split is for the reported "
                "result only")
    return None


@dataclass
class LagrangianSettings:
    """PPO-Lagrangian's dual ascent on the violation budget (agents/lagrangian.py)."""

    cost_limit: float = number(0.01, 0, 1e6, unit="mm", doc="budget d of the mean episode cost "
                               "(Feedrate-v1: violation length per episode)", why="a length.")  # fmt: skip
    lambda_init: float = number(1.0, 0, 1e6, doc="λ at the start (reward units per mm of violation)",
                                why="λ ≥ 0; the upper end keeps rewards finite.")  # fmt: skip
    lambda_lr: float = number(5.0, 0, 1e6, doc="η: λ += η·(mean episode cost − cost_limit) per rollout",
                              why="non-negative; 0 holds λ fixed.")  # fmt: skip
    lambda_max: float = number(1000.0, 0, 1e6, doc="λ is clipped to [0, lambda_max]",
                               why="keeps rewards finite.")  # fmt: skip


@dataclass
class DistillSettings:
    """Distillation of the oracle into a residual policy (agents/distillation.py, algorithm: distill)."""

    rounds: int = number(3, 0, 100, integer=True, doc="DAgger rounds after the behaviour-cloning round "
                         "(0: behaviour cloning only)", why="each round labels episodes_per_round "
                         "episodes and refits on everything so far.")  # fmt: skip
    episodes_per_round: int = number(240, 1, 100_000, integer=True, doc="training episodes labelled in "
                                     "every round (the programs in turn, each with a machine of its own)",
                                     why="an episode is a teacher's plan (about ten simulated episodes) "
                                     "and about 10⁴ samples of memory at most.")  # fmt: skip
    nominal_share: float = number(0.25, 0, 1, doc="share of each round's episodes on the nominal machine "
                                  "(randomisation off), the rest drawn by env.randomize",
                                  why="a fraction.")  # fmt: skip
    teacher_margin: float = number(0.85, 0.1, 1, doc="fraction of the contour tolerance the teacher "
                                   "(the oracle) aims at", why="the oracle's own range: at most the "
                                   "tolerance.")  # fmt: skip
    teacher_refine_iterations: int = number(12, 0, 100, integer=True, doc="the teacher's "
                                            "simulate-and-correct rounds per episode",
                                            why="each is one simulated episode.")  # fmt: skip
    teacher_raise_rounds: int = number(3, 0, 100, integer=True, doc="the teacher's raising rounds per "
                                       "episode", why="each is one simulated episode.")  # fmt: skip
    label_limit: float = number(1.0, 1, 10, doc="the student's targets: the teacher's residual action "
                                "clipped to ± this (1: the action box; above 1: how far beyond the range "
                                "the oracle would go, which saturates the student firmly there)",
                                why="1 is the box; 10 is a factor ρ¹⁰ beyond the planner.")  # fmt: skip
    teacher_prefers_planner: bool = flag(False, doc="the planner teaches an episode (labels 0) where its "
                                         "run of it is within tolerance and no slower than the teacher's "
                                         "(or the teacher's is not within tolerance)")  # fmt: skip
    teacher_floor_at_planner: bool = flag(False, doc="the teacher is never slower than the planner where "
                                          "the planner's run of the episode keeps within the teacher's "
                                          "target, teacher_margin × tolerance (it acts at the larger of "
                                          "the two overrides there)")  # fmt: skip
    quantile: float = number(0.3, 0, 1, low_open=True, high_open=True, doc="τ of the student's pinball "
                             "loss: it learns the τ-quantile of the teacher's action (< 0.5: the slow "
                             "side)", why="a quantile level strictly inside (0, 1).")  # fmt: skip
    violation_weight: float = number(4.0, 1, 1000, doc="weight of the samples of a DAgger episode in "
                                     "which the student cut path over tolerance (others: 1)",
                                     why="at least 1: violating episodes weigh more, not less.")  # fmt: skip
    epochs: int = number(10, 1, 1000, integer=True, doc="passes over the data after the first round")
    round_epochs: int = number(4, 1, 1000, integer=True, doc="passes over all data so far after each "
                               "DAgger round (the fit continues)")  # fmt: skip
    batch_size: int = number(512, 1, MAX_ROLLOUT, integer=True, doc="minibatch size of the fit")
    learning_rate: float = number(1e-3, 0, 1, low_open=True, doc="Adam step size of the fit",
                                  why="steps beyond 1 diverge at once.")  # fmt: skip
    finetune_timesteps: int = number(0, 0, 10**10, integer=True, doc="env steps of PPO-Lagrangian "
                                     "fine-tuning after distillation, with ppo: and lagrangian: (0: none)",
                                     why="10¹⁰ steps are months at this env's ~10⁴ steps/s.")  # fmt: skip
    finetune_critic_steps: int = number(20_000, 0, 10**10, integer=True, doc="fine-tune steps of those "
                                        "that train only the value net (the distilled actor held fixed)",
                                        why="at most the fine-tune's steps.")  # fmt: skip
    compare: bool = flag(True, doc="run the planner and the teacher on every labelled episode too (the "
                         "round statistics in TensorBoard)")  # fmt: skip
    shield_bins: int = number(0, 0, 64, integer=True, doc="the planner-fallback shield's reach, in bins "
                              "of the observation's preview (0: no shield): the student acts at the "
                              "planner's override or below while a junction turning at least shield_turn "
                              "lies there, or while the contour error is at least shield_error × "
                              "tolerance; in its DAgger rollouts and in the saved model",
                              why="the preview has at most 64 bins.")  # fmt: skip
    shield_turn: float = number(0.25, 0, 1, low_open=True, doc="the smallest junction turn (θ/π) the "
                                "shield falls back to the planner for",
                                why="θ/π of a turn is in (0, 1].")  # fmt: skip
    shield_error: float = number(0.0, 0, 5, doc="the contour error (× tolerance, the last step's largest) "
                                 "from which the shield falls back to the planner (0: no error rule)",
                                 why="the observation's error entry is clipped at 5.")  # fmt: skip
    shield_hold: int = number(0, 0, 1000, integer=True, doc="control periods the shield keeps holding "
                              "after a junction of shield_turn or more leaves its reach (the servo's "
                              "transient through the corner)", why="1000 periods are 10 s at the "
                              "10 ms period.")  # fmt: skip

    shield_envelope: bool = flag(False, doc="record in the saved model's shield the range of each of "
                                 "the observation's machine entries over the training samples: on a "
                                 "machine outside it the student acts as the planner (needs shield_bins "
                                 "> 0)")  # fmt: skip

    def shield(self, envelope: tuple[tuple[str, float, float], ...] = ()) -> PlannerShield | None:
        """The shield these settings ask for (None with ``shield_bins`` 0), with ``envelope`` if given."""
        if self.shield_bins == 0:
            return None
        return PlannerShield(self.shield_bins, self.shield_turn, self.shield_error or None, envelope,
                             self.shield_hold)  # fmt: skip


@dataclass
class PPOSettings:
    """Subset of ``stable_baselines3.PPO`` arguments (same names)."""

    learning_rate: float = number(3e-4, 0, 1, low_open=True, doc="Adam step size",
                                  why="steps beyond 1 diverge at once.")  # fmt: skip
    n_steps: int = number(512, 1, MAX_ROLLOUT, integer=True, doc="steps per env per rollout",
                          why="n_steps × n_envs is the rollout, at most 2²⁰ samples.")  # fmt: skip
    batch_size: int = number(128, 2, MAX_ROLLOUT, integer=True, doc="minibatch size",
                             why="SB3 needs at least 2; at most the rollout (n_steps × n_envs).")  # fmt: skip
    n_epochs: int = number(10, 1, 1000, integer=True, doc="passes over each rollout")
    gamma: float = number(0.99, 0, 1, low_open=True, doc="discount factor")
    gae_lambda: float = number(0.95, 0, 1, doc="GAE λ")
    clip_range: float = number(0.2, 0, 1, low_open=True, doc="PPO's policy-ratio clip",
                               why="0 or beyond 1 leaves nothing to clip (usual: 0.1-0.3).")  # fmt: skip
    ent_coef: float = number(0.0, 0, 1, doc="entropy bonus weight")
    vf_coef: float = number(0.5, 0, 1000, doc="value-loss weight")
    max_grad_norm: float = number(0.5, 0, 1e6, low_open=True, doc="gradient clipping norm")
    log_std_init: float = number(0.0, -20, 5, doc="initial log standard deviation of the actions",
                                 why="e⁻²⁰ to e⁵ (≈ 150): any useful spread in a [-1, 1] box.")  # fmt: skip
    net_arch: list[int] = items(  # noqa: RUF009
        lambda: [64, 64], Number(low=1, high=1024, integer=True), max_items=8, as_tuple=False, noun="layer",
        doc="hidden layer sizes of the policy and value MLPs", why="at most 8 layers of 1024: 8 M weights.")


@dataclass
class TrainConfig:
    """A training run: env, vectorisation, algorithm settings and where to write."""

    env: EnvSettings = section(EnvSettings, doc="the env and its arguments")  # noqa: RUF009
    algorithm: str = declared(Choice(choices=("ppo", "ppo_lagrangian", "distill"), doc="SB3 PPO, PPO with a "
                                     "Lagrange multiplier on the cost budget (Feedrate-v1), or distillation "
                                     "of the oracle into a residual policy (behaviour cloning and DAgger; "
                                     "ppo: gives its network)"), "ppo")  # fmt: skip
    ppo: PPOSettings = section(PPOSettings, doc="PPO's arguments (SB3 names)")  # noqa: RUF009
    lagrangian: LagrangianSettings = section(  # noqa: RUF009
        LagrangianSettings, doc="PPO-Lagrangian's dual ascent (algorithm: ppo_lagrangian, and distill's "
        "fine-tune)")  # fmt: skip
    distill: DistillSettings = section(  # noqa: RUF009
        DistillSettings, doc="distillation of the oracle (algorithm: distill)")  # fmt: skip
    total_timesteps: int = number(100_000, 1, 10**10, integer=True, doc="env steps to train for",
                                  why="10¹⁰ steps are months at this env's ~10⁴ steps/s.")  # fmt: skip
    n_envs: int = number(4, 1, 256, integer=True, doc="envs in the process, stepped together by one batched "
                         "engine", why="each env holds a controller, a plant and their buffers.")  # fmt: skip
    #: Scale rewards by a running estimate of the return's spread (VecNormalize with norm_obs=False):
    #: training only, so the saved model needs no extra statistics to run.
    normalize_reward: bool = flag(False, doc="training only: VecNormalize(norm_obs=False, norm_reward=True)")
    seed: int = number(0, 0, 2**32 - 1, integer=True, doc="seed of PPO and the envs (copy i: seed + i)",
                       why="NumPy's seed range.")  # fmt: skip
    torch_threads: int = number(1, 1, 256, integer=True, doc="torch threads (small MLPs gain little more)")
    output_dir: str = text("runs", max_length=4096, doc="where runs are written")
    run_name: str = text("ppo", max_length=100, pattern=r"[A-Za-z0-9][A-Za-z0-9._-]*",
                         pattern_doc="a plain name (letters, digits, '.', '_', '-'; no '/', no leading '.')",
                         doc="the run's folder under output_dir",
                         why="a name, not a path, so a run never writes outside output_dir.")  # fmt: skip
    progress_bar: bool = flag(True, doc="progress bar on a terminal")
    source: str = "<dict>"

    def config_problems(self) -> Iterator[tuple[str, str]]:
        """Rules across keys: ``(key, problem)``."""
        rollout = self.ppo.n_steps * self.n_envs
        if not 2 <= rollout <= MAX_ROLLOUT:
            yield "ppo.n_steps", f"× n_envs (the rollout, {rollout}) must be within 2 … {MAX_ROLLOUT}"
        elif self.ppo.batch_size > rollout:
            yield "ppo.batch_size", (f"must not exceed the rollout n_steps × n_envs = {rollout}, "
                                     f"got {self.ppo.batch_size}")  # fmt: skip
        if self.algorithm == "ppo_lagrangian" and self.env.id == "cnc_gym/Feedrate-v0":
            yield "algorithm", "ppo_lagrangian needs env.id: cnc_gym/Feedrate-v6 (or -v1 to -v5; cost per mm)"
        if self.algorithm == "distill":
            if self.env.action_mode != "residual":
                yield "env.action_mode", "distill trains a residual policy: set action_mode: residual"
            if self.distill.finetune_critic_steps > self.distill.finetune_timesteps > 0:
                yield "distill.finetune_critic_steps", (f"must not exceed finetune_timesteps "
                                                        f"({self.distill.finetune_timesteps})")  # fmt: skip


def load_config(path: str | Path, overrides: Sequence[str] = ()) -> TrainConfig:
    """Read and validate a training config (YAML via the bounded safe loader): a path, or the name of a
    shipped one (``ppo`` → ``configs/train/ppo.yaml``, package data in an installed wheel).
    ``overrides``: ``KEY=VALUE`` strings (``scripts/train.py --set``), a dotted key (``distill.rounds``)
    and a YAML value, applied to the file's data before it is checked, by the same rules."""
    path = config_path(path)
    data = read_yaml(path, "training config")
    for override in overrides:
        data = _with_override(data, override)
    return from_mapping(TrainConfig, data, str(path), "", {"source": str(path)})


def _with_override(data: Any, override: str) -> dict[str, Any]:
    """``data`` (a config's mapping) with ``KEY=VALUE`` applied (:func:`load_config`)."""
    key, sep, value = override.partition("=")
    parts = key.strip().split(".")
    if not sep or not all(parts):
        raise ConfigError(f"--set {shown(override)}: write KEY=VALUE, e.g. --set distill.rounds=1")
    out = dict(data) if isinstance(data, dict) else {}
    node = out
    for part in parts[:-1]:
        child = node.get(part)
        node[part] = child = dict(child) if isinstance(child, dict) else {}
        node = child
    node[parts[-1]] = parse_yaml(value, f"--set {key.strip()}")
    return out


def config_path(name_or_path: str | Path) -> Path:
    """A training config by path (``.yaml``/``.yml``) or by the name of a shipped one."""
    path = Path(name_or_path)
    if path.suffix in (".yaml", ".yml") or not str(name_or_path):
        return path
    shipped = configs_dir() / "train" / f"{name_or_path}.yaml"
    if not shipped.is_file():
        names = sorted(p.stem for p in (configs_dir() / "train").glob("*.yaml"))
        raise ConfigError(f"unknown training config {shown(str(name_or_path))}; shipped: {', '.join(names)}")
    return shipped


def with_overrides(config: TrainConfig, **values: Any) -> TrainConfig:
    """``config`` with top-level keys replaced (None: kept), each checked by its key's spec."""
    changes = {key: parse_value(spec_of(TrainConfig, key), value, "", f"--{key.replace('_', '-')}")
               for key, value in values.items() if value is not None}  # fmt: skip
    return dataclasses.replace(config, **changes)


def config_to_dict(config: TrainConfig) -> dict[str, Any]:
    data = dataclasses.asdict(config)
    data.pop("source", None)
    return data


def checked_run_dir(config: TrainConfig, out: str | None = None) -> Path:
    """``<output_dir>/<run_name>``, created and shown to be writable (``out`` overrides output_dir)."""
    output_dir = config.output_dir
    if out is not None:
        output_dir = parse_value(spec_of(TrainConfig, "output_dir"), out, "", "--out")
    run_dir = Path(output_dir) / config.run_name
    try:
        run_dir.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=run_dir):
            pass
    except OSError as exc:
        key = "--out" if out is not None else f"{config.source}: output_dir"
        raise ConfigError(f"{key}: cannot write to {run_dir}: {exc.strerror or exc}") from None
    return run_dir


def train(config: TrainConfig, *, timesteps: int | None = None, out: str | None = None,
          progress_bar: bool | None = None) -> Path:  # fmt: skip
    """Train PPO or PPO-Lagrangian as configured; returns the path of the saved ``model.zip``.
    ``timesteps`` and ``out`` override ``total_timesteps`` and ``output_dir`` (checked with the same
    rules). ``algorithm: distill`` is :func:`cnc_gym_agents.distillation.train_distilled`
    (``scripts/train.py`` picks by the config's algorithm)."""
    check_object(config, config.source)  # a config built in Python keeps the file's rules too
    if config.algorithm == "distill":
        raise ConfigError(f"{config.source}: algorithm distill is trained by cnc_gym_agents.distillation."
                          "train_distilled (scripts/train.py picks it)")  # fmt: skip
    total = config.total_timesteps
    if timesteps is not None:
        total = parse_value(spec_of(TrainConfig, "total_timesteps"), timesteps, "", "--timesteps")
    run_dir = checked_run_dir(config, out)
    tensorboard_dir = run_dir.parent / "tensorboard"

    import torch

    from cnc_gym.programs import load_program

    torch.set_num_threads(config.torch_threads)  # small MLPs: more threads only add overhead
    for program in config.env.program_list():  # interpret up front: program errors are one clear line
        load_program(program, config.env.dialect)
    vec_env = training_vec_env(config, config.seed)
    callback = None
    if config.algorithm == "ppo_lagrangian":
        from cnc_gym_agents.lagrangian import CostPenalty, DualAscent

        lag = config.lagrangian
        vec_env = penalty = CostPenalty(vec_env, lag.lambda_init)
        callback = DualAscent(penalty, lag.cost_limit, lag.lambda_lr, lag.lambda_max)
    if config.normalize_reward:
        from stable_baselines3.common.vec_env import VecNormalize

        vec_env = VecNormalize(vec_env, norm_obs=False, norm_reward=True, gamma=config.ppo.gamma)
    model = ppo_model(config, vec_env, tensorboard_dir)
    # Plain JSON in the model's zip: the env it acts in (cnc_gym/policies/model.py reads it back without
    # unpickling).
    model.cnc_gym_env = config.env.policy_env()
    show_bar = config.progress_bar if progress_bar is None else progress_bar
    started = time.perf_counter()
    model_path = run_dir / "model.zip"
    try:
        model.learn(total_timesteps=total, progress_bar=show_bar, tb_log_name=config.run_name,
                    callback=callback)  # fmt: skip
        elapsed = time.perf_counter() - started
        model.save(model_path)
        saved = config_to_dict(config)
        saved["total_timesteps"] = total
        (run_dir / "config.yaml").write_text(yaml.safe_dump(saved, sort_keys=False))
    except OSError as exc:  # the disk filled up or the folder went away while training
        raise CncGymError(f"cannot write the run under {run_dir}: {exc.strerror or exc}") from None
    finally:
        vec_env.close()
    print(f"trained {total} steps in {elapsed:.0f} s ({total / max(elapsed, 1e-9):.0f} steps/s)")
    print(f"model:       {model_path}")
    print(f"config:      {run_dir / 'config.yaml'}")
    print(f"tensorboard: {tensorboard_dir}")
    return model_path


def training_vec_env(config: TrainConfig, seed: int) -> Any:
    """The config's ``n_envs`` training envs, seeded from ``seed``: one batched engine steps every env
    (the numbers of DummyVecEnv over gym.make copies, bit for bit; DummyVecEnv itself when randomize is
    on: :mod:`cnc_gym.envs.sb3`)."""
    import cnc_gym  # noqa: F401  (registers the env)
    from cnc_gym.envs.sb3 import make_sb3_vec_env

    return make_sb3_vec_env(config.n_envs, seed=seed, env_kwargs=config.env.make_kwargs(),
                            env_id=config.env.id)  # fmt: skip


def ppo_model(config: TrainConfig, vec_env: Any, tensorboard_dir: Path) -> Any:
    """SB3 PPO with the config's ``ppo:`` settings on ``vec_env``, logging to ``tensorboard_dir``."""
    from stable_baselines3 import PPO

    p = config.ppo
    return PPO(
        "MlpPolicy", vec_env, learning_rate=p.learning_rate, n_steps=p.n_steps, batch_size=p.batch_size,
        n_epochs=p.n_epochs, gamma=p.gamma, gae_lambda=p.gae_lambda, clip_range=p.clip_range,
        ent_coef=p.ent_coef, vf_coef=p.vf_coef, max_grad_norm=p.max_grad_norm, seed=config.seed,
        policy_kwargs={"net_arch": list(p.net_arch), "log_std_init": p.log_std_init},
        tensorboard_log=str(tensorboard_dir), device="cpu", verbose=0,
    )  # fmt: skip
