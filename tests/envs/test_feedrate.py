"""cnc_gym/Feedrate-v0: API compliance, episodes, seeding, action modes, reward formula, info, render."""

from __future__ import annotations

import math
import warnings

import gymnasium as gym
import numpy as np
import pytest

import cnc_gym  # noqa: F401  (registers the env)
from cnc_gym.envs.engine import LOOKAHEAD_ROWS, ObservationSpec
from cnc_gym.envs.feedrate import (
    SCALAR_FEATURES,
    ActionError,
    FeedrateEnv,
    nominal_time_s,
    observation_layout_v0,
)
from cnc_gym.envs.observation import OBSERVATION_V0, markdown_table
from cnc_gym.errors import CncGymError, ConfigError
from cnc_gym.programs import BUILTIN_PROGRAMS, ProgramText, load_program

ENV_ID = "cnc_gym/Feedrate-v0"
INFO_KEYS = {
    "cycle_time_s", "contour_error_mm", "contour_error_max_mm", "contour_error_rms_mm", "tolerance_mm",
    "violations", "violation_length_mm", "violation_time_s", "cost", "line", "override", "feed_mm_min",
    "path_s", "progress", "program", "steps",
}  # fmt: skip
# circle.nc at 100 % with infinite acceleration, by hand (test_nominal_time_by_hand).
T_NOMINAL_CIRCLE = 2 * math.pi * 30 / 50 + 0.5 + 0.084
# circle.nc's whole path length (cutting + rapid), by hand: rapids 5 + 30 + 1 + 6 = 42 mm, plunge 5 mm,
# circle 2π·30 mm: 235.496 mm. The progress reward term is w_progress · Δs / this.
LENGTH_CIRCLE_MM = 42 + 5 + 2 * math.pi * 30


def run_constant(env: FeedrateEnv, knob: float, program: str | None = None, max_steps: int = 100_000):
    """Run one episode at a constant action; returns (rewards, infos, terminated, truncated)."""
    options = {"program": program} if program is not None else None
    _, info = env.reset(seed=0, options=options)
    rewards, infos = [], [info]
    action = np.array([knob], dtype=np.float32)
    for _ in range(max_steps):
        _, reward, terminated, truncated, info = env.step(action)
        rewards.append(reward)
        infos.append(info)
        if terminated or truncated:
            return np.array(rewards), infos, terminated, truncated
    raise AssertionError("episode did not end")


@pytest.fixture(scope="module")
def circle_env():
    env = FeedrateEnv(programs=["circle"])
    yield env
    env.close()


# ------------------------------------------------------------------------------------------ API checks
def test_make_with_no_arguments():
    env = gym.make(ENV_ID)
    obs, info = env.reset(seed=1)
    assert env.observation_space.contains(obs)
    assert set(info) == INFO_KEYS
    assert info["program"] in BUILTIN_PROGRAMS
    assert env.unwrapped.machine.name == "vmc-small"
    env.close()


def test_gymnasium_check_env_without_warnings():
    from gymnasium.utils.env_checker import check_env

    env = gym.make(ENV_ID, programs=["star", "circle"]).unwrapped
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # any checker warning fails the test
        check_env(env)  # also makes a render_mode="rgb_array" twin through the spec and renders it
    env.close()


def test_sb3_check_env_without_warnings():
    pytest.importorskip("stable_baselines3")
    from stable_baselines3.common.env_checker import check_env

    env = FeedrateEnv(programs=["star"])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_env(env, warn=True)
    env.close()


def test_spaces():
    env = FeedrateEnv(programs=["circle"], lookahead_points=6)
    assert env.action_space.shape == (1,)
    assert env.action_space.low[0] == -1.0 and env.action_space.high[0] == 1.0
    assert env.observation_space.shape == (9 + 4 * 6,)
    assert env.observation_space.dtype == np.float32
    assert np.all(np.isfinite(env.observation_space.low)) and np.all(np.isfinite(env.observation_space.high))


