"""`cnc-gym run` and the runner: the JSON contract, bounded series, truncation (exit 3), programs without
motion, the plot, and errors as one line with exit status 2."""

from __future__ import annotations

import io
import json
import math
from pathlib import Path

import gymnasium
import matplotlib.pyplot as plt
import numpy as np
import pytest

import cnc_gym.runner as runner
from cnc_gym.cli import main
from cnc_gym.errors import CncGymError
from cnc_gym.policies import make_policy
from cnc_gym.programs import ProgramText
from cnc_gym.runner import EXIT_TRUNCATED, JSON_KEYS, feed_limits, plot_run, record_run, run_figure, simulate

CONTRACT_KEYS = ("cycle_time_s", "contour_error_max_mm", "contour_error_rms_mm", "tolerance_mm", "violations",
                 "steps")  # fmt: skip


@pytest.fixture(scope="module")
def star_run():
    return simulate("star", policy="constant:1.0")


def test_summary_has_the_contract_fields(star_run):
    summary = star_run.summary()
    assert set(CONTRACT_KEYS) <= set(summary) and set(JSON_KEYS) == set(summary)
    json.dumps(summary)  # plain Python values only
    assert summary["finished"] is True and summary["stopped_by"] is None
    assert summary["steps"] == len(star_run.time_s) > 0  # 540 steps: one bin per step
    assert star_run.bin_steps == 1
    assert 0 < summary["nominal_time_s"] < summary["cycle_time_s"]
    assert all(math.isfinite(summary[k]) for k in CONTRACT_KEYS)


def test_summary_agrees_with_the_per_step_series(star_run):
    # Recomputed here from the per-step series the env reported, independently of the env's counters.
    errors = star_run.contour_error_mm
    assert star_run.violations == int(np.sum(errors > star_run.tolerance_mm))
    assert star_run.contour_error_max_mm == pytest.approx(float(errors.max()))
    assert 0.0 < star_run.contour_error_rms_mm <= star_run.contour_error_max_mm
    # Cycle time is the time of the last control step; steps are 10 ms apart.
    assert star_run.cycle_time_s == pytest.approx(star_run.time_s[-1])
    assert np.all(np.diff(star_run.time_s) > 0)
    assert star_run.tolerance_mm == pytest.approx(0.02)  # vmc-small's contour tolerance


def test_higher_override_is_faster(star_run):
    fast = simulate("star", policy="constant:2.0")
    assert fast.cycle_time_s < star_run.cycle_time_s
    assert fast.contour_error_max_mm >= star_run.contour_error_max_mm


def test_plot_is_a_png(star_run, tmp_path):
    path = plot_run(star_run, tmp_path / "sub" / "star.png")
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 10_000


def test_runner_errors_are_cnc_gym_errors():
    with pytest.raises(CncGymError):
        simulate("no-such-program", policy="constant:1.0")
    with pytest.raises(CncGymError):
        simulate("star", policy="bogus")
    with pytest.raises(CncGymError):
        simulate("star", policy="missing-model.zip")


def test_cli_run_json(capsys, tmp_path):
    plot = tmp_path / "run.png"
    status = main(["run", "star", "--policy", "constant:1.5", "--json", "--plot", str(plot), "--no-progress"])
    out = capsys.readouterr().out.strip().splitlines()
    assert status == 0 and len(out) == 1
    data = json.loads(out[0])
    assert set(CONTRACT_KEYS) <= set(data)
    assert data["policy"] == "constant:1.5" and data["violations"] >= 0
    assert plot.read_bytes()[:4] == b"\x89PNG"


def test_cli_run_units_inch(capsys, tmp_path):
    # A rapid of X1. (no G20/G21): 25.4 mm in inch, 1 mm in mm, at the machine's rapid rate, so the
    # nominal time is longer in inch by far (a feed move would scale its F with it and take the same time).
    program = tmp_path / "inch.nc"
    program.write_text("G00 X1.\n")
    nominal = {}
    for units in ("inch", "mm"):
        assert main(["run", str(program), "--units", units, "--json", "--no-progress"]) == 0
        nominal[units] = json.loads(capsys.readouterr().out)["nominal_time_s"]
    assert nominal["inch"] > 5 * nominal["mm"] > 0


@pytest.mark.parametrize("argv", [["run", "no-such-program"], ["run", "star", "--policy", "fast"],
                                  ["run", "star", "--policy", "nope.zip"]])  # fmt: skip
def test_cli_run_errors_are_one_line(capsys, argv):
    status = main([*argv, "--no-progress"])
    captured = capsys.readouterr()
    assert status == 2
    assert captured.out == ""
    assert len(captured.err.strip().splitlines()) == 1 and "Traceback" not in captured.err


