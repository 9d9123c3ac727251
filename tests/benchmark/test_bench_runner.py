"""``cnc-gym bench``: records, serial = process pool (= Ray, slow), CLI defaults and errors, plots, and the
bound never beaten by any policy."""

from __future__ import annotations

import json

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
