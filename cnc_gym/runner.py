"""``cnc-gym run``: simulate a whole program through controller and plant under a policy.

The run is the one rollout (:mod:`cnc_gym.rollout`): the policy drives the Gymnasium env
(``cnc_gym/Feedrate-v0``, or the version a trained model names), the same code path an RL agent and
``cnc-gym bench`` use, so a baseline's numbers and a trained agent's numbers are comparable. Its contour
error is the programmed-path meter's (:data:`cnc_gym.rollout.CONTOUR_RULE`, as ``cnc-gym bench`` and
Feedrate-v2 measure it), whatever env version the policy acts in. :func:`simulate` returns a
:class:`RunResult` (:func:`record_run` adds the bounded series and the stop rules to the rollout);
:func:`run_cli` is what the ``cnc-gym run`` command calls.

Bounded resources: the summary numbers are the env's streaming totals (exact over every servo sample);
the series kept for the plot are at most :data:`~cnc_gym.envs.render.DEFAULT_MAX_BINS` time bins
(max contour error per bin, mean feed and override), so memory does not grow with the episode's length.
A run ends when the program finishes, at the env's step budget, or at ``max_time_s`` of simulated time;
the last two leave ``finished`` false and ``stopped_by`` naming the limit.
"""

from __future__ import annotations

import json
import math
import os
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TextIO

import numpy as np

from cnc_gym.envs.render import DEFAULT_MAX_BINS, BinnedSeries, range_indices
from cnc_gym.errors import CncGymError, ConfigError
from cnc_gym.machine import DEFAULT_MACHINE
from cnc_gym.programs import DEFAULT_DIALECT
from cnc_gym.rollout import CHUNK_STEPS, announce_compiling, compiled_rule, play, play_compiled, policy_env

#: Keys of the ``--json`` object (the contract of docs/cli.md, "What `run` prints").
JSON_KEYS = (
    "program", "machine", "policy", "cycle_time_s", "contour_error_max_mm", "contour_error_rms_mm",
    "tolerance_mm", "violations", "steps", "total_return", "finished", "stopped_by", "nominal_time_s",
)  # fmt: skip

#: Exit status of ``cnc-gym run`` when the run stopped before the program's end (``finished: false``).
EXIT_TRUNCATED = 3

#: Values of ``stopped_by``: why a run that did not finish stopped.
STEP_BUDGET = "step_budget"
MAX_TIME = "max_time"

#: A program whose nominal time is longer than this (simulated seconds) gets a notice before it runs.
LONG_RUN_NOTICE_S = 600.0
#: Wall-clock seconds after which a run projects its remaining wall-clock time (and says so if long).
_PROJECTION_AFTER_WALL_S = 2.0
_PROJECTION_NOTICE_WALL_S = 60.0

#: Points of the programmed path drawn on the plot (plus every segment end).
_PATH_POINTS = 20_000
#: Path-length bins of the recorded error along the path (the plot merges them to its resolution).
PATH_ERROR_BINS = 8192

_SERIES_COLUMNS = {"time_s": "last", "path_s": "last", "feed_mm_min": "mean", "override": "mean",
                   "contour_error_mm": "max"}  # fmt: skip
#: Steps of a compiled run between two updates of the progress bar and the projection (a few ms).
_CHUNK_STEPS = CHUNK_STEPS
#: The info values of each step the series are made of (their columns, in order).
_RECORDED = ("cycle_time_s", "path_s", "feed_mm_min", "override", "contour_error_mm")