def test_observation_is_declared_once_with_structure_and_table():
    env = FeedrateEnv(programs=["circle"], lookahead_points=6)
    structure = env.observation_structure
    assert list(structure) == [e.name for e in OBSERVATION_V0]
    assert [i for idx in structure.values() for i in idx] == list(range(9 + 4 * 6))
    for entry in OBSERVATION_V0:
        assert np.all(env.observation_space.low[structure[entry.name]] == entry.low)
        assert np.all(env.observation_space.high[structure[entry.name]] == entry.high)
    assert tuple(name for name, idx in structure.items() if len(idx) == 1) == SCALAR_FEATURES
    assert [e.quantity for e in OBSERVATION_V0 if e.source == "lookahead"] == list(LOOKAHEAD_ROWS)
    assert markdown_table(OBSERVATION_V0) in (env.__doc__ or "").replace("\n    ", "\n")


def test_observation_spec_is_the_published_one():
    # Feedrate-v0's compiled observation, as published (a registered env's observation never changes):
    # written out here, not from OBSERVATION_V0, so an edit of the declaration that changes it fails.
    v, a, ov, tol, h = 250.0, 3000.0, 2.0, 0.02, 24.0
    published = ObservationSpec(
        (("speed", 1 / v, 0, 2), ("accel", 1 / a, -2, 2), ("override", 1 / ov, 0, 1), ("knob", 1.0, -1, 1),
         ("following_error", 1.0, 0, 5), ("contour_error_step", 1 / tol, 0, 5),
         ("contour_error_now", 1 / tol, 0, 5), ("path_fraction", 1.0, 0, 1),
         ("distance_to_stop", 1 / h, 0, 1)),
        (("speed_limit", "none", 0.0, 1 / v, 0.0, 2), ("curvature", "saturate", 10.0, 1.0, 0.0, 1),
         ("turn_angle", "none", 0.0, 1 / math.pi, 0.0, 1), ("programmed_feed", "none", 0.0, 1 / v, 0.0, 2)),
        8,
    )  # fmt: skip
    spec = observation_layout_v0(8, v, a, ov, tol, h).kernel_spec
    assert spec == published and repr(spec) == repr(published)


# ------------------------------------------------------------------------------------------- episodes
@pytest.mark.parametrize("program", BUILTIN_PROGRAMS)
def test_episode_terminates_at_constant_override(program):
    env = FeedrateEnv(programs=[program])
    rewards, infos, terminated, truncated = run_constant(env, 0.0)  # a = 0 is 100 % override
    end = infos[-1]
    assert terminated and not truncated
    assert end["progress"] == pytest.approx(1.0)
    assert bool(env.plant.settled(env.in_position_mm)[0])
    assert env.controller.finished
    # Cycle time: steps × 10 ms, and never shorter than the cutting moves at their programmed feed
    # (100 % override cannot exceed F): Σ length / F over cutting segments.
    assert end["cycle_time_s"] == pytest.approx(end["steps"] * 0.01)
    tp = env.toolpath
    cut = np.isfinite(tp.feed) & (tp.length > 0)
    assert end["cycle_time_s"] > float(np.sum(tp.length[cut] / (tp.feed[cut] / 60.0)))
    # Every observation along the way was inside the space (check at the end state here).
    assert all(set(i) == INFO_KEYS for i in infos)
    assert np.all(np.isfinite(rewards))
    env.close()


def test_truncation_by_step_budget():
    env = FeedrateEnv(programs=["circle"], max_episode_steps=100)
    rewards, infos, terminated, truncated = run_constant(env, -1.0)  # override 0: the machine never moves on
    assert truncated and not terminated
    assert len(rewards) == 100
    # Rapids ignore the feed override, so the approach still happens; no cutting move ever starts.
    first_cut = int(np.flatnonzero(np.isfinite(env.toolpath.feed))[0])
    assert infos[-1]["path_s"] == pytest.approx(env.toolpath.s_start[first_cut], abs=1e-6)


def test_default_budget_is_five_times_nominal_time(circle_env):
    t_nominal = nominal_time_s(circle_env.toolpath, circle_env.machine)
    assert circle_env.max_episode_steps == math.ceil(5 * t_nominal / 0.01) + 100


def test_nominal_time_by_hand():
    # circle.nc: full circle R 30 at F3000 (50 mm/s): 2π·30/50 = 3.76991 s; plunge Z4 → Z-1 at F600:
    # 5/10 = 0.5 s; rapids Z0→5, (0,0)→(30,0), Z5→4 and the final Z-1→5 = 5 + 30 + 1 + 6 = 42 mm at
    # the slowest rapid rate, 30 000 mm/min = 500 mm/s: 0.084 s. Total 4.35391 s.
    _, tp = load_program("circle")
    env = FeedrateEnv(programs=["circle"])
    assert nominal_time_s(tp, env.machine) == pytest.approx(T_NOMINAL_CIRCLE, rel=1e-9)


