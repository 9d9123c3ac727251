"""The distillation layer: the teacher's labels, the labelling tasks, the student's fit and the whole run.

Small programs (the built-in ``circle``, a short G01 zig-zag) and tiny networks: each test runs in seconds.
"""

from __future__ import annotations

import dataclasses
import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

from cnc_gym.errors import CncGymError, ConfigError
from cnc_gym.policies.shield import PlannerShield
from cnc_gym.programs import ProgramText
from cnc_gym_agents.labelling import EpisodeTask, Executor, TeacherSettings, label_all, label_episode
from cnc_gym_agents.student import ActorWeights, Student, quantile_huber_loss
from cnc_gym_agents.teacher import ResidualOracle, residual_label

REPO = Path(__file__).resolve().parents[2]
V5 = "cnc_gym/Feedrate-v5"  # (the id the config trains on)
#: Two long diagonal lines and a sharp reversal between them: the deployable planner (version 3) keeps a
#: margin on the lines that the teacher, simulating the exact plant, spends.
ZIGZAG = "G90 G21 G17\nG00 X0 Y0 Z1\nG01 Z0 F600\nG01 X60 Y5 F4000\nG01 X0 Y10\nG00 Z5\nM30\n"
#: A short teacher (the oracle's refinement costs one simulated episode per round).
QUICK = TeacherSettings(margin=0.85, refine_iterations=4, raise_rounds=1)
RANDOM = {"enabled": True, "machines": 1}


@pytest.fixture(autouse=True, scope="module")
def _one_torch_thread():
    """Small networks: one thread (as training runs them), no contention with the env."""
    torch = pytest.importorskip("torch")
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(threads)


def _env(action_mode: str = "residual", randomize: dict | None = None, program: str = ZIGZAG):
    import gymnasium

    import cnc_gym  # noqa: F401

    return gymnasium.make(V5, programs=[ProgramText(program, "zigzag")], action_mode=action_mode,
                          residual_range=1.25, randomize=randomize)  # fmt: skip


def _task(seed: int = 3, randomize: dict | None = None, actor: ActorWeights | None = None,
          compare: bool = True, shield: PlannerShield | None = None) -> EpisodeTask:  # fmt: skip
    kwargs = {"action_mode": "residual", "residual_range": 1.25, "randomize": randomize}
    return EpisodeTask(V5, kwargs, "zigzag", ProgramText(ZIGZAG, "zigzag"), seed, QUICK, actor, compare,
                       shield)  # fmt: skip


def _constant_actor(value: float, width: int = 46) -> ActorWeights:
    """A student whose every action is ``value`` (zero weights, the head's bias)."""
    layer = (np.zeros((4, width), np.float32), np.zeros(4, np.float32))
    return ActorWeights((layer,), (np.zeros((1, 4), np.float32), np.full(1, value, np.float32)))


# ------------------------------------------------------------------------------------------ teacher
@pytest.mark.parametrize(("oracle", "planner", "expected"), [
    (1.0, 1.0, 0.0), (1.25, 1.0, 1.0), (0.8, 1.0, -1.0), (2.0, 1.0, 1.0), (0.1, 1.0, -1.0),
    (1.0, 0.0, 0.0), (0.0, 1.0, -1.0), (math.inf, 1.0, 1.0), (1.0, math.nan, 0.0),
])  # fmt: skip
def test_residual_label_is_the_clipped_log_ratio(oracle, planner, expected):
    assert residual_label(oracle, planner, 1.25) == pytest.approx(expected, rel=1e-12, abs=1e-12)


def test_residual_label_inside_the_range():
    a = residual_label(1.1, 1.0, 1.25)
    assert a == pytest.approx(math.log(1.1) / math.log(1.25), rel=1e-12)
    assert 1.0 * 1.25**a == pytest.approx(1.1, rel=1e-12)