@dataclass
class RunResult:
    """One simulated run: the ``--json`` summary plus bounded series for plotting.

    The time series (``time_s`` … ``contour_error_mm``) have one entry per bin of ``bin_steps`` control
    steps (1 until the run outgrows :data:`~cnc_gym.envs.render.DEFAULT_MAX_BINS` steps): ``time_s`` and
    ``path_s`` at the bin's end, mean ``feed_mm_min`` and ``override``, and the bin's largest
    ``contour_error_mm`` (a max envelope). The path series (``path_xyz`` …) sample the programmed path.
    """

    program: str
    machine: str
    policy: str
    cycle_time_s: float
    contour_error_max_mm: float
    contour_error_rms_mm: float
    tolerance_mm: float
    violations: int  # control steps with contour error above tolerance
    steps: int
    total_return: float
    finished: bool  # the program ran to its end (not cut off by the step budget or max_time_s)
    stopped_by: str | None = None  # None when finished, else STEP_BUDGET or MAX_TIME
    nominal_time_s: float = 0.0  # the program's time at 100 % feed (the env's T_nominal)
    path_length_mm: float = 0.0  # the programmed path's length (cutting + rapid)
    last_path_s: float = 0.0  # how far along it the run got, mm
    # Time series, one entry per bin (not in the JSON summary).
    bin_steps: int = 1
    time_s: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0))
    path_s: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0))
    feed_mm_min: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0))
    override: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0))
    contour_error_mm: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0))
    # The programmed path: points (at path positions path_sample_s), whether each point's segment cuts,
    # the feed run there (NaN where the run did not get to), for the plot.
    path_xyz: np.ndarray = field(repr=False, default_factory=lambda: np.zeros((0, 3)))
    cutting: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0, dtype=bool))
    path_feed_mm_min: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0))
    path_sample_s: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0))
    # The largest contour error along the path (:class:`PathErrorEnvelope`; NaN where the run did not get
    # to): per path-length bin (edges, mm) and per programmed segment (one entry per tool path row, with
    # its edges along the path, program line and whether it cuts), for the plot.
    path_error_edges_mm: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0))
    path_error_mm: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0))
    segment_s_mm: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0))
    segment_line: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0, dtype=np.int64))
    segment_cutting: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0, dtype=bool))
    segment_error_mm: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0))

    def summary(self) -> dict[str, Any]:
        """The JSON-able summary (plain Python numbers)."""
        out: dict[str, Any] = {}
        for key in JSON_KEYS:
            value = getattr(self, key)
            out[key] = value.item() if isinstance(value, np.generic) else value
        return out

    @property
    def progress(self) -> float:
        """Share of the programmed path's length the run got through (1 when finished)."""
        if self.finished:
            return 1.0
        if self.path_length_mm <= 0:
            return 0.0
        return min(self.last_path_s / self.path_length_mm, 1.0)


def program_env(program: Any, policy: Any, *, dialect: str = DEFAULT_DIALECT, machine: str = DEFAULT_MACHINE,
                max_blocks: int | None = None, units: str | None = None,
                plant: str | None = None) -> Any:  # fmt: skip
    """The env ``policy`` runs one program in (:func:`cnc_gym.rollout.policy_env`: the env version and
    settings the policy names, the programmed-path meter); the program is interpreted up front, so
    program errors surface here. ``plant`` (``lti`` or ``mujoco``) overrides the machine preset's plant
    backend."""
    from cnc_gym.machine import load_machine
    from cnc_gym.programs import load_program

    options: dict[str, Any] = {"units": units}
    if max_blocks is not None:
        options["max_blocks"] = max_blocks
    # ProgramError / ConfigError with a clear message; the interpreted program goes to the env as it is.
    loaded = load_program(program, dialect, load_machine(machine), **options)
    return policy_env(policy, programs=[loaded], dialect=dialect, machine=machine, units=units, plant=plant)


