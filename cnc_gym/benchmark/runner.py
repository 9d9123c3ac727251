"""The bench runner: every program × policy × seed through the env, one record per episode.

Work comes in two phases, each a list of independent tasks: the time-optimal bound of every program
(cached on disk, see :mod:`cnc_gym.motion.bound`), then one task per (program, policy) that runs the
policy's episodes for every seed (so a planner plans a program once). Tasks run serially, on a local
process pool (``workers > 1``), or on a Ray cluster (``ray_address``); records are sorted into the same
order whatever ran them, and hold no timings, so all three give identical records.

A program whose bound cannot be computed (TOPP-RA finds no parameterization, the program has no motion)
is left out with one notice line; the others run. Records reach ``on_records`` as each task finishes
(``cnc-gym bench --json`` appends them to its file: :class:`JsonlAppender`). Ctrl-C stops the work at
once: pending tasks are cancelled, worker processes are ended (they ignore SIGINT themselves, so the
pool is shut down by the parent only), and the KeyboardInterrupt goes on to the caller with every
finished task's records already handed over. :class:`EpisodeLimits` bounds each episode by simulated
time and by CPU time (the policy's planning included); a cut episode is marked in its record
(``stopped_by``).
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import json
import math
import os
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from cnc_gym.benchmark.metrics import RECORD_VERSION, episode_score, is_feasible
from cnc_gym.errors import CncGymError
from cnc_gym.gcode.dialect import DEFAULT_DIALECT
from cnc_gym.machine import DEFAULT_MACHINE
from cnc_gym.rollout import CONTOUR_RULE, compiled_rule, play, play_compiled, policy_env

#: The baselines ``cnc-gym bench`` runs when no ``--policy`` is given.
DEFAULT_POLICIES = ("constant:1.0", "classical", "oracle", "bound")


@dataclass(frozen=True)
class BenchProgram:
    """A program to benchmark: its text and where it comes from."""

    name: str
    text: str
    family: str = "user"
    tier: str = ""
    split: str = "user"
    cut_length_mm: float | None = None
    #: The program as interpreted from its file (a :class:`cnc_gym.programs.Program`): its subprograms
    #: were found in the file's folder, as ``cnc-gym run`` finds them. None: interpret ``text``.
    loaded: Any = field(default=None, compare=False, repr=False)

    def source(self) -> Any:
        """What the env and the bound load: the interpreted program, else the text."""
        return self.loaded if self.loaded is not None else self.text


#: Values of a record's ``stopped_by``: why an episode that did not finish stopped.
STEP_BUDGET, MAX_TIME, MAX_CPU = "step_budget", "max_time", "max_cpu"


@dataclass(frozen=True)
class EpisodeLimits:
    """Per-episode limits: ``max_time_s`` of simulated time (deterministic, as ``cnc-gym run
    --max-time``), ``max_cpu_s`` of CPU time of the process running it, the policy's planning included
    (depends on the machine: a record it cut is not comparable across machines). None: no limit."""

    max_time_s: float | None = None
    max_cpu_s: float | None = None

    def __post_init__(self) -> None:
        for name in ("max_time_s", "max_cpu_s"):
            value = getattr(self, name)
            if value is not None and (isinstance(value, bool) or not isinstance(value, int | float)
                                      or not (math.isfinite(value) and value > 0)):  # fmt: skip
                option = "--max-time" if name == "max_time_s" else "--max-cpu"
                raise CncGymError(f"{option} must be a positive number of seconds, got {value!r}")


@dataclass
class BenchConfig:
    programs: list[BenchProgram]
    policies: list[str]
    seeds: list[int] = field(default_factory=lambda: [0])
    machine: str = DEFAULT_MACHINE
    dialect: str = DEFAULT_DIALECT
    #: Input unit at power-on ("mm"/"inch"); None: the machine preset's, else the dialect's.
    units: str | None = None
    #: Servo plant backend (``lti`` or ``mujoco``); None: the machine preset's.
    plant: str | None = None
    #: The benchmark track (:mod:`cnc_gym.benchmark.tracks`): which plant the episodes run on.
    track: str = "nominal"
    suite: str | None = None
    suite_version: int | None = None
    suite_sha256: str | None = None
    workers: int = 1
    ray_address: str | None = None
    use_ray: bool = False
    progress: bool = False
    limits: EpisodeLimits = field(default_factory=EpisodeLimits)


def suite_programs(suite_name: str, split: str) -> tuple[list[BenchProgram], Any]:
    """The programs of a split of a shipped suite, and the suite."""
    from cnc_gym.benchmark.suites import load_suite

    suite = load_suite(suite_name)
    programs = [BenchProgram(name=e.name, text=e.text(), family=e.family, tier=e.tier, split=e.split,
                             cut_length_mm=e.properties.get("cut_length_mm"))
                for e in suite.programs(split)]  # fmt: skip
    if not programs:
        raise CncGymError(f"suite {suite_name}: split {split!r} has no programs")
    return programs, suite


def user_programs(paths: Sequence[str], machine: str, dialect: str,
                  units: str | None = None) -> list[BenchProgram]:  # fmt: skip
    """Programs from files (``--programs``): family ``user``, tier measured like a suite's."""
    from cnc_gym.benchmark.suites import path_properties, tier_of
    from cnc_gym.machine import load_machine
    from cnc_gym.programs import load_program

    out = []
    seen: set[str] = set()
    mach = load_machine(machine)
    for raw in paths:
        path = Path(raw)
        if not path.is_file():
            raise CncGymError(f"{path}: no such program file")
        try:
            text = path.read_text()
        except (OSError, UnicodeDecodeError) as exc:
            raise CncGymError(f"{path}: cannot read: {exc}") from None
        name = path.stem if path.stem not in seen else str(path)
        seen.add(name)
        # Interpreted here, once, as `cnc-gym run` does (subprograms from the file's folder); a program
        # error is one line, here. The tasks get the interpreted program, not the text.
        loaded = load_program(path, dialect, mach, units=units)
        props = path_properties(loaded.toolpath, mach)
        out.append(BenchProgram(name=name, text=text, tier=tier_of(props),
                                cut_length_mm=props["cut_length_mm"], loaded=loaded))  # fmt: skip
    return out


