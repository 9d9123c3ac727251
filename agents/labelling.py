"""Teacher labelling: one task per training episode, run in this process, on a process pool or on Ray.

A task (:class:`EpisodeTask`) is one training episode: an interpreted program, the env's settings (its
domain randomisation included) and a seed, which together fix the episode's machine draw and feed scale,
so any worker rebuilds the same episode. The task

1. makes the env and resets it with the seed (the env draws the episode's machine);
2. lets the teacher (:class:`~cnc_gym_agents.teacher.ResidualOracle`) plan on that episode: it simulates
   copies of it, its true plant included;
3. runs the episode under the *behaviour* policy (the teacher itself in round 0, the student's actor in
   the DAgger rounds) with :func:`cnc_gym.rollout.play`, and records, at every step, the observation the
   student saw and the action the teacher would take there
   (:meth:`~cnc_gym_agents.teacher.ResidualOracle.label`), and which steps cut path over tolerance;
4. optionally runs the planner (the residual action 0) and the teacher on the same episode, so the round's
   statistics can say where the student is slower than the teacher or violates where the planner is
   clean.

With ``prefer_planner`` the planner and the teacher run the episode *before* step 3, and where the
planner's run is within tolerance and no slower than the teacher's (or the teacher's is not within
tolerance), the planner teaches that episode: every label is 0, its own action. The oracle plans
against the contour error, not against time, and its schedule can be the slower (docs/training.md,
the loop); a student that imitates it there inherits the loss.

Tasks are plain data (the interpreted program, settings, NumPy arrays of the student's actor) and a
module-level function, so :func:`label_all` runs them with ``cnc-gym bench``'s executor
(:func:`cnc_gym.benchmark.runner.run_tasks`): in the calling process, on a ``spawn`` process pool or on
Ray; the results come back in task order whatever ran them, and do not depend on it.
"""

from __future__ import annotations

import functools
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from cnc_gym.benchmark.runner import Executor, run_tasks
from cnc_gym.policies.shield import BoundShield, PlannerShield
from cnc_gym_agents.student import ActorWeights
from cnc_gym_agents.teacher import ResidualOracle


@dataclass(frozen=True)
class TeacherSettings:
    """The teacher's oracle settings (:class:`~cnc_gym_agents.teacher.ResidualOracle`)."""

    margin: float = 0.85
    refine_iterations: int = 12
    raise_rounds: int = 3
    #: Labels are the teacher's residual action clipped to [-label_limit, label_limit] (the teacher still
    #: acts within [-1, 1]): :func:`~cnc_gym_agents.teacher.residual_label`.
    label_limit: float = 1.0
    #: The planner teaches an episode where it is within tolerance and no slower (module docstring).
    prefer_planner: bool = False
    #: The teacher is never below the planner where the planner keeps within the teacher's target
    #: (:class:`~cnc_gym_agents.teacher.ResidualOracle`, ``planner_floor``).
    planner_floor: bool = False


@dataclass(frozen=True)
class EpisodeTask:
    """One training episode to label (module docstring): plain data, sent to a worker as it is.

    ``env_kwargs`` are the env's keyword arguments without ``programs`` (its randomisation included);
    ``program`` the interpreted program (a :class:`cnc_gym.programs.Program`, or anything the env takes);
    ``actor`` drives the episode (None: the teacher does), through ``shield`` if given (the shield
    the deployed student acts through); ``compare`` also runs the planner and the teacher on the same
    episode.
    """

    env_id: str
    env_kwargs: dict[str, Any]
    program_name: str
    program: Any
    seed: int
    teacher: TeacherSettings = field(default_factory=TeacherSettings)
    actor: ActorWeights | None = None
    compare: bool = True
    shield: PlannerShield | None = None


@dataclass(frozen=True)
class Outcome:
    """How one episode ended: its steps, cycle time, violation length and whether it finished."""

    steps: int
    cycle_time_s: float
    violation_length_mm: float
    finished: bool

    @property
    def feasible(self) -> bool:
        """Finished with no path cut over tolerance (the benchmark's rule)."""
        return self.finished and self.violation_length_mm == 0.0


@dataclass
class LabelledEpisode:
    """What a task returns: the student's observations with the teacher's actions, and the outcomes."""

    program: str
    seed: int
    observations: np.ndarray  # (n, observation size) float32: what the student saw
    labels: np.ndarray  # (n,) float32: the teacher's residual action at each of those states (up to
    #                     ± label_limit: beyond the box where the oracle would go further)
    violating: np.ndarray  # (n,) bool: the step cut path over tolerance
    behaviour: Outcome  # the episode the observations come from (teacher in round 0, else student)
    planner: Outcome | None  # the same episode under the planner (residual action 0), with compare
    teacher: Outcome | None  # ... and under the teacher, with compare
    randomized: bool  # the env drew the episode's machine (False: the nominal machine)
    cpu_s: float  # CPU seconds of the task (planning, the episodes, the env set-up)
    taught_by_planner: bool = False  # the labels are the planner's (0): TeacherSettings.prefer_planner


def _make_env(task: EpisodeTask) -> Any:
    import gymnasium

    import cnc_gym  # noqa: F401  (registers the env ids)

    return gymnasium.make(task.env_id, programs=[task.program], **task.env_kwargs)


