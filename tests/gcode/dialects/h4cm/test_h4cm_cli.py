"""``--dialect h4cm`` in the CLI (trace, run, bench) and ``dialect="h4cm"`` in the env, with the ``h4cm``
machine preset."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from cnc_gym.cli import main
from cnc_gym.envs import FeedrateEnv
from cnc_gym.machine import load_machine

ROOT = Path(__file__).resolve().parents[4]
#: A small H4C-M program: integer words in µm, U/V incremental in G90, a G65 loop.
PROGRAM = "G00 X0 Y0\nG65 L01 P#1 A0\nN1 G01 U2000 F600\nV2000\nG65 L02 P#1 A#1 B1\nG65 L84 P1 A#1 B2\nM02\n"


def test_trace_with_the_h4cm_dialect(tmp_path, capsys):
    program = tmp_path / "part.nc"
    program.write_text(PROGRAM)
    assert main(["trace", str(program), "--dialect", "h4cm"]) == 0
    records = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    # Two passes of the G65 loop: +2 mm in X, then +2 mm in Y, twice.
    assert [r["end"][:2] for r in records] == [[2.0, 0.0], [2.0, 2.0], [4.0, 2.0], [4.0, 4.0]]
    assert all(r["modes"] == ["exact_stop"] for r in records)  # CNC mode (#93 = 0)


def test_trace_reports_an_h4cm_error_in_one_line(tmp_path, capsys):
    program = tmp_path / "bad.nc"
    program.write_text("G01 X1. F100\nG65 L99 P7\n")
    assert main(["trace", str(program), "--dialect", "h4cm"]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"{program}:2: ") and err.rstrip().endswith("[user-alarm]") and err.count("\n") == 1


def test_run_and_bench_with_the_h4cm_dialect_and_preset(tmp_path, capsys):
    program = tmp_path / "part.nc"
    program.write_text(PROGRAM)
    argv = ["run", str(program), "--dialect", "h4cm", "--machine", "h4cm", "--json", "--no-progress"]
    assert main(argv) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["finished"] and result["machine"] == "h4cm"
    out = tmp_path / "bench.jsonl"
    assert main(["bench", "--programs", str(program), "--dialect", "h4cm", "--machine", "h4cm", "--policy",
                 "constant:1.0", "--json", str(out), "--no-progress"]) == 0  # fmt: skip
    record = json.loads(out.read_text().splitlines()[0])
    assert record["dialect"] == "h4cm" and record["machine"] == "h4cm"


def test_env_with_the_h4cm_dialect():
    env = FeedrateEnv(programs=[str(ROOT / "examples" / "h4cm_part.nc")], dialect="h4cm", machine="h4cm")
    env.reset(seed=0)
    for _ in range(20):
        env.step(np.array([0.0], dtype=np.float32))
    env.close()


def test_the_preset_carries_the_mcm_defaults():
    m = load_machine("h4cm")
    assert m.controller.post_filter_s == 0.1  # #166/#167 100 ms
    assert m.controller.lookahead_blocks == 0  # CNC mode: exact stop, no look-ahead
    # 85·√(1000·R) mm/min at R = 4 mm is 5376 mm/min = 89.6 mm/s: v²/R = 2006.9 mm/s².
    v = 85 * (1000 * 4.0) ** 0.5 / 60
    assert abs(v * v / 4.0 - m.controller.max_centripetal_accel_mm_s2) < 0.01
    assert m.axis_array("rapid_mm_min") == (10000.0, 10000.0, 10000.0)