def current_commit() -> str:
    """The git commit of the installed source (``+dirty`` with uncommitted changes), or ``unknown``."""
    root = Path(__file__).resolve().parents[2]
    try:
        git = ["git", "-C", str(root)]
        head = subprocess.run([*git, "rev-parse", "HEAD"], capture_output=True, text=True, timeout=10,
                              check=True).stdout.strip()  # fmt: skip
        dirty = subprocess.run([*git, "status", "--porcelain", "--untracked-files=no"], capture_output=True,
                               text=True, timeout=10, check=True).stdout.strip()  # fmt: skip
    except (OSError, subprocess.SubprocessError):
        return "unknown"
    return head + ("+dirty" if dirty else "") if head else "unknown"


def _version() -> str:
    try:
        from importlib.metadata import version

        return version("cnc-gym")
    except Exception:  # not installed as a distribution
        return "unknown"


def _sha(text: str) -> str:
    return hashlib.sha256(text.encode()).hexdigest()


# ------------------------------------------------------------------------------------------- tasks
def _bound_task(program: BenchProgram, machine: str, dialect: str, units: str | None) -> dict[str, Any]:
    """The bound of one program: ``{"bound": BoundResult dict, "notices": [...]}``, or ``{"error": why}``
    when it cannot be had (the program is then left out of the run, with one line)."""
    from cnc_gym.machine import load_machine
    from cnc_gym.motion.bound import time_optimal_bound
    from cnc_gym.programs import load_program

    notices: list[str] = []
    mach = load_machine(machine)
    _, toolpath = load_program(program.source(), dialect, mach, units=units)
    try:
        bound = time_optimal_bound(toolpath, mach, notice=notices.append).to_dict()
    except CncGymError as exc:
        return {"error": str(exc), "notices": notices}
    except Exception as exc:  # the solver's own failure on an odd path: that program, not the run
        return {"error": f"time-optimal bound failed: {type(exc).__name__}: {exc}", "notices": notices}
    if not bound["total_s"] > 0:
        return {"error": "no motion: nothing to time against the bound", "notices": notices}
    return {"bound": bound, "notices": notices}


class CpuLimitReached(BaseException):
    """Raised in the episode's process when its CPU time limit is reached (a BaseException, like
    KeyboardInterrupt, so that no ``except Exception`` in a policy swallows it)."""


