"""The classical baseline policy: the deployable planner, built from the machine and its own servo model,
never from the env."""

from __future__ import annotations

import gymnasium
import numpy as np
import pytest

import cnc_gym  # noqa: F401  (registers the env)
from cnc_gym.policies import ClassicalPlanner, ConstantOverride
from cnc_gym.runner import record_run


class _NoDynamics:
    """What the planner may see of an env: the program, the machine and the controller's static tables.
    Stepping, resetting or copying it fails the test."""

    def __init__(self, env) -> None:
        base = env.unwrapped
        self.toolpath, self.machine, self.controller = base.toolpath, base.machine, base.controller
        self.control_period_s, self.action_mode = base.control_period_s, base.action_mode
        self.unwrapped = self

    def step(self, action):
        pytest.fail("the deployable planner ran the env")

    def __deepcopy__(self, memo):
        pytest.fail("the deployable planner copied the env")


def test_planning_never_runs_the_env():
    env = gymnasium.make("cnc_gym/Feedrate-v0", programs=["star"])
    env.reset(seed=0)
    planner = ClassicalPlanner()
    planner.reset(_NoDynamics(env))
    assert planner.schedule is not None and np.all(np.isfinite(planner.schedule.override))
    env.close()


@pytest.mark.parametrize("program", ["circle", "star", "freeform", "pocket"])
def test_classical_is_fast_and_nearly_within_tolerance_on_the_built_ins(program):
    env = gymnasium.make("cnc_gym/Feedrate-v0", programs=[program])
    result = record_run(env, ClassicalPlanner(), record=False)
    careful = record_run(env, ConstantOverride(0.2), record=False)
    assert result.finished
    assert result.contour_error_max_mm < 1.5 * result.tolerance_mm
    assert result.cycle_time_s < 0.75 * careful.cycle_time_s
    env.close()


def _junction_pair(gap_mm: float, turn_deg: float) -> str:
    """A cut at F6000 that turns by ``turn_deg`` twice, ``gap_mm`` apart (CAM output of a rounded corner)."""
    a1, a2 = np.radians(turn_deg), np.radians(2.0 * turn_deg)
    x2, y2 = 40.0 + gap_mm * np.cos(a1), gap_mm * np.sin(a1)
    x3, y3 = x2 + 40.0 * np.cos(a2), y2 + 40.0 * np.sin(a2)
    return (f"G90 G54 G17 G21\nG00 X0 Y0 Z1\nG01 Z-1 F600\nG01 X40 Y0 F6000\nG01 X{x2:.4f} Y{y2:.4f}\n"
            f"G01 X{x3:.4f} Y{y3:.4f}\nG00 Z5\nM30\n")  # fmt: skip


def _run(program: str, policy) -> object:
    env = gymnasium.make("cnc_gym/Feedrate-v0", programs=[program], contour_rule="path")
    result = record_run(env, policy, record=False)
    env.close()
    return result


@pytest.mark.parametrize(("gap_mm", "turn_deg"), [(0.2, 20.0), (0.4, 10.0)])
def test_two_junctions_tenths_of_a_mm_apart_are_one_corner_to_the_servo(gap_mm, turn_deg):
    """Planner version 2 took the pair's window for an arc (its point floor was the window's width) and cut
    the corner over tolerance on the plant; version 3 measures the junctions' own extent."""
    program = _junction_pair(gap_mm, turn_deg)
    live = _run(program, ClassicalPlanner())
    assert live.finished and live.contour_error_max_mm <= live.tolerance_mm
    if (gap_mm, turn_deg) == (0.2, 20.0):  # what version 2 did (about 21.4 µm against 20)
        frozen = _run(program, ClassicalPlanner(version=2))
        assert frozen.contour_error_max_mm > frozen.tolerance_mm


def test_a_plunge_into_a_faster_cut_does_not_crawl():
    """circle: a plunge at F600 into an arc at F3000. The same speed at the junction is five times the
    override on the plunge as on the arc; version 2's knob looked 0.5 mm ahead and crawled the last half
    millimetre of the plunge at the arc's override (1.3 mm/s), slower in all than a constant 100 %.
    Version 3 lowers the override only as late as its slew allows, and beats the constant."""
    live = _run("circle", ClassicalPlanner())
    frozen = _run("circle", ClassicalPlanner(version=2))
    constant = _run("circle", ConstantOverride(1.0))
    assert constant.contour_error_max_mm <= constant.tolerance_mm
    assert live.contour_error_max_mm <= live.tolerance_mm
    assert frozen.contour_error_max_mm <= frozen.tolerance_mm
    assert frozen.cycle_time_s > constant.cycle_time_s > live.cycle_time_s
