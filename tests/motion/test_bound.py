"""The TOPP-RA time-optimal bound against closed forms, its cache, and against the controller itself."""

from __future__ import annotations

import math

import numpy as np
import pytest

from cnc_gym.gcode import interpret
from cnc_gym.machine import load_machine
from cnc_gym.motion import Controller
from cnc_gym.motion.bound import compute_bound, time_optimal_bound

VMC = load_machine("vmc-small")
A = 3000.0  # vmc-small: per-axis acceleration, mm/s²


def _bound(text: str, **kw):
    return compute_bound(interpret(text), VMC, **kw)


def test_line_along_an_axis_is_the_trapezoid():
    # F3000 × max override 2 = 100 mm/s; from rest to rest over 100 mm: T = L/v + v/A.
    b = _bound("G90 G21\nG01 X100 F3000\nM30\n")
    assert b.cutting_s == pytest.approx(100 / 100 + 100 / A, rel=1e-3)
    assert b.rapid_s == 0 and b.dwell_s == 0


def test_diagonal_line_gets_each_axis_share_of_the_acceleration():
    # At 45° each axis carries cos 45° of the tangential acceleration: the path may accelerate at √2·A.
    length = 100.0
    d = length / math.sqrt(2)
    b = _bound(f"G90 G21\nG01 X{d:.6f} Y{d:.6f} F3000\nM30\n")
    assert b.cutting_s == pytest.approx(length / 100 + 100 / (math.sqrt(2) * A), rel=1e-3)


def test_short_line_is_the_triangle():
    # 2 mm at F6000 × 2: the feed is never reached, T = 2·√(L/A).
    b = _bound("G90 G21\nG01 X2 F6000\nM30\n")
    assert b.cutting_s == pytest.approx(2 * math.sqrt(2 / A), rel=2e-3)


def test_full_circle_at_the_feed_cap():
    # R 30, F3000 × 2 = 100 mm/s (below every curvature cap): T = 2πR/v + v/A (the start and end tangent is
    # along Y, so the ramps load Y alone).
    circle = _bound("G90 G21\nG92 X30 Y0\nG03 X30 Y0 I-30 J0 F3000\nM30\n")
    assert circle.cutting_s == pytest.approx(2 * math.pi * 30 / 100 + 100 / A, rel=2e-3)


def test_tight_circle_runs_at_the_controllers_curvature_cap():
    # R 2 at F6000: the controller's cap is min(√(a_n·R), (J·R²)^(1/3), chord (2/T)·√(2Rδ − δ²)).
    r, dt, delta = 2.0, 0.002, 0.001
    cap = min(math.sqrt(3000 * r), (30000 * r * r) ** (1 / 3), (2 / dt) * math.sqrt(2 * r * delta - delta**2))
    b = _bound(f"G90 G21\nG92 X{r} Y0\nG03 X{r} Y0 I-{r} J0 F6000\nM30\n")
    assert b.cutting_s == pytest.approx(2 * math.pi * r / cap + cap / A, rel=3e-3)


def test_rapids_and_dwells_are_timed_rest_to_rest():
    b = _bound("G90 G21\nG00 X100\nG04 X1.5\nM30\n")
    # Rapid 30 m/min = 500 mm/s, 5000 mm/s², 70000 mm/s³: jerk-limited rest to rest (closed form).
    v, a, j, d = 500.0, 5000.0, 70000.0, 100.0
    ramp = v / a + a / j
    assert b.rapid_s == pytest.approx(2 * ramp + (d - v * ramp) / v, rel=1e-9)
    assert b.dwell_s == pytest.approx(1.5)
    assert b.cutting_s == 0 and b.gridpoints == 0
    assert b.total_s == pytest.approx(b.rapid_s + b.dwell_s)


def test_feed_mode_is_capped_by_the_clamp_only():
    # In feed mode the agent may command up to P1224 (15 000 mm/min = 250 mm/s).
    b = _bound("G90 G21\nG01 X100 F300\nM30\n", action_mode="feed")
    assert b.cutting_s == pytest.approx(100 / 250 + 250 / A, rel=1e-3)


@pytest.mark.parametrize("program", ["circle", "star", "freeform", "pocket"])
def test_the_controller_at_max_override_never_beats_the_bound(program):
    from cnc_gym.programs import load_program

    _, tp = load_program(program, "gsk25i", VMC)
    controller = Controller(tp, VMC)
    run = controller.run_to_end(override=VMC.controller.max_override)
    assert run.time_s[-1] >= time_optimal_bound(tp, VMC, cache=False).total_s