def record_run(env: Any, policy: Any, *, seed: int | None = 0, progress: bool = False,
               record: bool = True, max_time_s: float | None = None, log: TextIO | None = None,
               max_bins: int = DEFAULT_MAX_BINS) -> RunResult:  # fmt: skip
    """Run one episode of ``env`` under ``policy`` (:func:`cnc_gym.rollout.play`) and record it as a
    :class:`RunResult`; the env decides which program (its reset).

    ``max_time_s`` stops the run at that much simulated time (``stopped_by`` = ``"max_time"``). ``log``
    (e.g. ``sys.stderr``) gets a one-line projection of the wall-clock time when a run looks long.
    ``record=False`` keeps no series (the summary only).
    """
    _check_max_time(max_time_s)
    observation, info = env.reset(seed=seed)
    policy.reset(env)
    base = env.unwrapped
    toolpath = base.toolpath
    tolerance = float(info.get("tolerance_mm", base.machine.controller.contour_tolerance_mm))
    nominal = float(getattr(base, "nominal_time_s", 0.0))
    series = BinnedSeries(_SERIES_COLUMNS, max_bins) if record else None
    envelope = PathErrorEnvelope(toolpath) if record else None
    bar = None
    if progress:
        from tqdm import tqdm

        bar_format = "{desc}: {percentage:3.0f}%|{bar}| {elapsed}<{remaining}"
        desc = str(info.get("program", "program"))
        bar = tqdm(total=100, desc=desc, file=sys.stderr, leave=False, bar_format=bar_format)
    started = time.perf_counter()
    projection_due = started + _PROJECTION_AFTER_WALL_S if log is not None else math.inf
    baseline: tuple[float, float] | None = None  # (wall clock, simulated s) at the first projection sample

    def report(info: dict[str, Any]) -> None:
        """The progress bar and the projection of the wall-clock time (every few steps)."""
        nonlocal projection_due, baseline
        if bar is not None:
            bar.n = round(100 * float(info.get("progress", 0.0)))
            bar.refresh()
        now = time.perf_counter()
        if log is not None and now >= projection_due:
            # Two samples, _PROJECTION_AFTER_WALL_S apart, after the first such interval: the rate
            # between them leaves out start-up (compiling, the first in-position wait), which once
            # made a 31 s run project hours.
            simulated = float(info.get("cycle_time_s", 0.0))
            if baseline is None or now <= baseline[0]:
                baseline = (now, simulated)
                projection_due = now + _PROJECTION_AFTER_WALL_S
            else:
                projection_due = math.inf
                _project_wall_time(log, info, nominal, max_time_s, rate=(simulated - baseline[1])
                                   / (now - baseline[0]))  # fmt: skip

    def on_step(steps: int, reward: float, terminated: bool, truncated: bool, info: dict[str, Any]) -> bool:
        if series is not None:
            series.add(info["cycle_time_s"], info["path_s"], info["feed_mm_min"], info["override"],
                       info["contour_error_mm"])  # fmt: skip
        if envelope is not None:
            envelope.add(info["path_s"], info["contour_error_mm"])
        if steps % 20 == 0:
            report(info)
        # --max-time: stop at that much simulated time, unless the program has just ended.
        return max_time_s is not None and not terminated and info["cycle_time_s"] >= max_time_s - 1e-9

    def on_chunk(steps: int, total_return: float, rows: np.ndarray, info: dict[str, Any]) -> bool:
        if series is not None:
            series.extend_rows(rows)
        if envelope is not None:
            path_s, error = _RECORDED.index("path_s"), _RECORDED.index("contour_error_mm")
            envelope.add_many(rows[:, path_s], rows[:, error])
        report(info)
        return False

    # A constant or the deployable planner runs in compiled chunks (the same episode, bit for bit), any
    # other policy step by step in Python.
    rule = compiled_rule(env, policy)
    try:
        if rule is None:
            episode = play(env, policy, observation, info, on_step)
        else:
            recorded = _RECORDED if series is not None or envelope is not None else ()
            episode = play_compiled(env, rule, record=recorded, stop_time_s=max_time_s, on_chunk=on_chunk,
                                    chunk_steps=_CHUNK_STEPS)  # fmt: skip
    finally:
        if bar is not None:
            bar.close()
    info = episode.info
    rms = float(info.get("contour_error_rms_mm", 0.0))
    finished = episode.finished
    stopped_by = None if finished else (MAX_TIME if episode.stopped else STEP_BUDGET)
    result = RunResult(
        program=str(info.get("program", getattr(base, "program_name", "program"))),
        machine=str(base.machine.name),
        policy=str(getattr(policy, "name", type(policy).__name__)),
        cycle_time_s=float(info.get("cycle_time_s", 0.0)),
        contour_error_max_mm=float(info.get("contour_error_max_mm", 0.0)),
        contour_error_rms_mm=rms if math.isfinite(rms) else 0.0,
        tolerance_mm=tolerance,
        violations=int(info.get("violations", 0)),
        steps=episode.steps,
        total_return=episode.total_return,
        finished=finished,
        stopped_by=stopped_by,
        nominal_time_s=nominal,
        path_length_mm=float(toolpath.total_length),
        last_path_s=float(info.get("path_s", 0.0)),
    )
    if series is not None:
        data = series.arrays()
        result.bin_steps = series.width
        for name in _SERIES_COLUMNS:
            setattr(result, name, data[name])
        _sample_path(result, toolpath)
    if envelope is not None:
        envelope.finish()
        result.path_error_edges_mm, result.path_error_mm = envelope.grid_edges, envelope.grid
        result.segment_s_mm = envelope.segment_edges.copy()
        result.segment_line = np.asarray(toolpath.line).copy()
        result.segment_cutting = _cutting_rows(toolpath)
        result.segment_error_mm = envelope.segment
    return result


