"""Distilling the oracle into a deployable residual policy: behaviour cloning, then DAgger.

The **teacher** (:mod:`.teacher`) is the oracle held to the student's action range, planning on the true
plant of each training episode: with the env's domain randomisation on, every episode's machine (gains,
mismatch, feed-forward, acceleration) and feed scale get a teacher of their own, which simulates that very
episode to the end before its first step. The **student** (:mod:`.student`) is a ``residual`` policy over
the env's observation (the 24 mm preview of the path, the controller's limits there, the machine's
parameters, the servo's errors now, the planner's override): a deployable policy, since the planner and
the observation are what a controller has.

The loop (:func:`distill`), in the terms of Ross et al. (AISTATS 2011, DAgger):

- **round 0, behaviour cloning**: the teacher drives ``episodes_per_round`` training episodes; every
  step's observation is a sample, labelled with the teacher's action;
- **rounds 1 … ``rounds``, DAgger**: the student drives fresh episodes (fresh machines), and every state it
  visits is labelled with what the teacher would do there; the samples of an episode in which the
  student cut path over tolerance weigh ``violation_weight`` (its mistakes are rare and matter most);
- with ``teacher_prefers_planner`` the planner teaches an episode (every label 0) where its run of the
  episode is within tolerance and no slower than the teacher's (:mod:`.labelling`);
- with ``teacher_floor_at_planner`` the teacher is never slower than the planner where the planner's
  run of the episode keeps within the teacher's target (:mod:`.teacher`);
- after every round the student is fitted to all samples so far (the fit continues from the last round)
  with the **quantile (pinball) loss** at level ``quantile``: the τ-quantile of the teacher's actions in
  states the student cannot tell apart, below the median for τ < 0.5.

The saved model acts through the planner-fallback shield (:mod:`cnc_gym.policies.shield`) if
``shield_bins`` > 0; with ``shield_envelope`` its record also holds the range of each of the observation's
machine entries over all training samples (:func:`machine_envelope`), outside which the student hands the
knob to the planner.

Episodes are labelled by tasks (:mod:`.labelling`) on a process pool or on Ray, as ``cnc-gym bench`` runs
its episodes. Optionally the distilled student is then fine-tuned with PPO-Lagrangian
(:mod:`.lagrangian`) at the budget ``lagrangian.cost_limit`` (the benchmark's is 0), its actor held fixed
for the first ``finetune_critic_steps`` while the value net learns; ``student.zip`` (the distilled
student) stays beside ``model.zip`` so that the val split decides which to keep.

A run writes ``model.zip`` (an SB3 PPO zip: ``cnc-gym run``, ``cnc-gym bench`` and
``scripts/evaluate.py`` load it without unpickling, in the env it records), ``config.yaml`` and
``distill.json`` (per round: labelled episodes and steps, the student's, the teacher's and the planner's
times and violations on those episodes, the CPU seconds of the labelling and of the fit), and TensorBoard
scalars under ``<output_dir>/tensorboard/<run_name>_N`` (``distill/*``).
"""

from __future__ import annotations

import json
import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from cnc_gym.errors import CncGymError, ConfigError
from cnc_gym_agents.labelling import EpisodeTask, Executor, LabelledEpisode, TeacherSettings, label_all

if TYPE_CHECKING:
    from cnc_gym.envs.observation import ObservationLayout
    from cnc_gym.policies.shield import PlannerShield
    from cnc_gym.programs import Program
    from cnc_gym_agents.training import TrainConfig


