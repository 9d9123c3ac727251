"""cnc_gym/Feedrate-v1: the return ranks like the benchmark's score, the observation spec, the residual action
on the deployable planner, the cost signal and domain randomisation."""

from __future__ import annotations

import re
import warnings
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import cnc_gym  # noqa: F401  (registers the envs)
from cnc_gym.benchmark.metrics import episode_score, is_feasible
from cnc_gym.envs.feedrate import FeedrateEnv
from cnc_gym.envs.feedrate_v1 import FeedrateEnvV1, RankingReward, RelativeReward, env_arguments_v1
from cnc_gym.envs.observation import OBSERVATION_V1, markdown_table
from cnc_gym.errors import ConfigError
from cnc_gym.motion.bound import time_optimal_bound

REPO = Path(__file__).resolve().parents[2]
ENV_ID = "cnc_gym/Feedrate-v1"


def run_episode(env, actions, seed=0):
    """One episode; ``actions`` is a constant knob or a callable(step) -> knob. Returns (return, steps,
    terminated, truncated, last info, infos)."""
    _, info = env.reset(seed=seed)
    total, steps, infos = 0.0, 0, [info]
    while True:
        knob = actions(steps) if callable(actions) else actions
        _, reward, terminated, truncated, info = env.step(np.array([knob], dtype=np.float32))
        total += reward
        steps += 1
        infos.append(info)
        if terminated or truncated:
            return total, steps, terminated, truncated, info, infos


# ------------------------------------------------------------------------------------------ API checks
def test_gymnasium_and_sb3_checkers_pass_without_warnings():
    from gymnasium.utils.env_checker import check_env
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    env = gym.make(ENV_ID, programs=["star", "circle"], action_mode="residual").unwrapped
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_env(env)
        sb3_check_env(FeedrateEnvV1(programs=["circle"]), warn=True)
    env.close()


def test_observation_spec_gives_bounds_structure_and_table():
    env = FeedrateEnvV1(programs=["circle"], lookahead_points=5)
    n = 5
    assert env.observation_space.shape == (14 + 4 * n,)
    structure = env.observation_structure
    assert list(structure) == [e.name for e in OBSERVATION_V1]
    indices = [i for idx in structure.values() for i in idx]
    assert indices == list(range(14 + 4 * n))  # every entry once, in order
    for entry in OBSERVATION_V1:
        idx = structure[entry.name]
        assert len(idx) == (n if entry.source == "lookahead" else 1)
        assert np.all(env.observation_space.low[idx] == entry.low)
        assert np.all(env.observation_space.high[idx] == entry.high)
    # Nothing that places the tool in a particular program (v0's progress = s / L).
    assert not {"progress", "path_fraction"} & {e.quantity for e in OBSERVATION_V1}
    assert markdown_table() in (env.__doc__ or "").replace("\n    ", "\n")
    docs = (REPO / "docs/env.md").read_text()
    assert markdown_table() in docs, "docs/env.md's Feedrate-v1 observation table differs from the spec"


def test_observation_entries_hold_their_formulas():
    env = FeedrateEnvV1(programs=["circle"], action_mode="residual")
    s = env.observation_structure
    obs, info = env.reset(seed=0)
    for _ in range(150):
        obs, _, _, _, info = env.step(np.zeros(1, dtype=np.float32))
    assert obs[s["speed"][0]] == pytest.approx(info["feed_mm_min"] / 60 / 250, rel=1e-5)
    assert obs[s["override"][0]] == pytest.approx(info["override"] / 2.0, rel=1e-5)
    assert obs[s["contour_error_step"][0]] == pytest.approx(min(info["contour_error_mm"] / 0.02, 5), rel=1e-5)
    assert obs[s["planner_override"][0]] == pytest.approx(info["planner_override"] / 2.0, rel=1e-6)
    assert obs[s["kv"][0]] == pytest.approx(38 / 40)  # vmc-small: Y has the lowest Kv, 38 1/s
    assert obs[s["kv_mismatch"][0]] == pytest.approx((45 - 38) / np.mean([40, 38, 45]) / 0.1, rel=1e-6)
    assert obs[s["feedforward"][0]] == pytest.approx(0.7)
    assert obs[s["accel_limit"][0]] == pytest.approx(1.0)
    assert obs[s["violation_free"][0]] == float(info["violation_length_mm"] == 0.0) == 1.0