# -------------------------------------------------------------------------------------------- seeding
def rollout(env: FeedrateEnv, seed: int, n_steps: int = 40):
    obs, info = env.reset(seed=seed)
    env.action_space.seed(seed)
    trace = [obs]
    for _ in range(n_steps):
        obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
        trace.append(np.append(obs, reward))
        if terminated or truncated:
            break
    return info["program"], np.concatenate(trace)


def test_same_seed_same_episode():
    a = FeedrateEnv()
    b = FeedrateEnv()
    program_a, trace_a = rollout(a, seed=7)
    program_b, trace_b = rollout(b, seed=7)
    assert program_a == program_b
    np.testing.assert_array_equal(trace_a, trace_b)
    # Re-running on the same env (after other episodes) reproduces it too.
    rollout(a, seed=3)
    program_c, trace_c = rollout(a, seed=7)
    assert program_c == program_a
    np.testing.assert_array_equal(trace_c, trace_a)


def test_seed_draws_the_program_and_options_override_it():
    env = FeedrateEnv()
    drawn = {env.reset(seed=seed)[1]["program"] for seed in range(30)}
    assert drawn == set(BUILTIN_PROGRAMS)  # 30 draws from 4 programs: all appear (P(miss) < 4·0.75^30)
    for seed in range(5):
        assert env.reset(seed=seed, options={"program": "pocket"})[1]["program"] == "pocket"
    assert env.reset(options={"program": 1})[1]["program"] == "star"
    with pytest.raises(ConfigError):
        env.reset(options={"program": 9})
    with pytest.raises(ConfigError):
        env.reset(options={"toolpath": "circle"})


def test_reset_option_loads_a_program_outside_the_set():
    env = FeedrateEnv(programs=["circle"])
    _, info = env.reset(options={"program": "G90 G21\nG01 X5.0 F1200.0\nM30\n"})
    assert info["program"].startswith("text-")
    assert env.toolpath.total_length == pytest.approx(5.0)


# -------------------------------------------------------------------------------------- action modes
def test_override_mapping_and_clipping(circle_env):
    circle_env.reset(seed=0)
    for _ in range(80):
        circle_env.step(np.array([0.5], dtype=np.float32))
    # a = 0.5 → (0.5 + 1)/2 · 2.0 = 1.5 (150 %); the applied override has had 0.8 s to follow the knob.
    assert circle_env.unwrapped.controller.override_applied == pytest.approx(1.5, abs=1e-6)
    obs, *_ = circle_env.step(np.array([7.0], dtype=np.float32))  # clipped to 1.0 (200 %)
    assert obs[3] == pytest.approx(1.0)


def test_feed_mode_commands_the_feed():
    # a = -0.6 → (−0.6 + 1)/2 · 15 000 = 3000 mm/min; on the circle (programmed F3000) the path speed in
    # the middle of the circle is then 50 mm/s, the same as 100 % override in override mode. The
    # commanded feed replaces F on every cutting move, so the 5 mm plunge (F600 = 10 mm/s in the program)
    # runs at 50 mm/s: 0.5 s − 0.1 s = 0.4 s saved, less a little for the longer acceleration.
    env = FeedrateEnv(programs=["circle"], action_mode="feed")
    _, infos, terminated, _ = run_constant(env, -0.6)
    assert terminated
    middle = [i for i in infos if 0.3 < i["progress"] < 0.7]
    assert middle and all(i["feed_mm_min"] == pytest.approx(3000.0, rel=1e-3) for i in middle)
    _, infos_override, _, _ = run_constant(FeedrateEnv(programs=["circle"]), 0.0)
    saved = infos_override[-1]["cycle_time_s"] - infos[-1]["cycle_time_s"]
    assert 0.3 < saved < 0.4