def test_a_label_limit_keeps_how_far_beyond_the_box_the_oracle_would_go():
    expected = math.log(1.5) / math.log(1.25)
    assert residual_label(1.5, 1.0, 1.25, limit=3.0) == pytest.approx(expected, rel=1e-12)
    assert residual_label(2.0, 1.0, 1.25, limit=3.0) == 3.0  # log 2 / log 1.25 = 3.1: clipped at the limit
    assert residual_label(0.0, 1.0, 1.25, limit=3.0) == -3.0
    assert residual_label(1.0, 0.0, 1.25, limit=3.0) == 0.0


def test_the_teacher_asks_within_the_residual_range_what_the_oracle_asks():
    env = _env()
    _, info = env.reset(seed=0)
    teacher = ResidualOracle(1.25, refine_iterations=2, raise_rounds=0)
    teacher.reset(env)
    base = env.unwrapped
    for _ in range(400):
        label = teacher.label(info)
        oracle = teacher.override_at(float(info["path_s"]), info)
        planner = float(info["planner_override"])
        assert -1.0 <= label <= 1.0
        if planner > 1e-9:
            held = min(max(oracle, planner / 1.25), planner * 1.25)
            assert planner * 1.25**label == pytest.approx(held, rel=1e-9)
        _, _, terminated, truncated, info = env.step(np.array([label], np.float32))
        if terminated or truncated:
            break
    assert base.residual_range == 1.25


def test_the_teacher_refuses_an_env_it_cannot_speak_to():
    teacher = ResidualOracle(1.25, refine_iterations=0, raise_rounds=0)
    env = _env(action_mode="override")
    env.reset(seed=0)
    with pytest.raises(CncGymError, match="speaks the residual action; the env is in 'override' mode"):
        teacher.reset(env)
    import gymnasium

    other = gymnasium.make(V5, programs=["circle"], action_mode="residual", residual_range=2.0)
    other.reset(seed=0)
    with pytest.raises(CncGymError, match=r"planned for residual_range 1\.25, the env has 2"):
        teacher.reset(other)
    with pytest.raises(CncGymError, match="must be above 1"):
        ResidualOracle(1.0)


def test_every_randomised_episode_gets_a_teacher_planned_on_its_own_machine():
    first = label_episode(_task(seed=1, randomize=RANDOM, compare=False))
    again = label_episode(_task(seed=1, randomize=RANDOM, compare=False))
    other = label_episode(_task(seed=2, randomize=RANDOM, compare=False))
    assert first.randomized and other.randomized
    # The same seed is the same machine and the same teacher, in any process; another seed another one.
    np.testing.assert_array_equal(first.labels, again.labels)
    np.testing.assert_array_equal(first.observations, again.observations)
    kv = 8 + 4 * 8  # the observation's `kv` entry: the drawn machine's lowest gain
    assert first.observations[0, kv] != other.observations[0, kv]
    nominal = label_episode(_task(seed=1, randomize=None, compare=False))
    assert not nominal.randomized


# ---------------------------------------------------------------------------------------- labelling
def test_round_zero_is_the_teacher_and_the_comparison_runs_the_same_episode():
    episode = label_episode(_task())
    n = episode.behaviour.steps
    assert episode.observations.shape == (n, 46) and episode.labels.shape == (n,) == episode.violating.shape
    assert episode.teacher == episode.behaviour  # round 0: the teacher drives
    assert episode.planner is not None and episode.planner.finished
    # The teacher may only run as fast as 1.25 × the planner allows, and on these lines it is faster.
    assert episode.behaviour.cycle_time_s < episode.planner.cycle_time_s
    assert episode.behaviour.cycle_time_s >= episode.planner.cycle_time_s / 1.25 - 0.5
    assert episode.cpu_s > 0


#: Short strokes at 20-40 mm/min: the feed, not the contour error, limits the speed, and the oracle's
#: schedule is slower than the planner's.
SLOW_STROKES = "G90 G21 G17\nG00 X0 Y0 Z1\nG01 Z0 F20\nG01 X2 Y0.5 F40\nG01 X0 Y1\nG01 X2 Y1.5\nG00 Z5\nM30\n"