# ------------------------------------------------------------------------------------------ the ranking
@pytest.fixture(scope="module")
def circle_outcomes():
    """Episodes of known outcome on circle.nc: constant overrides 0.2, 0.5, 1.0 finish within tolerance,
    1.5 and 2.0 finish with violations, the knob at 0 is truncated, and so is 0.5 with a short budget."""
    env = FeedrateEnvV1(programs=["circle"])
    outcomes = {}
    for override in (0.2, 0.5, 1.0, 1.5, 2.0, 0.0):
        total, steps, terminated, _, info, infos = run_episode(env, override - 1.0)
        outcomes[override] = (total, steps, terminated, info, infos)
    short = FeedrateEnvV1(programs=["circle"], max_episode_steps=400)
    total, steps, terminated, _, info, infos = run_episode(short, -0.5)
    outcomes["truncated"] = (total, steps, terminated, info, infos)
    return env, outcomes


def test_outcomes_are_what_the_fixture_says(circle_outcomes):
    _, out = circle_outcomes
    for key in (0.2, 0.5, 1.0):
        assert out[key][2] and out[key][3]["violation_length_mm"] == 0.0
    for key in (1.5, 2.0):
        assert out[key][2] and out[key][3]["violation_length_mm"] > 0.0
    for key in (0.0, "truncated"):
        assert not out[key][2]


def test_returns_rank_like_the_benchmark_score(circle_outcomes):
    env, out = circle_outcomes
    bound = time_optimal_bound(env.toolpath, env.machine).total_s
    scores, returns = {}, {}
    for key, (total, _, terminated, info, _) in out.items():
        ratio = info["cycle_time_s"] / bound
        scores[key] = episode_score(terminated, info["violation_length_mm"], ratio)
        returns[key] = total
    feasible = [k for k in out if is_feasible(out[k][2], out[k][3]["violation_length_mm"])]
    infeasible = [k for k in out if k not in feasible]
    assert sorted(feasible, key=str) == [0.2, 0.5, 1.0]
    # 1. a finished, violation-free episode beats every violating or truncated one;
    assert min(returns[k] for k in feasible) > max(returns[k] for k in infeasible)
    # 2. among violation-free episodes the faster one wins: the same order as the score.
    by_return = sorted(feasible, key=lambda k: returns[k])
    assert by_return == sorted(feasible, key=lambda k: scores[k]) == [0.2, 0.5, 1.0]


def test_error_inside_tolerance_costs_nothing(circle_outcomes):
    # 3. a violation-free episode's return is the closed form of its length alone, whatever its error.
    env, out = circle_outcomes
    w = RankingReward()
    tau = env.control_period_s / env.nominal_time_s
    for key in (0.2, 0.5, 1.0):
        total, steps, _, info, _ = out[key]
        assert info["contour_error_max_mm"] > 0.0
        budget = env.max_episode_steps
        expected = w.progress - w.time * steps * tau + (w.time * budget * tau + w.finish)
        assert total == pytest.approx(expected, rel=1e-9, abs=1e-9)


def test_reward_terms_in_info_add_up_and_cost_is_the_violation_length(circle_outcomes):
    _, out = circle_outcomes
    for key in (1.0, 2.0, "truncated"):
        total, _, _, info, infos = out[key]
        terms = sum(i["reward_time"] + i["reward_progress"] + i["reward_violation"] + i["reward_finish"]
                    for i in infos[1:])  # fmt: skip
        assert terms == pytest.approx(total, rel=1e-9, abs=1e-9)
        assert sum(i["cost"] for i in infos[1:]) == pytest.approx(info["violation_length_mm"], abs=1e-12)
        assert all(i["cost"] >= 0 for i in infos)
        assert sum(i["reward_finish"] > 0 for i in infos) == (1 if key == 1.0 else 0)