@dataclass
class RoundStats:
    """What one round labelled and how its episodes went (``distill.json``; TensorBoard ``distill/*``)."""

    round: int
    episodes: int
    labelled_steps: int
    samples_total: int
    randomized_share: float
    #: Mean over episodes of the behaviour's (teacher's in round 0, student's after) cycle time over the
    #: planner's and over the teacher's on the same episode (NaN without compare).
    time_vs_planner: float
    time_vs_teacher: float
    teacher_time_vs_planner: float
    #: Share of episodes the behaviour finished with a violation, and of those where the planner was clean.
    violating_share: float
    added_violation_share: float
    planner_violating_share: float
    #: Share of episodes the planner taught (``teacher_prefers_planner``; 0 without it).
    planner_taught_share: float
    fit_loss: float
    labelling_cpu_s: float  # CPU seconds of the tasks (in whichever processes ran them)
    fit_cpu_s: float  # CPU seconds of this process's fit
    wall_s: float

    def scalars(self) -> dict[str, float]:
        return {k: float(v) for k, v in asdict(self).items() if k != "round"}


@dataclass
class Dataset:
    """All samples so far: observations, the teacher's actions, and each sample's weight."""

    observations: list[np.ndarray] = field(default_factory=list)
    labels: list[np.ndarray] = field(default_factory=list)
    weights: list[np.ndarray] = field(default_factory=list)

    def add(self, episode: LabelledEpisode, weight: float) -> None:
        self.observations.append(episode.observations)
        self.labels.append(episode.labels)
        self.weights.append(np.full(len(episode.labels), weight, dtype=np.float32))

    def arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return (np.concatenate(self.observations), np.concatenate(self.labels), np.concatenate(self.weights))

    def __len__(self) -> int:
        return sum(len(x) for x in self.labels)


def machine_envelope(observations: Sequence[np.ndarray],
                     layout: ObservationLayout) -> tuple[tuple[str, float, float], ...]:  # fmt: skip
    """The range of each of the observation's machine entries (``layout``'s entries of source
    ``machine``) over the arrays of ``observations`` (one per episode): the machines the student was
    trained on, the shield's envelope."""
    names = [e.name for e in layout.entries if e.source == "machine"]
    columns = [int(layout.structure[name][0]) for name in names]
    values = np.concatenate([episode[:, columns] for episode in observations])  # only those columns
    low, high = values.min(axis=0), values.max(axis=0)
    return tuple((name, float(low[i]), float(high[i])) for i, name in enumerate(names))


def sample_weight(episode: LabelledEpisode, round_index: int, violation_weight: float) -> float:
    """A DAgger episode in which the student cut path over tolerance weighs ``violation_weight``; every
    other episode (the teacher's of round 0 included) weighs 1."""
    violated = episode.behaviour.violation_length_mm > 0.0 or not episode.behaviour.finished
    return float(violation_weight) if round_index > 0 and violated else 1.0


def round_tasks(config: TrainConfig, programs: Sequence[Program], round_index: int,
                actor: Any) -> list[EpisodeTask]:  # fmt: skip
    """The episodes of one round: the programs in an order drawn from (seed, round), in turn until
    ``episodes_per_round``; each with a seed of its own (its machine draw and feed scale), on the nominal
    machine with probability ``nominal_share``."""
    d = config.distill
    rng = np.random.default_rng(np.random.SeedSequence([config.seed, round_index, 0xD157]))
    kwargs = config.env.make_kwargs()
    kwargs.pop("programs")
    nominal_kwargs = {**kwargs, "randomize": None}
    teacher = TeacherSettings(
        d.teacher_margin, d.teacher_refine_iterations, d.teacher_raise_rounds, d.label_limit,
        d.teacher_prefers_planner, d.teacher_floor_at_planner,
    )
    shield = d.shield()
    order: list[int] = []
    while len(order) < d.episodes_per_round:
        order += rng.permutation(len(programs)).tolist()
    tasks = []
    for index in order[: d.episodes_per_round]:
        program = programs[index]
        nominal = kwargs.get("randomize") is None or rng.random() < d.nominal_share
        seed = int(rng.integers(2**31 - 1))
        tasks.append(EpisodeTask(config.env.id, nominal_kwargs if nominal else kwargs, program.name, program,
                                 seed, teacher, actor, d.compare, shield))  # fmt: skip
    return tasks