def test_the_planner_teaches_an_episode_where_the_oracle_is_slower():
    prefer = dataclasses.replace(QUICK, prefer_planner=True)
    task = dataclasses.replace(_task(), program=ProgramText(SLOW_STROKES, "slow"), teacher=prefer)
    episode = label_episode(task)
    assert episode.planner is not None and episode.teacher is not None
    assert episode.planner.feasible and episode.planner.cycle_time_s < episode.teacher.cycle_time_s
    assert episode.taught_by_planner and np.all(episode.labels == 0.0)
    assert episode.behaviour == episode.planner  # round 0: the planner drives its own episode
    # Without the preference the oracle teaches it, slower.
    oracle = label_episode(dataclasses.replace(task, teacher=QUICK))
    assert not oracle.taught_by_planner and oracle.behaviour == episode.teacher


def test_where_the_oracle_is_faster_it_teaches_as_it_would_without_the_preference():
    prefer_planner = dataclasses.replace(QUICK, prefer_planner=True)
    prefer = label_episode(dataclasses.replace(_task(), teacher=prefer_planner))
    plain = label_episode(_task())
    assert not prefer.taught_by_planner and prefer.teacher == plain.teacher == plain.behaviour
    assert prefer.behaviour == plain.behaviour and prefer.planner == plain.planner
    np.testing.assert_array_equal(prefer.labels, plain.labels)
    np.testing.assert_array_equal(prefer.observations, plain.observations)


def test_the_floored_teacher_is_no_slower_than_the_planner_or_the_oracle():
    floored = dataclasses.replace(QUICK, planner_floor=True)
    for program in (ProgramText(SLOW_STROKES, "slow"), ProgramText(ZIGZAG, "zigzag")):
        task = dataclasses.replace(_task(randomize=RANDOM), program=program)
        plain, floor = label_episode(task), label_episode(dataclasses.replace(task, teacher=floored))
        assert plain.teacher is not None and floor.teacher is not None and floor.planner is not None
        assert floor.planner == plain.planner and floor.teacher.feasible
        # (on the slow strokes the oracle alone is the slower of the two; on the zigzag the planner)
        assert floor.teacher.cycle_time_s < min(plain.teacher.cycle_time_s, floor.planner.cycle_time_s)
        assert np.all(floor.labels >= 0.0)  # the planner keeps within the target everywhere: floored


class _ScriptedRuns:
    """Stands in for the teacher's simulations: the planner's run, then the combined schedule's; an error
    of 1 mm (over the target and the tolerance) at the listed path positions."""

    def __init__(self, teacher: ResidualOracle, runs: list[list[float]]) -> None:
        self.teacher, self.runs = teacher, list(runs)
        self.floors: list[np.ndarray | None] = []

    def __call__(self, env):
        self.floors.append(None if self.teacher.floor is None else self.teacher.floor.copy())
        over = self.runs.pop(0) if len(self.runs) > 1 else self.runs[0]  # path positions over tolerance
        path_s = np.arange(0.0, 60.0, 0.1)
        error = np.zeros(len(path_s))
        for where in over:
            error[np.argmin(np.abs(path_s - where))] = 1.0
        return path_s, error, np.full(len(path_s), 10.0)


def _floor_teacher(runs: list[list[float]], monkeypatch) -> tuple[ResidualOracle, _ScriptedRuns]:
    env = _env()
    env.reset(seed=0)
    teacher = ResidualOracle(1.25, refine_iterations=0, planner_floor=True)
    scripted = _ScriptedRuns(teacher, runs)
    monkeypatch.setattr(teacher, "_simulate", scripted)
    teacher.reset(env)
    return teacher, scripted


def test_the_floor_leaves_the_stretch_behind_a_planner_violation_to_the_oracle(monkeypatch):
    teacher, scripted = _floor_teacher([[30.0], []], monkeypatch)
    assert scripted.floors[0] is None  # the planner's run: no floor
    assert teacher.floor is not None and teacher.schedule is not None
    s = teacher.schedule.s
    # The stretch behind the planner's violation (at least 2 mm) up to 1 mm past it is the oracle's.
    assert not teacher.floor[(s >= 28.0) & (s <= 31.0)].any()
    assert teacher.floor[s < 20.0].all() and teacher.floor[(s > 32.0) & (s < 59.0)].all()
    np.testing.assert_array_equal(scripted.floors[1], teacher.floor)  # the floor kept is the one simulated
    info = {"path_s": 30.0, "planner_override": 1.0, "feed_mm_min": 600.0}
    assert teacher.label(info) == residual_label(teacher.override_at(30.0, info), 1.0, 1.25)


