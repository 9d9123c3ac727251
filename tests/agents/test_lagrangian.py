"""PPO-Lagrangian's layer over SB3: the cost-penalised reward and the dual ascent on λ."""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from stable_baselines3.common.vec_env import DummyVecEnv

from cnc_gym_agents.lagrangian import CostPenalty, DualAscent


class CostEnv(gym.Env):
    """Reward 1 and cost 0.5 every step; episodes of three steps."""

    observation_space = gym.spaces.Box(-1.0, 1.0, (1,), np.float32)
    action_space = gym.spaces.Box(-1.0, 1.0, (1,), np.float32)

    def reset(self, *, seed: int | None = None, options: Any = None):
        super().reset(seed=seed)
        self.t = 0
        return np.zeros(1, np.float32), {}

    def step(self, action):
        self.t += 1
        return np.zeros(1, np.float32), 1.0, self.t >= 3, False, {"cost": 0.5}


def test_penalised_reward_and_episode_costs():
    venv = CostPenalty(DummyVecEnv([CostEnv, CostEnv]), lam=2.0)
    venv.reset()
    rewards = []
    for _ in range(6):
        _, reward, _, _ = venv.step(np.zeros((2, 1), np.float32))
        rewards.append(reward)
    np.testing.assert_allclose(np.array(rewards), 1.0 - 2.0 * 0.5)
    assert venv.finished_costs == [1.5] * 4  # two episodes of each env, three steps of cost 0.5


class _Logger:
    def __init__(self) -> None:
        self.values: dict[str, float] = {}

    def record(self, key: str, value: float) -> None:
        self.values[key] = value


@pytest.mark.parametrize(("costs", "expected"), [([1.5, 1.5], 2.0 + 2.0 * 0.5), ([0.0], 0.0), ([], 2.0),
                                                 ([1000.0], 10.0)])  # fmt: skip
def test_dual_ascent_step(costs, expected):
    penalty = CostPenalty(DummyVecEnv([CostEnv]), lam=2.0)
    ascent = DualAscent(penalty, cost_limit=1.0, lr=2.0, lambda_max=10.0)
    logger = _Logger()
    ascent.model = SimpleNamespace(logger=logger)  # type: ignore[assignment]  (the callback logs there)
    penalty.finished_costs.extend(costs)
    ascent._on_rollout_end()
    assert penalty.lam == pytest.approx(expected)  # λ + lr·(mean cost − limit), clipped to [0, λ_max]
    assert penalty.finished_costs == []
    assert logger.values["lagrangian/lambda"] == pytest.approx(expected)
    assert ("lagrangian/episode_cost" in logger.values) == bool(costs)