def test_faster_override_finishes_sooner_with_more_error():
    env = FeedrateEnv(programs=["circle"])
    _, slow, *_ = run_constant(env, -0.5)  # 50 %
    _, fast, *_ = run_constant(env, 1.0)  # 200 %
    assert fast[-1]["cycle_time_s"] < 0.6 * slow[-1]["cycle_time_s"]
    # Circle error grows roughly with v² (radial) plus v (gain mismatch): 4× the speed, well over 3× the
    # RMS error (the max is dominated by the approach, the RMS by the circle itself).
    assert fast[-1]["contour_error_rms_mm"] > 3 * slow[-1]["contour_error_rms_mm"]
    assert fast[-1]["contour_error_max_mm"] > slow[-1]["contour_error_max_mm"]


@pytest.mark.parametrize(
    "action",
    [np.array([np.nan], dtype=np.float32), np.array([np.inf]), np.zeros(2), np.zeros((1, 2)), "fast", None],
)
def test_bad_actions_raise_one_clear_error(circle_env, action):
    circle_env.reset(seed=0)
    with pytest.raises(ActionError) as err:
        circle_env.step(action)
    assert isinstance(err.value, ValueError) and isinstance(err.value, CncGymError)
    assert "action" in str(err.value)


@pytest.mark.parametrize(
    "action", [0.25, np.float32(0.25), np.float64(0.25), [0.25], (0.25,), np.array(0.25), np.array([0.25])]
)
def test_scalar_and_python_float_actions_are_accepted(circle_env, action):
    # Any real number, or a sequence/array of one, is the same knob as the canonical float32 array.
    circle_env.reset(seed=0)
    expected = [circle_env.step(np.array([0.25], dtype=np.float32)) for _ in range(3)]
    circle_env.reset(seed=0)
    got = [circle_env.step(action) for _ in range(3)]
    for (obs, reward, terminated, truncated, info), want in zip(got, expected, strict=True):
        np.testing.assert_array_equal(obs, want[0])
        assert (reward, terminated, truncated, info) == want[1:]
        assert obs[SCALAR_FEATURES.index("knob")] == 0.25


@pytest.mark.parametrize("text", ["G90\nM30\n", "", "T1 M06\nM03 S1000\nM05\nM30\n"])
def test_a_program_without_motion_ends_at_the_first_step_in_zero_seconds(text):
    env = gym.make("cnc_gym/Feedrate-v0", programs=[ProgramText(text)])
    obs, info = env.reset(seed=0)
    assert env.observation_space.contains(obs) and info["progress"] == 1.0
    obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
    assert terminated and not truncated and reward == 0.0
    assert env.observation_space.contains(obs)
    assert info["cycle_time_s"] == 0.0 and info["violations"] == 0 and info["contour_error_max_mm"] == 0.0
    assert info["steps"] == 1
    env.reset(seed=1)  # and it starts over like any program
    env.close()


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"action_mode": "velocity"}, "action_mode"),
        ({"control_period_s": 0.003}, "multiple"),
        ({"control_period_s": -0.01}, "control_period_s"),
        ({"reward": {"time": 1.0, "speed": 2.0}}, "unknown key reward.speed"),
        ({"reward": {"violation": -1.0}}, "violation"),
        ({"render_mode": "human"}, "render_mode"),
        ({"max_episode_steps": 0}, "max_episode_steps"),
        ({"programs": []}, "at least one"),
        ({"programs": ["nosuchprogram"]}, "unknown program"),
        ({"machine": "nosuchmachine"}, "unknown machine"),
        ({"lookahead_mm": 0.0}, "lookahead_mm"),
        ({"lookahead_mm": float("nan")}, "lookahead_mm"),
        ({"lookahead_points": 0}, "lookahead_points"),
        ({"lookahead_points": 2.5}, "lookahead_points"),
    ],
)
def test_bad_configuration_is_a_config_error(kwargs, match):
    with pytest.raises(ConfigError, match=match):
        FeedrateEnv(**{"programs": ["circle"], **kwargs})