def test_a_floor_that_keeps_cutting_over_tolerance_is_dropped(monkeypatch):
    teacher, scripted = _floor_teacher([[], [12.0], [25.0], [40.0]], monkeypatch)
    assert teacher.floor is None  # every round cut somewhere new: the oracle alone
    assert len(scripted.floors) == 1 + ResidualOracle.FLOOR_ROUNDS
    # Each round handed the stretch where it cut back to the oracle before the next.
    assert scripted.floors[1].all() and not scripted.floors[2][np.abs(teacher.schedule.s - 12.0) < 1].any()
    teacher, _ = _floor_teacher([[], [12.0], []], monkeypatch)
    assert teacher.floor is not None and not teacher.floor[np.abs(teacher.schedule.s - 12.0) < 1].any()


def test_wider_labels_change_the_targets_not_the_teachers_episode():
    boxed = label_episode(_task(compare=False))
    wider = dataclasses.replace(QUICK, label_limit=3.0)
    wide = label_episode(dataclasses.replace(_task(compare=False), teacher=wider))
    assert wide.behaviour == boxed.behaviour  # the teacher acts within [-1, 1] either way
    np.testing.assert_array_equal(wide.observations, boxed.observations)
    np.testing.assert_array_equal(np.clip(wide.labels, -1.0, 1.0), boxed.labels)
    assert wide.labels.max() > 1.0 and boxed.labels.max() == 1.0


def test_a_student_drives_the_dagger_episodes_and_the_teacher_labels_them():
    planner_like = label_episode(_task(actor=_constant_actor(0.0)))
    # Residual 0 is exactly the planner: the same episode as the comparison's planner run.
    assert planner_like.behaviour == planner_like.planner
    # The teacher drove its own run of the same episode, and labelled the student's states.
    assert planner_like.teacher is not None and planner_like.teacher != planner_like.behaviour
    assert planner_like.labels.max() > 0.5  # the teacher would go faster on the lines
    slow = label_episode(_task(actor=_constant_actor(-1.0), compare=False))
    assert slow.behaviour.cycle_time_s > planner_like.behaviour.cycle_time_s
    assert slow.planner is None and slow.teacher is None


def test_the_shield_holds_the_students_dagger_rollouts_as_it_holds_the_deployed_student():
    free = label_episode(_task(actor=_constant_actor(1.0), compare=False))
    held = label_episode(_task(actor=_constant_actor(1.0), compare=False, shield=PlannerShield(8, 0.05)))
    # Held at the planner's override near the reversal: slower than the unshielded full raise, and the
    # teacher labels every state the shielded student visited.
    assert held.behaviour.cycle_time_s > free.behaviour.cycle_time_s
    assert len(held.labels) == held.behaviour.steps
    # The teacher's own round (no actor) is never shielded.
    teacher = label_episode(_task(compare=False, shield=PlannerShield(8, 0.05)))
    assert teacher.behaviour == label_episode(_task(compare=False)).behaviour


def test_a_process_pool_labels_as_the_serial_run_does():
    tasks = [_task(seed=1, compare=False), _task(seed=2, randomize=RANDOM, compare=False)]
    serial = label_all(tasks, Executor())
    seen: list[str] = []
    pooled = label_all(tasks, Executor(workers=2), on_done=lambda e: seen.append(e.program))
    assert len(seen) == 2
    for a, b in zip(serial, pooled, strict=True):
        np.testing.assert_array_equal(a.observations, b.observations)
        np.testing.assert_array_equal(a.labels, b.labels)
        assert a.behaviour == b.behaviour


def test_ray_labels_as_the_serial_run_does():
    ray = pytest.importorskip("ray")
    tasks = [_task(seed=1, compare=False)]
    try:
        on_ray = label_all(tasks, Executor(use_ray=True))
    finally:
        ray.shutdown()
    np.testing.assert_array_equal(on_ray[0].labels, label_all(tasks, Executor())[0].labels)


