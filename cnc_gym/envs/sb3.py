"""Stable-Baselines3 on the batched engine: a ``VecEnv`` over the native vector envs (:mod:`.vector`).

SB3 trains on its own ``VecEnv`` API (``reset() -> obs``, ``step_async``/``step_wait`` with a list of info
dicts, and the episode's end handled in the same step: the env is reset at once and its last observation
put in ``infos[i]["terminal_observation"]``). :class:`FeedrateSB3VecEnv` gives that API on the batched
engine of any registered id, so one compiled call per step serves every env, and :func:`make_sb3_vec_env`
is the drop-in for SB3's ``make_vec_env(env_id, n_envs, seed=..., env_kwargs=..., vec_env_cls=DummyVecEnv)``
(the same seeds, programs and numbers, bit for bit; Monitor's episode records from ``VecMonitor``)::

    from cnc_gym.envs.sb3 import make_sb3_vec_env
    vec_env = make_sb3_vec_env(8, seed=0, env_id="cnc_gym/Feedrate-v6",
                               env_kwargs={"programs": ["star", "circle"]})
    model = PPO("MlpPolicy", vec_env).learn(100_000)

With domain randomisation on (each episode draws a machine, so the envs cannot share one engine)
:func:`make_sb3_vec_env` returns SB3's ``DummyVecEnv`` over single envs, the same numbers at the single
env's speed. Infos: at an episode's end a dict with the episode's totals (the env's info keys),
``terminal_observation`` and ``TimeLimit.truncated``; on other steps a read-only mapping with the same
keys, its values taken when the step ends but made Python numbers only when read (SB3 looks for
``"episode"`` in every info every step).
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from stable_baselines3.common.vec_env import VecEnv, VecMonitor
from stable_baselines3.common.vec_env.base_vec_env import VecEnvIndices, VecEnvStepReturn

from cnc_gym.envs.vector import FeedrateVectorEnv
from cnc_gym.errors import ConfigError


class _StepInfos:
    """One step's infos of every env (arrays taken when the step ends, one per info key in the env's
    order), for :class:`StepInfo`."""

    __slots__ = ("arrays",)

    def __init__(self, arrays: dict[str, np.ndarray]) -> None:
        self.arrays = arrays

    def value(self, key: str, env: int) -> Any:
        value = self.arrays[key][env]  # (a KeyError for a key the env has not)
        return value if key == "program" else value.item()


class StepInfo(Mapping):
    """The info of one env on a step that did not end its episode (a read-only mapping of the env's info
    keys; ``copy()`` gives a dict)."""

    __slots__ = ("_env", "_infos")

    def __init__(self, infos: _StepInfos, env: int) -> None:
        self._infos = infos
        self._env = env

    def __getitem__(self, key: str) -> Any:
        return self._infos.value(key, self._env)

    def __iter__(self) -> Iterator[str]:
        return iter(self._infos.arrays)

    def __len__(self) -> int:
        return len(self._infos.arrays)

    def copy(self) -> dict[str, Any]:
        return dict(self)


class FeedrateSB3VecEnv(VecEnv):
    """``num_envs`` episodes of ``env_id`` (a registered ``cnc_gym/Feedrate`` id; keyword arguments as
    its env's) as an SB3 ``VecEnv``, on the id's native vector env (``parallel`` as
    :class:`~cnc_gym.envs.vector.FeedrateVectorEnv`'s)."""

    def __init__(self, num_envs: int, parallel: bool | None = None, *, env_id: str = "cnc_gym/Feedrate-v0",
                 venv: FeedrateVectorEnv | None = None, **env_kwargs: Any) -> None:  # fmt: skip
        if venv is None:
            built = _native_vector_env(env_id, num_envs, parallel, env_kwargs)
            if not isinstance(built, FeedrateVectorEnv):
                built.close()
                raise ConfigError(f"{env_id} with these arguments has no batched engine (randomize is on): "
                                  "use make_sb3_vec_env, which falls back to DummyVecEnv")  # fmt: skip
            venv = built
        #: The native vector env (``venv``: one already built, of ``num_envs`` envs).
        self.venv = venv
        super().__init__(venv.num_envs, venv.single_observation_space, venv.single_action_space)
        self._actions: np.ndarray | None = None

    def reset(self) -> np.ndarray:
        envs = list(range(self.num_envs))
        self.venv.reset_envs(envs, list(self._seeds), [dict(o) if o else None for o in self._options])
        self.reset_infos = [self.venv.batch.info(i) for i in envs]
        self._reset_seeds()
        self._reset_options()
        return self.venv.batch.observations.copy()

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = actions

    def step_wait(self) -> VecEnvStepReturn:
        venv, batch = self.venv, self.venv.batch
        venv.set_actions(self._actions)
        batch.step()
        obs, rewards, terminated, truncated, arrays, n_ended = batch.gather()
        dones = terminated | truncated
        step_infos = _StepInfos(arrays)
        infos: list[Any] = [StepInfo(step_infos, i) for i in range(self.num_envs)]
        if n_ended:
            ended = np.flatnonzero(dones).tolist()
            for i in ended:  # the episode's totals, then a reset in this same step (SB3's convention)
                infos[i] = batch.info(i)
                infos[i]["terminal_observation"] = obs[i].copy()
                infos[i]["TimeLimit.truncated"] = bool(truncated[i] and not terminated[i])
            programs = [venv.task.program_slot(batch, venv.task.draw_program(venv._rngs[i])) for i in ended]
            batch.reset(ended, programs)
            obs[ended] = batch.observations[ended]
            for i in ended:
                self.reset_infos[i] = batch.info(i)
        return obs, rewards.astype(np.float32), dones, infos

    def close(self) -> None:
        self.venv.close()

    # ------------------------------------------------------------------ SB3's per-env attribute access
    def _targets(self, indices: VecEnvIndices) -> Sequence[int]:
        return list(self._get_indices(indices))

    def get_attr(self, attr_name: str, indices: VecEnvIndices = None) -> list[Any]:
        """An attribute of the task (the same for every env)."""
        return [getattr(self.venv.task, attr_name) for _ in self._targets(indices)]

    def set_attr(self, attr_name: str, value: Any, indices: VecEnvIndices = None) -> None:
        raise AttributeError("the batched envs share one task; build a new FeedrateSB3VecEnv to change it")

    def env_method(self, method_name: str, *method_args: Any, indices: VecEnvIndices = None,
                   **method_kwargs: Any) -> list[Any]:  # fmt: skip
        """A method of the task (e.g. ``nominal_time_s``), once per target env."""
        return [getattr(self.venv.task, method_name)(*method_args, **method_kwargs)
                for _ in self._targets(indices)]  # fmt: skip

    def env_is_wrapped(self, wrapper_class: type[gym.Wrapper], indices: VecEnvIndices = None) -> list[bool]:
        return [False for _ in self._targets(indices)]

    def get_images(self) -> Sequence[np.ndarray | None]:
        return [None for _ in range(self.num_envs)]


def _native_vector_env(env_id: str, num_envs: int, parallel: bool | None,
                       env_kwargs: dict[str, Any]) -> gym.vector.VectorEnv:  # fmt: skip
    """The id's vector env from its vector entry point (``env_kwargs`` over the id's registered ones)."""
    import cnc_gym  # noqa: F401  (registers the ids)

    try:
        spec = gym.spec(env_id)
    except gym.error.Error as exc:
        raise ConfigError(f"unknown env id {env_id!r}: {exc}") from None
    if spec.vector_entry_point is None or not env_id.startswith("cnc_gym/"):
        raise ConfigError(f"{env_id} is not a cnc_gym id with a vector entry point")
    return gym.make_vec(env_id, num_envs, vectorization_mode="vector_entry_point", parallel=parallel,
                        **env_kwargs)  # fmt: skip


def make_sb3_vec_env(n_envs: int, seed: int | None = None, env_kwargs: dict[str, Any] | None = None,
                     monitor: bool = True, parallel: bool | None = None,
                     env_id: str = "cnc_gym/Feedrate-v0") -> VecEnv:  # fmt: skip
    """The batched env for SB3, in place of ``make_vec_env(env_id, n_envs, seed=seed, env_kwargs=env_kwargs,
    vec_env_cls=DummyVecEnv)``: env i is seeded with ``seed + i`` at the first reset, and ``monitor`` adds
    SB3's episode records (``VecMonitor``). With domain randomisation on, that ``DummyVecEnv`` itself (the
    same numbers; each env steps its own engine)."""
    kwargs = dict(env_kwargs or {})
    native = _native_vector_env(env_id, n_envs, parallel, kwargs)
    if not isinstance(native, FeedrateVectorEnv):  # randomised: one engine per env
        native.close()
        from stable_baselines3.common.env_util import make_vec_env
        from stable_baselines3.common.vec_env import DummyVecEnv

        return make_vec_env(env_id, n_envs=n_envs, seed=seed, env_kwargs=kwargs, vec_env_cls=DummyVecEnv)
    venv: VecEnv = FeedrateSB3VecEnv(n_envs, venv=native)
    if seed is not None:
        venv.seed(seed)
    return VecMonitor(venv) if monitor else venv