def _outcome(episode: Any) -> Outcome:
    info = episode.info
    return Outcome(steps=int(episode.steps), cycle_time_s=float(info["cycle_time_s"]),
                   violation_length_mm=float(info["violation_length_mm"]),
                   finished=bool(episode.finished))  # fmt: skip


class _Planner:
    """The residual action 0: exactly the deployable planner."""

    name = "planner"

    def __init__(self) -> None:
        self._action = np.zeros(1, dtype=np.float32)

    def reset(self, env: Any) -> None:
        return None

    def act(self, observation: Any, info: dict[str, Any]) -> np.ndarray:
        return self._action


class _Labeller:
    """A policy that records what the student sees and what the teacher would do, then lets the behaviour
    act: the teacher (``actor`` None, its label clipped to the action box) or the student's actor,
    through ``shield`` if given; with ``planner_teaches`` every label is the planner's action, 0."""

    name = "labeller"

    def __init__(self, teacher: ResidualOracle, actor: ActorWeights | None, label_limit: float,
                 shield: BoundShield | None = None, planner_teaches: bool = False) -> None:  # fmt: skip
        self.teacher = teacher
        self.actor = actor
        self.label_limit = label_limit
        self.shield = shield
        self.planner_teaches = planner_teaches
        self.observations: list[np.ndarray] = []
        self.labels: list[float] = []

    def reset(self, env: Any) -> None:
        return None

    def act(self, observation: Any, info: dict[str, Any]) -> np.ndarray:
        label = 0.0 if self.planner_teaches else self.teacher.label(info, self.label_limit)
        self.observations.append(np.asarray(observation, dtype=np.float32))
        self.labels.append(label)
        if self.actor is None:
            return np.array([min(max(label, -1.0), 1.0)], dtype=np.float32)
        action = self.actor.act(observation)
        return action if self.shield is None else self.shield.apply(observation, action)


def _replay(task: EpisodeTask, policy: Any, teacher: ResidualOracle | None = None) -> Outcome:
    """One more run of the task's episode (fresh env, same seed: the same machine and feed scale), under
    ``policy``, or the teacher following the schedule it planned already."""
    from cnc_gym.rollout import play, run_episode

    env = _make_env(task)
    try:
        if teacher is None:
            return _outcome(run_episode(env, policy, seed=task.seed))
        observation, info = env.reset(seed=task.seed)
        teacher.attach(env)
        return _outcome(play(env, teacher, observation, info))
    finally:
        env.close()


def label_episode(task: EpisodeTask) -> LabelledEpisode:
    """Run one task (module docstring)."""
    from cnc_gym.rollout import play

    started = time.process_time()
    s = task.teacher
    teacher = ResidualOracle(float(task.env_kwargs.get("residual_range", 2.0)), margin=s.margin,
                             refine_iterations=s.refine_iterations, raise_rounds=s.raise_rounds,
                             planner_floor=s.planner_floor)  # fmt: skip
    env = _make_env(task)
    violating: list[bool] = []

    def on_step(steps: int, reward: float, terminated: bool, truncated: bool, info: dict[str, Any]) -> None:
        violating.append(float(info.get("cost", 0.0)) > 0.0)

    planner = teacher_run = None
    planner_teaches = False
    try:
        observation, info = env.reset(seed=task.seed)
        teacher.reset(env)  # plans on this episode: its machine draw, feed scale and plant
        if s.prefer_planner:  # who teaches this episode (module docstring)
            planner, teacher_run = _replay(task, _Planner()), _replay(task, None, teacher)
            planner_teaches = planner.feasible and (
                not teacher_run.feasible or planner.cycle_time_s <= teacher_run.cycle_time_s)  # fmt: skip
            teacher.attach(env)
        randomized = getattr(env.unwrapped, "episode_draw", None) is not None
        shield = None if task.shield is None or task.actor is None else task.shield.bind(env)
        labeller = _Labeller(teacher, task.actor, s.label_limit, shield, planner_teaches)
        behaviour = _outcome(play(env, labeller, observation, info, on_step))
        width = int(env.observation_space.shape[0])
    finally:
        env.close()
    if task.compare and planner is None:
        planner = _replay(task, _Planner())
        teacher_run = behaviour if task.actor is None else _replay(task, None, teacher)
    return LabelledEpisode(
        program=task.program_name, seed=task.seed,
        observations=np.asarray(labeller.observations, dtype=np.float32).reshape(-1, width),
        labels=np.asarray(labeller.labels, dtype=np.float32), violating=np.asarray(violating, dtype=bool),
        behaviour=behaviour, planner=planner, teacher=teacher_run, randomized=randomized,
        cpu_s=time.process_time() - started, taught_by_planner=planner_teaches)  # fmt: skip


def label_all(tasks: Sequence[EpisodeTask], executor: Executor,
              on_done: Callable[[LabelledEpisode], None] | None = None) -> list[LabelledEpisode]:  # fmt: skip
    """:func:`label_episode` of every task on ``executor`` (``cnc-gym bench``'s), in task order;
    ``on_done`` sees each result as it arrives (a progress bar)."""
    calls = [functools.partial(label_episode, task) for task in tasks]
    hook = None if on_done is None else (lambda index, result: on_done(result))
    return run_tasks(calls, executor, hook)


__all__ = ["EpisodeTask", "Executor", "LabelledEpisode", "Outcome", "TeacherSettings", "label_all",
           "label_episode"]  # fmt: skip
