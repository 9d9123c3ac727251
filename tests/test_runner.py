"""`cnc-gym run` and the runner: the JSON contract, the plot, and errors as one line with exit status 2."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from cnc_gym.errors import CncGymError
from cnc_gym.runner import JSON_KEYS, plot_run, simulate

CONTRACT_KEYS = ("cycle_time_s", "contour_error_max_mm", "contour_error_rms_mm", "tolerance_mm", "violations",
                 "steps")  # fmt: skip


@pytest.fixture(scope="module")
def star_run():
    return simulate("star", policy="constant:1.0")


def test_summary_has_the_contract_fields(star_run):
    summary = star_run.summary()
    assert set(CONTRACT_KEYS) <= set(summary) and set(JSON_KEYS) == set(summary)
    json.dumps(summary)  # plain Python values only
    assert summary["finished"] is True
    assert summary["steps"] == len(star_run.time_s) > 0
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
    from cnc_gym.cli import main

    plot = tmp_path / "run.png"
    status = main(["run", "star", "--policy", "constant:1.5", "--json", "--plot", str(plot), "--no-progress"])
    out = capsys.readouterr().out.strip().splitlines()
    assert status == 0 and len(out) == 1
    data = json.loads(out[0])
    assert set(CONTRACT_KEYS) <= set(data)
    assert data["policy"] == "constant:1.5" and data["violations"] >= 0
    assert plot.read_bytes()[:4] == b"\x89PNG"


@pytest.mark.parametrize("argv", [["run", "no-such-program"], ["run", "star", "--policy", "fast"],
                                  ["run", "star", "--policy", "nope.zip"]])  # fmt: skip
def test_cli_run_errors_are_one_line(capsys, argv):
    from cnc_gym.cli import main

    status = main([*argv, "--no-progress"])
    captured = capsys.readouterr()
    assert status == 2
    assert captured.out == ""
    assert len(captured.err.strip().splitlines()) == 1 and "Traceback" not in captured.err