# -------------------------------------------------------------------------------------------- reward
def test_reward_matches_the_documented_formula():
    # r = −w_time·dt/T_nominal − w_error·min(e/tol, cap)² − w_violation·[e > tol], with weights chosen here
    # and T_nominal of circle.nc computed by hand (see test_nominal_time_by_hand): 4.35391 s.
    # The progress term + w_progress·Δp uses p = path_s / L with L of circle.nc by hand (LENGTH_CIRCLE_MM),
    # and p = 1 exactly once the program is done (the last steps settle: Δp = 0 there).
    weights = {"time": 2.0, "progress": 3.0, "contour_error": 0.3, "violation": 5.0, "error_ratio_cap": 1.5}
    env = FeedrateEnv(programs=["circle"], reward=weights)
    t_nominal = T_NOMINAL_CIRCLE
    rewards, infos, terminated, _ = run_constant(env, 1.0)  # 200 %: some steps exceed the tolerance
    assert terminated
    tol = 0.02
    seen_violation = seen_capped = False
    for reward, info, before in zip(rewards, infos[1:], infos[:-1], strict=True):
        e = info["contour_error_mm"]
        ratio = min(e / tol, 1.5)
        progress_now = 1.0 if info is infos[-1] else info["path_s"] / LENGTH_CIRCLE_MM
        progress_before = before["path_s"] / LENGTH_CIRCLE_MM
        delta_p = progress_now - progress_before
        expected = 3.0 * delta_p - 2.0 * 0.01 / t_nominal - 0.3 * ratio**2 - (5.0 if e > tol else 0.0)
        assert reward == pytest.approx(expected, rel=1e-9, abs=1e-9)
        assert info["cost"] == (1.0 if e > tol else 0.0)
        seen_violation |= e > tol
        seen_capped |= e > 1.5 * tol
    assert seen_violation and seen_capped
    assert infos[-1]["violations"] == sum(i["cost"] for i in infos[1:])


def test_hand_checked_first_step(circle_env):
    # First step from rest: the tool rises from Z0 on a rapid, which is not a cutting move, so the contour
    # error is 0 and the reward is the time term alone: −10 · 0.01 / 4.35391 = −0.0229679.
    # Plus the progress term: 10 · path_s / 235.496 mm (the rapid's first 10 ms of travel).
    circle_env.reset(seed=0)
    _, reward, *_, info = circle_env.step(np.zeros(1, dtype=np.float32))
    assert info["contour_error_mm"] == 0.0
    assert 0.0 < info["path_s"] < 5.0  # still on the first rapid
    assert reward == pytest.approx(-0.0229679 + 10.0 * info["path_s"] / LENGTH_CIRCLE_MM, rel=1e-5)


def test_hand_checked_progress_term():
    # Only the progress term (w_progress = 4, all other weights 0). circle.nc is 235.496 mm long (see
    # LENGTH_CIRCLE_MM), so every step pays 4 · Δs / 235.496 and a finished episode pays exactly 4,
    # whatever the override: 4 at 100 % and at 200 %, though the 200 % run pays it in fewer steps.
    weights = {"time": 0.0, "progress": 4.0, "contour_error": 0.0, "violation": 0.0}
    env = FeedrateEnv(programs=["circle"], reward=weights)
    env.reset(seed=0)
    total, before = 0.0, 0.0
    for _ in range(60):  # 0.6 s: past the 42 mm of rapids, into the plunge and the circle
        _, reward, *_, info = env.step(np.zeros(1, dtype=np.float32))
        expected = 4.0 * (info["path_s"] - before) / LENGTH_CIRCLE_MM
        assert reward == pytest.approx(expected, rel=1e-9, abs=1e-15)
        assert info["progress"] == pytest.approx(info["path_s"] / LENGTH_CIRCLE_MM, rel=1e-12)
        before = info["path_s"]
        total += reward
    assert total == pytest.approx(4.0 * before / LENGTH_CIRCLE_MM, rel=1e-9)
    returns = {}
    for knob in (0.0, 1.0):
        rewards, infos, terminated, _ = run_constant(env, knob)
        assert terminated and infos[-1]["progress"] == 1.0
        assert np.all(rewards >= 0.0)
        returns[knob] = (rewards.sum(), len(rewards))
    assert returns[0.0][0] == pytest.approx(4.0, rel=1e-12)
    assert returns[1.0][0] == pytest.approx(4.0, rel=1e-12)
    assert returns[1.0][1] < 0.7 * returns[0.0][1]
    # Discounted (γ = 0.99), the faster run is worth more: the same 4 paid earlier.
    def discounted(rewards):
        return float(np.sum(rewards * 0.99 ** np.arange(len(rewards))))
    fast, *_ = run_constant(env, 1.0)
    slow, *_ = run_constant(env, 0.0)
    assert discounted(fast) > discounted(slow) > 0.0