# ------------------------------------------------------------------------------------- bounded series
def test_long_runs_keep_a_bounded_series_with_exact_summary_numbers(star_run):
    # simulate() measures with the programmed-path meter (contour_rule "path"), whatever the env id.
    env = gymnasium.make("cnc_gym/Feedrate-v0", programs=["star"], contour_rule="path")
    binned = record_run(env, make_policy("constant:1.0"), max_bins=32)
    env.close()
    assert binned.steps == star_run.steps == 540
    assert len(binned.time_s) <= 33 and binned.bin_steps == 32  # 540 steps in bins of 32
    # The summary is the env's streaming totals, the same whatever the binning ...
    assert binned.summary() == star_run.summary()
    # ... and the envelope keeps the largest step error, the bins' ends the run's time.
    assert binned.contour_error_mm.max() == pytest.approx(star_run.contour_error_max_mm, abs=1e-15)
    assert binned.time_s[-1] == pytest.approx(star_run.cycle_time_s)
    worst_bin = int(np.argmax(binned.contour_error_mm))
    worst_step = int(np.argmax(star_run.contour_error_mm))
    assert worst_bin * 32 <= worst_step < (worst_bin + 1) * 32
    assert np.all(np.diff(binned.path_s) >= 0)


def test_record_false_keeps_no_series():
    env = gymnasium.make("cnc_gym/Feedrate-v0", programs=["circle"])
    result = record_run(env, make_policy("constant:1.0"), record=False)
    env.close()
    assert result.finished and len(result.time_s) == 0 and len(result.path_xyz) == 0


# ------------------------------------------------------------------------------------------ truncation
def test_max_time_stops_the_run_and_says_so(capsys, tmp_path):
    plot = tmp_path / "cut.png"
    status = main(["run", "star", "--max-time", "1.5", "--json", "--no-progress", "--plot", str(plot)])
    captured = capsys.readouterr()
    assert status == EXIT_TRUNCATED == 3
    data = json.loads(captured.out)
    assert data["finished"] is False and data["stopped_by"] == "max_time"
    assert data["cycle_time_s"] == pytest.approx(1.5) and data["steps"] == 150
    err = captured.err.strip().splitlines()
    assert len(err) == 1 and "truncated" in err[0] and "--max-time" in err[0] and "exit status 3" in err[0]
    assert plot.read_bytes()[:4] == b"\x89PNG"


def test_step_budget_truncation_table_plot_and_exit_status(capsys):
    # Knob at 0 % override: the program never ends, the env stops at its step budget (5 x T_nominal + 1 s).
    status = main(["run", "star", "--policy", "constant:0", "--no-progress"])
    captured = capsys.readouterr()
    assert status == 3
    header, _, row = captured.out.strip().splitlines()
    assert header.split()[-1] == "finished" and row.split()[-1] == "NO"
    assert "step budget" in captured.err and "truncated" in captured.err
    result = simulate("star", policy="constant:0")
    assert not result.finished and result.stopped_by == "step_budget"
    assert result.steps == math.ceil(5 * result.nominal_time_s / 0.01) + 100
    assert 0.0 < result.progress < 0.5
    fig = run_figure(result)
    try:
        assert "truncated" in fig._suptitle.get_text() and "step budget" in fig._suptitle.get_text()
    finally:
        plt.close(fig)


def test_finished_runs_have_no_truncation_title(star_run):
    fig = run_figure(star_run)
    try:
        assert fig._suptitle is None
    finally:
        plt.close(fig)


def test_long_programs_are_announced_and_projected(monkeypatch):
    monkeypatch.setattr(runner, "LONG_RUN_NOTICE_S", 1.0)
    monkeypatch.setattr(runner, "_PROJECTION_AFTER_WALL_S", 0.0)
    monkeypatch.setattr(runner, "_PROJECTION_NOTICE_WALL_S", -1.0)
    monkeypatch.setattr(runner, "_CHUNK_STEPS", 20)  # (a compiled run reports between chunks)
    for policy in ("constant:1.0", "module:callable"):
        log = io.StringIO()
        simulate("star", log=log, policy=_python_knob() if policy.startswith("module") else policy)
        lines = log.getvalue().splitlines()
        assert len(lines) == 2
        assert "nominal cycle time" in lines[0] and "step budget" in lines[0]
        assert "wall-clock time to go" in lines[1] and "--max-time" in lines[1]


