"""The bench runner: every program × policy × seed through the env, one record per episode.

Work comes in two phases, each a list of independent tasks: the time-optimal bound of every program
(cached on disk, see :mod:`cnc_gym.motion.bound`), then one task per (program, policy) that runs the
policy's episodes for every seed (so a planner plans a program once). Tasks run serially, on a local
process pool (``workers > 1``), or on a Ray cluster (``ray_address``); records are sorted into the same
order whatever ran them, and hold no timings, so all three give identical records.
"""

from __future__ import annotations

import functools
import hashlib
import os
import subprocess
import sys
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from cnc_gym.benchmark.metrics import RECORD_VERSION, episode_score, is_feasible
from cnc_gym.errors import CncGymError
from cnc_gym.rollout import CONTOUR_RULE, policy_env, run_episode

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


@dataclass
class BenchConfig:
    programs: list[BenchProgram]
    policies: list[str]
    seeds: list[int] = field(default_factory=lambda: [0])
    machine: str = "vmc-small"
    dialect: str = "gsk25i"
    #: Input unit at power-on ("mm"/"inch"); None: the machine preset's, else the dialect's.
    units: str | None = None
    #: Servo plant backend (``lti`` or ``mujoco``); None: the machine preset's.
    plant: str | None = None
    suite: str | None = None
    suite_version: int | None = None
    suite_sha256: str | None = None
    workers: int = 1
    ray_address: str | None = None
    use_ray: bool = False
    progress: bool = False


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
        _, toolpath = load_program(path, dialect, mach, units=units)  # a program error is one line, here
        props = path_properties(toolpath, mach)
        out.append(BenchProgram(name=name, text=text, tier=tier_of(props),
                                cut_length_mm=props["cut_length_mm"]))
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
    from cnc_gym.machine import load_machine
    from cnc_gym.motion.bound import time_optimal_bound
    from cnc_gym.programs import load_program

    mach = load_machine(machine)
    _, toolpath = load_program(program.text, dialect, mach, units=units)
    return time_optimal_bound(toolpath, mach).to_dict()


def _episode_task(program: BenchProgram, policy_spec: str, seeds: Sequence[int], machine: str,
                  dialect: str, units: str | None, bound: dict[str, Any], common: dict[str, Any],
                  progress: bool, plant: str | None = None) -> list[dict[str, Any]]:  # fmt: skip
    """Every seed of one (program, policy): records in seed order."""
    base = {**common, "split": program.split, "program": program.name,
            "program_sha256": _sha(program.text), "family": program.family, "tier": program.tier,
            "policy": policy_spec, "bound_s": bound["total_s"], "bound_version": bound["version"],
            "cut_length_mm": program.cut_length_mm}  # fmt: skip
    if policy_spec == "bound":  # the reference itself: no episode is run
        return [{**base, "seed": int(seed), "cycle_time_s": bound["total_s"], "time_ratio": 1.0,
                 "violation_length_mm": None, "violation_time_s": None, "contour_error_max_mm": None,
                 "contour_error_rms_mm": None, "tolerance_mm": None, "violations": None, "steps": None,
                 "finished": True, "feasible": True, "score": 1.0, "total_return": None, "reference": True}
                for seed in seeds]  # fmt: skip
    records = []
    # A spec with "{seed}" names one policy per seed (e.g. a model per training seed): each seed's episode
    # runs its own; every other policy is built once. A policy runs in the env it names (env_id,
    # env_kwargs: a trained model's), else in Feedrate-v0; with randomisation off, every version has the
    # same dynamics, and every episode is measured with the benchmark's contour rule (the rollout's
    # policy_env).
    from cnc_gym.policies import make_policy

    policy = env = None
    try:
        for seed in seeds:
            if policy is None or "{seed}" in policy_spec:
                if env is not None:
                    env.close()
                policy = make_policy(policy_spec.replace("{seed}", str(seed)),
                                     progress=None if progress else False)  # fmt: skip
                env = policy_env(policy, programs=[program.text], dialect=dialect, machine=machine,
                                 units=units, plant=plant)  # fmt: skip
            episode = run_episode(env, policy, int(seed))
            info, finished = episode.info, episode.finished
            cycle = float(info["cycle_time_s"])
            ratio = cycle / bound["total_s"] if bound["total_s"] > 0 else float("inf")
            length = float(info["violation_length_mm"])
            records.append({**base, "seed": int(seed), "cycle_time_s": cycle, "time_ratio": ratio,
                            "violation_length_mm": length,
                            "violation_time_s": float(info["violation_time_s"]),
                            "contour_error_max_mm": float(info["contour_error_max_mm"]),
                            "contour_error_rms_mm": float(info["contour_error_rms_mm"]),
                            "tolerance_mm": float(info["tolerance_mm"]),
                            "violations": int(info["violations"]), "steps": episode.steps,
                            "finished": finished, "feasible": is_feasible(finished, length),
                            "score": episode_score(finished, length, ratio),
                            "total_return": episode.total_return, "reference": False})  # fmt: skip
    finally:
        if env is not None:
            env.close()
    return records