class PathErrorEnvelope:
    """The largest contour error along the path, from a run's control steps: per path-length bin (a fixed
    grid of :data:`PATH_ERROR_BINS` over the whole path) and per programmed segment.

    A step's error (its largest over its servo samples) goes to every bin and every segment its reference
    swept, from the previous step's path position to this one's, so that a chain of segments shorter than
    a step leaves no gaps and a long segment is marked only where its error was. The position is the
    reference's: the servo follows it by the following error (v/Kv, a fraction of a millimetre where the
    path turns and the feed drops), so an error shows at most that far ahead of the tool. Memory: the grid
    and one number per segment (the tool path holds many more), whatever the length of the run; steps are
    taken in batches.
    """

    _BATCH = 4096

    def __init__(self, toolpath: Any, bins: int = 0) -> None:
        bins = bins or PATH_ERROR_BINS
        self.segment_edges = np.asarray(toolpath.s_start, dtype=float)
        total = float(self.segment_edges[-1]) if len(self.segment_edges) else 0.0
        self.grid_edges = np.linspace(0.0, total, bins + 1) if total > 0 else np.zeros(1)
        self.segment = np.full(max(len(self.segment_edges) - 1, 0), np.nan)
        self.grid = np.full(len(self.grid_edges) - 1, np.nan)
        self._s: list[float] = []
        self._e: list[float] = []
        self._last_s = 0.0

    def add(self, path_s: float, error_mm: float) -> None:
        self._s.append(float(path_s))
        self._e.append(float(error_mm))
        if len(self._s) >= self._BATCH:
            self._flush()

    def add_many(self, path_s: np.ndarray, error_mm: np.ndarray) -> None:
        """Several steps at once (the same envelope as :meth:`add` of each: a maximum, whatever the
        batches)."""
        self._s.extend(np.asarray(path_s, dtype=float).tolist())
        self._e.extend(np.asarray(error_mm, dtype=float).tolist())
        if len(self._s) >= self._BATCH:
            self._flush()

    def finish(self) -> PathErrorEnvelope:
        self._flush()
        return self

    def _flush(self) -> None:
        s, error = np.asarray(self._s), np.asarray(self._e)
        self._s.clear()
        self._e.clear()
        if not len(s):
            return
        before = np.concatenate(([self._last_s], s[:-1]))
        self._last_s = float(s[-1])
        low, high = np.minimum(before, s), np.maximum(before, s)
        for edges, target in ((self.segment_edges, self.segment), (self.grid_edges, self.grid)):
            if len(target):
                last = len(target) - 1
                first_row = np.clip(np.searchsorted(edges, low, side="right") - 1, 0, last)
                last_row = np.clip(np.searchsorted(edges, high, side="right") - 1, first_row, last)
                rows, step = range_indices(first_row, last_row)
                np.fmax.at(target, rows, error[step])


def _cutting_rows(toolpath: Any) -> np.ndarray:
    from cnc_gym.toolpath import SegmentKind

    kind = np.asarray(toolpath.kind)
    return (kind == SegmentKind.LINE) | (kind == SegmentKind.ARC) | (kind == SegmentKind.NURBS)


def _sample_path(result: RunResult, toolpath: Any) -> None:
    """The programmed path for the plot: points, cutting flags, and the feed the run had there."""
    if not len(toolpath) or toolpath.total_length <= 0:
        return
    from cnc_gym.toolpath import SegmentKind

    s, points = toolpath.sample(max(toolpath.total_length / _PATH_POINTS, 1e-3))
    kind = toolpath.kind[toolpath.segment_at(s)]
    result.path_xyz = points
    result.path_sample_s = s
    result.cutting = (kind == SegmentKind.LINE) | (kind == SegmentKind.ARC) | (kind == SegmentKind.NURBS)
    feed = np.full(len(s), np.nan)
    if len(result.path_s):
        reached = s <= result.path_s[-1] + 1e-9
        # path_s never decreases, so the feed at a path position is read off the run's bins.
        feed[reached] = np.interp(s[reached], result.path_s, result.feed_mm_min)
    result.path_feed_mm_min = feed


