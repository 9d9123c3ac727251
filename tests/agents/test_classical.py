"""The deployable classical planner: built from the machine and its own servo model, never from the env."""

from __future__ import annotations

import math

import gymnasium
import numpy as np
import pytest

import cnc_gym  # noqa: F401  (registers the env)
from agents import ClassicalPlanner, ConstantOverride
from agents.classical import ServoErrorModel, arc_caps, corner_error_per_speed, plan_schedule, servo_tables
from cnc_gym.machine import load_machine
from cnc_gym.programs import load_program
from cnc_gym.runner import run_episode


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


def test_ramp_error_response_of_a_p_loop_is_the_closed_form():
    # P loop, no feed-forward, ideal velocity loop: after a unit velocity step the following error is
    # (1 − e^(−Kv·t))/Kv, which settles at the steady lag 1/Kv.
    tables = servo_tables(load_machine("p-loop-30"))
    expected = (1.0 - np.exp(-30.0 * tables.ramp_t)) / 30.0
    np.testing.assert_allclose(tables.ramp_error[0], expected, atol=1e-9)
    assert tables.lag_s[0] == pytest.approx(1 / 30)


def test_arc_table_matches_the_bisection_of_the_model():
    machine = load_machine("vmc-small")
    tables, model = servo_tables(machine), ServoErrorModel(machine)
    for radius in (0.5, 5.0, 40.0):
        cap = arc_caps(tables, np.array([radius]), np.array([0]), 0.014)[0]
        assert cap == pytest.approx(model.arc_speed_cap(radius, 0, 0.014), rel=0.02)


def test_corner_error_of_a_p_loop():
    tables = servo_tables(load_machine("p-loop-30"))  # matched axes: no sideways lag on lines
    turns = np.radians([0.0, 30.0, 60.0, 90.0, 120.0, 180.0])
    out = np.column_stack((np.cos(turns), np.sin(turns), np.zeros(len(turns))))
    c = corner_error_per_speed(tables, np.repeat([[1.0, 0.0, 0.0]], len(turns), axis=0), out)
    # Straight on, or straight back along the same line: the tool stays on the path.
    assert c[0] == pytest.approx(0.0, abs=1e-12) and c[-1] == pytest.approx(0.0, abs=1e-12)
    # Deepest at a right angle, symmetric about it, and less than the lag distance v/Kv.
    assert np.all(np.diff(c[:4]) > 0)
    assert c[2] == pytest.approx(c[4], rel=1e-9)
    assert c[3] < 1 / 30


@pytest.mark.parametrize("program", ["circle", "star", "freeform", "pocket"])
def test_classical_is_fast_and_nearly_within_tolerance_on_the_built_ins(program):
    env = gymnasium.make("cnc_gym/Feedrate-v0", programs=[program])
    result = run_episode(env, ClassicalPlanner(), record=False)
    careful = run_episode(env, ConstantOverride(0.2), record=False)
    assert result.finished
    assert result.contour_error_max_mm < 1.5 * result.tolerance_mm
    assert result.cycle_time_s < 0.75 * careful.cycle_time_s
    env.close()


def test_schedule_of_a_line_runs_at_the_knobs_top_away_from_its_ends():
    machine = load_machine("vmc-small")
    _, toolpath = load_program("G90 G21\nG01 X100 F3000\nM30\n", "gsk25i", machine)
    schedule = plan_schedule(toolpath, machine)
    middle = (schedule.s > 20) & (schedule.s < 80)
    assert np.all(schedule.override[middle] == pytest.approx(2.0))
    assert math.isclose(schedule.s[-1], 100.0)