@contextlib.contextmanager
def _cpu_limit(seconds: float | None) -> Iterator[bool]:
    """Raise :class:`CpuLimitReached` once the process has spent ``seconds`` more CPU time (SIGPROF from
    an ITIMER_PROF timer). Yields whether the timer is armed: not without a limit, nor where signals
    cannot be set (not the main thread, no setitimer); the caller then checks the CPU time itself."""
    if seconds is None or not hasattr(signal, "setitimer") or threading.current_thread() is not \
            threading.main_thread():  # fmt: skip
        yield False
        return

    active = [True]

    def reached(signum: int, frame: Any) -> None:
        if active[0]:
            raise CpuLimitReached

    previous = signal.signal(signal.SIGPROF, reached)
    signal.setitimer(signal.ITIMER_PROF, seconds)
    try:
        yield True
    finally:
        try:
            active[0] = False
            signal.setitimer(signal.ITIMER_PROF, 0)
        finally:
            signal.signal(signal.SIGPROF, previous)


def _limited_episode(env: Any, policy: Any, seed: int, limits: EpisodeLimits) -> tuple[dict[str, Any], float,
                                                                                       int, bool, str | None]:
    """One episode (the rollout's reset, ``policy.reset``, :func:`~cnc_gym.rollout.play`) within
    ``limits``: ``(info, total_return, steps, finished, stopped_by)``. A limit keeps what was run: the
    last step's info (the reset's when the limit came during the policy's planning)."""
    observation, info = env.reset(seed=int(seed))
    last = {"info": info, "steps": 0, "return": 0.0, "why": None}
    started = time.process_time()

    def on_step(steps: int, reward: float, terminated: bool, truncated: bool, info: dict[str, Any]) -> bool:
        last["info"], last["steps"] = info, steps
        last["return"] = float(last["return"]) + float(reward)
        if terminated:
            return False
        if limits.max_time_s is not None and info["cycle_time_s"] >= limits.max_time_s - 1e-9:
            last["why"] = MAX_TIME
            return True
        if not armed and limits.max_cpu_s is not None and steps % 16 == 0 and \
                time.process_time() - started >= limits.max_cpu_s:  # fmt: skip
            last["why"] = MAX_CPU
            return True
        return False

    def on_chunk(steps: int, total_return: float, rows: Any, info: dict[str, Any]) -> bool:
        last["info"], last["steps"], last["return"] = info, steps, total_return
        if not armed and limits.max_cpu_s is not None and time.process_time() - started >= limits.max_cpu_s:
            last["why"] = MAX_CPU
            return True
        return False

    episode = None
    armed = False
    try:
        with _cpu_limit(limits.max_cpu_s) as armed:
            policy.reset(env)
            # A constant or the deployable planner runs in compiled chunks (the same episode, bit for bit;
            # the CPU limit is checked between chunks, a few ms apart), any other policy step by step.
            rule = compiled_rule(env, policy)
            if rule is None:
                episode = play(env, policy, observation, info, on_step)
            else:
                episode = play_compiled(env, rule, stop_time_s=limits.max_time_s, on_chunk=on_chunk)
                if episode.stopped and last["why"] is None:
                    last["why"] = MAX_TIME
    except CpuLimitReached:
        if episode is None:  # (the limit may fall just after the episode ended: then it did not cut it)
            return dict(last["info"]), float(last["return"]), int(last["steps"]), False, MAX_CPU
    finished = episode.finished
    stopped_by = None if finished else (last["why"] if episode.stopped else STEP_BUDGET)
    return episode.info, episode.total_return, episode.steps, finished, stopped_by


