"""``cnc-gym bench``: records, serial = process pool (= Ray, slow), CLI defaults and errors, plots, and the
bound never beaten by any policy."""

from __future__ import annotations

import json
import os

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from cnc_gym.benchmark.metrics import RECORD_KEYS
from cnc_gym.benchmark.runner import BenchConfig, read_jsonl, run_bench, suite_programs
from cnc_gym.cli import main


def _tiny(n: int = 2):
    """The n shortest programs of the default suite's test split (by nominal time), of different families."""
    from cnc_gym.benchmark.suites import load_suite

    suite = load_suite()
    by_time = sorted(suite.programs("test"), key=lambda e: e.properties["nominal_time_s"])
    picked, families = [], set()
    for e in by_time:
        if e.family not in families and e.family != "holes":
            picked.append(e.name)
            families.add(e.family)
        if len(picked) == n:
            break
    programs, _ = suite_programs(suite.name, "test")
    return [p for p in programs if p.name in picked], suite


def _config(programs, suite, **kw):
    return BenchConfig(programs=programs, policies=["constant:1.0", "classical", "bound"], seeds=[0, 1],
                       machine=suite.machine, dialect=suite.dialect, suite=suite.name,
                       suite_version=suite.version, suite_sha256=suite.sha256, **kw)  # fmt: skip


def test_a_process_pool_gives_the_serial_records():
    programs, suite = _tiny(2)
    serial = run_bench(_config(programs, suite))
    pooled = run_bench(_config(programs, suite, workers=2))
    assert serial == pooled
    assert len(serial) == 2 * 3 * 2
    for r in serial:
        assert set(RECORD_KEYS) <= set(r)
        assert r["suite"] == suite.name and r["split"] == "test" and r["machine"] == "vmc-small"
        if not r["reference"]:
            assert r["time_ratio"] >= 1.0  # never faster than the bound
            assert r["time_ratio"] == pytest.approx(r["cycle_time_s"] / r["bound_s"])
    # Deterministic policies on a deterministic env: the seeds agree.
    by = {(r["program"], r["policy"], r["seed"]): r["cycle_time_s"] for r in serial}
    assert all(by[(p, q, 0)] == by[(p, q, 1)] for p, q, _ in by)


@pytest.mark.slow
def test_ray_gives_the_serial_records():
    pytest.importorskip("ray")
    programs, suite = _tiny(2)
    serial = run_bench(_config(programs, suite))
    assert run_bench(_config(programs, suite, use_ray=True)) == serial


def test_cli_defaults_to_the_default_suite_test_split(tmp_path, capsys):
    out = tmp_path / "r.jsonl"
    assert main(["bench", "--per-family", "1", "--policy", "constant:1.0", "--policy", "bound",
                 "--json", str(out), "--no-progress"]) == 0  # fmt: skip
    records = read_jsonl([out])
    assert {r["split"] for r in records} == {"test"}
    assert {r["suite"] for r in records} == {"cnc-bench-v1"}
    assert len({r["family"] for r in records}) == 7
    table = capsys.readouterr().out
    assert "constant:1.0" in table and "all" in table and "score" in table


def test_cli_user_programs_plots_and_leaderboard(tmp_path, capsys):
    from cnc_gym.benchmark.leaderboard import render_markdown
    from cnc_gym.programs import program_path

    program = tmp_path / "mine.nc"
    program.write_text(program_path("star").read_text())
    out = tmp_path / "r.jsonl"
    assert main(["bench", "--programs", str(program), "--policy", "constant:0.5", "--policy", "constant:1.0",
                 "--policy", "bound", "--json", str(out), "--plot", str(tmp_path / "plots"),
                 "--no-progress"]) == 0  # fmt: skip
    records = read_jsonl([out])
    assert {r["program"] for r in records} == {"mine"} and {r["family"] for r in records} == {"user"}
    assert (tmp_path / "plots" / "pareto.png").stat().st_size > 1000
    assert (tmp_path / "plots" / "families.png").stat().st_size > 1000
    table = render_markdown(records, [str(out)])
    assert "best of 2 constants" in table and "| bound |" in table
    assert json.loads(out.read_text().splitlines()[0])["policy"] == "constant:0.5"