def test_violations_and_time_do_not_depend_on_the_control_period():
    totals = []
    for period in (0.01, 0.02):
        env = FeedrateEnvV1(programs=["circle"], control_period_s=period)
        _, _, _, _, info, infos = run_episode(env, 0.5)  # override 1.5: violating
        time_cost = sum(i["reward_time"] for i in infos[1:])
        # The time term is the cycle time over the nominal time, whatever the period.
        assert time_cost == pytest.approx(-info["cycle_time_s"] / env.nominal_time_s, rel=1e-9)
        totals.append((info["cycle_time_s"], info["violation_length_mm"], sum(i["cost"] for i in infos[1:])))
    (t1, v1, c1), (t2, v2, c2) = totals
    # The same motion (a constant knob): the same violation length, measured per servo sample.
    assert v1 > 0 and v1 == pytest.approx(v2, rel=1e-9) and c1 == pytest.approx(c2, rel=1e-9)
    # The cycle times differ only by the in-position checks, made once per control step (five stops).
    assert abs(t1 - t2) <= 5 * 0.02


@pytest.mark.parametrize("kwargs", [{"time": 0}, {"finish": 0}, {"violation": -1}])
def test_reward_weights_that_would_break_the_ranking_are_refused(kwargs):
    with pytest.raises(ConfigError, match=r"FeedrateEnv-v1: reward\.\w+ must be"):
        FeedrateEnvV1(programs=["circle"], reward=kwargs)


# ---------------------------------------------------------------------------------- residual and v0 parity
@pytest.mark.parametrize("version", [1, 2])
def test_residual_zero_is_the_classical_planner(version):
    # Feedrate-v1/v2 residual mode follows the frozen planner version 1; Feedrate-v3's the live version 2.
    from cnc_gym.policies.classical import ClassicalPlanner

    v0 = FeedrateEnv(programs=["star"])
    planner = ClassicalPlanner(version=version)
    obs, info = v0.reset(seed=0)
    planner.reset(v0)
    done, steps = False, 0
    while not done:
        obs, _, terminated, truncated, info = v0.step(planner.act(obs, info))
        done, steps = terminated or truncated, steps + 1
    _, steps1, _, _, info1, _ = run_episode(FeedrateEnvV1(programs=["star"], action_mode="residual",
                                                       planner_version=version), 0.0)
    assert (steps1, info1["cycle_time_s"], info1["violation_length_mm"], info1["contour_error_max_mm"]) == (
        steps, info["cycle_time_s"], info["violation_length_mm"], info["contour_error_max_mm"])


def test_residual_scales_the_planner_override():
    env = FeedrateEnvV1(programs=["circle"], action_mode="residual")
    env.reset(seed=0)
    for _ in range(20):
        env.step(np.zeros(1, dtype=np.float32))
    planned = env.planner_override
    _, _, _, _, info = env.step(np.array([-1.0], dtype=np.float32))  # × 1/2
    assert env.unwrapped._batch.actions[0] == pytest.approx(2 * (planned / 2) / 2.0 - 1, abs=1e-6)
    assert info["planner_override"] > 0


def test_without_randomisation_v1_moves_like_v0():
    _, _, _, _, info1, _ = run_episode(FeedrateEnvV1(programs=["freeform"]), 0.3)
    _, _, _, _, info0, _ = run_episode(FeedrateEnv(programs=["freeform"]), 0.3)
    for key in ("cycle_time_s", "violation_length_mm", "contour_error_max_mm", "contour_error_rms_mm"):
        assert info1[key] == info0[key]


# ---------------------------------------------------------------------------------- domain randomisation
def test_randomisation_draws_machines_and_feeds_within_the_ranges():
    ranges = {"enabled": True, "machines": 3, "kv_scale": [0.8, 1.2], "kv_mismatch": [0.0, 0.05],
              "feedforward": [0.5, 0.6], "accel_scale": [0.9, 1.1], "feed_scale": [0.7, 0.8]}  # fmt: skip
    env = FeedrateEnvV1(programs=["circle", "star"], randomize=ranges)
    machines, feeds = set(), []
    for seed in range(8):
        obs, _ = env.reset(seed=seed)
        draw = env.episode_draw
        machines.add(draw.machine)
        feeds.append(env.feed_scale)
        kv = np.array(draw.machine.axis_array("kv_1_s")) / np.array([40, 38, 45])
        assert np.all((kv >= 0.8 * 0.95 - 1e-12) & (kv <= 1.2 * 1.05 + 1e-12))
        assert 0.5 <= draw.feedforward <= 0.6 and 0.9 <= draw.accel_scale <= 1.1
        assert env.observation_space.contains(obs)
        assert obs[env.observation_structure["feedforward"][0]] == pytest.approx(draw.feedforward, rel=1e-6)
        original = env.resolve_program(env.program_name)[1]
        np.testing.assert_allclose(env.toolpath.feed, original.feed * env.feed_scale, rtol=1e-12)
    assert 2 <= len(machines) <= 3 and all(0.7 <= f <= 0.8 for f in feeds) and len(set(feeds)) == 8
    # The same seed, the same episode.
    env.reset(seed=3)
    first = (env.episode_draw, env.feed_scale, env.program_name)
    env.reset(seed=3)
    assert (env.episode_draw, env.feed_scale, env.program_name) == first


