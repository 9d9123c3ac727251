"""The compiled step (:mod:`cnc_gym.envs.engine.step`) against the reference path, and what it computes.

Every observation, reward, termination, truncation and info value of the compiled step must equal the
modular reference path's (``reference_step.py``) — exactly, not to a tolerance — on the built-in programs
and on random programs (lines, polylines, arcs and helices in three planes, NURBS, dwells, exact stops,
rapids), in every action mode, through truncations and resets; Feedrate-v1 and v2 against their entries,
reward and info computed in Python.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from random_gcode import bench_program, random_gcode
from reference_step import (
    ReferenceEnv,
    ReferenceEnvV1,
    assert_same_run,
    assert_same_run_v1,
    knob_schedule,
)

from cnc_gym.envs.feedrate import FeedrateEnv
from cnc_gym.envs.feedrate_v1 import FeedrateEnvV1
from cnc_gym.envs.vector import FeedrateVectorEnv
from cnc_gym.programs import BUILTIN_PROGRAMS


@pytest.mark.parametrize("mode", ["override", "feed"])
def test_builtins_same_as_the_reference_path(mode):
    # Whole episodes of every built-in, a helical bore and a chain of NURBS under a random knob, each ending
    # in a termination.
    rng = np.random.default_rng(0)
    for program in (*BUILTIN_PROGRAMS, bench_program("helix"), bench_program("nurbs")):
        compiled = FeedrateEnv(programs=[program], action_mode=mode)
        reference = ReferenceEnv(programs=[program], action_mode=mode)
        assert assert_same_run(compiled, reference, knob_schedule(rng, 3000)) >= 1


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**31 - 1), n_blocks=st.integers(1, 25),
       mode=st.sampled_from(["override", "feed"]), budget=st.sampled_from([None, 40, 150]))  # fmt: skip
def test_random_programs_same_as_the_reference_path(seed, n_blocks, mode, budget):
    rng = np.random.default_rng(seed)
    text = random_gcode(rng, n_blocks)
    compiled = FeedrateEnv(programs=[text], action_mode=mode, max_episode_steps=budget)
    reference = ReferenceEnv(programs=[text], action_mode=mode, max_episode_steps=budget)
    assert_same_run(compiled, reference, knob_schedule(rng, 300), seed=seed % 1000)


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


# ------------------------------------------------------------------------------------ Feedrate-v1 and v2
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


def test_the_step_descriptor_reads_back_its_arrays_and_rejects_others():
    # run_serial takes one address in place of the step's twelve arrays: the descriptor gives back each
    # array's own memory and shape in compiled code; an array of another type, or not C-ordered, is refused
    # (the step would read it wrongly).
    from numba import njit

    from cnc_gym.envs.engine.step import STEP_ARRAYS, describe, step_arrays

    rng = np.random.default_rng(7)
    shapes = [(5,), (6,), (2, 3), (2, 4), (3, 3, 2), (3, 2, 2), (3, 2), (3, 1, 4, 6), (2,), (2, 5), (2, 7),
              (2, 3)]  # fmt: skip
    arrays = tuple((rng.normal(size=shape) * 100).astype(dtype)
                   for shape, (_, dtype, _) in zip(shapes, STEP_ARRAYS, strict=True))  # fmt: skip

    @njit
    def checksums(address):
        views = step_arrays(address)
        out = np.empty(len(views))  # (a tuple of arrays of several types: one by one)
        out[0], out[1], out[2], out[3] = views[0].sum(), views[1].sum(), views[2].sum(), views[3].sum()
        out[4], out[5], out[6], out[7] = views[4].sum(), views[5].sum(), views[6].sum(), views[7].sum()
        out[8], out[9], out[10], out[11] = views[8].sum(), views[9].sum(), views[10].sum(), views[11].sum()
        views[9][1, 4] = 123.0  # writes reach the array
        return out, views[7].shape, views[2][1, 2]

    expected = [a.sum(dtype=np.float64) for a in arrays]
    descriptor = describe(arrays)
    sums, lifted_shape, corner = checksums(descriptor.ctypes.data)
    np.testing.assert_allclose(sums, expected, rtol=1e-5)
    assert lifted_shape == shapes[7]
    assert corner == arrays[2][1, 2]
    assert arrays[9][1, 4] == 123.0
    for k, bad in ((2, arrays[2].T.copy().T), (9, arrays[9].astype(np.float64)), (0, arrays[0][:, None])):
        with pytest.raises(ValueError, match="C-ordered"):
            describe((*arrays[:k], bad, *arrays[k + 1 :]))
    with pytest.raises(ValueError, match="takes 12 arrays"):
        describe(arrays[:-1])
