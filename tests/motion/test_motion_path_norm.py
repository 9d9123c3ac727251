"""Path-norm limits (``controller.path_max_accel_mm_s2``, ``controller.path_max_jerk_mm_s3``): the norms of
the path acceleration and jerk vectors stay within them, on lines and arcs, with the braking envelope."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st
from motion_checks import check_run, random_program

from cnc_gym.machine import machine_from_dict
from cnc_gym.motion import Controller
from cnc_gym.motion import kernel as K
from cnc_gym.toolpath import Plane, ToolpathBuilder

A_PATH, J_PATH = 800.0, 9000.0


def machine(path_accel: float = A_PATH, path_jerk: float = J_PATH):
    # per-axis limits well above the path ones, so that the norms bind
    return machine_from_dict({
        "name": "path-norm",
        "controller": {"max_centripetal_accel_mm_s2": 50000, "path_max_accel_mm_s2": path_accel,
                       "path_max_jerk_mm_s3": path_jerk},
        "axis_defaults": {"max_accel_mm_s2": 20000, "max_jerk_mm_s3": 500000, "rapid_accel_mm_s2": 20000,
                          "rapid_jerk_mm_s3": 500000, "corner_step_mm_min": 300},
    })  # fmt: skip


def norms(c: Controller, chunk) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per tick inside one piece (not across a junction): the acceleration norm √(a_t² + (v²κ)²), the jerk
    bound |j_t| + κ²v³ + 3κv|a_t| (≥ the jerk vector's norm on a line or an arc), and the mask (empty
    when the program has no motion pieces: a dwell alone, say)."""
    seg_f = c.limits.seg_f
    if len(seg_f) == 0:
        none = np.zeros(len(chunk), dtype=bool)
        return np.zeros(len(chunk)), np.zeros(len(chunk)), none
    starts = seg_f[:, K.F_S0]
    s_before = np.concatenate(([0.0], chunk.path_s[:-1]))
    piece = np.clip(np.searchsorted(starts, chunk.path_s, side="right") - 1, 0, None)
    piece_before = np.clip(np.searchsorted(starts, s_before, side="right") - 1, 0, None)
    inside = (piece == piece_before) & chunk.cutting
    kappa = seg_f[piece, K.F_CURV]
    v, a, j = chunk.speed, chunk.accel, chunk.jerk
    acc = np.hypot(a, v * v * kappa)
    jerk = np.abs(j) + kappa**2 * v**3 + 3 * kappa * v * np.abs(a)
    return acc, jerk, inside


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**31 - 1), n_blocks=st.integers(1, 20), override=st.floats(0.2, 2.0))
@example(seed=522, n_blocks=1, override=1.0)  # a dwell alone: no motion pieces (found with a fresh seed)
def test_path_acceleration_and_jerk_norms_hold(seed, n_blocks, override):
    tp = random_program(np.random.default_rng(seed), n_blocks)
    c = Controller(tp, machine(), in_position_check=False)
    chunk = c.run_to_end(override=override)
    check_run(c, chunk, overrides=np.full(len(chunk), override))
    acc, jerk, inside = norms(c, chunk)
    assert np.all(acc[inside] <= A_PATH * (1 + 1e-9) + 1e-6)
    assert np.all(jerk[inside] <= J_PATH * (1 + 1e-6) + 1e-3)


def test_path_limits_bind_and_default_off_changes_nothing():
    b = ToolpathBuilder()
    b.line((0, 0, 0), (40, 0, 0), feed=6000, line=1)
    b.arc((40, 0, 0), (40, 20, 0), (40, 10, 0), Plane.XY, math.pi, feed=6000, line=2)
    tp = b.build()
    free = Controller(tp, machine(0.0, 0.0), in_position_check=False)
    limited = Controller(tp, machine(), in_position_check=False)
    t_free = free.run_to_end().time_s[-1]
    chunk = limited.run_to_end()
    assert chunk.time_s[-1] > t_free  # the norms slow it down
    acc, _, inside = norms(limited, chunk)
    assert np.max(acc[inside]) > 0.5 * A_PATH  # and they are used, not just respected
    # with both keys 0 the limits are the per-axis ones, bit for bit
    base = machine_from_dict({**{"name": "path-norm"}, "controller": {"max_centripetal_accel_mm_s2": 50000},
                              "axis_defaults": {"max_accel_mm_s2": 20000, "max_jerk_mm_s3": 500000,
                                                "rapid_accel_mm_s2": 20000, "rapid_jerk_mm_s3": 500000,
                                                "corner_step_mm_min": 300}})  # fmt: skip
    np.testing.assert_array_equal(Controller(tp, base).limits.seg_f, free.limits.seg_f)