def _check_max_time(max_time_s: float | None) -> None:
    if max_time_s is None:
        return
    if isinstance(max_time_s, bool) or not isinstance(max_time_s, int | float) or not (
        math.isfinite(max_time_s) and max_time_s > 0
    ):
        raise ConfigError(f"--max-time (max_time_s) must be a positive number of seconds, got {max_time_s!r}")


def _project_wall_time(log: TextIO, info: dict[str, Any], nominal: float, max_time_s: float | None, *,
                       rate: float) -> None:  # fmt: skip
    """One stderr line when the run, at ``rate`` simulated seconds per wall-clock second, will take long
    in wall-clock time."""
    simulated = float(info.get("cycle_time_s", 0.0))
    if not rate > 0:
        return
    target = nominal if max_time_s is None else min(nominal, max_time_s)
    remaining = (target - simulated) / rate
    if remaining > _PROJECTION_NOTICE_WALL_S:
        print(f"cnc-gym run: {info.get('program', 'program')}: about {_duration(remaining)} of wall-clock "
              f"time to go at the speed so far ({rate:.0f} simulated s per s); "
              "Ctrl-C stops it, --max-time SECONDS bounds it", file=log)  # fmt: skip


def _duration(seconds: float) -> str:
    """``1 h 02 min``, ``12 min 5 s``, ``42 s``."""
    seconds = max(0.0, float(seconds))
    if seconds >= 3600:
        return f"{int(seconds // 3600)} h {int(seconds % 3600 // 60):02d} min"
    if seconds >= 60:
        return f"{int(seconds // 60)} min {int(seconds % 60)} s"
    return f"{seconds:.0f} s"


def simulate(program: Any, *, dialect: str = DEFAULT_DIALECT, machine: str = DEFAULT_MACHINE,
             policy: str | Any = "constant:1.0", progress: bool = False, max_time_s: float | None = None,
             max_blocks: int | None = None, log: TextIO | None = None, units: str | None = None,
             plant: str | None = None, record: bool = True) -> RunResult:  # fmt: skip
    """Simulate ``program`` (built-in name, file or G-code text: the rule of :mod:`cnc_gym.programs`)
    under ``policy`` (spec or Policy). ``log`` (e.g. ``sys.stderr``) gets a notice before a long program
    and a projection of the wall-clock time once it has run a while. ``units``: the input unit at
    power-on (``"mm"``/``"inch"``; default the machine preset's ``power_on_units``, else the dialect's).
    ``record=False``: the summary only, no series for a plot (:func:`record_run`)."""
    from cnc_gym.policies import make_policy

    _check_max_time(max_time_s)
    pol = make_policy(policy, progress=progress) if isinstance(policy, str) else policy
    # A trained model runs in the env version and settings it was trained with (policy_env).
    env = program_env(program, pol, dialect=dialect, machine=machine, max_blocks=max_blocks, units=units,
                      plant=plant)  # fmt: skip
    try:
        if log is not None:
            for _, toolpath in env.unwrapped._programs:  # the interpreter's notes about the program
                for note in toolpath.notices:
                    print(note, file=log)
            _announce_long_program(env.unwrapped, max_time_s, log)
            announce_compiling(log)
        return record_run(env, pol, progress=progress, max_time_s=max_time_s, log=log, record=record)
    finally:
        env.close()


def _announce_long_program(base: Any, max_time_s: float | None, log: TextIO) -> None:
    nominal = float(base.nominal_time_s)
    if nominal <= LONG_RUN_NOTICE_S or (max_time_s is not None and max_time_s <= LONG_RUN_NOTICE_S):
        return
    limit = "" if max_time_s is None else f"; --max-time stops it at {_duration(max_time_s)}"
    print(f"cnc-gym run: {base.program_name}: nominal cycle time {_duration(nominal)} of simulated time "
          f"(at 100 % feed){limit}; the step budget is {base.max_episode_steps} control steps "
          f"({_duration(base.max_episode_steps * base.control_period_s)})", file=log)  # fmt: skip


def truncation_message(result: RunResult) -> str:
    """The stderr line of a run that stopped before the program's end."""
    where = f"at {result.cycle_time_s:g} s simulated, {100 * result.progress:.0f} % of the path"
    if result.stopped_by == MAX_TIME:
        why = "stopped by --max-time"
    else:
        why = f"stopped at the step budget ({result.steps} control steps)"
    return (f"cnc-gym run: {result.program}: truncated: {why} {where}; the results cover the part run "
            f"(finished: false, exit status {EXIT_TRUNCATED})")  # fmt: skip