def _episode_task(program: BenchProgram, policy_spec: str, seeds: Sequence[int], machine: str,
                  dialect: str, units: str | None, bound: dict[str, Any], common: dict[str, Any],
                  progress: bool, plant: str | None = None,
                  limits: EpisodeLimits | None = None,
                  track: str = "nominal") -> list[dict[str, Any]]:  # fmt: skip
    """Every seed of one (program, policy): records in seed order. On a track other than ``nominal`` the
    episodes run on the track's plant for this program, and planners that plan on the nominal machine
    (``classical``, ``nominal-oracle``) are given it (:mod:`cnc_gym.benchmark.tracks`)."""
    from cnc_gym.benchmark.tracks import track_plant
    from cnc_gym.machine import load_machine, with_plant_backend

    limits = limits or EpisodeLimits()
    nominal = with_plant_backend(load_machine(machine), plant)
    true_machine, plant_parameters = track_plant(track, nominal, str(common.get("suite")), program.name)
    base = {**common, "plant": true_machine.plant.backend, "plant_parameters": plant_parameters,
            "split": program.split, "program": program.name,
            "program_sha256": _sha(program.text), "family": program.family, "tier": program.tier,
            "policy": policy_spec, "bound_s": bound["total_s"], "bound_version": bound["version"],
            "cut_length_mm": program.cut_length_mm}  # fmt: skip
    if policy_spec == "bound":  # the reference itself: no episode is run
        return [{**base, "seed": int(seed), "cycle_time_s": bound["total_s"], "time_ratio": 1.0,
                 "violation_length_mm": None, "violation_time_s": None, "contour_error_max_mm": None,
                 "contour_error_rms_mm": None, "tolerance_mm": None, "violations": None, "steps": None,
                 "finished": True, "stopped_by": None, "feasible": True, "score": 1.0, "total_return": None,
                 "reference": True}
                for seed in seeds]  # fmt: skip
    records = []
    # A spec with "{seed}" names one policy per seed (e.g. a model per training seed): each seed's episode
    # runs its own; every other policy is built once. A policy runs in the env it names (env_id,
    # env_kwargs: a trained model's), else in Feedrate-v0; with randomisation off, every version has the
    # same dynamics, and every episode is measured with the benchmark's contour rule (the rollout's
    # policy_env).
    from cnc_gym.policies import make_policy

    policy = env = planning_env = None
    try:
        for seed in seeds:
            if policy is None or env is None or "{seed}" in policy_spec:
                if env is not None:
                    env.close()
                    env = None
                if policy is None or "{seed}" in policy_spec:
                    policy = make_policy(policy_spec.replace("{seed}", str(seed)),
                                         progress=None if progress else False)  # fmt: skip
                if track == "nominal":
                    env = policy_env(policy, programs=[program.source()], dialect=dialect, machine=machine,
                                     units=units, plant=plant)  # fmt: skip
                else:
                    env = policy_env(policy, programs=[program.source()], dialect=dialect,
                                     machine=true_machine, units=units)  # fmt: skip
                    if hasattr(policy, "nominal_machine"):
                        policy.nominal_machine = nominal
                    if hasattr(env.unwrapped, "plan_on"):  # the env's own planner entries and residual mode
                        env.unwrapped.plan_on(nominal)
                    if getattr(policy, "plans_on_nominal", False):
                        if planning_env is None:
                            planning_env = policy_env(policy, programs=[program.source()], dialect=dialect,
                                                      machine=nominal, units=units)  # fmt: skip
                        policy.nominal_env = planning_env
            info, total_return, steps, finished, stopped_by = _limited_episode(env, policy, seed, limits)
            if stopped_by == MAX_CPU:  # cut at any point of a step: the env starts afresh for the next seed
                with contextlib.suppress(Exception):
                    env.close()
                env = None
            cycle = float(info["cycle_time_s"])
            ratio = cycle / bound["total_s"]
            length = float(info["violation_length_mm"])
            records.append({**base, "seed": int(seed), "cycle_time_s": cycle, "time_ratio": ratio,
                            "violation_length_mm": length,
                            "violation_time_s": float(info["violation_time_s"]),
                            "contour_error_max_mm": float(info["contour_error_max_mm"]),
                            "contour_error_rms_mm": float(info["contour_error_rms_mm"]),
                            "tolerance_mm": float(info["tolerance_mm"]),
                            "violations": int(info["violations"]), "steps": steps,
                            "finished": finished, "stopped_by": stopped_by,
                            "feasible": is_feasible(finished, length),
                            "score": episode_score(finished, length, ratio),
                            "total_return": total_return, "reference": False})  # fmt: skip
    finally:
        for opened in (env, planning_env):
            if opened is not None:
                opened.close()
    return records


# --------------------------------------------------------------------------------------- executors
#: ``on_result(task_index, result)``: called in the caller's process as each task finishes.
ResultHook = Callable[[int, Any], None]


