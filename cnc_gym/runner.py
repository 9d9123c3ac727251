"""``cnc-gym run``: simulate a whole program through controller and plant under a policy.

The run goes through the Gymnasium env (``cnc_gym/Feedrate-v0``), the same code path an RL agent uses, so
a baseline's numbers and a trained agent's numbers are comparable. :func:`simulate` returns a
:class:`RunResult`; :func:`run_cli` is what the ``cnc-gym run`` command calls.
"""

from __future__ import annotations

import json
import math
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from cnc_gym.errors import CncGymError

#: Keys of the ``--json`` object (the contract of docs/architecture.md, plus a few extras).
JSON_KEYS = (
    "program", "machine", "policy", "cycle_time_s", "contour_error_max_mm", "contour_error_rms_mm",
    "tolerance_mm", "violations", "steps", "total_return", "finished",
)  # fmt: skip


@dataclass
class RunResult:
    """One simulated run: the ``--json`` summary plus per-control-step series for plotting."""

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
    finished: bool  # the program ran to its end (not cut off by a step limit)
    # Per-control-step series (not in the JSON summary).
    time_s: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0))
    path_xyz: np.ndarray = field(repr=False, default_factory=lambda: np.zeros((0, 3)))
    feed_mm_min: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0))
    override: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0))
    contour_error_mm: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0))
    cutting: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0, dtype=bool))

    def summary(self) -> dict[str, Any]:
        """The JSON-able summary (plain Python numbers)."""
        out: dict[str, Any] = {}
        for key in JSON_KEYS:
            value = getattr(self, key)
            out[key] = value.item() if isinstance(value, np.generic) else value
        return out


def make_env(program: str, *, dialect: str = "gsk25i", machine: str = "vmc-small", **kwargs: Any):
    """The Feedrate env on one program (interpreted up front, so program errors surface here)."""
    import gymnasium

    import cnc_gym  # noqa: F401  (registers the env ids)
    from cnc_gym.machine import load_machine
    from cnc_gym.programs import load_program

    load_program(program, dialect, load_machine(machine))  # ProgramError / ConfigError with a clear message
    return gymnasium.make(
        "cnc_gym/Feedrate-v0", programs=[program], dialect=dialect, machine=machine, **kwargs
    )


def run_episode(env: Any, policy: Any, *, seed: int | None = 0, progress: bool = False,
                record: bool = True) -> RunResult:  # fmt: skip
    """Run one episode of ``env`` under ``policy``; the env decides which program (its reset)."""
    observation, info = env.reset(seed=seed)
    policy.reset(env)
    base = env.unwrapped
    toolpath = base.toolpath
    tolerance = float(info.get("tolerance_mm", base.machine.controller.contour_tolerance_mm))
    times, path_s, feeds, overrides, errors = [], [], [], [], []
    total_return, steps = 0.0, 0
    terminated = truncated = False
    bar = None
    if progress:
        from tqdm import tqdm

        bar_format = "{desc}: {percentage:3.0f}%|{bar}| {elapsed}<{remaining}"
        desc = str(info.get("program", "program"))
        bar = tqdm(total=100, desc=desc, file=sys.stderr, leave=False, bar_format=bar_format)
    try:
        while not (terminated or truncated):
            action = policy.act(observation, info)
            observation, reward, terminated, truncated, info = env.step(action)
            total_return += float(reward)
            steps += 1
            if record:
                times.append(float(info["cycle_time_s"]))
                path_s.append(float(info.get("path_s", 0.0)))
                feeds.append(float(info.get("feed_mm_min", 0.0)))
                overrides.append(float(info.get("override", 0.0)))
                errors.append(float(info.get("contour_error_mm", 0.0)))
            if bar is not None and steps % 20 == 0:
                bar.n = round(100 * float(info.get("progress", 0.0)))
                bar.refresh()
    finally:
        if bar is not None:
            bar.close()
    rms = float(info.get("contour_error_rms_mm", 0.0))
    path_xyz, cutting = np.zeros((0, 3)), np.zeros(0, dtype=bool)
    if record and path_s:
        from cnc_gym.toolpath import SegmentKind

        path_xyz = toolpath.evaluate(np.asarray(path_s))[0]
        kind = toolpath.kind[toolpath.segment_at(np.asarray(path_s))]
        cutting = (kind == SegmentKind.LINE) | (kind == SegmentKind.ARC) | (kind == SegmentKind.NURBS)
    return RunResult(
        program=str(info.get("program", getattr(base, "program_name", "program"))),
        machine=str(base.machine.name),
        policy=str(getattr(policy, "name", type(policy).__name__)),
        cycle_time_s=float(info["cycle_time_s"]),
        contour_error_max_mm=float(info.get("contour_error_max_mm", 0.0)),
        contour_error_rms_mm=rms if math.isfinite(rms) else 0.0,
        tolerance_mm=tolerance,
        violations=int(info.get("violations", 0)),
        steps=steps,
        total_return=total_return,
        finished=bool(terminated),
        time_s=np.asarray(times),
        path_xyz=path_xyz,
        feed_mm_min=np.asarray(feeds),
        override=np.asarray(overrides),
        contour_error_mm=np.asarray(errors),
        cutting=cutting,
    )