def test_randomised_episodes_run_and_differ():
    env = FeedrateEnvV1(programs=["circle"], randomize={"enabled": True, "machines": 4})
    outcomes = {run_episode(env, 0.0, seed=seed)[4]["cycle_time_s"] for seed in range(3)}
    assert len(outcomes) > 1


@pytest.mark.parametrize(("ranges", "match"), [
    ({"kv_scale": [1.2, 0.8]}, r"randomize\.kv_scale must be \[low, high\] with low <= high"),
    ({"kv_scale": [0, 1]}, r"randomize\.kv_scale ends must be in \[0\.1, 10\]"),
    ({"feedforward": [0.5, 1.5]}, r"randomize\.feedforward ends must be in \[0, 1\]"),
    ({"feed_scale": 1.0}, r"randomize\.feed_scale must be a range \[low, high\]"),
    ({"kv_spread": [0, 1]}, "unknown key randomize.kv_spread"),
    ({"enabled": True, "kv_scale": [1, 10], "kv_mismatch": [0, 0.5]}, "stability limit"),
])  # fmt: skip
def test_bad_randomisation_is_one_config_error(ranges, match):
    with pytest.raises(ConfigError, match=match) as err:
        FeedrateEnvV1(programs=["circle"], randomize=ranges)
    assert "\n" not in str(err.value)


def test_bad_arguments_are_one_config_error():
    with pytest.raises(ConfigError, match=r"FeedrateEnv-v1: action_mode must be one of override, feed, "
                                          r"residual"):  # fmt: skip
        FeedrateEnvV1(programs=["circle"], action_mode="knob")
    with pytest.raises(ConfigError, match="unknown argument progress_bonus"):
        env_arguments_v1(progress_bonus=1.0)
    with pytest.raises(ConfigError, match=re.escape("residual_range must be in (1, 10]")):
        FeedrateEnvV1(programs=["circle"], residual_range=1.0)


# ----------------------------------------------------------------------- v6: the relative reward rule
V6 = "cnc_gym/Feedrate-v6"


@pytest.fixture(scope="module")
def circle_outcomes_v6():
    """Feedrate-v6 episodes on circle.nc: overrides 0.2, 0.5, 1.0 (within tolerance), 2.0 (violating), the
    knob at 0 (truncated by the step budget), and 0.5 with a short budget (truncated)."""
    env = gym.make(V6, programs=["circle"]).unwrapped
    outcomes = {}
    for override in (0.2, 0.5, 1.0, 2.0, 0.0):
        total, steps, terminated, _, info, infos = run_episode(env, override - 1.0)
        outcomes[override] = (total, steps, terminated, info, infos)
    short = gym.make(V6, programs=["circle"], max_episode_steps=200)  # (TimeLimit truncates)
    total, steps, terminated, _, info, infos = run_episode(short, -0.5)
    outcomes["truncated"] = (total, steps, terminated, info, infos)
    return env, outcomes