@dataclass(frozen=True)
class Executor:
    """Where tasks run: in this process (``workers`` 1), on a local ``spawn`` process pool (``workers``
    > 1), or on Ray (``use_ray``; ``ray_address`` None: a local instance, else that cluster, whose
    workers have cnc-gym installed). ``cnc-gym bench``'s ``--workers``/``--ray``; the learning code's
    teacher labelling runs on it too."""

    workers: int = 1
    use_ray: bool = False
    ray_address: str | None = None


def run_tasks(tasks: Sequence[Callable[[], Any]], executor: Executor,
              on_result: ResultHook | None = None) -> list[Any]:  # fmt: skip
    """Run zero-argument tasks (``functools.partial`` of module-level functions, picklable) on
    ``executor``; results in task order whatever ran them, each also handed to ``on_result`` as it
    finishes. On any exception (a task's error, Ctrl-C) pending tasks are cancelled and workers ended
    before it goes on."""
    results: list[Any] = [None] * len(tasks)

    def finished(index: int, result: Any) -> None:
        results[index] = result
        if on_result is not None:
            on_result(index, result)

    if executor.use_ray:
        _run_ray(tasks, executor, finished)
    elif executor.workers > 1 and len(tasks) > 1:
        _run_pool(tasks, min(executor.workers, len(tasks)), finished)
    else:
        for index, task in enumerate(tasks):
            finished(index, task())
    return results


def _run_tasks(tasks: Sequence[Callable[[], Any]], config: BenchConfig, bar: Any, label: str,
               on_result: ResultHook | None = None) -> list[Any]:  # fmt: skip
    """:func:`run_tasks` on the executor ``config`` names, with a progress bar."""
    if bar is not None:
        bar.set_description(label)

    def finished(index: int, result: Any) -> None:
        if on_result is not None:
            on_result(index, result)
        if bar is not None:
            bar.update()

    executor = Executor(workers=config.workers, use_ray=config.use_ray, ray_address=config.ray_address)
    return run_tasks(tasks, executor, finished)


def _ignore_sigint() -> None:
    """Pool workers leave Ctrl-C to the parent, which ends them (no traceback from each worker)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


@contextlib.contextmanager
def _sigint_ignored() -> Iterator[None]:
    """SIGINT ignored while worker processes are started: they inherit the ignored disposition from
    their first instruction (a handler installed later would leave a window where Ctrl-C prints a
    traceback from each starting worker)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def _run_pool(tasks: Sequence[Callable[[], Any]], workers: int, finished: ResultHook) -> None:
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor, as_completed

    context = multiprocessing.get_context("spawn")  # the same on every platform; numba caches on disk
    pool = ProcessPoolExecutor(max_workers=workers, mp_context=context, initializer=_ignore_sigint)
    try:
        with _sigint_ignored():  # submit starts the workers (spawn: one per submit up to `workers`)
            futures = {pool.submit(task): i for i, task in enumerate(tasks)}
        for future in as_completed(futures):
            finished(futures[future], future.result())
    except BaseException:
        _stop_pool(pool)
        raise
    pool.shutdown(wait=True)


def _stop_pool(pool: Any) -> None:
    """End a process pool now: its workers terminated (then killed if they linger), pending tasks
    cancelled. ``ProcessPoolExecutor`` has no public way to end running tasks before Python 3.14."""
    processes = list((getattr(pool, "_processes", None) or {}).values())
    manager = getattr(pool, "_executor_manager_thread", None)
    for process in processes:
        with contextlib.suppress(Exception):
            process.terminate()
    pool.shutdown(wait=False, cancel_futures=True)
    for process in processes:
        with contextlib.suppress(Exception):
            process.join(timeout=2.0)
            if process.is_alive():
                process.kill()
                process.join(timeout=2.0)
    # The pool's own thread sees its workers gone and releases its queues and locks: let it finish, so
    # that nothing of the pool is still being torn down when the process ends.
    if manager is not None:
        manager.join(timeout=2.0)