def simulate(program: str, *, dialect: str = "gsk25i", machine: str = "vmc-small",
             policy: str | Any = "constant:1.0", progress: bool = False) -> RunResult:  # fmt: skip
    """Simulate ``program`` (built-in name, file or G-code text) under ``policy`` (spec or Policy)."""
    from agents import make_policy

    pol = make_policy(policy) if isinstance(policy, str) else policy
    env = make_env(program, dialect=dialect, machine=machine)
    try:
        return run_episode(env, pol, progress=progress)
    finally:
        env.close()


def plot_run(result: RunResult, path: str | Path) -> Path:
    """PNG: left, the XY path coloured by feed; right, contour error over time with the tolerance line."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection

    path = Path(path)
    fig, (ax_path, ax_err) = plt.subplots(1, 2, figsize=(12, 5), constrained_layout=True)
    xy = result.path_xyz[:, :2]
    if len(xy) >= 2:
        segments = np.stack([xy[:-1], xy[1:]], axis=1)
        cut = result.cutting[1:] if len(result.cutting) == len(xy) else np.ones(len(segments), dtype=bool)
        # Rapids in thin grey: their speed would swamp the colour scale of the cutting feed.
        if np.any(~cut):
            ax_path.add_collection(LineCollection(segments[~cut], colors="0.7", linewidths=0.8))
        lines = LineCollection(segments[cut], cmap="viridis", linewidths=2)
        lines.set_array(result.feed_mm_min[1:][cut])
        ax_path.add_collection(lines)
        ax_path.autoscale()
        fig.colorbar(lines, ax=ax_path, label="feed on cutting moves (mm/min)")
    ax_path.set_aspect("equal", adjustable="datalim")
    ax_path.set_xlabel("X (mm)")
    ax_path.set_ylabel("Y (mm)")
    ax_path.set_title(f"{result.program}: tool path coloured by feed")
    ax_err.plot(result.time_s, result.contour_error_mm * 1000.0, lw=1, label="contour error")
    ax_err.axhline(result.tolerance_mm * 1000.0, color="r", ls="--", label="tolerance")
    ax_err.set_xlabel("time (s)")
    ax_err.set_ylabel("contour error (µm)")
    ax_err.set_title(f"{result.policy}: cycle {result.cycle_time_s:.2f} s, {result.violations} violations")
    ax_err.legend(loc="upper right")
    path.parent.mkdir(parents=True, exist_ok=True)
    try:
        fig.savefig(path, dpi=110)
    except OSError as exc:
        raise CncGymError(f"{path}: cannot write plot: {exc.strerror or exc}") from None
    finally:
        plt.close(fig)
    return path


def run_cli(args: Any) -> int:
    """``cnc-gym run``: errors (bad program, policy, model) propagate as CncGymError for the CLI to print."""
    progress = not getattr(args, "no_progress", False) and sys.stderr.isatty()
    # The CLI leaves --machine unset (None) when not given: the runner's default is vmc-small.
    machine = getattr(args, "machine", None) or "vmc-small"
    dialect = getattr(args, "dialect", None) or "gsk25i"
    result = simulate(args.program, dialect=dialect, machine=machine,
                      policy=getattr(args, "policy", None) or "constant:1.0", progress=progress)  # fmt: skip
    if getattr(args, "plot", None):
        plot_run(result, args.plot)
    summary = result.summary()
    if getattr(args, "json", False):
        print(json.dumps(summary))
    else:
        print(format_table([summary]))
    return 0


def format_table(rows: list[dict[str, Any]]) -> str:
    """A plain-text table of run summaries (program, policy, cycle time, errors, violations)."""
    header = ("program", "policy", "cycle s", "max err µm", "rms err µm", "tol µm", "violations", "return")
    lines = [header]
    for r in rows:
        lines.append((
            str(r["program"]), str(r["policy"]), f"{r['cycle_time_s']:.3f}",
            f"{1000 * r['contour_error_max_mm']:.1f}", f"{1000 * r['contour_error_rms_mm']:.1f}",
            f"{1000 * r['tolerance_mm']:.0f}", str(r["violations"]), f"{r.get('total_return', 0.0):.2f}",
        ))  # fmt: skip
    widths = [max(len(row[i]) for row in lines) for i in range(len(header))]
    text = ["  ".join(cell.rjust(w) if i >= 2 else cell.ljust(w) for i, (cell, w) in
                      enumerate(zip(row, widths, strict=True))) for row in lines]  # fmt: skip
    text.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(text)
