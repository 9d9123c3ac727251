"""The fused step (one compiled call) and the batched vector env against the per-env reference path.

The reference path is the modular step: the same state arrays driven through the Controller objects,
the plant object's ``step``/``settled`` and the ContourErrorMeter, one env at a time (the path a plant
backend without compiled kernels takes). For Feedrate-v1 and v2 the reference also computes in Python
what the compiled step computes for them: the machine, episode and planner entries of the observation,
the planner's override (with the planner's ``override_at``), the reward terms, the finish
bonus, the cost and the info keys. Every observation, reward, termination, truncation and info
value must be equal — exactly, not to a tolerance — on the built-in programs and on random programs
(lines, polylines, arcs and helices in three planes, NURBS, dwells, exact stops, rapids), in both action
modes, through truncations and next-step autoresets, serial and in threads.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from random_gcode import bench_program, random_gcode

from cnc_gym.envs.feedrate import FeedrateEnv
from cnc_gym.envs.feedrate_v1 import FeedrateEnvV1
from cnc_gym.envs.fused import (
    F_SIGNAL,
    INFO_KEYS,
    SIG_PROGRESS_DELTA,
    SIG_TIME_FRACTION,
    SIG_VIOLATION_LENGTH,
)
from cnc_gym.envs.observation import machine_quantities
from cnc_gym.envs.vector import FeedrateVectorEnv
from cnc_gym.plant import ServoPlant
from cnc_gym.programs import BUILTIN_PROGRAMS


class ReferencePlant(ServoPlant):
    """The LTI plant, stepped through its object interface (not inside the fused kernel)."""

    compiled_step = False


class ReferenceEnv(FeedrateEnv):
    """Feedrate-v0 on the modular (reference) step."""

    def make_batch(self, n_envs, parallel=None, plant=None):
        return super().make_batch(n_envs, parallel, ReferencePlant(self.machine, n_envs))


def knob_schedule(rng: np.random.Generator, n: int) -> np.ndarray:
    """A random walk of the knob with jumps: long stretches at high and low override, sudden changes."""
    knob = np.empty(n, dtype=np.float32)
    x = 0.0
    for i in range(n):
        jump = rng.random() >= 0.9
        x = float(rng.uniform(-1, 1)) if jump else float(np.clip(x + rng.normal() * 0.3, -1, 1))
        knob[i] = max(x, 0.2) if i % 200 < 60 else x
    return knob


def assert_same_run(fused: FeedrateEnv, reference: FeedrateEnv, knobs: np.ndarray, seed: int = 0) -> int:
    """Step both envs with ``knobs`` (resetting at episode ends); returns the number of episode ends."""
    out_f, out_r = fused.reset(seed=seed), reference.reset(seed=seed)
    np.testing.assert_array_equal(out_f[0], out_r[0])
    assert out_f[1] == out_r[1]
    ends = 0
    for t, knob in enumerate(knobs):
        out_f = fused.step(np.array([knob]))
        out_r = reference.step(np.array([knob]))
        np.testing.assert_array_equal(out_f[0], out_r[0], err_msg=f"step {t}")
        assert out_f[1:] == out_r[1:], f"step {t}"
        if out_f[2] or out_f[3]:
            ends += 1
            reset_f, reset_r = fused.reset(), reference.reset()
            np.testing.assert_array_equal(reset_f[0], reset_r[0])
            assert reset_f[1] == reset_r[1]
    return ends


def test_reference_env_takes_the_modular_step():
    assert FeedrateEnv(programs=["circle"])._batch.fused
    assert not ReferenceEnv(programs=["circle"])._batch.fused


@pytest.mark.parametrize("mode", ["override", "feed"])
def test_builtins_same_as_the_reference_path(mode):
    # Whole episodes of every built-in, a helical bore and a chain of NURBS under a random knob, each ending
    # in a termination.
    rng = np.random.default_rng(0)
    for program in (*BUILTIN_PROGRAMS, bench_program("helix"), bench_program("nurbs")):
        fused = FeedrateEnv(programs=[program], action_mode=mode)
        reference = ReferenceEnv(programs=[program], action_mode=mode)
        assert assert_same_run(fused, reference, knob_schedule(rng, 3000)) >= 1


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**31 - 1), n_blocks=st.integers(1, 25),
       mode=st.sampled_from(["override", "feed"]), budget=st.sampled_from([None, 40, 150]))  # fmt: skip
def test_random_programs_same_as_the_reference_path(seed, n_blocks, mode, budget):
    rng = np.random.default_rng(seed)
    text = random_gcode(rng, n_blocks)
    fused = FeedrateEnv(programs=[text], action_mode=mode, max_episode_steps=budget)
    reference = ReferenceEnv(programs=[text], action_mode=mode, max_episode_steps=budget)
    assert_same_run(fused, reference, knob_schedule(rng, 300), seed=seed % 1000)


@pytest.mark.parametrize("parallel", [False, True])
def test_vector_env_same_as_reference_envs_one_by_one(parallel):
    # Six envs over three random programs and a built-in with a short budget: truncations, terminations
    # and next-step autoresets happen mid-run in different envs. The batched env (serial, or in numba's
    # threads) must equal Gymnasium's SyncVectorEnv over reference envs, infos included.
    rng = np.random.default_rng(11)
    programs = [random_gcode(rng, 6) for _ in range(3)] + ["star"]
    kwargs = {"programs": programs, "max_episode_steps": 60}
    batched = FeedrateVectorEnv(6, parallel=parallel, **kwargs)
    assert batched.batch.parallel == parallel
    sync = gym.vector.SyncVectorEnv([lambda: ReferenceEnv(**kwargs)] * 6)
    obs_b, info_b = batched.reset(seed=5)
    obs_s, info_s = sync.reset(seed=5)
    np.testing.assert_array_equal(obs_b, obs_s)
    for key, value in info_s.items():
        np.testing.assert_array_equal(info_b[key], value, err_msg=key)
    ends = 0
    for t in range(200):
        actions = rng.uniform(-1, 1, (6, 1)).astype(np.float32)
        out_b, out_s = batched.step(actions), sync.step(actions)
        for a, b in zip(out_b[:4], out_s[:4], strict=True):
            np.testing.assert_array_equal(a, b, err_msg=f"step {t}")
        assert set(out_b[4]) == set(out_s[4])
        for key, value in out_s[4].items():
            np.testing.assert_array_equal(out_b[4][key], value, err_msg=f"step {t}: {key}")
        ends += int(np.sum(out_b[2] | out_b[3]))
    assert ends >= 12


def test_resetting_some_envs_leaves_the_others_as_they_are():
    envs = FeedrateVectorEnv(3, programs=["star", "circle"])
    envs.reset(seed=0)
    for _ in range(20):
        envs.step(np.full((3, 1), 0.5, dtype=np.float32))
    before_f, before_i = envs.batch.state_f.copy(), envs.batch.state_i.copy()
    envs.reset_envs([1], [None], [{"program": "circle"}])
    np.testing.assert_array_equal(envs.batch.state_f[[0, 2]], before_f[[0, 2]])
    np.testing.assert_array_equal(envs.batch.state_i[[0, 2]], before_i[[0, 2]])
    info = envs.batch.info(1)
    assert info["program"] == "circle" and info["steps"] == 0 and info["cycle_time_s"] == 0.0


def test_a_program_outside_the_set_joins_the_bank():
    # reset(options={"program": text}) on the vector env: the program is packed once and every env runs it.
    envs = FeedrateVectorEnv(2, programs=["circle"])
    text = "G90 G21\nG01 X5.0 F1200.0\nM30\n"
    _, infos = envs.reset(seed=0, options={"program": text})
    assert all(name.startswith("text-") for name in infos["program"])
    assert len(envs.batch.bank.programs) == 1  # packed on first use, once for both envs
    for _ in range(5):
        *_, infos = envs.step(np.zeros((2, 1), dtype=np.float32))
    np.testing.assert_array_equal(infos["path_s"], infos["path_s"][0])


def test_vector_env_rejects_bad_actions_and_steps_before_reset():
    envs = FeedrateVectorEnv(2, programs=["circle"])
    with pytest.raises(gym.error.ResetNeeded):
        envs.step(np.zeros((2, 1), dtype=np.float32))
    envs.reset(seed=0)
    with pytest.raises(ValueError, match="finite"):
        envs.step(np.array([[0.0], [np.nan]]))
    with pytest.raises(ValueError, match="shape"):
        envs.step(np.zeros((3, 1)))


def test_violation_length_and_time_add_up_per_sample():
    # Cumulative violation length and time: per servo sample with contour error above the tolerance, the
    # reference's advance along the path and one interpolation period. At 200 % on the star, summed here
    # from every step's samples.
    env = FeedrateEnv(programs=["star"])
    env.reset(seed=0)
    length = time = s_before = 0.0
    for _ in range(2000):
        *_, terminated, truncated, info = env.step(np.ones(1, dtype=np.float32))
        _, error, path_s = env._batch.last_samples(0)
        advance = np.diff(np.concatenate(([s_before], path_s)))
        over = error > env.tolerance_mm
        length += float(np.sum(advance[over]))
        time += env.interpolation_period_s * int(np.sum(over))
        s_before = path_s[-1]
        assert info["violation_length_mm"] == pytest.approx(length, rel=1e-9, abs=1e-12)
        assert info["violation_time_s"] == pytest.approx(time, rel=1e-9, abs=1e-12)
        if terminated or truncated:
            break
    assert terminated and info["violation_time_s"] > 0.0 and info["violation_length_mm"] > 0.0
    # Bounded by the cycle time and by the path: a violation is a part of both.
    assert info["violation_time_s"] <= info["cycle_time_s"]
    assert info["violation_length_mm"] <= env.toolpath.total_length


def test_a_program_without_motion_ends_at_once_on_both_paths():
    # Only modal codes and M30: the first step terminates, in 0 s, with reward 0; batched beside a program
    # that moves, the other env runs on.
    text = "G90 G21 G17\nM30\n"
    for env in (FeedrateEnv(programs=[text]), ReferenceEnv(programs=[text])):
        env.reset(seed=0)
        obs, reward, terminated, truncated, info = env.step(np.array([0.5], dtype=np.float32))
        assert (reward, terminated, truncated) == (0.0, True, False)
        assert info["cycle_time_s"] == 0.0 and info["steps"] == 1 and obs[3] == pytest.approx(0.5)
    envs = FeedrateVectorEnv(2, programs=[text, "circle"])
    envs.reset(seed=0, options=None)
    envs.reset_envs([0, 1], [None, None], [{"program": text}, {"program": "circle"}])
    _, rewards, terminated, _, infos = envs.step(np.zeros((2, 1), dtype=np.float32))
    assert terminated.tolist() == [True, False] and rewards[0] == 0.0 and infos["cycle_time_s"][1] == 0.01


@pytest.mark.parametrize("env_class", [FeedrateEnv, ReferenceEnv])
def test_a_copied_or_pickled_env_steps_like_the_env(env_class):
    # The oracle planner simulates on copy.deepcopy of the env: the copy's compiled call, state views and
    # controllers must be its own, and the original must run on untouched.
    import copy
    import pickle

    env = env_class(programs=["star", "circle"])
    env.reset(seed=3)
    rng = np.random.default_rng(3)
    for _ in range(40):
        env.step(rng.uniform(-1, 1, 1).astype(np.float32))
    copies = [copy.deepcopy(env), pickle.loads(pickle.dumps(env))]
    ends = 0
    for t in range(1500):
        action = rng.uniform(-1, 1, 1).astype(np.float32)
        out = env.step(action)
        for other in copies:
            out_c = other.step(action)
            np.testing.assert_array_equal(out[0], out_c[0], err_msg=f"step {t}")
            assert out[1:] == out_c[1:], f"step {t}"
        if out[2] or out[3]:
            ends += 1
            first = env.reset()
            for other in copies:
                assert other.reset()[1] == first[1]
    assert ends >= 1


def test_borrowed_and_matrix_views_are_the_arrays_own_memory():
    # The batch call's two view helpers: a borrowed array (no reference count) and a direct (rows, cols)
    # view of a stretch of a flat table are the same memory as the array they come from, read and written.
    from numba import njit

    from cnc_gym.envs.fused import _borrowed, _matrix

    @njit
    def fill(flat, start, rows, cols):
        view = _matrix(_borrowed(flat), start, rows, cols)
        for i in range(rows):
            for j in range(cols):
                view[i, j] += 100.0 * i + j
        return _matrix(flat, start, rows, cols).sum()

    flat = np.arange(40, dtype=np.float64)
    expected = flat.copy()
    expected[7:19] += (100.0 * np.arange(3)[:, None] + np.arange(4)).ravel()
    total = fill(flat, 7, 3, 4)
    np.testing.assert_array_equal(flat, expected)
    assert total == expected[7:19].sum()


# ------------------------------------------------------------------------------------ Feedrate-v1 and v2
class ReferenceEnvV1(FeedrateEnvV1):
    """Feedrate-v1 on the modular step, with its own entries, reward and info computed in Python from the
    step's v0 outputs (the planner's override with cnc_gym.motion.planner.override_at)."""

    def make_batch(self, n_envs, parallel=None, plant=None):
        return super().make_batch(n_envs, parallel, ReferencePlant(self.machine, n_envs))

    def _parse_action(self, action):
        a = FeedrateEnv._parse_action(self, action)
        if self.action_mode != "residual":
            return a
        override = min(max(self.reference_override * self.residual_range**a, 0.0), self.max_override)
        return self._planner.knob(override)

    def reset(self, *, seed=None, options=None):
        obs, info = super().reset(seed=seed, options=options)
        return self._v1(obs, info, None)

    def step(self, action):
        obs, _, terminated, truncated, info = super().step(action)
        obs, info = self._v1(obs, info, terminated)
        return obs, self._reward, terminated, truncated, info

    def _v1(self, obs, info, terminated):
        """The v1 entries of ``obs`` and the v1 info (``terminated`` None: a reset), and the reward."""
        from cnc_gym.motion.planner import override_at

        program = self._batch.program(0)
        schedule = self._planner.schedule(program.toolpath, self.machine, program.limits)
        self.reference_override = override_at(schedule, info["path_s"], info["feed_mm_min"],
                                              self._planner.lead_s)  # fmt: skip
        quantities = machine_quantities(self.machine)
        violation_free = info["violation_length_mm"] <= 0.0
        at = self.layout.kernel_spec.size - len(self.layout.kernel_spec.tail)
        for e in self.layout.entries:
            if e.source in ("machine", "episode", "planner"):
                value = {"machine": quantities.get(e.quantity), "episode": float(violation_free),
                         "planner": self.reference_override}[e.source]  # fmt: skip
                obs[at] = min(max(value * self.layout.scale(e), e.low), e.high)
                at += 1
        out = {key: info[key] for key in INFO_KEYS}
        signals = self._batch.state_f[0, F_SIGNAL:]
        w = self.reward_weights
        terms, finish, cost, self._reward = (0.0, 0.0, 0.0), 0.0, 0.0, 0.0
        if terminated is not None:
            terms = (float(-w.time * signals[SIG_TIME_FRACTION]),
                     float(w.progress * signals[SIG_PROGRESS_DELTA]),
                     float(-w.violation * signals[SIG_VIOLATION_LENGTH]))  # fmt: skip
            if len(program.toolpath):
                self._reward = 0.0
                for term in terms:
                    self._reward += term
            budget, t_nominal = program.max_episode_steps, max(self.nominal_time_s, 1e-12)
            finish = w.time * budget * self.control_period_s / t_nominal + w.finish if (
                terminated and violation_free) else 0.0  # fmt: skip
            self._reward += finish
            cost = float(signals[SIG_VIOLATION_LENGTH])
        out["cost"] = cost
        out.update(zip(("reward_time", "reward_progress", "reward_violation"), terms, strict=True))
        out["reward_finish"] = finish
        out["planner_override"] = self.reference_override
        return obs, out


def assert_same_run_v1(fast: FeedrateEnvV1, reference: ReferenceEnvV1, actions: np.ndarray,
                       seed: int = 0) -> int:  # fmt: skip
    """Step both envs with ``actions`` (resetting at episode ends): the same observations (bytes), rewards
    (sign of zero included), flags and infos (keys in order, values with their types); the episode ends."""
    def same(out_f, out_r, where):
        np.testing.assert_array_equal(out_f[0], out_r[0], err_msg=where)
        assert out_f[0].tobytes() == out_r[0].tobytes(), where
        assert repr(out_f[1:]) == repr(out_r[1:]), where
        assert [type(x) for x in out_f[1:]] == [type(x) for x in out_r[1:]], where

    same(fast.reset(seed=seed), reference.reset(seed=seed), "reset")
    ends = 0
    for t, a in enumerate(actions):
        out_f, out_r = fast.step(np.array([a])), reference.step(np.array([a]))
        same(out_f, out_r, f"step {t}")
        if out_f[2] or out_f[3]:
            ends += 1
            same(fast.reset(), reference.reset(), f"reset after step {t}")
    return ends


V1_CASES = {
    "v1 built-ins": {"programs": list(BUILTIN_PROGRAMS)},
    "v2 residual, short budget": {"programs": ["star", "pocket"], "action_mode": "residual",
                                  "contour_rule": "path", "max_episode_steps": 200, "residual_range": 3.0},
    "v2 feed, helix and NURBS": {"programs": [bench_program("helix"), bench_program("nurbs")],
                                 "action_mode": "feed", "contour_rule": "path", "machine": "gsk25i"},
    "v1 without motion, weights": {"programs": ["G90 G21 G17\nM30\n", "circle"],
                                   "reward": {"time": 2.0, "violation": 3.0, "finish": 0.5, "progress": 0.0}},
    "v2 randomised, period, points": {"programs": ["circle", "freeform"], "contour_rule": "path",
                                      "randomize": {"enabled": True, "machines": 2}, "control_period_s": 0.02,
                                      "lookahead_points": 5, "max_episode_steps": 300},
}  # fmt: skip


@pytest.mark.parametrize("case", list(V1_CASES))
def test_v1_and_v2_same_as_the_reference_path(case):
    # Whole episodes under a random knob (and its jumps): every entry, reward, flag and info key of the
    # compiled step equals the Python reference, bit for bit.
    kwargs = V1_CASES[case]
    rng = np.random.default_rng(len(case))
    ends = assert_same_run_v1(FeedrateEnvV1(**kwargs), ReferenceEnvV1(**kwargs), knob_schedule(rng, 2500))
    assert ends >= 2


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**31 - 1), n_blocks=st.integers(1, 20),
       mode=st.sampled_from(["override", "feed", "residual"]), rule=st.sampled_from(["cuts", "path"]),
       budget=st.sampled_from([None, 40, 150]))  # fmt: skip
def test_v1_random_programs_same_as_the_reference_path(seed, n_blocks, mode, rule, budget):
    rng = np.random.default_rng(seed)
    kwargs = {"programs": [random_gcode(rng, n_blocks)], "action_mode": mode, "contour_rule": rule,
              "max_episode_steps": budget}  # fmt: skip
    assert_same_run_v1(FeedrateEnvV1(**kwargs), ReferenceEnvV1(**kwargs), knob_schedule(rng, 300),
                       seed=seed % 1000)  # fmt: skip


def test_v1_copied_env_steps_like_the_env():
    # The planner's tables and the v1 outputs travel with a copy of the env.
    import copy

    env = FeedrateEnvV1(programs=["star"], action_mode="residual")
    env.reset(seed=0)
    for _ in range(30):
        env.step(np.zeros(1, dtype=np.float32))
    other = copy.deepcopy(env)
    for t in range(200):
        action = np.array([0.3 * np.sin(t / 7)], dtype=np.float32)
        out, out_c = env.step(action), other.step(action)
        np.testing.assert_array_equal(out[0], out_c[0])
        assert repr(out[1:]) == repr(out_c[1:])