def round_stats(round_index: int, episodes: list[LabelledEpisode], samples_total: int, fit_loss: float,
                fit_cpu_s: float, wall_s: float) -> RoundStats:  # fmt: skip
    """The round's statistics (:class:`RoundStats`)."""

    def mean(values: list[float]) -> float:
        return float(np.mean(values)) if values else float("nan")

    def ratio(a: Any, b: Any) -> float:
        return a.cycle_time_s / b.cycle_time_s if a is not None and b is not None and b.cycle_time_s > 0 \
            else float("nan")  # fmt: skip

    compared = [e for e in episodes if e.planner is not None and e.teacher is not None]
    clean = [e for e in compared if e.planner is not None and e.planner.feasible]
    return RoundStats(
        round=round_index,
        episodes=len(episodes),
        labelled_steps=sum(len(e.labels) for e in episodes),
        samples_total=samples_total,
        randomized_share=mean([float(e.randomized) for e in episodes]),
        time_vs_planner=mean([ratio(e.behaviour, e.planner) for e in compared]),
        time_vs_teacher=mean([ratio(e.behaviour, e.teacher) for e in compared]),
        teacher_time_vs_planner=mean([ratio(e.teacher, e.planner) for e in compared]),
        violating_share=mean([float(not e.behaviour.feasible) for e in episodes]),
        added_violation_share=mean([float(not e.behaviour.feasible) for e in clean]),
        planner_violating_share=mean([float(not e.planner.feasible) for e in compared if e.planner]),
        planner_taught_share=mean([float(e.taught_by_planner) for e in episodes]),
        fit_loss=fit_loss,
        labelling_cpu_s=sum(e.cpu_s for e in episodes),
        fit_cpu_s=fit_cpu_s,
        wall_s=wall_s,
    )


def training_programs(config: TrainConfig) -> list[Program]:
    """Every training program, interpreted once here as the env interprets it (the dialect, the machine
    preset and its power-on units): a program error is one line before any work, and the tasks carry the
    interpreted programs (a worker, on Ray another machine, needs no file)."""
    from cnc_gym.machine import load_machine
    from cnc_gym.programs import load_program

    machine = load_machine(config.env.machine)
    return [load_program(program, config.env.dialect, machine) for program in config.env.program_list()]


def train_distilled(config: TrainConfig, *, timesteps: int | None = None, out: str | None = None,
                    progress_bar: bool | None = None, workers: int = 1, use_ray: bool = False,
                    ray_address: str | None = None) -> Path:  # fmt: skip
    """``scripts/train.py`` for ``algorithm: distill``: :func:`distill` into ``<output_dir>/<run_name>``
    (``out`` overrides output_dir, as for PPO); ``workers``, ``use_ray`` and ``ray_address`` say where
    the labelling runs (a process pool of that many workers, or Ray: a local instance, or the cluster at
    the address), as for ``cnc-gym bench``. ``timesteps`` is refused: the run is counted in rounds and
    episodes. Returns the path of ``model.zip``."""
    from cnc_gym.config import check_object
    from cnc_gym.errors import ConfigError
    from cnc_gym_agents.training import checked_run_dir

    check_object(config, config.source)  # a config built in Python keeps the file's rules too
    if config.algorithm != "distill":
        raise ConfigError(f"{config.source}: algorithm {config.algorithm} is trained by "
                          "cnc_gym_agents.training.train")  # fmt: skip
    if timesteps is not None:
        raise ConfigError("--timesteps: algorithm distill has no total_timesteps (it runs distill.rounds "
                          "of distill.episodes_per_round episodes; its PPO-Lagrangian fine-tune runs "
                          "distill.finetune_timesteps)")  # fmt: skip
    if not 1 <= workers <= 256:
        raise ConfigError(f"--workers must be in [1, 256], got {workers}")
    executor = Executor(workers=workers, use_ray=use_ray or ray_address is not None, ray_address=ray_address)
    show_bar = config.progress_bar if progress_bar is None else progress_bar
    return distill(config, checked_run_dir(config, out), executor=executor, progress_bar=show_bar)