def test_reward_yaml_path(tmp_path):
    path = tmp_path / "task.yaml"
    path.write_text("reward:\n  time: 1.0\n  contour_error: 0.0\n  violation: 0.0\n")
    env = FeedrateEnv(programs=["circle"], reward=path)
    rewards, infos, *_ = run_constant(env, 1.0)
    # The time term and the default progress term (10, summing to 10 over a finished episode): the
    # return is 10 − 1 · (cycle time / T_nominal).
    t_nominal = nominal_time_s(env.toolpath, env.machine)
    assert rewards.sum() == pytest.approx(10.0 - infos[-1]["cycle_time_s"] / t_nominal, rel=1e-9)
    path.write_text("reward:\n  time: 1.0\nprogrammes: [circle]\n")
    with pytest.raises(ConfigError, match="programmes"):
        FeedrateEnv(programs=["circle"], reward=path)


def test_default_return_is_in_a_sane_range():
    # At 100 % the time term sums to about −w_time·(cycle time / T_nominal) ≈ −10 … −15; the episode
    # return stays within the order 1–100 that PPO handles without reward scaling.
    env = FeedrateEnv(programs=["star"])
    rewards, *_ = run_constant(env, 0.0)
    assert -100.0 < rewards.sum() < -5.0


# ---------------------------------------------------------------------------------------------- info
def test_info_totals_are_consistent(circle_env):
    rewards, infos, *_ = run_constant(circle_env, 0.6)
    end = infos[-1]
    assert set(end) == INFO_KEYS
    step_errors = np.array([i["contour_error_mm"] for i in infos[1:]])
    assert end["contour_error_max_mm"] == pytest.approx(step_errors.max())
    assert 0 < end["contour_error_rms_mm"] <= end["contour_error_max_mm"]
    assert end["violations"] == int(np.sum(step_errors > 0.02))
    assert end["tolerance_mm"] == 0.02
    assert end["steps"] == len(rewards)
    assert end["program"] == "circle"
    # The circle block (G03) is line 10 of circle.nc; mid-episode the current line is that block.
    middle = infos[len(infos) // 2]
    assert middle["line"] == 10
    assert middle["override"] == pytest.approx(1.6, abs=1e-6)
    assert middle["feed_mm_min"] == pytest.approx(1.6 * 3000.0, rel=1e-3)


def test_lookahead_sees_the_star_tips():
    # A pentagram tip turns by 144°; while the tool approaches it the look-ahead block must show a
    # turning angle near 144/180 = 0.8 (in absolute value) somewhere in the window.
    env = FeedrateEnv(programs=["star"])
    obs, _ = env.reset(seed=0)
    n = env.lookahead_points
    turn = slice(9 + 2 * n, 9 + 3 * n)
    seen = []
    for _ in range(200):
        obs, *_ = env.step(np.zeros(1, dtype=np.float32))
        seen.append(np.abs(obs[turn]).max())
    assert max(seen) == pytest.approx(0.8, abs=0.02)


# -------------------------------------------------------------------------------------------- render
def test_render_rgb_array():
    env = FeedrateEnv(programs=["star"], render_mode="rgb_array")
    env.reset(seed=0)
    for _ in range(60):
        env.step(np.ones(1, dtype=np.float32))
    frame = env.render()
    assert frame.dtype == np.uint8 and frame.ndim == 3 and frame.shape[2] == 3
    assert frame.shape[0] > 100 and frame.shape[1] > 100
    assert len(np.unique(frame.reshape(-1, 3), axis=0)) > 10  # a drawing, not a blank canvas
    env.close()


def test_no_render_mode_builds_nothing(circle_env):
    assert circle_env.render_mode is None
    assert circle_env._renderer is None


@pytest.mark.parametrize("rule", ["cuts", "path"])
def test_env_contour_error_is_the_meter_on_the_reference_segments(rule):
    # The env passes the meter one scalar hint when a step stays on one segment (a shortcut). On the
    # freeform program (0.5 mm segments, several per step) and at 200 %, its per-step error must be the
    # largest per-sample error of a separate meter fed the same actual points with per-sample hints,
    # under either rule of the meter.
    from cnc_gym.motion import Controller
    from cnc_gym.plant import ContourErrorMeter, ServoPlant

    env = FeedrateEnv(programs=["freeform"], contour_rule=rule)
    env.reset(seed=0)
    tp = env.toolpath
    controller, plant = Controller(tp, env.machine), ServoPlant(env.machine)
    controller.reset()
    plant.reset(tp.start[0])
    meter = ContourErrorMeter(tp, window_back_mm=env._max_lag_mm, rapids_behind=rule == "path")
    action = np.ones(1, dtype=np.float32)
    for _ in range(300):
        *_, info = env.step(action)
        chunk = controller.advance(5, override=2.0)
        actual = plant.step(chunk.position[None])[0]
        if controller.waiting_in_position and plant.settled(env.in_position_mm)[0]:  # as the env does
            controller.release_in_position()
        expected = meter.measure(actual, chunk.segment).max()
        assert info["contour_error_mm"] == pytest.approx(expected, abs=1e-12)


def test_sync_vector_env():
    envs = gym.make_vec(ENV_ID, num_envs=3, vectorization_mode="sync", programs=["star", "circle"])
    obs, infos = envs.reset(seed=5)
    assert obs.shape == (3, 41) and obs.dtype == np.float32
    for _ in range(23):
        obs, rewards, _, _, infos = envs.step(np.zeros((3, 1), dtype=np.float32))
    # On the second opening rapid (after the Z rapid and its in-position wait) the progress term (fast
    # travel) outweighs the time cost: rewards are positive.
    assert rewards.shape == (3,) and np.all(np.isfinite(rewards)) and np.all(rewards > 0)
    assert set(infos["program"]) <= {"star", "circle"} and infos["cycle_time_s"][0] == pytest.approx(0.23)
    envs.close()


@pytest.mark.parametrize("machine", ["vmc-small", "p-loop-30"])
def test_plunge_after_a_rapid_starts_in_position(machine):
    # The controller waits at the rapid's end until the servo is within in_position_mm (P1471), so the
    # plunge starts from a settled axis: at 10 % override (F1200 → 2 mm/s, a steady lag of 2/Kv ≈ 0.07 mm
    # on a P loop with Kv 30 along the path, which is not contour error) no step on the cut exceeds the
    # tolerance. Before the wait, the servo still lagged the rapid by 20 µm (vmc-small) / ~350 µm
    # (p-loop-30) when the plunge began, and the first plunge step was a violation at any override.
    program = "G90 G21 G17\nG00 X10 Y0 Z5\nG01 Z0 F1200\nX30\nM30\n"
    env = FeedrateEnv(programs=[program], machine=machine, max_episode_steps=5000)
    env.reset(seed=0)
    action = np.array([-0.9], dtype=np.float32)  # 10 %
    waited = False
    while True:
        *_, terminated, truncated, info = env.step(action)
        waited |= env.controller.waiting_in_position
        assert info["contour_error_mm"] <= env.tolerance_mm, info
        if terminated or truncated:
            break
    assert terminated and info["violations"] == 0 and waited


@pytest.mark.parametrize("env_id", ["cnc_gym/Feedrate-v0", "cnc_gym/Feedrate-v2"])
def test_setup_keyword_gives_the_programs_their_offsets(env_id, tmp_path):
    """``setup=`` (a dict, a YAML path or a SetupConfig) rides in the env's machine record: the programs are
    interpreted with the operator's tables; a bad setup is one ConfigError line."""
    text = ProgramText("G54 G00 X0 Y0\nG43 H1 Z10.\nG01 X10. F1000.\n", name="setup-part")
    setup = {"work_offsets": {"G54": [100.0, 50.0, -200.0]}, "tools": {1: {"length_mm": 120.0}}}
    path = tmp_path / "job.yaml"
    path.write_text("work_offsets:\n  G54: [100.0, 50.0, -200.0]\ntools:\n  1: {length_mm: 120.0}\n")
    for given in (setup, str(path)):
        env = gym.make(env_id, programs=[text], dialect="fanuc", setup=given)
        base = env.unwrapped
        assert base.machine.setup.work_offsets["G54"] == (100.0, 50.0, -200.0)
        toolpath = base._programs[0][1]
        assert toolpath.end[-1].tolist() == [110.0, 50.0, -70.0]
        env.reset(seed=0)
        env.close()
    with pytest.raises(ConfigError, match=r"unknown key tools\.1\.length"):
        gym.make(env_id, programs=[text], dialect="fanuc", setup={"tools": {1: {"length": 1.0}}})