def _python_knob():
    """A policy in Python (the step-by-step loop)."""

    class Knob:
        name = "knob"

        def reset(self, env):
            pass

        def act(self, observation, info):
            return np.array([0.0], dtype=np.float32)

    return Knob()


@pytest.mark.parametrize("bad", [0, -1.0, math.nan, math.inf, "5"])
def test_bad_max_time_is_a_config_error(bad):
    with pytest.raises(CncGymError, match="max_time_s"):
        simulate("star", max_time_s=bad)


# --------------------------------------------------------------------------------- no-motion programs
NO_MOTION = {
    "modal-only": "G90\nM30\n",
    "empty": "",
    "tool-and-spindle": "T1 M06\nM03 S1000\nM05\nM30\n",
}


@pytest.mark.parametrize("policy", ["constant:1.0", "classical"])
@pytest.mark.parametrize("name", list(NO_MOTION))
def test_programs_without_motion_run_to_a_zero_second_result(tmp_path, capsys, name, policy):
    program = tmp_path / f"{name}.nc"
    program.write_text(NO_MOTION[name])
    status = main(["run", str(program), "--policy", policy, "--json", "--no-progress",
                   "--plot", str(tmp_path / "p.png")])  # fmt: skip
    captured = capsys.readouterr()
    assert status == 0 and captured.err == ""
    data = json.loads(captured.out)
    assert data["finished"] is True and data["cycle_time_s"] == 0.0
    assert data["violations"] == 0 and data["contour_error_max_mm"] == 0.0 and data["total_return"] == 0.0
    assert (tmp_path / "p.png").read_bytes()[:4] == b"\x89PNG"


def test_a_dwell_only_program_takes_its_dwell():
    result = simulate(ProgramText("G04 P500\nM30\n"), policy="classical")
    assert result.finished and result.cycle_time_s == pytest.approx(0.5)


# ---------------------------------------------------------------------------------------------- plots
def test_paired_plots_share_one_feed_scale(star_run):
    classical = simulate("star", policy="classical")
    low, high = feed_limits([star_run, classical])
    top = max(np.nanmax(r.path_feed_mm_min[r.cutting]) for r in (star_run, classical))
    assert low == 0.0 and high == pytest.approx(top)
    for result in (star_run, classical):
        fig = run_figure(result, feed_range=(low, high))
        try:
            colourbar = fig.axes[0].collections[-1]
            assert colourbar.norm.vmin == 0.0 and colourbar.norm.vmax == pytest.approx(high)
        finally:
            plt.close(fig)


def test_error_panel_legend_sits_outside_the_axes(star_run):
    fig = run_figure(star_run)
    try:
        fig.canvas.draw()
        ax_err = fig.axes[1]
        legend = ax_err.get_legend()
        inside = ax_err.get_window_extent()
        # The legend lies below the plotting area, so it cannot hide the tolerance line.
        assert legend.get_window_extent().y1 <= inside.y0
        tol_line = [line for line in ax_err.get_lines() if line.get_label().startswith("tolerance")]
        assert tol_line and ax_err.get_ylim()[1] > tol_line[0].get_ydata()[0]
    finally:
        plt.close(fig)


def test_programs_with_z_motion_get_side_views():
    ramp = ProgramText("G90 G21 G17\nG01 X20. Z-2. F600.\nG01 X40. Z-4.\nM30\n", name="ramp")
    result = simulate(ramp)
    fig = run_figure(result)
    try:
        titles = [ax.get_title() for ax in fig.axes]
        assert "XZ view" in titles and "YZ view" in titles
    finally:
        plt.close(fig)


@pytest.mark.parametrize("target", ["out.txt", "out", ""])
def test_unknown_plot_formats_are_one_line_errors_before_the_run(capsys, tmp_path, monkeypatch, target):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(runner, "simulate", lambda *a, **k: pytest.fail("ran before checking --plot"))
    status = main(["run", "star", "--plot", target, "--no-progress"])
    captured = capsys.readouterr()
    assert status == 2 and captured.out == "" and len(captured.err.splitlines()) == 1
    assert "--plot" in captured.err and "Traceback" not in captured.err


def test_plot_into_a_folder_names_the_file_after_program_and_policy(capsys, tmp_path):
    folder = tmp_path / "plots"
    assert main(["run", "star", "--policy", "constant:1.5", "--plot", f"{folder}/", "--no-progress"]) == 0
    assert (folder / "star_constant-1.5.png").read_bytes()[:4] == b"\x89PNG"
    existing = tmp_path / "existing"
    existing.mkdir()
    assert main(["run", "star", "--plot", str(existing), "--no-progress"]) == 0  # no trailing slash
    assert (existing / "star_constant-1.png").is_file() and not (tmp_path / "existing.png").exists()


