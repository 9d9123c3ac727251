"""A native vector env of ``cnc_gym/Feedrate-v0``: N copies stepped in one call, infos as arrays.

``gymnasium.vector.SyncVectorEnv`` over N ``gymnasium.make`` copies spends more per env-step on its own
bookkeeping than the env spends stepping: each copy goes through three wrappers, and its info dict
(14 keys) is merged key by key, env by env, with type checks. This class keeps N unwrapped
:class:`~cnc_gym.envs.feedrate.FeedrateEnv` copies and gathers their observations, rewards and infos
directly into arrays. Semantics are those of ``SyncVectorEnv`` in its default next-step autoreset mode:
the step after an episode ends resets that copy and returns its first observation, reward 0 and no
termination. Infos: every documented key maps to an (N,) array (``program`` an object array), with the
``_key`` all-true masks Gymnasium's vector infos carry.

    from cnc_gym.envs.vector import FeedrateVectorEnv
    envs = FeedrateVectorEnv(8, programs=["star", "circle"])
    obs, infos = envs.reset(seed=0)                       # copy i is seeded with seed + i
    obs, rewards, terminated, truncated, infos = envs.step(envs.action_space.sample())
"""

from __future__ import annotations

from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
from gymnasium.vector import AutoresetMode
from gymnasium.vector.utils import batch_space

from cnc_gym.envs.feedrate import FeedrateEnv
from cnc_gym.errors import ConfigError

#: Numeric info keys, gathered into one float array per step; the integer ones are cast back.
_NUMERIC_KEYS = ("cycle_time_s", "contour_error_mm", "contour_error_max_mm", "contour_error_rms_mm",
                 "tolerance_mm", "violations", "violation_length_mm", "violation_time_s", "cost", "line",
                 "override", "feed_mm_min", "path_s", "progress", "steps")  # fmt: skip
_INT_KEYS = frozenset(("violations", "line", "steps"))


class FeedrateVectorEnv(gym.vector.VectorEnv):
    """``num_envs`` independent Feedrate-v0 copies (keyword arguments as :class:`FeedrateEnv`'s)."""

    metadata: ClassVar[dict[str, Any]] = {"autoreset_mode": AutoresetMode.NEXT_STEP, "render_modes": []}

    def __init__(self, num_envs: int = 8, **env_kwargs: Any) -> None:
        if isinstance(num_envs, bool) or not isinstance(num_envs, int) or num_envs < 1:
            raise ConfigError(f"num_envs must be a positive integer, got {num_envs!r}")
        if env_kwargs.get("render_mode") is not None:
            raise ConfigError("FeedrateVectorEnv does not render; use SyncVectorEnv for rgb_array frames")
        self.num_envs = num_envs
        self.envs = [FeedrateEnv(**env_kwargs) for _ in range(num_envs)]
        first = self.envs[0]
        self.single_observation_space = first.observation_space
        self.single_action_space = first.action_space
        self.observation_space = batch_space(self.single_observation_space, num_envs)
        self.action_space = batch_space(self.single_action_space, num_envs)
        self.render_mode = None
        self._observations = np.zeros((num_envs, *self.single_observation_space.shape), dtype=np.float32)
        self._rewards = np.zeros(num_envs)
        self._terminated = np.zeros(num_envs, dtype=bool)
        self._truncated = np.zeros(num_envs, dtype=bool)
        self._autoreset = np.zeros(num_envs, dtype=bool)
        self._mask = np.ones(num_envs, dtype=bool)
        self._mask.flags.writeable = False  # shared by every "_key" entry

    def reset(
        self, *, seed: int | list[int | None] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        if seed is None or isinstance(seed, int):
            seeds = [None if seed is None else seed + i for i in range(self.num_envs)]
        else:
            seeds = list(seed)
            if len(seeds) != self.num_envs:
                raise ConfigError(f"reset needs {self.num_envs} seeds, got {len(seeds)}")
        infos = []
        for i, (env, env_seed) in enumerate(zip(self.envs, seeds, strict=True)):
            self._observations[i], info = env.reset(seed=env_seed, options=options)
            infos.append(info)
        self._autoreset[:] = False
        return self._observations.copy(), self._gather(infos)

    def step(self, actions: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        actions = np.asarray(actions)
        if actions.shape[:1] != (self.num_envs,):
            raise ValueError(f"actions must have shape ({self.num_envs}, 1), got {actions.shape}")
        observations, rewards = self._observations, self._rewards
        terminated, truncated = self._terminated, self._truncated
        infos = []
        for i, env in enumerate(self.envs):
            if self._autoreset[i]:  # next-step autoreset: this step only resets the finished copy
                observations[i], info = env.reset()
                rewards[i] = 0.0
                terminated[i] = truncated[i] = False
            else:
                observations[i], rewards[i], terminated[i], truncated[i], info = env.step(actions[i])
            infos.append(info)
        np.logical_or(terminated, truncated, out=self._autoreset)
        return observations.copy(), rewards.copy(), terminated.copy(), truncated.copy(), self._gather(infos)

    def _gather(self, infos: list[dict[str, Any]]) -> dict[str, Any]:
        """Per-env info dicts → one (N,) array per key, plus Gymnasium's ``_key`` masks."""
        numeric = np.array([[info[key] for key in _NUMERIC_KEYS] for info in infos], dtype=np.float64)
        out: dict[str, Any] = {}
        for column, key in enumerate(_NUMERIC_KEYS):
            values = numeric[:, column]
            out[key] = values.astype(np.int64) if key in _INT_KEYS else values
            out[f"_{key}"] = self._mask
        programs = np.empty(self.num_envs, dtype=object)
        programs[:] = [info["program"] for info in infos]
        out["program"] = programs
        out["_program"] = self._mask
        return out

    def close_extras(self, **kwargs: Any) -> None:
        for env in self.envs:
            env.close()
