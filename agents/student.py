"""The student: a residual policy over the env's observation, an SB3 ``MlpPolicy`` fitted to quantiles.

The student is the actor of a Stable-Baselines3 PPO ``ActorCriticPolicy`` (an MLP with ``tanh`` layers,
``net_arch`` wide, over the env's observation; its deterministic action is the Gaussian's mean clipped to
[-1, 1]), so the saved model is an ordinary SB3 PPO zip: ``cnc-gym run``, ``cnc-gym bench`` and
``scripts/evaluate.py`` load it without unpickling (:mod:`cnc_gym.policies.model`), and PPO-Lagrangian can
fine-tune it as it is.

Fitting (:meth:`Student.fit`) regresses the actor's mean on the teacher's residual actions with a
weighted **quantile (pinball) loss** at level ``τ`` (``quantile``), smoothed near zero as in quantile
regression DQN (Dabney et al. 2018; Huber's κ = :data:`HUBER_KAPPA`): the student learns the τ-quantile
of what the teacher does in states that look alike to it, so ``τ < 0.5`` makes it err on the slow side
where its observation cannot tell the teacher's situations apart (the teacher knows the whole program and
the exact plant; the student a 24 mm preview and the machine's parameters).

:class:`ActorWeights` is the actor as plain NumPy arrays: the labelling workers run the student with it
(no torch in the workers, nothing but arrays sent to them), with SB3's arithmetic in float32.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from cnc_gym.policies.shield import PlannerShield

#: Width of the quadratic zone of the smoothed pinball loss, in action units (1 = the whole residual).
HUBER_KAPPA = 0.02


@dataclass(frozen=True)
class ActorWeights:
    """The student's actor as NumPy arrays: ``tanh`` layers ``(W, b)`` then the linear mean ``(W, b)``."""

    layers: tuple[tuple[np.ndarray, np.ndarray], ...]
    head: tuple[np.ndarray, np.ndarray]

    def act(self, observation: np.ndarray) -> np.ndarray:
        """The deterministic action of one observation, as SB3's ``predict``: the mean, clipped."""
        h = np.asarray(observation, dtype=np.float32)
        for w, b in self.layers:
            h = np.tanh(w @ h + b)
        w, b = self.head
        return np.clip(w @ h + b, -1.0, 1.0).astype(np.float32)


def quantile_huber_loss(prediction: Any, target: Any, weight: Any, quantile: float,
                        kappa: float = HUBER_KAPPA) -> Any:  # fmt: skip
    """Weighted mean of the smoothed pinball loss ``|τ − [u < 0]| · huber_κ(u) / κ``, ``u = target −
    prediction`` (torch tensors): its minimiser is the τ-quantile of the targets (the κ-smoothed one)."""
    import torch

    u = target - prediction
    huber = torch.where(u.abs() <= kappa, 0.5 * u * u / kappa, u.abs() - 0.5 * kappa)
    tilt = torch.abs(quantile - (u < 0).to(u.dtype))
    return (weight * tilt * huber).sum() / weight.sum().clamp_min(1e-12)


class Student:
    """An SB3 PPO model whose actor is fitted to the teacher's labels (module docstring).

    ``env`` gives the spaces (a residual-mode Feedrate env); ``net_arch`` the actor's hidden layers (the
    value net, only used by a PPO fine-tune, gets the same); ``log_std_init`` the spread a PPO fine-tune
    starts exploring with.
    """

    def __init__(self, env: Any, net_arch: Sequence[int], log_std_init: float, seed: int) -> None:
        from stable_baselines3 import PPO

        kwargs = {"net_arch": list(net_arch), "log_std_init": log_std_init}
        self.model = PPO("MlpPolicy", env, seed=seed, device="cpu", verbose=0, policy_kwargs=kwargs)
        self._optimizer: Any = None
        self._rng = np.random.default_rng(seed)

    @property
    def policy(self) -> Any:
        return self.model.policy

    def _actor_parameters(self) -> list[Any]:
        p = self.policy
        return [*p.mlp_extractor.policy_net.parameters(), *p.action_net.parameters()]

    def mean(self, observations: Any) -> Any:
        """The actor's mean action of a batch of observations (a torch tensor, shape (n,))."""
        p = self.policy
        features = p.extract_features(observations, p.pi_features_extractor)
        return p.action_net(p.mlp_extractor.forward_actor(features)).squeeze(-1)

    def fit(self, observations: np.ndarray, labels: np.ndarray, weights: np.ndarray, *, epochs: int,
            batch_size: int, learning_rate: float, quantile: float,
            on_epoch: Any = None) -> float:  # fmt: skip
        """Fit the actor's mean to ``labels`` (weighted quantile loss) for ``epochs`` passes of shuffled
        minibatches; the optimizer's state carries over between calls (DAgger rounds continue the fit).
        Returns the last epoch's mean loss; ``on_epoch(epoch, loss)`` is called after each pass."""
        import torch

        if self._optimizer is None:
            self._optimizer = torch.optim.Adam(self._actor_parameters(), lr=learning_rate)
        for group in self._optimizer.param_groups:
            group["lr"] = learning_rate
        obs = torch.as_tensor(observations, dtype=torch.float32)
        target = torch.as_tensor(labels, dtype=torch.float32)
        weight = torch.as_tensor(weights, dtype=torch.float32)
        n = len(target)
        self.policy.set_training_mode(True)
        loss_value = float("nan")
        for epoch in range(epochs):
            order = torch.as_tensor(self._rng.permutation(n))
            total, mass = 0.0, 0.0
            for start in range(0, n, batch_size):
                index = order[start : start + batch_size]
                loss = quantile_huber_loss(self.mean(obs[index]), target[index], weight[index], quantile)
                self._optimizer.zero_grad()
                loss.backward()
                self._optimizer.step()
                batch_mass = float(weight[index].sum())
                total += float(loss.detach()) * batch_mass
                mass += batch_mass
            loss_value = total / max(mass, 1e-12)
            if on_epoch is not None:
                on_epoch(epoch, loss_value)
        self.policy.set_training_mode(False)
        return loss_value

    def actor_weights(self) -> ActorWeights:
        """The actor as NumPy arrays (for the labelling workers)."""
        p = self.policy
        linear = [m for m in p.mlp_extractor.policy_net if hasattr(m, "weight")]
        activations = [type(m).__name__ for m in p.mlp_extractor.policy_net if not hasattr(m, "weight")]
        if any(name != "Tanh" for name in activations):  # SB3's PPO MlpPolicy default
            raise ValueError(f"the student's actor must use tanh layers, got {activations}")

        def arrays(m: Any) -> tuple[np.ndarray, np.ndarray]:
            return (m.weight.detach().numpy().astype(np.float32).copy(),
                    m.bias.detach().numpy().astype(np.float32).copy())  # fmt: skip

        return ActorWeights(tuple(arrays(m) for m in linear), arrays(p.action_net))

    def save(self, path: str | Path, policy_env: dict[str, Any], shield: PlannerShield | None = None) -> Path:
        """Write the SB3 model zip (:func:`save_model`)."""
        return save_model(self.model, path, policy_env, shield)


def save_model(model: Any, path: str | Path, policy_env: dict[str, Any],
               shield: PlannerShield | None) -> Path:  # fmt: skip
    """Write an SB3 model zip, recording the env it acts in (``cnc_gym_env``) and the shield it acts
    through (``cnc_gym_shield``), as plain JSON (what :mod:`cnc_gym.policies.model` reads)."""
    model.cnc_gym_env = policy_env
    if shield is not None:
        model.cnc_gym_shield = shield.record()
    path = Path(path)
    model.save(path)
    return path