def run_cli(args: Any) -> int:
    """``cnc-gym run``: errors (bad program, policy, model) propagate as CncGymError for the CLI to print.

    Exit status 0 when the program finished, :data:`EXIT_TRUNCATED` (3) when the run stopped before its
    end (step budget or ``--max-time``), after printing the results and a line on stderr.
    """
    progress = not getattr(args, "no_progress", False) and sys.stderr.isatty()
    # The CLI leaves --machine unset (None) when not given: the runner's default is vmc-small.
    machine = args.machine if getattr(args, "machine", None) is not None else DEFAULT_MACHINE
    plot = plot_target(args.plot) if getattr(args, "plot", None) is not None else None
    result = simulate(args.program, dialect=args.dialect, machine=machine, policy=args.policy,
                      progress=progress, max_time_s=getattr(args, "max_time", None),
                      max_blocks=getattr(args, "max_blocks", None), log=sys.stderr,
                      units=getattr(args, "units", None), plant=getattr(args, "plant", None),
                      record=plot is not None)  # the series are the plot's  # fmt: skip
    if plot is not None:
        target, is_folder = plot
        plot_run(result, target / default_plot_name(result) if is_folder else target)
    summary = result.summary()
    if getattr(args, "json", False):
        try:
            text = json.dumps(summary, allow_nan=False)
        except ValueError:
            bad = [k for k, v in summary.items() if isinstance(v, float) and not math.isfinite(v)]
            raise CncGymError(f"cnc-gym run: {result.program}: {', '.join(bad) or 'a value'} is not a finite "
                              "number, which JSON cannot hold") from None  # fmt: skip
        print(text)
    else:
        print(format_table([summary]))
    if not result.finished:
        sys.stdout.flush()
        print(truncation_message(result), file=sys.stderr)
        return EXIT_TRUNCATED
    return 0


#: Formats ``--plot`` writes (matplotlib's raster and vector backends).
PLOT_FORMATS = (".png", ".pdf", ".svg")


def plot_target(value: str) -> tuple[Path, bool]:
    """Check ``--plot`` before the run. Returns ``(path, is_folder)``: a file with a known format, or a
    folder (the argument ends in ``/`` or names one), where the plot gets :func:`default_plot_name`."""
    if not value:
        raise CncGymError("cnc-gym run: --plot needs a file name (e.g. out/run.png) or a folder")
    path = Path(value)
    is_folder = value.endswith(("/", "\\")) or path.is_dir()
    if not is_folder and path.suffix.lower() not in PLOT_FORMATS:
        raise CncGymError(f"cnc-gym run: --plot {value}: unknown plot format {path.suffix or '(none)'!r}; "
                          f"use {', '.join(PLOT_FORMATS)}, or a folder ending in /")  # fmt: skip
    # Fail before a long run, not after it: the folder must exist (or be made) and be writable.
    folder = path if is_folder else path.parent
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise CncGymError(f"{folder}: cannot make the plot's folder: {exc.strerror or exc}") from None
    if not os.access(folder, os.W_OK):
        raise CncGymError(f"{folder}: cannot write the plot there: permission denied")
    return path, is_folder


def default_plot_name(result: RunResult) -> str:
    """``<program>_<policy>.png`` with characters that are awkward in file names replaced."""
    policy = Path(result.policy.replace(":", "-")).name
    return "".join(c if c.isalnum() or c in "-_." else "_" for c in f"{result.program}_{policy}") + ".png"


def feed_limits(results: list[RunResult]) -> tuple[float, float]:
    """One feed colour scale for several runs (e.g. two policies on one program): 0 to the largest feed
    any of them ran on a cutting move."""
    top = 0.0
    for r in results:
        feeds = r.path_feed_mm_min[r.cutting] if len(r.cutting) == len(r.path_feed_mm_min) else np.zeros(0)
        feeds = feeds[np.isfinite(feeds)]
        if len(feeds):
            top = max(top, float(feeds.max()))
    return 0.0, max(top, 1.0)