def _run_ray(tasks: Sequence[Callable[[], Any]], executor: Executor, finished: ResultHook) -> None:
    try:
        import ray
    except ImportError:
        raise CncGymError("--ray needs the ray extra: pip install 'cnc-gym[ray]'") from None
    if not ray.is_initialized():
        ray.init(address=executor.ray_address or None, include_dashboard=False, log_to_driver=False,
                 ignore_reinit_error=True)  # fmt: skip
    remote = ray.remote(_call)
    refs = [remote.remote(task) for task in tasks]
    index = {ref: i for i, ref in enumerate(refs)}
    pending = list(refs)
    try:
        while pending:
            done, pending = ray.wait(pending, num_returns=1)
            for ref in done:
                finished(index[ref], ray.get(ref))
    except BaseException:
        for ref in pending:
            with contextlib.suppress(Exception):
                ray.cancel(ref, force=True)
        raise


def _call(task: Callable[[], Any]) -> Any:
    return task()


#: ``on_records(records)``: a finished (program, policy) task's records, in the caller's process.
RecordsHook = Callable[[list[dict[str, Any]]], None]


def run_bench(config: BenchConfig, *, on_records: RecordsHook | None = None,
              notice: Callable[[str], None] | None = None) -> list[dict[str, Any]]:  # fmt: skip
    """Run the benchmark; records sorted by (program order, policy order, seed).

    ``on_records`` gets each (program, policy) task's records as soon as it finishes (in completion
    order), so nothing finished is lost to an interruption; ``notice`` (default: stderr, above the
    progress bar) gets one line per program left out (its bound could not be computed) and per bound
    cache file that was recomputed. A KeyboardInterrupt stops the run at once and goes on to the caller.
    """
    from cnc_gym.machine import load_machine, with_plant_backend
    from cnc_gym.motion.bound import machine_digest

    if not config.programs:
        raise CncGymError("nothing to benchmark: no programs")
    if not config.policies:
        raise CncGymError("nothing to benchmark: no policies")
    from cnc_gym.policies import make_policy

    for spec in config.policies:  # a bad spec is one clear error before any work
        if spec != "bound":
            for seed in config.seeds if "{seed}" in spec else [None]:
                make_policy(spec.replace("{seed}", str(seed)), progress=False)
    mach = with_plant_backend(load_machine(config.machine), config.plant)
    from cnc_gym.benchmark.tracks import check_track

    common = {"record_version": RECORD_VERSION, "contour_rule": CONTOUR_RULE,
              "track": check_track(config.track), "suite": config.suite or "user",
              "suite_version": config.suite_version,
              "suite_sha256": config.suite_sha256, "machine": mach.name,
              "machine_sha256": machine_digest(mach), "plant": mach.plant.backend,
              "dialect": config.dialect, "units": config.units, "commit": current_commit(),
              "cnc_gym_version": _version()}  # fmt: skip
    bar = None
    total = len(config.programs) * (1 + len(config.policies))
    if config.progress:
        from tqdm import tqdm

        bar = tqdm(total=total, desc="bench", file=sys.stderr, unit="task", dynamic_ncols=True)

    def say(line: str) -> None:
        if notice is not None:
            notice(line)
        elif bar is not None:
            bar.write(line, file=sys.stderr)
        else:
            print(line, file=sys.stderr)

    def bound_done(index: int, result: dict[str, Any]) -> None:
        for line in result.get("notices", ()):
            say(line)
        if "error" in result:
            say(f"cnc-gym bench: {config.programs[index].name}: left out: {result['error']}")

    serial_progress = config.progress and config.workers <= 1 and not config.use_ray
    try:
        bound_tasks = [functools.partial(_bound_task, p, config.machine, config.dialect, config.units)
                       for p in config.programs]  # fmt: skip
        bounds = _run_tasks(bound_tasks, config, bar, "bench: bounds", bound_done)
        kept = [(program, result["bound"]) for program, result in zip(config.programs, bounds, strict=True)
                if "bound" in result]  # fmt: skip
        if bar is not None and len(kept) < len(config.programs):
            bar.total -= (len(config.programs) - len(kept)) * len(config.policies)
            bar.refresh()
        if not kept:
            raise CncGymError("nothing to benchmark: no program has a bound (each one's reason is above)")
        episode_tasks = [functools.partial(_episode_task, program, spec, tuple(config.seeds), config.machine,
                                           config.dialect, config.units, bound, common, serial_progress,
                                           config.plant, config.limits, config.track)
                         for program, bound in kept for spec in config.policies]  # fmt: skip

        def episodes_done(index: int, records: list[dict[str, Any]]) -> None:
            if on_records is not None:
                on_records(records)

        groups = _run_tasks(episode_tasks, config, bar, "bench: episodes", episodes_done)
    finally:
        if bar is not None:
            bar.close()
    return [record for group in groups for record in group]