# --------------------------------------------------------------------------------------- executors
def _run_tasks(tasks: Sequence[Callable[[], Any]], config: BenchConfig, bar: Any, label: str) -> list[Any]:
    """Run zero-argument tasks (``functools.partial`` of module-level functions) serially, on a process
    pool or on Ray; results in task order."""
    if bar is not None:
        bar.set_description(label)
    if config.use_ray:
        return _run_ray(tasks, config, bar)
    if config.workers > 1 and len(tasks) > 1:
        import multiprocessing
        from concurrent.futures import ProcessPoolExecutor

        results: list[Any] = [None] * len(tasks)
        context = multiprocessing.get_context("spawn")  # the same on every platform; numba caches on disk
        with ProcessPoolExecutor(max_workers=config.workers, mp_context=context) as pool:
            futures = {pool.submit(task): i for i, task in enumerate(tasks)}
            from concurrent.futures import as_completed

            for future in as_completed(futures):
                results[futures[future]] = future.result()
                if bar is not None:
                    bar.update()
        return results
    out = []
    for task in tasks:
        out.append(task())
        if bar is not None:
            bar.update()
    return out


def _run_ray(tasks: Sequence[Callable[[], Any]], config: BenchConfig, bar: Any) -> list[Any]:
    try:
        import ray
    except ImportError:
        raise CncGymError("--ray needs the ray extra: pip install 'cnc-gym[ray]'") from None
    if not ray.is_initialized():
        ray.init(address=config.ray_address or None, include_dashboard=False, log_to_driver=False,
                 ignore_reinit_error=True)  # fmt: skip
    remote = ray.remote(_call)
    refs = [remote.remote(task) for task in tasks]
    index = {ref: i for i, ref in enumerate(refs)}
    results: list[Any] = [None] * len(refs)
    pending = list(refs)
    while pending:
        done, pending = ray.wait(pending, num_returns=1)
        for ref in done:
            results[index[ref]] = ray.get(ref)
            if bar is not None:
                bar.update()
    return results


def _call(task: Callable[[], Any]) -> Any:
    return task()


def run_bench(config: BenchConfig) -> list[dict[str, Any]]:
    """Run the benchmark; records sorted by (program order, policy order, seed)."""
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
    common = {"record_version": RECORD_VERSION, "contour_rule": CONTOUR_RULE,
              "suite": config.suite or "user", "suite_version": config.suite_version,
              "suite_sha256": config.suite_sha256, "machine": mach.name,
              "machine_sha256": machine_digest(mach), "plant": mach.plant.backend,
              "dialect": config.dialect, "units": config.units, "commit": current_commit(),
              "cnc_gym_version": _version()}  # fmt: skip
    bar = None
    total = len(config.programs) * (1 + len(config.policies))
    if config.progress:
        from tqdm import tqdm

        bar = tqdm(total=total, desc="bench", file=sys.stderr, unit="task", dynamic_ncols=True)
    serial_progress = config.progress and config.workers <= 1 and not config.use_ray
    try:
        bound_tasks = [functools.partial(_bound_task, p, config.machine, config.dialect, config.units)
                       for p in config.programs]  # fmt: skip
        bounds = _run_tasks(bound_tasks, config, bar, "bench: bounds")
        episode_tasks = [functools.partial(_episode_task, program, spec, tuple(config.seeds), config.machine,
                                           config.dialect, config.units, bound, common, serial_progress,
                                           config.plant)
                         for program, bound in zip(config.programs, bounds, strict=True)
                         for spec in config.policies]  # fmt: skip
        groups = _run_tasks(episode_tasks, config, bar, "bench: episodes")
    finally:
        if bar is not None:
            bar.close()
    return [record for group in groups for record in group]


def write_jsonl(records: Iterable[dict[str, Any]], path: str | os.PathLike) -> Path:
    import json

    path = Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with path.open("w") as fh:
            for r in records:
                fh.write(json.dumps(r, sort_keys=False) + "\n")
    except OSError as exc:
        raise CncGymError(f"{path}: cannot write: {exc.strerror or exc}") from None
    return path


def read_jsonl(paths: Iterable[str | os.PathLike]) -> list[dict[str, Any]]:
    """Records from JSON Lines files; a malformed line is one clear error naming file and line."""
    import json

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
                record = json.loads(line)
            except ValueError as exc:
                raise CncGymError(f"{path}:{number}: not a JSON record ({exc})") from None
            if not isinstance(record, dict) or "policy" not in record or "score" not in record:
                raise CncGymError(f"{path}:{number}: not a cnc-gym bench record")
            out.append(record)
    return out