def test_module_callable_policies(tmp_path, monkeypatch):
    from cnc_gym.policies import make_policy

    (tmp_path / "my_policies.py").write_text(
        "import numpy as np\n"
        "from cnc_gym.policies import ConstantOverride\n"
        "def factory():\n    return ConstantOverride(0.8)\n"
        "def act(observation, info):\n    return np.array([-0.2], dtype=np.float32)\n"
        "instance = ConstantOverride(0.3)\n"
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    assert make_policy("my_policies:factory").override == 0.8
    assert make_policy("my_policies:instance").override == 0.3
    function = make_policy("my_policies:act")
    assert function.name == "my_policies:act" and function.act(None, {})[0] == pytest.approx(-0.2)


@pytest.mark.parametrize(("argv", "message"), [
    (["--policy", "greedy"], "unknown policy"),
    (["--policy", "no_such_module:thing"], "cannot import"),
    (["--seeds", "a,b"], "--seeds"),
    (["--workers", "0"], "--workers"),
    (["--split", "test", "--suite", "nope"], "unknown suite"),
])  # fmt: skip
def test_bad_arguments_are_one_line(argv, message, capsys):
    assert main(["bench", "--no-progress", *argv]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and "\n" not in err and "Traceback" not in err


class _Knob:
    """A policy that plays a fixed sequence of (steps, override) pieces, then the last override."""

    name = "knob"

    def __init__(self, pieces):
        self.pieces = pieces

    def reset(self, env):
        self.step = 0

    def act(self, observation, info):
        self.step += 1
        ends = np.cumsum([steps for steps, _ in self.pieces])
        piece = min(int(np.searchsorted(ends, self.step)), len(self.pieces) - 1)
        return np.array([self.pieces[piece][1] - 1.0], dtype=np.float32)


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(pieces=st.lists(st.tuples(st.integers(1, 80), st.floats(0.3, 2.0)), min_size=1, max_size=6))
def test_no_policy_beats_the_bound(pieces):
    import gymnasium

    import cnc_gym  # noqa: F401
    from cnc_gym.machine import load_machine
    from cnc_gym.motion.bound import time_optimal_bound
    from cnc_gym.rollout import run_episode

    programs, _ = _tiny(2)
    machine = load_machine("vmc-small")
    for program in programs:
        env = gymnasium.make("cnc_gym/Feedrate-v0", programs=[program.text])
        bound = time_optimal_bound(env.unwrapped.toolpath, machine).total_s
        episode = run_episode(env, _Knob(pieces), 0)
        if episode.finished:
            assert episode.info["cycle_time_s"] >= bound
        env.close()


def test_cli_units_reads_user_programs_in_inch(tmp_path, capsys):
    # A program without G20/G21: --units inch makes X1. an inch, so the path is 25.4 times longer; the
    # records say which unit was in force (null: the preset's, else the dialect's).
    program = tmp_path / "part.nc"
    program.write_text("G00 X0 Y0\nG01 X1. Y1. F100.\n")
    records = {}
    for units in ("inch", None):
        out = tmp_path / f"{units}.jsonl"
        argv = ["bench", "--programs", str(program), "--policy", "bound", "--json", str(out), "--no-progress"]
        assert main([*argv, *(["--units", units] if units else [])]) == 0
        (records[units],) = read_jsonl([out])
    capsys.readouterr()
    assert records["inch"]["units"] == "inch" and records[None]["units"] is None
    assert records["inch"]["cut_length_mm"] == pytest.approx(25.4 * records[None]["cut_length_mm"])


def test_cli_setup_applies_the_work_offsets_to_user_programs(tmp_path, capsys):
    # G54 at X200: the rapid to the start is 200 mm longer, so the bound is longer (the machine's dynamics,
    # and so its digest, are the same).
    program = tmp_path / "part.nc"
    program.write_text("G54 G00 X0 Y0\nG01 X10. Y10. F1000.\n")
    setup = tmp_path / "job.yaml"
    setup.write_text("work_offsets:\n  G54: [200.0, 0.0, 0.0]\n")
    records = {}
    for name, extra in (("plain", []), ("setup", ["--setup", str(setup)])):
        out = tmp_path / f"{name}.jsonl"
        argv = ["bench", "--programs", str(program), "--policy", "bound", "--json", str(out), "--no-progress"]
        assert main([*argv, *extra]) == 0
        (records[name],) = read_jsonl([out])
    capsys.readouterr()
    assert records["setup"]["machine"] == records["plain"]["machine"] == "vmc-small"
    assert records["setup"]["machine_sha256"] == records["plain"]["machine_sha256"]
    assert records["setup"]["bound_s"] > records["plain"]["bound_s"]
    assert main(["bench", "--programs", str(program), "--policy", "bound", "--no-progress", "--setup",
                 str(tmp_path / "missing.yaml")]) == 2  # fmt: skip
    assert "cannot read setup file" in capsys.readouterr().err


def test_records_stream_to_the_file_as_tasks_finish(tmp_path):
    from cnc_gym.benchmark.runner import JsonlAppender

    programs, suite = _tiny(2)
    out = JsonlAppender(tmp_path / "r.jsonl")
    sizes = []

    def append(records):
        out.append(records)
        lines = (tmp_path / "r.jsonl").read_text().splitlines()
        sizes.append(len(lines))
        assert all(json.loads(line)["policy"] for line in lines)  # valid JSON Lines after each task

    records = run_bench(_config(programs, suite), on_records=append)
    out.finish(records)
    assert sizes == [2 * k for k in range(1, 7)]  # 2 programs × 3 policies, 2 seeds each, one by one
    assert read_jsonl([tmp_path / "r.jsonl"]) == records


def test_the_final_file_is_in_record_order_whatever_order_the_tasks_finished_in(tmp_path):
    from cnc_gym.benchmark.runner import JsonlAppender

    records = [{"policy": "p", "score": 0.0, "seed": s} for s in range(4)]
    out = JsonlAppender(tmp_path / "r.jsonl")
    out.append(records[2:])
    out.append(records[:2])
    assert [r["seed"] for r in read_jsonl([out.path])] == [2, 3, 0, 1]
    out.finish(records)
    assert read_jsonl([out.path]) == records
    assert [p.name for p in tmp_path.iterdir()] == ["r.jsonl"]  # no temporary file left


def test_a_record_that_is_not_finite_json_is_one_error_and_never_written(tmp_path):
    from cnc_gym.benchmark.runner import JsonlAppender, write_jsonl
    from cnc_gym.errors import CncGymError

    bad = {"program": "p", "policy": "q", "seed": 0, "score": 0.0, "time_ratio": float("inf")}
    out = JsonlAppender(tmp_path / "r.jsonl")
    with pytest.raises(CncGymError, match="time_ratio is not a finite number") as err:
        out.append([{"policy": "q", "score": 1.0}, bad])
    assert "\n" not in str(err.value) and out.path.read_text() == ""
    with pytest.raises(CncGymError, match="time_ratio"):
        write_jsonl([bad], tmp_path / "w.jsonl")
    # ... nor read: NaN and Infinity are not JSON.
    (tmp_path / "nan.jsonl").write_text('{"policy": "q", "score": NaN}\n')
    with pytest.raises(CncGymError, match=r"nan.jsonl:1: not a JSON record \(NaN is not a JSON number\)"):
        read_jsonl([tmp_path / "nan.jsonl"])


def test_an_unwritable_json_path_fails_before_any_work(tmp_path, capsys, monkeypatch):
    from cnc_gym.benchmark import runner

    monkeypatch.setattr(runner, "run_bench", lambda *a, **k: pytest.fail("work started"))
    (tmp_path / "file").write_text("")
    assert main(["bench", "--per-family", "1", "--json", str(tmp_path / "file" / "r.jsonl"),
                 "--no-progress"]) == 2  # fmt: skip
    assert "cannot write" in capsys.readouterr().err


def test_max_time_cuts_each_episode_and_marks_the_record(tmp_path, capsys):
    out = tmp_path / "r.jsonl"
    assert main(["bench", "--programs", str(_star(tmp_path)), "--policy", "constant:1.0", "--policy", "bound",
                 "--max-time", "0.5", "--json", str(out), "--no-progress"]) == 0  # fmt: skip
    cut, reference = read_jsonl([out])
    assert cut["stopped_by"] == "max_time" and cut["finished"] is False and cut["score"] == 0.0
    assert 0.5 <= cut["cycle_time_s"] < 0.52 and cut["steps"] == 50
    assert reference["stopped_by"] is None and reference["finished"] is True
    assert "(1 cut by --max-time/--max-cpu)" in capsys.readouterr().err


def test_max_cpu_cuts_an_episode_even_inside_the_policys_planning(tmp_path, monkeypatch):
    import signal

    from cnc_gym.benchmark.runner import BenchProgram, EpisodeLimits
    from cnc_gym.policies.oracle import OraclePlanner

    planned = []

    def plan_forever(self, env):  # a planner that never finishes (its planning is Python, as the oracle's)
        planned.append(True)
        while True:
            sum(range(1000))

    monkeypatch.setattr(OraclePlanner, "reset", plan_forever)
    program = BenchProgram("star", _star(tmp_path).read_text())
    handler = signal.getsignal(signal.SIGPROF)
    records = run_bench(BenchConfig(programs=[program], policies=["oracle"], seeds=[0, 1],
                                    limits=EpisodeLimits(max_cpu_s=0.2)))  # fmt: skip
    assert planned == [True, True] and [r["stopped_by"] for r in records] == ["max_cpu", "max_cpu"]
    assert all(r["steps"] == 0 and r["finished"] is False and r["score"] == 0.0 for r in records)
    assert signal.getsignal(signal.SIGPROF) == handler  # the limit's timer and handler are gone
    # A limit that is not reached changes nothing.
    free = run_bench(BenchConfig(programs=[program], policies=["constant:1.0"]))
    limited = run_bench(BenchConfig(programs=[program], policies=["constant:1.0"],
                                    limits=EpisodeLimits(max_time_s=1e6, max_cpu_s=1e6)))  # fmt: skip
    assert limited == free and free[0]["stopped_by"] is None and free[0]["finished"]


@pytest.mark.parametrize("bad", ["0", "-1", "nan", "inf"])
def test_bad_episode_limits_are_one_line(bad, capsys):
    for option in ("--max-time", "--max-cpu"):
        assert main(["bench", "--no-progress", option, bad]) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith(option) and "\n" not in err


def test_a_program_without_a_bound_is_left_out_with_one_line(tmp_path, capsys, monkeypatch):
    from cnc_gym.errors import CncGymError
    from cnc_gym.motion import bound

    real = bound.compute_bound

    def fails_on_circles(tp, machine, **kw):  # as TOPP-RA does on a path it cannot parameterize
        if any(int(k) == 2 for k in tp.kind):  # an arc
            raise CncGymError("time-optimal bound: TOPP-RA found no parameterization of the cutting moves")
        return real(tp, machine, **kw)

    monkeypatch.setattr(bound, "compute_bound", fails_on_circles)
    monkeypatch.setattr(bound, "_MEMORY", {})
    monkeypatch.setenv("CNC_GYM_CACHE_DIR", str(tmp_path / "cache"))
    from cnc_gym.programs import program_path

    (tmp_path / "round.nc").write_text(program_path("circle").read_text())
    (tmp_path / "empty.nc").write_text("G90 G21\nM30\n")
    out = tmp_path / "r.jsonl"
    programs = [str(_star(tmp_path)), str(tmp_path / "round.nc"), str(tmp_path / "empty.nc")]
    argv = ["bench", "--programs", *programs, "--policy", "constant:1.0", "--json", str(out), "--no-progress"]
    assert main(argv) == 0
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert lines[0] == ("cnc-gym bench: round: left out: time-optimal bound: TOPP-RA found no "
                        "parameterization of the cutting moves")  # fmt: skip
    assert lines[1] == "cnc-gym bench: empty: left out: no motion: nothing to time against the bound"
    assert len(lines) == 3 and "1 episodes" in lines[2]
    assert [r["program"] for r in read_jsonl([out])] == ["mine"]
    assert "1 programs (2 left out)" in captured.out


def test_per_family_with_programs_is_an_error(tmp_path, capsys):
    assert main(["bench", "--programs", str(_star(tmp_path)), "--per-family", "1", "--no-progress"]) == 2
    err = capsys.readouterr().err.strip()
    assert "--per-family" in err and "--programs" in err and "\n" not in err


def test_user_programs_find_their_subprograms_in_their_folder_as_run_does(tmp_path, capsys):
    folder = tmp_path / "job"
    folder.mkdir()
    (folder / "O1234.nc").write_text("O1234\nG91 G01 X5. F600\nY5.\nX-5.\nY-5.\nG90\nM99\n")
    (folder / "main.nc").write_text("G90 G21 G00 X0 Y0 Z0\nG01 Z-1. F300\nM98 P1234 L2\nG00 Z5.\nM30\n")
    out = tmp_path / "r.jsonl"
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    cwd = os.getcwd()
    os.chdir(elsewhere)  # not the program's folder
    try:
        assert main(["bench", "--programs", str(folder / "main.nc"), "--policy", "constant:1.0", "--policy",
                     "bound", "--workers", "2", "--json", str(out), "--no-progress"]) == 0  # fmt: skip
        assert main(["run", str(folder / "main.nc"), "--json"]) == 0
    finally:
        os.chdir(cwd)
    run = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    episode, reference = read_jsonl([out])
    assert episode["cut_length_mm"] == pytest.approx(1.0 + 2 * 20.0)  # the plunge and two squares
    assert episode["cycle_time_s"] == pytest.approx(run["cycle_time_s"], rel=1e-9)
    assert reference["bound_s"] > 0


def _star(tmp_path):
    from cnc_gym.programs import program_path

    program = tmp_path / "mine.nc"
    program.write_text(program_path("star").read_text())
    return program


def test_compiled_episodes_give_the_python_loops_records():
    # constant:x and classical run in compiled chunks on the LTI plant; every field of every record is
    # what the Python loop gives (both run here, on this CPU: exact), --max-time cuts included.
    from cnc_gym.benchmark.runner import EpisodeLimits
    from cnc_gym.rollout import step_by_step

    programs, suite = _tiny(3)
    for limits in (EpisodeLimits(), EpisodeLimits(max_time_s=0.3)):
        config = _config(programs, suite, limits=limits)
        config.policies = ["constant:1.0", "constant:0.45", "classical"]
        with step_by_step():
            loop = run_bench(config)
        assert run_bench(config) == loop
    assert any(r["stopped_by"] == "max_time" for r in loop)