def plot_run(result: RunResult, path: str | Path, *, feed_range: tuple[float, float] | None = None) -> Path:
    """Save the run's plot (:func:`run_figure`; PNG, PDF or SVG by the suffix) and return its path."""
    import matplotlib.pyplot as plt

    path = Path(path)
    if path.suffix.lower() not in PLOT_FORMATS:
        raise CncGymError(f"{path}: unknown plot format; use {', '.join(PLOT_FORMATS)}")
    fig = run_figure(result, feed_range=feed_range)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(path, dpi=110)
    except OSError as exc:
        raise CncGymError(f"{path}: cannot write plot: {exc.strerror or exc}") from None
    finally:
        plt.close(fig)
    return path


def run_figure(result: RunResult, *, feed_range: tuple[float, float] | None = None):
    """The run's matplotlib figure (Agg; close it with ``plt.close``).

    The XY path coloured by the feed run there (rapids thin grey; the part the run did not reach dashed),
    XZ and YZ views when the program cuts in Z (more than plunges), with the stretches cut over tolerance
    marked in red and the worst one named by its program line; and the contour error along the path
    (path length on the x axis, so that a 10 000-line program reads like its drawing): the largest error
    per stretch of path (:class:`PathErrorEnvelope`), merged to the plot's resolution by maximum, over
    the tolerance line, the violations in red, rapids shaded. A truncated run says so in the figure's
    title. ``feed_range`` fixes the colour scale, so that plots of several runs compare
    (:func:`feed_limits`).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from cnc_gym.envs.render import (
        mark_violations,
        plot_error_along_path,
        plot_path_views,
        wants_z_views,
        worst_violation,
    )

    if wants_z_views(result.path_xyz, result.cutting):
        fig, axes = plt.subplots(2, 2, figsize=(12, 9.5), constrained_layout=True)
        ax_xy, ax_err, ax_xz, ax_yz = axes.ravel()
        views = {"XY": ax_xy, "XZ": ax_xz, "YZ": ax_yz}
    else:
        fig, (ax_xy, ax_err) = plt.subplots(1, 2, figsize=(12, 5.2), constrained_layout=True)
        views = {"XY": ax_xy}
    plot_path_views(fig, views, result.path_xyz, result.cutting, result.path_feed_mm_min, feed_range)
    ax_xy.set_title(f"{result.program}: tool path coloured by feed")
    worst = worst_violation(result, result.tolerance_mm)
    mark_violations(views, result.path_xyz, result.path_sample_s, result.path_error_edges_mm,
                    result.path_error_mm, result.tolerance_mm, worst)  # fmt: skip
    plot_error_along_path(ax_err, result.path_error_edges_mm, result.path_error_mm, result.tolerance_mm,
                          segment_edges_mm=result.segment_s_mm, cutting=result.segment_cutting,
                          worst=worst)  # fmt: skip
    ax_err.set_title(f"{result.policy}: cycle {result.cycle_time_s:.2f} s, {result.violations} violations")
    if not result.finished:
        why = "--max-time" if result.stopped_by == MAX_TIME else "step budget"
        fig.suptitle(f"truncated ({why}) at {result.cycle_time_s:g} s, {100 * result.progress:.0f} % of the "
                     "path: the numbers cover the part run", color="C3", fontsize=12)  # fmt: skip
    return fig


def format_table(rows: list[dict[str, Any]]) -> str:
    """A plain-text table of run summaries (program, policy, cycle time, errors, violations, finished)."""
    header = ("program", "policy", "cycle s", "max err µm", "rms err µm", "tol µm", "violations", "return",
              "finished")  # fmt: skip
    lines = [header]
    for r in rows:
        lines.append((
            str(r["program"]), str(r["policy"]), f"{r['cycle_time_s']:.3f}",
            f"{1000 * r['contour_error_max_mm']:.1f}", f"{1000 * r['contour_error_rms_mm']:.1f}",
            f"{1000 * r['tolerance_mm']:.0f}", str(r["violations"]), f"{r.get('total_return', 0.0):.2f}",
            "yes" if r.get("finished", True) else "NO",
        ))  # fmt: skip
    widths = [max(len(row[i]) for row in lines) for i in range(len(header))]
    text = ["  ".join(cell.rjust(w) if i >= 2 else cell.ljust(w) for i, (cell, w) in
                      enumerate(zip(row, widths, strict=True))) for row in lines]  # fmt: skip
    text.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(text)