# ------------------------------------------------------------------------------------------ student
@pytest.mark.parametrize("quantile", [0.2, 0.5, 0.8])
def test_the_pinball_loss_is_minimised_at_the_quantile(quantile):
    import torch

    rng = np.random.default_rng(0)
    targets = torch.as_tensor(rng.uniform(-1.0, 1.0, 2000), dtype=torch.float32)
    weights = torch.ones_like(targets)
    grid = torch.linspace(-1.0, 1.0, 201)
    losses = [float(quantile_huber_loss(torch.full_like(targets, float(x)), targets, weights, quantile))
              for x in grid]  # fmt: skip
    best = float(grid[int(np.argmin(losses))])
    assert best == pytest.approx(float(np.quantile(targets.numpy(), quantile)), abs=0.03)


def test_weights_pull_the_fit_towards_their_samples():
    import torch

    targets = torch.tensor([0.0, 1.0])
    prediction = torch.tensor([0.5, 0.5], requires_grad=True)
    loss = quantile_huber_loss(prediction, targets, torch.tensor([1.0, 4.0]), 0.5)
    loss.backward()
    assert prediction.grad is not None and float(prediction.grad.sum()) < 0  # the heavy sample wins: go up


def test_the_numpy_actor_is_the_models_deterministic_action():
    env = _env()
    student = Student(env, [16, 16], -2.0, seed=0)
    actor = student.actor_weights()
    rng = np.random.default_rng(1)
    low, high = env.observation_space.low, env.observation_space.high
    for _ in range(20):
        observation = rng.uniform(low, np.minimum(high, 5.0)).astype(np.float32)
        expected, _ = student.model.predict(observation, deterministic=True)
        np.testing.assert_allclose(actor.act(observation), expected, rtol=1e-5, atol=1e-6)


def test_the_student_fits_a_state_dependent_teacher():
    env = _env()
    student = Student(env, [32, 32], -2.0, seed=0)
    rng = np.random.default_rng(2)
    observations = rng.uniform(0.0, 1.0, (2000, 46)).astype(np.float32)
    labels = np.where(observations[:, 5] > 0.5, -0.8, 0.6).astype(np.float32)  # slow down on error
    weights = np.ones(len(labels), np.float32)
    first = student.fit(observations, labels, weights, epochs=1, batch_size=128, learning_rate=3e-3,
                        quantile=0.5)  # fmt: skip
    last = student.fit(observations, labels, weights, epochs=30, batch_size=128, learning_rate=3e-3,
                       quantile=0.5)  # fmt: skip
    assert last < 0.3 * first
    actor = student.actor_weights()
    predicted = np.array([actor.act(o)[0] for o in observations[:200]])
    assert np.mean(np.abs(predicted - labels[:200])) < 0.15


# ------------------------------------------------------------------------------------------- config
def test_the_shipped_distill_config_loads():
    from cnc_gym.benchmark import load_suite
    from cnc_gym_agents.training import load_config

    config = load_config("distill-residual")
    assert config.algorithm == "distill" and config.env.action_mode == "residual"
    assert config.env.randomize is not None and config.env.randomize.enabled
    assert set(config.env.program_list()) == {str(p) for p in load_suite().paths("train")}
    assert config.lagrangian.cost_limit == 0.0  # the fine-tune's budget is the benchmark's


@pytest.mark.parametrize(("text", "message"), [
    ("algorithm: distill\nenv: {id: cnc_gym/Feedrate-v5, programs: [circle]}\n",
     "env.action_mode distill trains a residual policy"),
    ("algorithm: distill\ndistill: {quantile: 1}\n", r"distill.quantile must be in \(0, 1\)"),
    ("algorithm: distill\ndistill: {violation_weight: 0.5}\n",
     r"distill.violation_weight must be in \[1, 1000\]"),
    ("algorithm: distill\nenv: {id: cnc_gym/Feedrate-v5, programs: [circle], action_mode: residual}\n"
     "distill: {finetune_timesteps: 10, finetune_critic_steps: 20}\n",
     "distill.finetune_critic_steps must not exceed finetune_timesteps"),
    ("distill: {roundz: 1}\n", "unknown key distill.roundz"),
])  # fmt: skip
def test_distill_config_mistakes_are_one_line(tmp_path, text, message):
    from cnc_gym_agents.training import load_config

    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(ConfigError, match=message):
        load_config(path)


