"""The jerk-limited corner rule (``controller.corner_rule: jerk``, docs/motion.md §7): the finite-difference
jerk of the reference at the interpolation period, (p(t+T) − 3p(t) + 3p(t−T) − p(t−2T))/T³, stays within
every axis's jerk limit (and the path-norm jerk) at junctions too — kinks and curvature jumps — while the
presets that keep GSK's per-axis step (``corner_rule: step``) deliberately allow a velocity step there."""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from motion_checks import check_run

from cnc_gym.machine import load_machine, machine_from_dict, machine_names
from cnc_gym.motion import Controller, MotionChunk
from cnc_gym.motion.limits import JUNCTION_JERK_SHARE
from cnc_gym.toolpath import Plane, Toolpath, ToolpathBuilder

T = 0.002
#: Where a stop is reached, the period is snapped onto it; the snapped position is within ~1e-9 mm of the
#: braking manoeuvre's end, which the third difference divides by T³.
POSITION_NOISE_MM = 1e-9

SCRIPT = Path(__file__).resolve().parents[2] / "scripts" / "bench_junction_jerk.py"
_spec = importlib.util.spec_from_file_location("bench_junction_jerk", SCRIPT)
bench = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(bench)  # the random programs and machines the docs' figures come from

AXIS_JERK, PATH_JERK = bench.AXIS_JERK, bench.PATH_JERK
PER_AXIS = bench.axis_machine("jerk")
path_norm_machine = bench.path_norm_machine
random_polyline, random_chain = bench.random_polyline, bench.random_chain


def finite_difference_jerk(tp: Toolpath, chunk: MotionChunk) -> np.ndarray:
    return bench.finite_difference_jerk(tp, chunk, T)


def run(tp: Toolpath, machine, knobs: list[float]) -> tuple[Controller, MotionChunk]:
    controller = Controller(tp, machine, in_position_check=False)
    chunks = [controller.advance(120, override=k) for k in knobs]
    chunks.append(controller.run_to_end(override=1.0))
    fields = ("time_s", "position", "path_s", "speed", "accel", "jerk", "segment", "cutting")
    chunk = MotionChunk(*(np.concatenate([getattr(c, f) for c in chunks]) for f in fields))
    check_run(controller, chunk, overrides=np.zeros(1))
    return controller, chunk


SETTINGS = settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
knob_lists = st.lists(st.floats(0.0, 2.0), min_size=0, max_size=6)


@SETTINGS
@given(seed=st.integers(0, 2**31 - 1), n_blocks=st.integers(2, 25), knobs=knob_lists)
def test_finite_difference_jerk_of_every_axis_holds_through_kinks(seed, n_blocks, knobs):
    tp = random_polyline(np.random.default_rng(seed), n_blocks)
    _, chunk = run(tp, PER_AXIS, knobs)
    jerk = np.abs(finite_difference_jerk(tp, chunk))
    assert np.all(jerk <= AXIS_JERK * (1 + 1e-9) + POSITION_NOISE_MM / T**3)


@SETTINGS
@given(seed=st.integers(0, 2**31 - 1), n_blocks=st.integers(2, 20), knobs=knob_lists)
def test_finite_difference_jerk_norm_holds_through_line_arc_junctions(seed, n_blocks, knobs):
    tp = random_chain(np.random.default_rng(seed), n_blocks)
    _, chunk = run(tp, path_norm_machine("jerk"), knobs)
    jerk = np.linalg.norm(finite_difference_jerk(tp, chunk), axis=1)
    assert np.all(jerk <= PATH_JERK * (1 + 1e-9) + POSITION_NOISE_MM / T**3)


def test_the_step_rule_allows_a_step_and_only_kirl_planar_limits_the_jerk():
    # GSK's P1227 alone: a 90° corner at the axis step (1000 mm/min on vmc-small) in 2 ms is a finite-
    # difference jerk of (16.7 mm/s)/T² ≈ 4·10⁶ mm/s³, far above the axes' 30 000.
    rules = {name: load_machine(name).controller.corner_rule for name in machine_names()}
    assert {name for name, rule in rules.items() if rule == "jerk"} == {"kirl-planar"}
    b = ToolpathBuilder()
    b.line((0, 0, 0), (20, 0, 0), feed=6000, line=1)
    b.line((20, 0, 0), (20, 20, 0), feed=6000, line=2)
    tp = b.build()
    vmc = load_machine("vmc-small")
    step = np.abs(finite_difference_jerk(tp, Controller(tp, vmc, in_position_check=False).run_to_end()))
    assert np.max(step) > 10 * vmc.axes[0].max_jerk_mm_s3
    chunk = Controller(tp, path_norm_machine("jerk"), in_position_check=False).run_to_end()
    held = np.linalg.norm(finite_difference_jerk(tp, chunk), axis=1)
    assert np.max(held) <= PATH_JERK * (1 + 1e-9) + POSITION_NOISE_MM / T**3