def test_cache_on_disk(tmp_path, monkeypatch):
    from cnc_gym.motion import bound

    monkeypatch.setenv("CNC_GYM_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(bound, "_MEMORY", {})
    tp = interpret("G90 G21\nG01 X10 Y3 F1200\nG02 X20 Y3 R5\nM30\n")
    first = time_optimal_bound(tp, VMC)
    files = list((tmp_path / "bound").glob("*.json"))
    assert len(files) == 1
    monkeypatch.setattr(bound, "_MEMORY", {})
    monkeypatch.setattr(bound, "compute_bound", lambda *a, **k: pytest.fail("not read from the cache"))
    assert time_optimal_bound(tp, VMC) == first
    # Another machine is another key.
    monkeypatch.setattr(bound, "compute_bound", compute_bound)
    time_optimal_bound(tp, load_machine("p-loop-30"))
    assert len(list((tmp_path / "bound").glob("*.json"))) == 2


def test_a_broken_cache_file_is_recomputed(tmp_path, monkeypatch):
    from cnc_gym.motion import bound

    monkeypatch.setenv("CNC_GYM_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(bound, "_MEMORY", {})
    tp = interpret("G90 G21\nG01 X10 F1200\nM30\n")
    first = time_optimal_bound(tp, VMC)
    for f in (tmp_path / "bound").glob("*.json"):
        f.write_text("{not json")
    monkeypatch.setattr(bound, "_MEMORY", {})
    assert time_optimal_bound(tp, VMC).total_s == pytest.approx(first.total_s)
    assert np.isfinite(first.total_s)


def test_short_cuts_between_stops_are_the_closed_form():
    # Pecks of 0.3-1.2 mm at F100 × 2 = 3.33 mm/s, each from rest to rest (a rapid on either side): the
    # ramps take v/A ≈ 1 ms over about 2 µm, so T = Σ (L/v + v/A). A grid interval (up to 0.5 mm) ramped
    # at constant acceleration would take twice L/v on a 0.5 mm peck.
    depths = [0.3, 0.5, 0.8, 1.2]
    lines, z = ["G90 G21", "G00 X0 Y0 Z1"], 0.0
    for depth in depths:
        lines += [f"G00 Z{z:.3f}", f"G01 Z{z - depth:.3f} F100", "G00 Z1"]
        z -= depth
    b = _bound("\n".join([*lines, "M30"]) + "\n")
    v = 100 * 2 / 60
    closed = sum(d / v + v / A for d in depths)
    assert b.cutting_s <= closed * (1 + 1e-9)
    assert b.cutting_s == pytest.approx(closed, rel=1e-3)


def test_a_cut_between_stops_on_a_coarse_grid_stays_below_the_closed_form():
    # One grid interval per 5 mm: the ramps lie inside the first and last interval, and the bound is still
    # the trapezoid (the time inside an interval is the fastest motion between its end speeds, not a ramp
    # over the whole interval).
    b = _bound("G90 G21\nG01 X20 F600\nG04 X0.1\nG01 X21 F600\nM30\n", grid_mm=5.0)
    v = 600 * 2 / 60
    closed = 20 / v + v / A + 1 / v + v / A
    assert b.cutting_s <= closed * (1 + 1e-9)
    assert b.cutting_s == pytest.approx(closed, rel=1e-3)


def test_an_arc_interval_allows_at_least_the_acceleration_of_its_best_point():
    # On a coarse grid an interval of an arc turns by up to 5°: its tangent is relaxed so that each axis's
    # limit allows at least the path acceleration of any point in it, so the bound on a coarse grid is
    # never above the bound on a fine one by more than rounding.
    text = "G90 G21\nG92 X10 Y0\nG03 X-10 Y0 I-10 J0 F6000\nM30\n"
    coarse, fine = _bound(text, grid_mm=2.0), _bound(text, grid_mm=0.05)
    assert coarse.cutting_s <= fine.cutting_s * (1 + 1e-6)
    assert coarse.cutting_s == pytest.approx(fine.cutting_s, rel=2e-2)


@pytest.mark.parametrize("name", ["holes-val-000", "holes-test-000"])
def test_no_baseline_beats_the_bound_on_pecking_cycles(name):
    # Canned drilling cycles (G73 / G83 pecks) are short cuts between stops: the bound must stay below
    # every policy there too, the oracle included.
    from cnc_gym.benchmark.runner import BenchConfig, run_bench, suite_programs

    programs, _ = suite_programs("cnc-bench-v1", name.split("-")[1])
    program = [p for p in programs if p.name == name]
    policies = ["constant:2.0", "classical", "oracle", "bound"]
    records = run_bench(BenchConfig(programs=program, policies=policies, seeds=[0], machine="vmc-small",
                                    dialect="gsk25i", progress=False))  # fmt: skip
    bound = [r for r in records if r["reference"]]
    assert len(bound) == 1 and len(records) == 4
    for r in records:
        if r["finished"]:
            assert r["cycle_time_s"] >= r["bound_s"], r["policy"]
    # ... and stays close to the fastest of them: the bound is not loose by a whole grid interval per peck.
    fastest = min(r["cycle_time_s"] for r in records if r["finished"] and not r["reference"])
    assert fastest / bound[0]["bound_s"] < 1.5


BAD_CACHE_FILES = {
    "a list": "[]",
    "null": "null",
    "a string": '"fast"',
    "a number": "1.5",
    "NaN": None,  # the stored record with total_s NaN (json.dumps writes it by default)
    "Infinity": None,
    "a negative time": None,
    "a forged total_s": None,  # a plausible number, the digest left as it was
    "a forged total_s with the parts changed to match": None,
    "another version": None,
    "another key": None,
    "a bool for gridpoints": None,
    "an extra field": None,
    "deep nesting": "[" * 5000,
    "too large": " " * 10_000 + "{}",
}


def _tampered(record: dict, case: str) -> str:
    import json

    r = dict(record)
    if case == "NaN":
        r["total_s"] = math.nan
    elif case == "Infinity":
        r["total_s"] = math.inf
    elif case == "a negative time":
        r["rapid_s"] = -1.0
    elif case == "a forged total_s":
        r["total_s"] = record["total_s"] * 0.5
    elif case == "a forged total_s with the parts changed to match":
        r["total_s"] = record["total_s"] * 0.5
        r["cutting_s"] = record["cutting_s"] - 0.5 * record["total_s"]
    elif case == "another version":
        r["version"] = r["version"] + 1
    elif case == "another key":
        r["key"] = "0" * 64
    elif case == "a bool for gridpoints":
        r["gridpoints"] = True
    elif case == "an extra field":
        r["note"] = "hi"
    return json.dumps(r)


@pytest.mark.parametrize("case", sorted(BAD_CACHE_FILES))
def test_a_bad_cache_file_is_recomputed_with_one_notice(tmp_path, monkeypatch, case):
    import json

    from cnc_gym.motion import bound

    monkeypatch.setenv("CNC_GYM_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(bound, "_MEMORY", {})
    tp = interpret("G90 G21\nG01 X10 Y2 F1200\nG00 Z5\nG04 P200\nM30\n")
    first = time_optimal_bound(tp, VMC)
    (path,) = (tmp_path / "bound").glob("*.json")
    record = json.loads(path.read_text())
    assert record["key"] == path.stem and bound.check_cache_record(record, path.stem) == first
    text = BAD_CACHE_FILES[case]
    path.write_text(text if text is not None else _tampered(record, case))
    monkeypatch.setattr(bound, "_MEMORY", {})
    notices: list[str] = []
    again = time_optimal_bound(tp, VMC, notice=notices.append)
    assert again.total_s == pytest.approx(first.total_s, rel=1e-9)
    assert len(notices) == 1 and str(path) in notices[0] and "\n" not in notices[0], notices
    # ... and the file is rewritten: the next read uses it, silently.
    monkeypatch.setattr(bound, "_MEMORY", {})
    notices.clear()
    monkeypatch.setattr(bound, "compute_bound", lambda *a, **k: pytest.fail("not read from the cache"))
    assert time_optimal_bound(tp, VMC, notice=notices.append) == again and notices == []


def test_a_cache_file_under_another_programs_key_is_not_used(tmp_path, monkeypatch):
    from cnc_gym.motion import bound

    monkeypatch.setenv("CNC_GYM_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(bound, "_MEMORY", {})
    short, long = interpret("G01 X10 F1200\nM30\n"), interpret("G01 X100 F1200\nM30\n")
    time_optimal_bound(short, VMC)
    (short_file,) = (tmp_path / "bound").glob("*.json")
    # The short program's valid record, copied under the long program's key.
    long_file = short_file.with_name(f"{bound.bound_key(long, VMC)}.json")
    long_file.write_text(short_file.read_text())
    monkeypatch.setattr(bound, "_MEMORY", {})
    notices: list[str] = []
    result = time_optimal_bound(long, VMC, notice=notices.append)
    assert result.total_s == pytest.approx(compute_bound(long, VMC).total_s, rel=1e-9)
    assert result.total_s > 2 * time_optimal_bound(short, VMC).total_s
    assert len(notices) == 1 and "another program or machine" in notices[0]