def distill(config: TrainConfig, run_dir: Path, *, executor: Executor | None = None,
            progress_bar: bool = True) -> Path:  # fmt: skip
    """Run the distillation of ``config`` (module docstring) into ``run_dir``; returns ``model.zip``.
    ``executor``: where the labelling tasks run (None: in this process)."""
    executor = executor or Executor()
    import gymnasium
    import torch
    import yaml
    from stable_baselines3.common.utils import configure_logger

    import cnc_gym  # noqa: F401  (registers the env ids)
    from cnc_gym_agents.student import Student
    from cnc_gym_agents.training import config_to_dict

    torch.set_num_threads(config.torch_threads)
    torch.manual_seed(config.seed)
    started_cpu, started = time.process_time(), time.perf_counter()
    d = config.distill
    programs = training_programs(config)
    kwargs = config.env.make_kwargs()
    kwargs["programs"] = [programs[0]]
    spaces_env = gymnasium.make(config.env.id, **kwargs)  # the spaces of the student's policy
    shield = d.shield()
    if shield is not None:
        try:
            shield.bind(spaces_env)  # the env's preview has the bins it reads
        except CncGymError as exc:
            spaces_env.close()
            raise ConfigError(f"{config.source}: distill.shield_bins: {exc}") from None
    elif d.shield_envelope or d.shield_hold:
        spaces_env.close()
        key = "shield_envelope: the envelope" if d.shield_envelope else "shield_hold: the hold"
        raise ConfigError(f"{config.source}: distill.{key} is the shield's; set distill.shield_bins > "
                          "0")  # fmt: skip
    layout: ObservationLayout = spaces_env.unwrapped.layout  # type: ignore[attr-defined]
    tensorboard_dir = run_dir.parent / "tensorboard"
    student = Student(spaces_env, config.ppo.net_arch, config.ppo.log_std_init, config.seed)
    logger = configure_logger(0, str(tensorboard_dir), config.run_name)
    data = Dataset()
    history: list[RoundStats] = []
    fit_step = 0
    from tqdm.auto import tqdm

    bar = tqdm(total=(d.rounds + 1) * d.episodes_per_round, desc="distill", unit="episode",
               disable=not progress_bar, dynamic_ncols=True)  # fmt: skip
    try:
        for r in range(d.rounds + 1):
            round_started = time.perf_counter()
            bar.set_description(f"distill: round {r}/{d.rounds}, labelling")
            actor = None if r == 0 else student.actor_weights()
            episodes = label_all(round_tasks(config, programs, r, actor), executor,
                                 on_done=lambda _: bar.update())  # fmt: skip
            for episode in episodes:
                data.add(episode, sample_weight(episode, r, d.violation_weight))
            bar.set_description(f"distill: round {r}/{d.rounds}, fitting {len(data)} samples")
            fit_cpu = time.process_time()

            def on_epoch(epoch: int, loss: float) -> None:
                nonlocal fit_step
                fit_step += 1
                logger.record("distill/fit_loss", loss)
                logger.dump(fit_step)

            loss = student.fit(*data.arrays(), epochs=d.epochs if r == 0 else d.round_epochs,
                               batch_size=d.batch_size, learning_rate=d.learning_rate, quantile=d.quantile,
                               on_epoch=on_epoch)  # fmt: skip
            stats = round_stats(r, episodes, len(data), loss, time.process_time() - fit_cpu,
                                time.perf_counter() - round_started)  # fmt: skip
            history.append(stats)
            for key, value in stats.scalars().items():
                logger.record(f"distill/round_{key}", value)
            logger.dump(fit_step)
            bar.set_postfix_str(f"time/planner {stats.time_vs_planner:.3f} violating "
                                f"{stats.violating_share:.0%}")  # fmt: skip
    finally:
        bar.close()
        logger.close()
        spaces_env.close()
    if shield is not None and d.shield_envelope:
        shield = d.shield(machine_envelope(data.observations, layout))
    try:
        student_path = student.save(run_dir / "student.zip", config.env.policy_env(), shield)
        model_path = run_dir / "model.zip"
        finetuned = None
        if d.finetune_timesteps > 0:
            finetuned = finetune(student, config, model_path, progress_bar, shield)
        else:
            student.save(model_path, config.env.policy_env(), shield)
        summary = {
            "rounds": [asdict(s) for s in history],
            "labelled_episodes": sum(s.episodes for s in history),
            "labelled_steps": sum(s.labelled_steps for s in history),
            "labelling_cpu_s": sum(s.labelling_cpu_s for s in history),
            "main_cpu_s": time.process_time() - started_cpu,
            "wall_s": time.perf_counter() - started,
            "finetune": finetuned,
        }
        (run_dir / "distill.json").write_text(json.dumps(summary, indent=1))
        saved = config_to_dict(config)
        (run_dir / "config.yaml").write_text(yaml.safe_dump(saved, sort_keys=False))
    except OSError as exc:
        raise CncGymError(f"cannot write the run under {run_dir}: {exc.strerror or exc}") from None
    print(f"distilled {summary['labelled_steps']} labelled steps ({summary['labelled_episodes']} episodes) "
          f"in {summary['wall_s']:.0f} s; CPU: {summary['main_cpu_s']:.0f} s here, labelling "
          f"{summary['labelling_cpu_s']:.0f} s")  # fmt: skip
    print(f"student:     {student_path}")
    print(f"model:       {model_path}")
    print(f"summary:     {run_dir / 'distill.json'}")
    print(f"tensorboard: {tensorboard_dir}")
    return model_path


