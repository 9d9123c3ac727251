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