# ------------------------------------------------------------------------------------------ records
def record_lines(records: Iterable[dict[str, Any]]) -> str:
    """Records as JSON Lines text; a value that is not finite (NaN, Infinity: not JSON) is one clear
    error naming the record and key, never written."""
    lines = []
    for r in records:
        try:
            lines.append(json.dumps(r, sort_keys=False, allow_nan=False))
        except ValueError:
            bad = [k for k, v in r.items() if isinstance(v, float) and not math.isfinite(v)]
            raise CncGymError(f"bench record of {r.get('program', '?')} / {r.get('policy', '?')} seed "
                              f"{r.get('seed', '?')}: {', '.join(bad) or 'a value'} is not a finite number, "
                              "which JSON cannot hold") from None  # fmt: skip
    return "".join(line + "\n" for line in lines)


@contextlib.contextmanager
def _sigint_deferred() -> Iterator[None]:
    """Hold Ctrl-C while a few lines are written, then raise it: a record is written whole or not at all,
    so the file is valid JSON Lines at every moment."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    caught: list[int] = []
    previous = signal.signal(signal.SIGINT, lambda signum, frame: caught.append(signum))
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
    if caught:
        raise KeyboardInterrupt


class JsonlAppender:
    """``--json``: records appended to a JSON Lines file as they come, each batch in one write with
    Ctrl-C held, so the file is valid JSON Lines at every moment. The file is created (emptied) when the
    appender is made, so an unwritable path fails before any work. :meth:`finish` rewrites it in the
    final record order (atomically: a new file renamed over it) when the records came in another."""

    def __init__(self, path: str | os.PathLike) -> None:
        self.path = Path(path)
        self.count = 0
        self._written: list[dict[str, Any]] = []
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self._fd = os.open(self.path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC | os.O_APPEND, 0o644)
        except OSError as exc:
            raise CncGymError(f"{self.path}: cannot write: {exc.strerror or exc}") from None

    def append(self, records: list[dict[str, Any]]) -> None:
        data = record_lines(records).encode()
        with _sigint_deferred():
            try:
                view = memoryview(data)
                while view:
                    view = view[os.write(self._fd, view):]
            except OSError as exc:
                raise CncGymError(f"{self.path}: cannot write: {exc.strerror or exc}") from None
            self.count += len(records)
            self._written.extend(records)

    def finish(self, records: list[dict[str, Any]]) -> None:
        """Close the file; rewrite it as ``records`` (the run's final order) if they differ from what was
        appended (a process pool or Ray finishes tasks in any order)."""
        self.close()
        if records == self._written or not self.path.is_file():
            return
        write_jsonl(records, self.path)

    def close(self) -> None:
        if self._fd >= 0:
            os.close(self._fd)
            self._fd = -1


def write_jsonl(records: Iterable[dict[str, Any]], path: str | os.PathLike) -> Path:
    """Write records as a JSON Lines file, atomically (a new file renamed over the old one)."""
    path = Path(path)
    text = record_lines(records)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
        tmp.write_text(text)
        os.replace(tmp, path)
    except OSError as exc:
        raise CncGymError(f"{path}: cannot write: {exc.strerror or exc}") from None
    return path


def read_jsonl(paths: Iterable[str | os.PathLike]) -> list[dict[str, Any]]:
    """Records from JSON Lines files; a malformed line (NaN and Infinity included: they are not JSON) is
    one clear error naming file and line."""
    out = []
    for raw in paths:
        path = Path(raw)
        try:
            lines = path.read_text().splitlines()
        except OSError as exc:
            raise CncGymError(f"{path}: cannot read: {exc.strerror or exc}") from None
        for number, line in enumerate(lines, 1):
            if not line.strip():
                continue
            try:
                record = json.loads(line, parse_constant=_not_json)
            except ValueError as exc:
                raise CncGymError(f"{path}:{number}: not a JSON record ({exc})") from None
            if not isinstance(record, dict) or "policy" not in record or "score" not in record:
                raise CncGymError(f"{path}:{number}: not a cnc-gym bench record")
            out.append(record)
    return out


def _not_json(name: str) -> float:
    raise ValueError(f"{name} is not a JSON number")
