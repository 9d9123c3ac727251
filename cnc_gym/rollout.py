"""One rollout: a policy drives a Feedrate env through an episode, the same way everywhere.

``cnc-gym run`` (:mod:`cnc_gym.runner`), ``cnc-gym bench`` (:mod:`cnc_gym.benchmark.runner`), the suite
generator's feasibility check, ``scripts/evaluate.py`` and the oracle's simulations all go through this
module, so a baseline, a trained model and an RL agent are measured by the same code path:

- :class:`Policy`, the protocol a policy implements (``reset(env)`` once per episode, after
  ``env.reset()``; ``act(observation, info) -> action`` every control step);
- :func:`policy_env`, the env a policy runs a program in: the env id and settings the policy names (a
  trained model's: :mod:`cnc_gym.policies.model`), else ``cnc_gym/Feedrate-v0``, measured with the
  programmed-path contour meter (:data:`CONTOUR_RULE`) on the live controller
  (:data:`cnc_gym.motion.kernel.CONTROLLER_REVISION`);
- :func:`run_episode` (reset, then :func:`play`) and :func:`play` (the step loop from a given state),
  which return an :class:`Episode` record; an optional ``on_step`` hook sees every step and can stop the
  episode (``cnc-gym run``'s series, progress bar and ``--max-time``; the oracle's record of its
  simulation);
- :class:`DeployablePolicy`, a policy whose knob needs no Python in the loop (a constant, the
  deployable planner's schedule): it states its :class:`~cnc_gym.envs.engine.KnobRule`, and
  :func:`compiled_rule` says whether an episode can run on it in compiled code; :func:`play_compiled`
  runs it there, chunk by chunk, with the same steps, infos and return as :func:`play` (an ``on_chunk``
  hook sees each chunk's info values);
- :func:`announce_compiling`, the line a command prints before the simulator compiles (a cold numba
  cache: the first run after an install or an update).
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol, TextIO, runtime_checkable

import numpy as np

if TYPE_CHECKING:  # (the engine loads numba: imported where an episode runs, not with this module)
    from cnc_gym.envs.engine import KnobRule

#: The env a policy runs in when it names none (the baselines: they turn the feed-override knob).
DEFAULT_ENV_ID = "cnc_gym/Feedrate-v0"
#: The contour meter of every ``run`` and ``bench`` episode: the programmed path ("path": the rapids the
#: reference has left are part of it), whatever env version the policy acts in.
CONTOUR_RULE = "path"

#: What a command prints before the simulator compiles: numba's disk cache keeps the machine code, so only
#: the first run after an install or an update waits (docs/env.md, "Speed": the cold and warm figures).
COMPILING_NOTICE = ("cnc-gym: compiling the simulator (first run only, about {} s; longer on a busy "
                    "machine)")
#: The CPU seconds the notice quotes: the compile of the first ``make demo`` (94 s of CPU at commit
#: cc9988f, load average 1 to 4: docs/env.md, "Speed"); a run that needs fewer kernels waits less.
COMPILE_CPU_S = 90
_announced = False

#: ``on_step(steps, reward, terminated, truncated, info)``, called after every step (``steps`` counts it);
#: True stops the episode there.
StepHook = Callable[[int, float, bool, bool, dict[str, Any]], bool | None]


@runtime_checkable
class Policy(Protocol):
    """Anything that can turn the feed-override knob of a Feedrate env (or command its feed).

    A policy may also name the env it acts in: ``env_id`` and ``env_kwargs`` attributes (a trained
    model's env version and settings); :func:`policy_env` reads them.
    """

    #: Short human-readable name used in tables and plots (``constant:1.0``, ``classical``, a model file).
    name: str

    def reset(self, env: Any) -> None:
        """Prepare for a new episode; ``env`` has just been reset (``env.unwrapped`` gives the toolpath,
        machine and controller)."""

    def act(self, observation: np.ndarray, info: dict[str, Any]) -> np.ndarray:
        """The env action for this control step."""


@dataclass
class Episode:
    """What a rollout returns: the last ``info`` (the episode's totals), the return and the step count."""

    info: dict[str, Any]
    total_return: float
    steps: int
    terminated: bool  # the program ran to its end
    truncated: bool  # the env's step budget cut it off
    stopped: bool = False  # the ``on_step`` hook asked to stop

    @property
    def finished(self) -> bool:
        """The program ran to its end (terminated, not truncated or stopped)."""
        return self.terminated


def policy_env(policy: Any, *, programs: list[Any], env_id: str | None = None,
               contour_rule: str | None = CONTOUR_RULE, controller_revision: int | None = 0,
               **settings: Any) -> Any:  # fmt: skip
    """The Gymnasium env ``policy`` runs ``programs`` in: the env id and settings the policy names
    (``env_id``, ``env_kwargs`` attributes), else ``env_id`` (default :data:`DEFAULT_ENV_ID`); then
    ``settings`` (dialect, machine, units, plant …); measured with ``contour_rule`` (None: the env id's
    own meter), on the controller of ``controller_revision`` (0: the live one,
    :data:`cnc_gym.motion.kernel.CONTROLLER_REVISION`; None: the env id's own)."""
    import gymnasium

    import cnc_gym  # noqa: F401  (registers the env ids)

    chosen = getattr(policy, "env_id", None) or env_id or DEFAULT_ENV_ID
    kwargs = {**dict(getattr(policy, "env_kwargs", None) or {}), **settings, "programs": programs}
    if contour_rule is not None:
        kwargs["contour_rule"] = contour_rule
    if controller_revision == 0:
        from cnc_gym.envs.options import CONTROLLER_REVISION

        controller_revision = CONTROLLER_REVISION
    if controller_revision is not None:
        kwargs["controller_revision"] = controller_revision
    return gymnasium.make(chosen, **kwargs)


def run_episode(env: Any, policy: Any, seed: int | None = 0, on_step: StepHook | None = None) -> Episode:
    """One episode of ``env`` under ``policy``: reset with ``seed``, ``policy.reset(env)``, then
    :func:`play`."""
    observation, info = env.reset(seed=seed)
    policy.reset(env)
    return play(env, policy, observation, info, on_step)


def play(env: Any, policy: Any, observation: Any, info: dict[str, Any],
         on_step: StepHook | None = None) -> Episode:  # fmt: skip
    """Step ``env`` under ``policy`` from ``observation`` and ``info`` (a state the caller reset or copied)
    until the episode ends or ``on_step`` returns True."""
    total, steps = 0.0, 0
    terminated = truncated = stopped = False
    while not (terminated or truncated):
        observation, reward, terminated, truncated, info = env.step(policy.act(observation, info))
        total += float(reward)
        steps += 1
        if on_step is not None and on_step(steps, reward, terminated, truncated, info):
            stopped = True
            break
    return Episode(info, total, steps, bool(terminated), bool(truncated), stopped)


@runtime_checkable
class DeployablePolicy(Protocol):
    """A policy whose knob needs no Python in the loop: after its ``reset(env)`` it states the knob as
    data (:class:`~cnc_gym.envs.engine.KnobRule`: a constant, or a schedule read by the planner's knob
    rule), and its ``act`` gives exactly that knob. None: not this episode (it acts in Python)."""

    def knob_rule(self) -> KnobRule | None:
        """The rule of the episode the policy has just been reset for, or None."""


#: Steps per compiled call of :func:`play_compiled` (its hook, a progress bar, a CPU-time check, run
#: between calls: a few ms apart).
CHUNK_STEPS = 2048
#: ``on_chunk(steps, total_return, rows, info)``: after each compiled chunk, with the steps and return so
#: far, the chunk's rows of recorded info values (one row per step) and its last step's info; True stops
#: the episode there (if it has not ended).
ChunkHook = Callable[[int, float, np.ndarray, dict[str, Any]], bool | None]


_compiled_episodes = True  # False inside step_by_step()


@contextlib.contextmanager
def step_by_step() -> Iterator[None]:
    """Within it, :func:`compiled_rule` answers None: every episode runs in the Python loop (:func:`play`),
    as before compiled episodes existed (the tests and ``scripts/bench_episodes.py`` compare the two)."""
    global _compiled_episodes
    before, _compiled_episodes = _compiled_episodes, False
    try:
        yield
    finally:
        _compiled_episodes = before


def compiled_rule(env: Any, policy: Any) -> KnobRule | None:
    """The knob rule ``policy`` (just reset for ``env``) runs ``env``'s episode on in compiled code, or
    None when something needs the Python loop: a policy that is not a :class:`DeployablePolicy` (or has
    no rule for this episode); an env whose step is not the compiled one (the MuJoCo plant), that records
    frames (a render mode), or whose knob is turned in Python (``residual`` mode); a wrapper other than
    Gymnasium's order and passive checkers (which change no step) around it; inside
    :func:`step_by_step`."""
    from gymnasium import Wrapper
    from gymnasium.wrappers import OrderEnforcing, PassiveEnvChecker

    from cnc_gym.envs.feedrate import FeedrateEnv

    if not _compiled_episodes or not isinstance(policy, DeployablePolicy):
        return None
    inner = env
    while isinstance(inner, Wrapper):
        if type(inner) not in (OrderEnforcing, PassiveEnvChecker):
            return None
        inner = inner.env
    if not (isinstance(inner, FeedrateEnv) and inner.compiled_episodes):
        return None
    return policy.knob_rule()


def play_compiled(env: Any, rule: KnobRule, *, record: Sequence[str] = (), stop_time_s: float | None = None,
                  on_chunk: ChunkHook | None = None, chunk_steps: int = CHUNK_STEPS) -> Episode:  # fmt: skip
    """:func:`play` of a policy whose knob is ``rule`` (:func:`compiled_rule`), from the state ``env`` is
    in, in compiled chunks of ``chunk_steps`` steps: the same episode (steps, last info, return) bit for
    bit. ``record``: the info keys (of ``OUTPUT_INFO_KEYS``) whose values ``on_chunk`` gets, one row per
    step; ``stop_time_s``: stop after the step whose ``cycle_time_s`` reaches it, less 1 ns, unless that
    step terminated the episode (``stopped``), as ``cnc-gym run --max-time`` and ``bench --max-time`` do."""
    from cnc_gym.envs.engine import OUTPUT_INFO_KEYS
    from cnc_gym.envs.engine.episode import NOT_FINITE, RAN, STOPPED

    base = env.unwrapped
    columns = np.array([OUTPUT_INFO_KEYS.index(key) for key in record], dtype=np.int64)
    rows = np.empty((chunk_steps, len(columns)))
    stop = math.inf if stop_time_s is None else float(stop_time_s)
    total, steps = 0.0, 0
    while True:
        n, total, why, terminated, truncated, info = base.run_rule(rule, chunk_steps, stop_time_s=stop,
                                                                   columns=columns, rows=rows,
                                                                   total=total)  # fmt: skip
        steps += n
        stopped = why == STOPPED
        if on_chunk is not None and n and on_chunk(steps, total, rows[:n], info) and why == RAN:
            stopped = True
        if why == NOT_FINITE:  # the action the Python loop would have given, and the env's error for it
            from cnc_gym.envs.options import parse_action

            parse_action(np.array([math.nan], dtype=np.float32))
        if why != RAN or stopped:
            return Episode(info, total, steps, bool(terminated), bool(truncated), stopped)


def announce_compiling(log: TextIO, *, parallel: bool = False) -> bool:
    """Print :data:`COMPILING_NOTICE` on ``log`` when this process's first env step will compile (the
    fused step is neither loaded nor in numba's disk cache), once per process; True if printed. Cheap:
    it reads the cache's index, compiles nothing."""
    global _announced
    from cnc_gym.envs.engine.batch import step_needs_compiling

    if _announced or not step_needs_compiling(parallel=parallel):
        return False
    _announced = True
    print(COMPILING_NOTICE.format(COMPILE_CPU_S), file=log, flush=True)
    return True