# --------------------------------------------------------------------------------------- end to end
TINY = {
    "env": {"id": V5, "programs": ["circle", "star"], "action_mode": "residual", "residual_range": 1.25,
            "randomize": RANDOM},
    "algorithm": "distill",
    "distill": {"rounds": 1, "episodes_per_round": 2, "nominal_share": 0.5, "teacher_refine_iterations": 2,
                "teacher_raise_rounds": 0, "epochs": 2, "round_epochs": 1, "batch_size": 256,
                "shield_bins": 1, "shield_error": 0.6, "shield_envelope": True},
    "ppo": {"net_arch": [8, 8]},
    "run_name": "tiny-distill",
    "progress_bar": False,
}  # fmt: skip


def test_overrides_reach_any_key_and_keep_its_rules(tmp_path):
    from cnc_gym_agents.training import load_config

    config = load_config("distill-residual", overrides=["distill.rounds=1", "env.randomize.machines=2",
                                                        "seed=7"])  # fmt: skip
    assert (config.distill.rounds, config.env.randomize.machines, config.seed) == (1, 2, 7)
    assert config.distill.episodes_per_round == load_config("distill-residual").distill.episodes_per_round
    with pytest.raises(ConfigError, match=r"distill.rounds must be an integer in \[0, 100\], got 101"):
        load_config("distill-residual", overrides=["distill.rounds=101"])
    with pytest.raises(ConfigError, match=r"unknown key distill\.roundz"):
        load_config("distill-residual", overrides=["distill.roundz=1"])
    with pytest.raises(ConfigError, match=r"--set 'distill\.rounds': write KEY=VALUE"):
        load_config("distill-residual", overrides=["distill.rounds"])


def _config(**distill):
    from cnc_gym.config import from_mapping
    from cnc_gym_agents.training import TrainConfig

    data = {**TINY, "distill": {**TINY["distill"], **distill}}
    return from_mapping(TrainConfig, data, "<test>")


def test_a_round_takes_the_programs_in_turn_each_episode_with_a_machine_of_its_own():
    from cnc_gym.programs import load_program
    from cnc_gym_agents.distillation import round_tasks

    programs = [load_program("circle"), load_program("star")]
    tasks = round_tasks(_config(episodes_per_round=40, nominal_share=0.25), programs, 1, None)
    assert len(tasks) == 40 and len({t.seed for t in tasks}) == 40
    names = [t.program_name for t in tasks]
    assert all(sorted(names[i : i + 2]) == ["circle", "star"] for i in range(0, 40, 2))  # in turn
    nominal = sum(t.env_kwargs["randomize"] is None for t in tasks)
    assert 2 <= nominal <= 20  # about a quarter on the nominal machine
    again = round_tasks(_config(episodes_per_round=40, nominal_share=0.25), programs, 1, None)
    assert [t.seed for t in again] == [t.seed for t in tasks]  # drawn from (seed, round)
    other = round_tasks(_config(episodes_per_round=40, nominal_share=0.25), programs, 2, None)
    assert [t.seed for t in other] != [t.seed for t in tasks]
    fixed = round_tasks(_config(episodes_per_round=4, nominal_share=0.0), programs, 1, None)
    assert all(t.env_kwargs["randomize"] is not None for t in fixed)