def test_a_gentle_kink_gets_the_closed_form_limit_and_its_pieces_the_rest_of_the_jerk():
    # A 0.05° kink in XY on equal axes (J = 50 000, A = 5000 projected): the velocity step of axis k is
    # v·|Δu_k|, its difference term |Δu_k|·(v/T² + ¾A/T) ≤ ½·J gives v = (½·J − ¾|Δu_k|·A/T)·T²/|Δu_k|
    # for the larger |Δu_k|; both lines (within reach) keep J·(1 − ½).
    theta = math.radians(0.05)
    b = ToolpathBuilder()
    b.line((0, 0, 0), (30, 0, 0), feed=6000, line=1)
    b.line((30, 0, 0), (30 + 30 * math.cos(theta), 30 * math.sin(theta), 0), feed=6000, line=2)
    machine = machine_from_dict({"name": "kink", "controller": {"corner_rule": "jerk"}})
    controller = Controller(b.build(), machine, in_position_check=False)
    du = max(abs(math.cos(theta) - 1.0), abs(math.sin(theta)))
    a_near = 5000.0 / math.cos(theta)  # the second line's projected acceleration
    expected = (JUNCTION_JERK_SHARE * 50000.0 - 0.75 * du * a_near / T) * T**2 / du
    junctions = controller.junction_limits()
    assert not junctions["stop"][1]
    assert junctions["limit_mm_s"][1] == pytest.approx(expected, rel=1e-9)
    projected = 50000.0 * np.array([1.0, 1.0 / math.cos(theta)])
    jerk = controller.segment_limits()["jerk_mm_s3"]
    np.testing.assert_allclose(jerk, projected * (1 - JUNCTION_JERK_SHARE), rtol=1e-9)
    # the step rule on the same machine: P1227 alone (1000 mm/min / |Δu_y|), the pieces keep their jerk
    step = Controller(b.build(), machine_from_dict({"name": "kink"}), in_position_check=False)
    assert step.junction_limits()["limit_mm_s"][1] == pytest.approx(min(1000.0 / 60.0 / du, 250.0))  # P1224
    np.testing.assert_array_equal(step.segment_limits()["jerk_mm_s3"], projected)


def test_a_sharp_kink_is_passed_at_rest_without_an_in_position_wait():
    # 90°: the acceleration term alone, |Δu|·¾A/T = 1.9·10⁶ mm/s³, is above the share of J: a stop.
    b = ToolpathBuilder()
    b.line((0, 0, 0), (10, 0, 0), feed=6000, line=1)
    b.line((10, 0, 0), (10, 10, 0), feed=6000, line=2)
    machine = machine_from_dict({"name": "kink", "controller": {"corner_rule": "jerk"}})
    controller = Controller(b.build(), machine)  # with the in-position check
    junctions = controller.junction_limits()
    assert junctions["stop"][1] and junctions["limit_mm_s"][1] == 0.0
    waited = False
    while not controller.finished:
        controller.advance(1)
        if controller.waiting_in_position:
            waited = waited or not controller.path_s >= junctions["s"][-1] - 1e-9
            controller.release_in_position()
    assert not waited  # only the program end waits


def test_a_curvature_jump_gets_the_closed_form_limit():
    # Line along X into a tangent arc of radius R (curvature vector (0, 1/R) at its start): the centripetal
    # acceleration v²/R appears within one period; ¾·(1/R)·v²/T ≤ ½·J_y gives v = √(½·J·T·R/¾).
    radius = 5.0
    b = ToolpathBuilder()
    b.line((0, 0, 0), (20, 0, 0), feed=6000, line=1)
    b.arc((20, 0, 0), (20 + radius, radius, 0), (20, radius, 0), Plane.XY, math.pi / 2, feed=6000, line=2)
    machine = machine_from_dict({"name": "bend", "controller": {"corner_rule": "jerk"}})
    controller = Controller(b.build(), machine, in_position_check=False)
    expected = math.sqrt(JUNCTION_JERK_SHARE * 50000.0 * T * radius / 0.75)
    assert controller.junction_limits()["limit_mm_s"][1] == pytest.approx(expected, rel=1e-9)
    chunk = controller.run_to_end()
    jerk = np.abs(finite_difference_jerk(b.build(), chunk))
    assert np.max(jerk) <= 50000.0 * (1 + 1e-9) + POSITION_NOISE_MM / T**3
