"""A native vector env of ``cnc_gym/Feedrate-v0``: N episodes stepped by one compiled call, infos as arrays.

``gymnasium.vector.SyncVectorEnv`` over N ``gymnasium.make`` copies steps them one by one, each through
three wrappers, and merges their info dicts key by key. This class runs the N episodes in one
:class:`~cnc_gym.envs.engine.batch.FeedrateBatch`: one numba call per step moves every env (in numba's threads
from 16 envs on, where numba has at least four), and the infos are read from the batch's state arrays.
Semantics are those of ``SyncVectorEnv`` in its default next-step autoreset mode, so the two give the
same numbers: the step after an episode ends resets that env (its program drawn with its own generator)
and returns its first observation, reward 0 and no termination. ``reset(seed=s)`` seeds env i with
``s + i`` (a list gives one seed per env). Infos: every documented key maps to an (N,) array (``program``
an object array), with the ``_key`` all-true masks Gymnasium's vector infos carry.

    from cnc_gym.envs.vector import FeedrateVectorEnv
    envs = FeedrateVectorEnv(8, programs=["star", "circle"])
    obs, infos = envs.reset(seed=0)                       # env i is seeded with seed + i
    obs, rewards, terminated, truncated, infos = envs.step(envs.action_space.sample())

For Stable-Baselines3, :func:`cnc_gym.envs.sb3.make_sb3_vec_env` wraps this class as an SB3 ``VecEnv``.
"""

from __future__ import annotations

from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode
from gymnasium.vector.utils import batch_space

from cnc_gym.envs.engine.layout import I_PROGRAM, I_RESET
from cnc_gym.envs.feedrate import FeedrateEnv
from cnc_gym.errors import ConfigError
from cnc_gym.motion import ActionError


class FeedrateVectorEnv(gym.vector.VectorEnv):
    """``num_envs`` Feedrate-v0 episodes (keyword arguments as :class:`FeedrateEnv`'s). ``parallel``: step
    them in numba's threads (default: from 16 envs on, when numba has at least 4 threads)."""

    metadata: ClassVar[dict[str, Any]] = {"autoreset_mode": AutoresetMode.NEXT_STEP, "render_modes": []}

    def __init__(self, num_envs: int = 8, parallel: bool | None = None, **env_kwargs: Any) -> None:
        if isinstance(num_envs, bool) or not isinstance(num_envs, int) or num_envs < 1:
            raise ConfigError(f"num_envs must be a positive integer, got {num_envs!r}")
        if env_kwargs.get("render_mode") is not None:
            raise ConfigError("FeedrateVectorEnv does not render; use SyncVectorEnv for rgb_array frames")
        self.num_envs = num_envs
        #: The task (validated arguments, programs, spaces); its own one-episode batch is not stepped.
        self.task = FeedrateEnv(**env_kwargs)
        self.batch = self.task.make_batch(num_envs, parallel=parallel)
        self.single_observation_space = self.task.observation_space
        self.single_action_space = self.task.action_space
        self.observation_space = batch_space(self.single_observation_space, num_envs)
        self.action_space = batch_space(self.single_action_space, num_envs)
        self.render_mode = None
        self._rngs = [seeding.np_random()[0] for _ in range(num_envs)]
        self._autoreset = np.zeros(num_envs, dtype=bool)
        self._mask = np.ones(num_envs, dtype=bool)
        self._mask.flags.writeable = False  # shared by every "_key" entry
        self._started = False
        self._ended = 0  # envs whose episode ended on the last step (reset on the next)

    def reset(
        self, *, seed: int | list[int | None] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        if seed is None or isinstance(seed, int):
            seeds = [None if seed is None else seed + i for i in range(self.num_envs)]
        else:
            seeds = list(seed)
            if len(seeds) != self.num_envs:
                raise ConfigError(f"reset needs {self.num_envs} seeds, got {len(seeds)}")
        self.reset_envs(list(range(self.num_envs)), seeds, [options] * self.num_envs)
        return self.batch.observations.copy(), self._infos()

    def reset_envs(self, envs: list[int], seeds: list[int | None],
                   options: list[dict[str, Any] | None]) -> None:  # fmt: skip
        """Reset ``envs`` now, each with its seed and options (as ``FeedrateEnv.reset``: a seed starts the
        env's generator afresh, None keeps it; ``{"program": ...}`` picks the program)."""
        programs = []
        for env, env_seed, env_options in zip(envs, seeds, options, strict=True):
            choice = None
            if env_options is not None:
                if not isinstance(env_options, dict):
                    raise ConfigError(f"options must be a dict, got {type(env_options).__name__}")
                unknown = sorted(set(env_options) - {"program"})
                if unknown:
                    raise ConfigError(f"unknown reset option {unknown[0]!r} (allowed: program)")
                choice = env_options.get("program")
            if env_seed is not None:
                self._rngs[env] = seeding.np_random(env_seed)[0]
            pick = self.task.draw_program(self._rngs[env]) if choice is None else choice
            programs.append(self.task.program_slot(self.batch, pick))
        self.batch.reset(envs, programs)
        self._autoreset[envs] = False
        self._ended = int(np.count_nonzero(self._autoreset))
        self._started = True

    def set_actions(self, actions: Any) -> None:
        """Check ``actions`` ((N, 1) or (N,), finite) and put them, clipped to [-1, 1], in the batch."""
        knobs = actions if type(actions) is np.ndarray and actions.dtype == np.float64 else np.asarray(
            actions, dtype=np.float64)  # fmt: skip
        if knobs.shape != (self.num_envs, 1) and knobs.shape != (self.num_envs,):
            raise ValueError(f"actions must have shape ({self.num_envs}, 1), got {knobs.shape}")
        if not self.batch.set_actions(knobs.reshape(self.num_envs)):
            raise ActionError(f"actions must be finite, got {actions!r}")

    def step(self, actions: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        if not self._started:
            raise gym.error.ResetNeeded("call reset() before step()")
        batch = self.batch
        self.set_actions(actions)
        # Next-step autoreset: the envs whose episode ended last step are reset in this call instead.
        if self._ended:
            for i in np.flatnonzero(self._autoreset):
                batch.state_i[i, I_RESET] = 1
                slot = self.task.program_slot(batch, self.task.draw_program(self._rngs[i]))
                batch.state_i[i, I_PROGRAM] = slot
        batch.step()
        obs, rewards, terminated, truncated, infos, self._ended = batch.gather()
        if self._ended:
            np.logical_or(terminated, truncated, out=self._autoreset)
        return obs, rewards, terminated, truncated, self._with_masks(infos)

    def _infos(self) -> dict[str, Any]:
        return self._with_masks(self.batch.infos())

    def _with_masks(self, infos: dict[str, np.ndarray]) -> dict[str, Any]:
        """Gymnasium's ``_key`` masks beside every key."""
        out: dict[str, Any] = {}
        for key, values in infos.items():
            out[key] = values
            out[f"_{key}"] = self._mask
        return out

    def close_extras(self, **kwargs: Any) -> None:
        self.task.close()
