"""Native vector envs of every ``cnc_gym/Feedrate`` id: N episodes stepped by one compiled call.

``gymnasium.vector.SyncVectorEnv`` over N ``gymnasium.make`` copies steps them one by one, each through
three wrappers, and merges their info dicts key by key. These classes run the N episodes in one
:class:`~cnc_gym.envs.engine.batch.FeedrateBatch`: one numba call per step moves every env (in numba's
threads from 16 envs on, where numba has at least four), and the infos are read from the batch's state
arrays. Semantics are those of ``SyncVectorEnv`` in its default next-step autoreset mode, so the two give
the same numbers, bit for bit: the step after an episode ends resets that env (its program drawn with its
own generator) and returns its first observation, reward 0 and no termination. ``reset(seed=s)`` seeds env
i with ``s + i`` (a list gives one seed per env). Infos: every key of the id's info maps to an (N,) array
(``program`` an object array), with the ``_key`` all-true masks Gymnasium's vector infos carry.

- :class:`FeedrateVectorEnv`: ``cnc_gym/Feedrate-v0`` (keyword arguments as :class:`FeedrateEnv`'s);
- :class:`FeedrateVectorEnvV1`: ``-v1``, ``-v2`` and ``-v3`` (keyword arguments as
  :class:`~cnc_gym.envs.feedrate_v1.FeedrateEnvV1`'s, the ``residual`` action mode included);
- :func:`make_vector_env`: the registered ids' vector entry point, so that
  ``gymnasium.make_vec(id, n, vectorization_mode="vector_entry_point")`` builds them. With domain
  randomisation on (every episode draws a machine of its own, so the envs no longer share one engine) it
  returns ``SyncVectorEnv`` over ``n`` single envs: the same semantics and numbers, one call per env.

::

    import gymnasium as gym
    import cnc_gym
    envs = gym.make_vec("cnc_gym/Feedrate-v6", 8, vectorization_mode="vector_entry_point",
                        programs=["star", "circle"])
    obs, infos = envs.reset(seed=0)                       # env i is seeded with seed + i
    obs, rewards, terminated, truncated, infos = envs.step(envs.action_space.sample())

For Stable-Baselines3, :func:`cnc_gym.envs.sb3.make_sb3_vec_env` wraps these classes as an SB3 ``VecEnv``.
"""

from __future__ import annotations

from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode
from gymnasium.vector.utils import batch_space

from cnc_gym.envs.engine.layout import F_SIGNAL, I_PROGRAM, I_RESET, SIG_PLANNER_OVERRIDE
from cnc_gym.envs.feedrate import FeedrateEnv
from cnc_gym.envs.feedrate_v1 import FeedrateEnvV1
from cnc_gym.errors import ConfigError
from cnc_gym.motion import ActionError


class FeedrateVectorEnv(gym.vector.VectorEnv):
    """``num_envs`` Feedrate-v0 episodes (keyword arguments as :class:`FeedrateEnv`'s). ``parallel``: step
    them in numba's threads (default: from 16 envs on, when numba has at least 4 threads)."""

    metadata: ClassVar[dict[str, Any]] = {"autoreset_mode": AutoresetMode.NEXT_STEP, "render_modes": []}
    #: The single env whose task the batch runs.
    task_class: ClassVar[type[FeedrateEnv]] = FeedrateEnv

    def __init__(self, num_envs: int = 8, parallel: bool | None = None, *, task: FeedrateEnv | None = None,
                 **env_kwargs: Any) -> None:  # fmt: skip
        if isinstance(num_envs, bool) or not isinstance(num_envs, int) or num_envs < 1:
            raise ConfigError(f"num_envs must be a positive integer, got {num_envs!r}")
        name = type(self).__name__
        if env_kwargs.get("render_mode") is not None or (task is not None and task.render_mode is not None):
            raise ConfigError(f"{name} does not render; use SyncVectorEnv for rgb_array frames")
        self.num_envs = num_envs
        #: The task (validated arguments, programs, spaces); its own one-episode batch is not stepped.
        #: ``task``: one already built (a :attr:`task_class` env, its arguments then taken from it).
        if task is not None and (env_kwargs or not isinstance(task, self.task_class)):
            raise ConfigError(f"{name}: give a {self.task_class.__name__} task or its arguments")
        self.task = task if task is not None else self.task_class(**env_kwargs)
        self._check_task()
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

    def _check_task(self) -> None:
        """Refuse a task the shared batch cannot run (hooks of the subclasses)."""

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


class FeedrateVectorEnvV1(FeedrateVectorEnv):
    """``num_envs`` episodes of ``cnc_gym/Feedrate-v1`` to ``-v6`` (keyword arguments as
    :class:`~cnc_gym.envs.feedrate_v1.FeedrateEnvV1`'s; the ids differ only in them: ``contour_rule``,
    ``planner_version``, ``controller_revision``, ``reward_rule``). In ``residual`` mode each env's action
    scales the deployable planner's override of its own episode, as in the single env. Domain
    randomisation is refused here (each episode would need an engine of its own): :func:`make_vector_env`
    gives ``SyncVectorEnv`` for it."""

    task_class: ClassVar[type[FeedrateEnv]] = FeedrateEnvV1

    def _check_task(self) -> None:
        task = self.task
        assert isinstance(task, FeedrateEnvV1)
        if task.randomize.enabled:
            raise ConfigError("FeedrateVectorEnvV1 runs one machine for every env; with randomize, build the "
                              "envs with cnc_gym.envs.vector.make_vector_env (or gymnasium.make_vec)")
        self._residual = task.action_mode == "residual"

    def set_actions(self, actions: Any) -> None:
        """As :meth:`FeedrateVectorEnv.set_actions`; in ``residual`` mode each clipped action ``a`` then
        becomes the knob of ``clip(ov_plan · ρ^a, 0, max_override)`` with the env's planner override, the
        same arithmetic as ``FeedrateEnvV1`` (Python floats, so the numbers are the single env's)."""
        super().set_actions(actions)
        if not self._residual:
            return
        task = self.task
        assert isinstance(task, FeedrateEnvV1)
        batch = self.batch
        planned = batch.state_f[:, F_SIGNAL + SIG_PLANNER_OVERRIDE].tolist()
        knobs = batch.actions.tolist()
        rho, top, planner = task.residual_range, task.max_override, task._planner
        for i, (a, ov_plan) in enumerate(zip(knobs, planned, strict=True)):
            batch.actions[i] = planner.knob(min(max(ov_plan * rho**a, 0.0), top))


def make_vector_env_v1(num_envs: int = 8, parallel: bool | None = None,
                       **env_kwargs: Any) -> gym.vector.VectorEnv:  # fmt: skip
    """The vector entry point of ``cnc_gym/Feedrate-v1`` to ``-v6``: :class:`FeedrateVectorEnvV1`,
    or with domain randomisation on (or a render mode) ``SyncVectorEnv`` over ``num_envs`` single envs
    (the same semantics and numbers; each env steps its own engine)."""
    if isinstance(num_envs, bool) or not isinstance(num_envs, int) or num_envs < 1:
        raise ConfigError(f"num_envs must be a positive integer, got {num_envs!r}")
    task = FeedrateEnvV1(**env_kwargs)  # the arguments checked here, with one clear line
    if task.randomize.enabled or task.render_mode is not None:
        task.close()
        return gym.vector.SyncVectorEnv([lambda: FeedrateEnvV1(**env_kwargs)] * num_envs)
    return FeedrateVectorEnvV1(num_envs, parallel=parallel, task=task)