def finetune(student: Any, config: TrainConfig, model_path: Path, progress_bar: bool,
             shield: PlannerShield | None) -> dict[str, Any]:  # fmt: skip
    """PPO-Lagrangian on the distilled student (module docstring), with the PPO and env of ``train``
    (:func:`~cnc_gym_agents.training.training_vec_env`, :func:`~cnc_gym_agents.training.ppo_model`);
    saves ``model_path``, recording ``shield``."""
    from stable_baselines3.common.callbacks import BaseCallback, CallbackList

    from cnc_gym_agents.lagrangian import CostPenalty, DualAscent
    from cnc_gym_agents.student import save_model
    from cnc_gym_agents.training import ppo_model, training_vec_env

    d, lag = config.distill, config.lagrangian
    vec_env = training_vec_env(config, config.seed + 1)
    penalty = CostPenalty(vec_env, lag.lambda_init)
    model = ppo_model(config, penalty, model_path.parent.parent / "tensorboard")
    model.policy.load_state_dict(student.policy.state_dict())  # the distilled actor (the same network)
    actor = [*model.policy.mlp_extractor.policy_net.parameters(), *model.policy.action_net.parameters(),
             model.policy.log_std]  # fmt: skip

    class CriticFirst(BaseCallback):
        """Holds the actor fixed until ``finetune_critic_steps`` (an untrained value net's advantages
        would undo the distillation)."""

        def _on_training_start(self) -> None:
            self._set(d.finetune_critic_steps <= 0)

        def _set(self, trainable: bool) -> None:
            for parameter in actor:
                parameter.requires_grad_(trainable)

        def _on_step(self) -> bool:
            return True

        def _on_rollout_end(self) -> None:  # before the update of the rollout just collected
            if self.num_timesteps > d.finetune_critic_steps:
                self._set(True)

    try:
        model.learn(total_timesteps=d.finetune_timesteps, progress_bar=progress_bar,
                    tb_log_name=f"{config.run_name}-finetune",
                    callback=CallbackList([DualAscent(penalty, lag.cost_limit, lag.lambda_lr, lag.lambda_max),
                                           CriticFirst()]))  # fmt: skip
        save_model(model, model_path, config.env.policy_env(), shield)
    finally:
        vec_env.close()
    return {"timesteps": d.finetune_timesteps, "critic_steps": d.finetune_critic_steps, "lambda": penalty.lam}