def test_a_plot_that_cannot_be_written_is_reported_as_a_write_error(capsys, tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("")
    status = main(["run", "star", "--plot", str(blocker / "p.png"), "--no-progress"])
    captured = capsys.readouterr()
    assert status == 2 and captured.out == "" and len(captured.err.splitlines()) == 1
    assert "cannot read" not in captured.err and "plot" in captured.err


def test_drilled_holes_show_as_dots_seen_from_above():
    from matplotlib.collections import PathCollection

    drill = Path(__file__).resolve().parents[1] / "examples" / "drill.nc"
    result = simulate(drill)
    fig = run_figure(result)
    try:
        ax_xy = fig.axes[0]
        dots = [c for c in ax_xy.collections if isinstance(c, PathCollection)]
        assert len(dots) == 1 and len(dots[0].get_offsets()) == 6  # six holes
        assert {ax.get_title() for ax in fig.axes} >= {"XZ view", "YZ view"}
    finally:
        plt.close(fig)


def test_simulate_passes_its_progress_choice_to_the_policy(monkeypatch):
    """``--no-progress`` (progress=False) must also silence a planner's own planning bar."""
    from cnc_gym import policies

    seen = []
    real = policies.make_policy

    def spy(spec, *, progress=None):
        seen.append(progress)
        return real(spec, progress=progress)

    monkeypatch.setattr(policies, "make_policy", spy)
    simulate("G91 G01 X5 F600\nM30\n", policy="constant:1.0", progress=False)
    assert seen == [False]


def test_the_projection_leaves_out_a_slow_start(monkeypatch):
    """The wall-clock projection uses the rate after start-up: 20 steps of 1 s each (compiling, say), then
    10 ms per step. Projecting from the start would say 0.1 simulated s per s; the rate after it is ~1."""
    import types

    clock = types.SimpleNamespace(now=0.0)
    monkeypatch.setattr(runner, "time", types.SimpleNamespace(perf_counter=lambda: clock.now))
    monkeypatch.setattr(runner, "LONG_RUN_NOTICE_S", 1e9)
    monkeypatch.setattr(runner, "_PROJECTION_NOTICE_WALL_S", -1.0)
    steps = []

    class SlowStart:
        def reset(self, env):
            pass

        def act(self, observation, info):
            steps.append(None)
            clock.now += 1.0 if len(steps) <= 20 else 0.01
            return np.array([1.0], dtype=np.float32)

    log = io.StringIO()
    simulate("star", policy=SlowStart(), log=log)
    (line,) = log.getvalue().splitlines()
    rate = float(line.split("(")[1].split()[0])
    period = gymnasium.make("cnc_gym/Feedrate-v0").unwrapped.control_period_s
    assert rate == pytest.approx(period / 0.01, rel=0.2)


def test_run_json_never_prints_a_number_that_is_not_json(monkeypatch, capsys):
    star = simulate("star", max_time_s=0.05)
    star.contour_error_max_mm = math.nan
    monkeypatch.setattr(runner, "simulate", lambda *a, **k: star)
    assert main(["run", "star", "--json"]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.strip() == ("cnc-gym run: star: contour_error_max_mm is not a finite number, "
                                         "which JSON cannot hold")  # fmt: skip


def test_a_step_marks_every_segment_its_reference_swept_and_only_those():
    from cnc_gym.runner import PathErrorEnvelope
    from cnc_gym.toolpath import ToolpathBuilder

    builder = ToolpathBuilder()
    for k in range(10):  # ten 0.1 mm chords, then one 50 mm line
        builder.line((0.1 * k, 0, 0), (0.1 * (k + 1), 0, 0), feed=600, line=k + 1)
    builder.line((1.0, 0, 0), (51.0, 0, 0), feed=600, line=11)
    envelope = PathErrorEnvelope(builder.build(), bins=102)  # 0.5 mm bins
    envelope.add(0.35, 0.001)  # the first step sweeps chords 1-4
    envelope.add(0.95, 0.003)  # the second, chords 4-10
    envelope.add(20.0, 0.002)  # then far into the long line
    envelope.finish()
    np.testing.assert_array_equal(envelope.segment[:3], 0.001)
    np.testing.assert_array_equal(envelope.segment[3:10], 0.003)  # chord 4 got the larger of the two
    assert envelope.segment[10] == 0.002
    assert envelope.grid[0] == 0.003 and envelope.grid[1] == 0.003  # the bins of 0-0.5 and 0.5-1 mm
    assert np.all(envelope.grid[2:40] == 0.002) and np.all(np.isnan(envelope.grid[41:]))  # not reached


def test_a_long_program_plots_its_error_along_the_path_with_the_violations_marked():
    # 10 000 G01 chords of a wiggly spiral at 150 %: the time panel drew a solid band on such a program.
    from matplotlib.lines import Line2D

    from cnc_gym.envs.render import ALONG_PATH_BINS

    lines = ["G90 G21 G17", "G00 X10 Y0 Z5", "G01 Z-1 F600", "F3000"]
    for k in range(1, 10_001):
        t = k / 10_000
        angle = 2 * math.pi * 6 * t
        radius = 10 + 20 * t + 1.2 * math.sin(40 * angle)
        lines.append(f"X{radius * math.cos(angle):.3f} Y{radius * math.sin(angle):.3f}")
    result = simulate(ProgramText("\n".join([*lines, "M30"]) + "\n", name="spiral"), policy="constant:1.5",
                      max_time_s=8.0)  # fmt: skip
    assert len(result.segment_line) > 10_000 and not result.finished
    # The recorded envelope holds the run's largest error, where the run got to and nowhere else.
    assert np.nanmax(result.path_error_mm) == pytest.approx(result.contour_error_max_mm, rel=1e-12)
    reached = result.path_error_edges_mm[:-1] <= result.last_path_s
    assert np.all(np.isfinite(result.path_error_mm[reached][1:])) and np.all(~np.isfinite(
        result.path_error_mm[~reached]))  # fmt: skip
    fig = run_figure(result)
    try:
        ax_xy, ax_err = fig.axes[0], fig.axes[1]
        assert ax_err.get_xlabel().startswith("path length")
        envelope = [line for line in ax_err.get_lines() if line.get_label().startswith("contour error")]
        assert len(envelope) == 1 and len(envelope[0].get_xdata()) <= 2 * ALONG_PATH_BINS  # steps, no band
        assert ax_err.get_xlim()[1] == pytest.approx(result.path_length_mm)
        ticks = [line for line in ax_err.get_lines() if line.get_marker() == "|"]
        assert ticks and len(ticks[0].get_xdata()) > 0  # the violations, under the axis
        halo = [line for line in ax_xy.get_lines() if isinstance(line, Line2D) and line.get_label() ==
                "over tolerance"]  # fmt: skip
        assert halo and len(halo[0].get_xdata()) > 0
        worst = int(result.segment_line[np.nanargmax(result.segment_error_mm)])
        assert any(f"line {worst}" in text.get_text() for ax in (ax_xy, ax_err) for text in ax.texts)
    finally:
        plt.close(fig)


# ------------------------------------------------------------------------------- compiled episodes
_RESULT_ARRAYS = ("time_s", "path_s", "feed_mm_min", "override", "contour_error_mm", "path_feed_mm_min",
                  "path_error_edges_mm", "path_error_mm", "segment_error_mm")  # fmt: skip


@pytest.mark.parametrize(("policy", "max_time_s", "max_bins"), [("classical", None, 64),
                                                               ("constant:0.6", 0.7, 8),
                                                               ("constant:1.3", None, 4096)])  # fmt: skip
def test_a_compiled_run_is_the_python_loops_run(policy, max_time_s, max_bins):
    # The whole RunResult: the summary, the binned series and the error along the path, bit for bit.
    from cnc_gym.rollout import step_by_step

    def run():
        pol = make_policy(policy)
        env = runner.program_env("pocket", pol, machine="vmc-small")
        try:
            return record_run(env, pol, max_time_s=max_time_s, max_bins=max_bins)
        finally:
            env.close()

    with step_by_step():
        loop = run()
    compiled = run()
    assert compiled.summary() == loop.summary() and compiled.bin_steps == loop.bin_steps
    for name in _RESULT_ARRAYS:
        a, b = getattr(loop, name), getattr(compiled, name)
        assert a.shape == b.shape and np.array_equal(a, b, equal_nan=True), name
    assert (loop.stopped_by is not None) == (max_time_s is not None)


def test_run_without_a_plot_keeps_no_series(monkeypatch, capsys):
    kept = []
    monkeypatch.setattr(runner, "record_run", lambda *a, **kw: kept.append(kw["record"]) or simulate_stub())

    def simulate_stub():
        return runner.RunResult("p", "m", "constant:1", 1.0, 0.0, 0.0, 0.02, 0, 1, 0.0, True)

    assert main(["run", "star", "--policy", "constant:1.0", "--json"]) == 0
    assert kept == [False]