def test_the_students_violating_dagger_episodes_weigh_more():
    from cnc_gym_agents.distillation import Dataset, sample_weight
    from cnc_gym_agents.labelling import LabelledEpisode, Outcome

    def episode(violation_mm: float, finished: bool = True, n: int = 3) -> LabelledEpisode:
        outcome = Outcome(n, 1.0, violation_mm, finished)
        return LabelledEpisode("p", 0, np.zeros((n, 46), np.float32), np.zeros(n, np.float32),
                               np.zeros(n, bool), outcome, None, None, False, 0.0)  # fmt: skip

    assert sample_weight(episode(0.01), 1, 4.0) == 4.0
    assert sample_weight(episode(0.0, finished=False), 2, 4.0) == 4.0  # cut off: not a success either
    assert sample_weight(episode(0.0), 1, 4.0) == 1.0
    assert sample_weight(episode(0.01), 0, 4.0) == 1.0  # round 0 is the teacher's own episode
    data = Dataset()
    data.add(episode(0.01, n=2), sample_weight(episode(0.01), 1, 4.0))
    data.add(episode(0.0, n=3), 1.0)
    observations, _, weights = data.arrays()
    assert len(data) == 5 and observations.shape == (5, 46)
    np.testing.assert_array_equal(weights, [4, 4, 1, 1, 1])


def test_ppo_training_refuses_the_distill_algorithm_and_labelling_options(tmp_path):
    from cnc_gym_agents.training import train

    with pytest.raises(ConfigError, match="algorithm distill is trained by"):
        train(_config())
    command = [sys.executable, "scripts/train.py", "--config", "ppo-residual", "--workers", "2",
               "--no-progress", "--out", str(tmp_path)]  # fmt: skip
    result = subprocess.run(command, cwd=REPO, capture_output=True, text=True, timeout=120)
    assert result.returncode == 2
    assert "--workers and --ray are for algorithm distill" in result.stderr