def test_v6_counts_time_per_the_planners_scheduled_time(circle_outcomes_v6):
    env, out = circle_outcomes_v6
    assert env.reward_rule == "relative" and isinstance(env.reward_weights, RelativeReward)
    _, toolpath = env.resolve_program(0)
    t_plan = env._planner.schedule(toolpath, env.machine, None).time_s + float(np.sum(toolpath.dwell_s))
    assert env.reward_time_s(toolpath, env.nominal_time_s) == t_plan
    # The planner's schedule is slower than the programmed feed on this program, and it is what τ counts in.
    assert t_plan > env.nominal_time_s
    w = RelativeReward()
    for key in (0.2, 0.5, 1.0):
        total, steps, terminated, info, infos = out[key]
        assert terminated and info["violation_length_mm"] == 0.0
        # No finish bonus: a violation-free return is the progress less the time, per T_plan.
        assert total == pytest.approx(w.progress - w.time * steps * env.control_period_s / t_plan,
                                      rel=1e-9, abs=1e-9)  # fmt: skip
        assert all("reward_finish" not in i for i in infos)
        terms = sum(i["reward_time"] + i["reward_progress"] + i["reward_violation"] for i in infos[1:])
        assert terms == pytest.approx(total, rel=1e-9, abs=1e-9)


def test_v6_ranks_violation_free_finishes_like_the_score_and_finishes_above_truncations(circle_outcomes_v6):
    env, out = circle_outcomes_v6
    bound = time_optimal_bound(env.resolve_program(0)[1], env.machine).total_s
    feasible = [0.2, 0.5, 1.0]
    scores = {k: episode_score(True, 0.0, out[k][3]["cycle_time_s"] / bound) for k in feasible}
    assert sorted(feasible, key=lambda k: out[k][0]) == sorted(feasible, key=lambda k: scores[k]) == feasible
    # Every finish outranks the episode the same budget truncated (p < 1 and n ≤ N_max).
    assert not out[0.0][2] and min(out[k][0] for k in feasible) > out[0.0][0]
    # A truncated episode's return is its progress less its time: nothing more.
    total, steps, terminated, info, infos = out["truncated"]
    progress = sum(i["reward_progress"] for i in infos[1:])
    assert not terminated and 0.0 < progress < 1.0
    assert total == pytest.approx(progress - steps * env.control_period_s / env.reward_time_s(
        env.resolve_program(0)[1], env.nominal_time_s), rel=1e-9)
    # The violating episode pays its violation length (w_violation per mm) and its cost is that length.
    total, steps, _, info, infos = out[2.0]
    assert info["violation_length_mm"] > 0.0
    assert sum(i["cost"] for i in infos[1:]) == pytest.approx(info["violation_length_mm"], abs=1e-12)
    assert sum(i["reward_violation"] for i in infos[1:]) == pytest.approx(
        -RelativeReward().violation * info["violation_length_mm"], rel=1e-9)


def test_v6_moves_and_observes_like_v5():
    # Only the reward differs: the same knob sequence gives the same observations and motion.
    knobs = np.random.default_rng(3).uniform(-1.0, 1.0, 900).astype(np.float32)
    runs = []
    for env_id in ("cnc_gym/Feedrate-v5", V6):
        env = gym.make(env_id, programs=["star", "circle"], action_mode="residual").unwrapped
        obs, _ = env.reset(seed=5)
        seen = [obs]
        for knob in knobs:
            obs, _, terminated, truncated, info = env.step(np.array([knob]))
            seen.append(obs)
            if terminated or truncated:
                obs, _ = env.reset()
                seen.append(obs)
        runs.append((np.array(seen), info["cycle_time_s"], info["violation_length_mm"]))
    (obs5, t5, v5), (obs6, t6, v6) = runs
    np.testing.assert_array_equal(obs5, obs6)
    assert (t5, v5) == (t6, v6)


def test_v6_reward_weights_are_its_own():
    with pytest.raises(ConfigError, match=r"^FeedrateEnv-v1: unknown key reward.finish \(allowed: progress, "
                                          r"time, violation\)$"):  # fmt: skip
        gym.make(V6, reward={"finish": 1.0})
    with pytest.raises(ConfigError, match=r"reward.progress must be in \(0, 1e6\]"):
        gym.make(V6, reward={"progress": 0.0})
    assert gym.make(V6, reward={"time": 2.0}).unwrapped.reward_weights == RelativeReward(time=2.0)
    # v5 keeps its ranking rule and its weights.
    v5 = gym.make("cnc_gym/Feedrate-v5").unwrapped
    assert v5.reward_rule == "ranking" and v5.reward_weights == RankingReward()
