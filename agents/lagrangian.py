"""PPO-Lagrangian as a small layer over Stable-Baselines3: a cost-penalised reward and dual ascent on λ.

The constrained problem (Safety-Gymnasium's convention, Ray et al. 2019; Altman 1999) is

    max_π  E[Σ_t γ^t r_t]    subject to    J_c(π) = E[Σ_t c_t] ≤ d,

with ``c_t = info["cost"]`` (on ``cnc_gym/Feedrate-v1`` the step's violation length in mm, so ``J_c`` is
the mean episode violation length) and ``d`` the budget (``cost_limit``). Its Lagrangian
``L(π, λ) = J_r(π) − λ (J_c(π) − d)`` is solved by alternating

1. a PPO update of π on the reward ``r_t − λ c_t`` (:class:`CostPenalty`, a ``VecEnvWrapper``: SB3's PPO
   is used as it is, on a changed reward), and
2. a projected gradient step on λ after every rollout (:class:`DualAscent`, an SB3 callback):
   ``λ ← clip(λ + η (Ĵ_c − d), 0, λ_max)``, ``Ĵ_c`` the mean cost of the episodes that ended during the
   rollout (λ is left as it is when none ended).

λ starts at ``lambda_init``; ``η = lambda_lr``. TensorBoard gets ``lagrangian/lambda`` and
``lagrangian/episode_cost``. Nothing of SB3 is copied or patched.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.vec_env import VecEnv, VecEnvWrapper


class CostPenalty(VecEnvWrapper):
    """Rewards ``r − λ·c`` with ``c = info[cost_key]``; keeps the costs of finished episodes for
    :class:`DualAscent`. ``lam`` is read every step, so the callback's updates take effect at once."""

    def __init__(self, venv: VecEnv, lam: float, cost_key: str = "cost") -> None:
        super().__init__(venv)
        self.lam = float(lam)
        self.cost_key = cost_key
        self._episode_cost = np.zeros(self.num_envs)
        self.finished_costs: list[float] = []

    def reset(self) -> Any:
        self._episode_cost[:] = 0.0
        return self.venv.reset()

    def step_wait(self) -> Any:
        obs, rewards, dones, infos = self.venv.step_wait()
        costs = np.array([float(info.get(self.cost_key, 0.0)) for info in infos])
        self._episode_cost += costs
        for i in np.flatnonzero(dones):
            self.finished_costs.append(float(self._episode_cost[i]))
            self._episode_cost[i] = 0.0
        return obs, rewards - np.float32(self.lam) * costs.astype(np.float32), dones, infos


class DualAscent(BaseCallback):
    """After each rollout: ``λ ← clip(λ + lr·(mean finished-episode cost − cost_limit), 0, lambda_max)``."""

    def __init__(self, penalty: CostPenalty, cost_limit: float, lr: float, lambda_max: float) -> None:
        super().__init__()
        self.penalty = penalty
        self.cost_limit = float(cost_limit)
        self.lr = float(lr)
        self.lambda_max = float(lambda_max)

    def _on_step(self) -> bool:
        return True

    def _on_rollout_end(self) -> None:
        costs = self.penalty.finished_costs
        if costs:
            mean_cost = float(np.mean(costs))
            self.penalty.lam = float(np.clip(self.penalty.lam + self.lr * (mean_cost - self.cost_limit), 0.0,
                                             self.lambda_max))  # fmt: skip
            self.logger.record("lagrangian/episode_cost", mean_cost)
            costs.clear()
        self.logger.record("lagrangian/lambda", self.penalty.lam)