@pytest.fixture(scope="module")
def distilled(tmp_path_factory):
    out = tmp_path_factory.mktemp("distill")
    config = out / "tiny.yaml"
    config.write_text(yaml.safe_dump(TINY))
    command = [sys.executable, "scripts/train.py", "--config", str(config), "--out", str(out), "--seed", "4",
               "--no-progress"]  # fmt: skip
    result = subprocess.run(command, cwd=REPO, capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    return out / "tiny-distill", result


def test_a_distill_run_saves_a_model_that_loads_without_unpickling(distilled):
    from cnc_gym.policies.model import load_sb3_model
    from cnc_gym.rollout import policy_env, run_episode

    run, result = distilled
    assert f"model:       {run / 'model.zip'}" in result.stdout
    model = load_sb3_model(run / "model.zip")
    assert model.env_id == V5
    assert model.env_kwargs == {"action_mode": "residual", "control_period_s": 0.01, "residual_range": 1.25}
    shield = model.shield
    # shield_bins, shield_error; shield_turn default; the envelope of the machines it was trained on
    assert shield is not None and (shield.bins, shield.turn, shield.error) == (1, 0.25, 0.6)
    envelope = {name: (low, high) for name, low, high in shield.envelope}
    assert list(envelope) == ["kv", "kv_mismatch", "feedforward", "accel_limit"]
    assert all(low <= high for low, high in envelope.values())
    # The default ranges draw feed-forward in [0.5, 0.9], and the nominal machine's 0.7 lies within.
    assert 0.5 <= envelope["feedforward"][0] <= 0.7 <= envelope["feedforward"][1] <= 0.9
    assert load_sb3_model(run / "student.zip").shield == shield
    from cnc_gym.policies import make_policy

    policy = make_policy(str(run / "model.zip"))
    env = policy_env(policy, programs=["circle"])
    episode = run_episode(env, policy)
    assert episode.finished
    saved = yaml.safe_load((run / "config.yaml").read_text())
    assert saved["algorithm"] == "distill" and saved["seed"] == 4


def test_a_distill_run_reports_its_rounds_and_budget(distilled):
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    run, _ = distilled
    summary = json.loads((run / "distill.json").read_text())
    rounds = summary["rounds"]
    assert [r["round"] for r in rounds] == [0, 1] and all(r["episodes"] == 2 for r in rounds)
    assert rounds[0]["time_vs_teacher"] == pytest.approx(1.0, rel=1e-12)  # round 0: the teacher drives
    assert summary["labelled_steps"] == sum(r["labelled_steps"] for r in rounds) > 0
    assert rounds[1]["samples_total"] == summary["labelled_steps"]
    assert summary["labelling_cpu_s"] > 0 and summary["finetune"] is None
    events = EventAccumulator(str(next((run.parent / "tensorboard").glob("tiny-distill_*"))))
    events.Reload()
    assert {"distill/fit_loss", "distill/round_time_vs_planner"} <= set(events.Tags()["scalars"])


def test_an_envelope_without_a_shield_is_refused_before_any_labelling(tmp_path):
    from cnc_gym_agents.distillation import distill

    config = _config(shield_bins=0, shield_envelope=True)
    with pytest.raises(ConfigError, match=r"distill\.shield_envelope: the envelope is the shield's"):
        distill(config, tmp_path, progress_bar=False)
    with pytest.raises(ConfigError, match=r"distill\.shield_hold: the hold is the shield's"):
        distill(_config(shield_bins=0, shield_envelope=False, shield_hold=10), tmp_path, progress_bar=False)
    assert not any(tmp_path.iterdir())


def test_the_envelope_is_each_machine_entrys_range_over_the_samples():
    from cnc_gym_agents.distillation import machine_envelope

    layout = _env().unwrapped.layout
    observations = np.zeros((3, layout.size), np.float32)
    for row, (kv, ff) in enumerate(((0.8, 0.6), (1.2, 0.5), (1.0, 0.9))):
        observations[row, layout.structure["kv"][0]] = kv
        observations[row, layout.structure["feedforward"][0]] = ff
    episodes = [observations[:1], observations[1:]]  # one array per episode
    envelope = {name: (low, high) for name, low, high in machine_envelope(episodes, layout)}
    assert envelope["kv"] == pytest.approx((0.8, 1.2))
    assert envelope["feedforward"] == pytest.approx((0.5, 0.9))
    assert envelope["kv_mismatch"] == (0.0, 0.0) and set(envelope) == {
        e.name for e in layout.entries if e.source == "machine"}  # fmt: skip


def test_timesteps_is_refused_for_distill(tmp_path):
    config = tmp_path / "tiny.yaml"
    config.write_text(yaml.safe_dump({**TINY, "output_dir": str(tmp_path)}))
    command = [sys.executable, "scripts/train.py", "--config", str(config), "--timesteps", "5",
               "--no-progress"]  # fmt: skip
    result = subprocess.run(command, cwd=REPO, capture_output=True, text=True, timeout=120)
    assert result.returncode == 2
    assert "algorithm distill has no total_timesteps" in result.stderr


def test_the_fine_tune_starts_from_the_distilled_actor(tmp_path):
    from cnc_gym.config import from_mapping
    from cnc_gym_agents.distillation import finetune
    from cnc_gym_agents.training import TrainConfig, config_to_dict

    data = {
        **TINY,
        "distill": {**TINY["distill"], "finetune_timesteps": 128, "finetune_critic_steps": 128},
        "ppo": {"net_arch": [8, 8], "n_steps": 64, "batch_size": 64, "n_epochs": 1},
        "n_envs": 2,
    }
    config = from_mapping(TrainConfig, data, "<test>")
    assert config_to_dict(config)["distill"]["finetune_timesteps"] == 128
    student = Student(_env(), [8, 8], -2.0, seed=0)
    before = student.actor_weights()
    (tmp_path / "runs").mkdir()
    config = dataclasses.replace(config, output_dir=str(tmp_path))
    shield = PlannerShield(1, 0.25, None, (("feedforward", 0.5, 0.9),))
    result = finetune(student, config, tmp_path / "runs" / "m.zip", progress_bar=False, shield=shield)
    assert result["timesteps"] == 128
    from cnc_gym.policies.model import load_sb3_model

    tuned = load_sb3_model(tmp_path / "runs" / "m.zip")
    assert tuned.shield == shield  # the fine-tuned model records the distilled student's shield
    # The critic-only phase covered every step: the actor is the distilled one, weight for weight.
    weights = tuned.policy.mlp_extractor.policy_net[0].weight.detach().numpy()
    np.testing.assert_array_equal(weights, before.layers[0][0])
