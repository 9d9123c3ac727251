"""The planner's servo error model and its tables, against the plant and closed forms."""

from __future__ import annotations

import math

import numpy as np
import pytest

from cnc_gym.machine import load_machine
from cnc_gym.motion.planner import ServoErrorModel, arc_caps, corner_error_per_speed, servo_tables
from cnc_gym.plant import ServoPlant


def _simulated_circle_error(machine_name: str, radius: float, speed: float) -> float:
    """Run a circle reference through the real plant; steady radial error over the last revolution."""
    machine = load_machine(machine_name)
    period = machine.controller.interpolation_period_s
    omega = speed / radius
    t = np.arange(0.0, 5 * 2 * np.pi / omega + 2.0, period)
    ref = np.stack([radius * np.cos(omega * t), radius * np.sin(omega * t), np.zeros_like(t)], axis=1)
    plant = ServoPlant(machine)
    plant.reset(ref[0])
    actual = plant.step(ref)
    last = t > t[-1] - 2 * np.pi / omega
    return float(np.max(np.abs(np.hypot(actual[last, 0], actual[last, 1]) - radius)))


def test_p_loop_circle_matches_textbook_closed_form():
    # p-loop-30: Kv = 30 1/s, f = 0: radial error = R(1 − 1/√(1 + (v/(R·Kv))²)) ≈ v²/(2·R·Kv²).
    model = ServoErrorModel(load_machine("p-loop-30"))
    radius, speed = 50.0, 5000.0 / 60.0
    exact = radius * (1.0 - 1.0 / math.sqrt(1.0 + (speed / (radius * 30.0)) ** 2))
    assert model.arc_error(speed, radius, 0)[0] == pytest.approx(exact, rel=1e-9)
    assert exact == pytest.approx(speed**2 / (2 * radius * 30.0**2), rel=0.01)  # 77 µm


@pytest.mark.parametrize("machine_name", ["p-loop-30", "vmc-small", "gsk25i", "h4cm"])
@pytest.mark.parametrize(("radius", "speed"), [(25.0, 4000.0 / 60.0), (10.0, 100.0)])
def test_arc_error_model_matches_the_plant(machine_name, radius, speed):
    # vmc-small has feed-forward 0.7, a 60 Hz velocity loop and Kv 40/38 (mismatch): no textbook form,
    # so the model is checked against the plant simulated sample by sample.
    predicted = ServoErrorModel(load_machine(machine_name)).arc_error(speed, radius, 0)[0]
    simulated = _simulated_circle_error(machine_name, radius, speed)
    assert predicted == pytest.approx(simulated, rel=0.06, abs=2e-4)


def test_ff_reduces_circle_error_by_one_minus_f_squared():
    # Ideal velocity loop, matched Kv, FF fraction f: |G|² = (Kv² + f²ω²)/(Kv² + ω²), so the radial
    # error is ≈ (1 − f²)·v²/(2·R·Kv²) — 0.51 × the plain P loop's at f = 0.7.
    from cnc_gym.machine import machine_from_dict

    base = {"axis_defaults": {"kv_1_s": 30, "velocity_loop_hz": 0}}
    plain = ServoErrorModel(machine_from_dict(base))
    with_ff = ServoErrorModel(
        machine_from_dict({"axis_defaults": {**base["axis_defaults"], "feedforward": 0.7}})
    )
    radius, speed = 50.0, 30.0
    ratio = with_ff.arc_error(speed, radius, 0)[0] / plain.arc_error(speed, radius, 0)[0]
    assert ratio == pytest.approx(1 - 0.7**2, rel=0.01)


def test_line_lateral_error_from_gain_mismatch():
    # Steady lag per axis (1 − f)·v/Kv; on a 45° line with Kv 40 / 38, f = 0.7 the sideways part is
    # (1 − f)·v·(1/38 − 1/40)/2 (the lag vector's component normal to the line).
    model = ServoErrorModel(load_machine("vmc-small"))
    tangent = np.array([[1.0, 1.0, 0.0]]) / math.sqrt(2.0)
    expected_per_speed = 0.3 * (1 / 38 - 1 / 40) / 2
    assert model.line_error_per_speed(tangent)[0] == pytest.approx(expected_per_speed, rel=1e-9)
    # Axis-parallel lines have no sideways error.
    assert model.line_error_per_speed(np.array([[1.0, 0.0, 0.0]]))[0] == pytest.approx(0.0, abs=1e-15)
    # And the plant agrees: ramp along the diagonal at 100 mm/s, lateral offset once settled.
    machine = load_machine("vmc-small")
    t = np.arange(0.0, 3.0, machine.controller.interpolation_period_s)
    ref = 100.0 * t[:, None] * tangent
    plant = ServoPlant(machine)
    plant.reset(ref[0])
    actual = plant.step(ref)[-1]
    lateral = np.linalg.norm(actual - (actual @ tangent[0]) * tangent[0])
    assert lateral == pytest.approx(100.0 * expected_per_speed, rel=0.01)


def test_ramp_error_response_of_a_p_loop_is_the_closed_form():
    # P loop, no feed-forward, ideal velocity loop: after a unit velocity step the following error is
    # (1 − e^(−Kv·t))/Kv, which settles at the steady lag 1/Kv.
    tables = servo_tables(load_machine("p-loop-30"))
    expected = (1.0 - np.exp(-30.0 * tables.ramp_t)) / 30.0
    np.testing.assert_allclose(tables.ramp_error[0], expected, atol=1e-9)
    assert tables.lag_s[0] == pytest.approx(1 / 30)


def test_arc_table_matches_the_bisection_of_the_model():
    machine = load_machine("vmc-small")
    tables, model = servo_tables(machine), ServoErrorModel(machine)
    for radius in (0.5, 5.0, 40.0):
        cap = arc_caps(tables, np.array([radius]), np.array([0]), 0.014)[0]
        assert cap == pytest.approx(model.arc_speed_cap(radius, 0, 0.014), rel=0.02)


def test_corner_error_of_a_p_loop():
    tables = servo_tables(load_machine("p-loop-30"))  # matched axes: no sideways lag on lines
    turns = np.radians([0.0, 30.0, 60.0, 90.0, 120.0, 180.0])
    out = np.column_stack((np.cos(turns), np.sin(turns), np.zeros(len(turns))))
    c = corner_error_per_speed(tables, np.repeat([[1.0, 0.0, 0.0]], len(turns), axis=0), out)
    # Straight on, or straight back along the same line: the tool stays on the path.
    assert c[0] == pytest.approx(0.0, abs=1e-12) and c[-1] == pytest.approx(0.0, abs=1e-12)
    # Deepest at a right angle, symmetric about it, and less than the lag distance v/Kv.
    assert np.all(np.diff(c[:4]) > 0)
    assert c[2] == pytest.approx(c[4], rel=1e-9)
    assert c[3] < 1 / 30


# ------------------------------------------------------------------ the planner's fast corner routines
def _corner_case(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    a = rng.normal(size=3)
    b = rng.normal(size=3)
    return a / np.linalg.norm(a), b / np.linalg.norm(b)


@pytest.mark.parametrize("machine_name", ["vmc-small", "gsk25i", "p-loop-30"])
def test_fast_corner_routines_agree_with_the_full_model(machine_name):
    """corner_error_unit is corner_approach_error at unit speed without an approach, to the bit (the
    same operations in a loop of their own); corner_approach_exceeds says exactly whether the error
    passes a limit, from whichever grid index it starts; stop_above never hides a passing error."""
    from cnc_gym.motion.planner.error_model import (
        approach_tables,
        corner_approach_error,
        corner_approach_exceeds,
        corner_error_unit,
    )

    machine = load_machine(machine_name)
    tables, approach = servo_tables(machine), approach_tables(machine)
    grid = (tables.ramp_t, approach.ramp_error, approach.excess_integral, tables.lag_s)
    rng = np.random.default_rng()
    for _ in range(60):
        u_in, u_out = _corner_case(rng)
        full = corner_approach_error(u_in, u_out, 1.0, 0.0, 0.0, 0.0, *grid)
        assert corner_error_unit(u_in, u_out, tables.ramp_t, approach.ramp_error, tables.lag_s) == full
        speed, drop = 40.0 * rng.random(), 30.0 * rng.random()
        ramp, hold = 0.1 * rng.random() * (rng.random() < 0.8), 0.05 * rng.random()
        error = corner_approach_error(u_in, u_out, speed, drop, ramp, hold, *grid)
        assert math.isfinite(error) and error >= 0.0
        for limit in (0.5 * error, 0.999 * error, error, 1.001 * error):
            first = int(rng.integers(len(tables.ramp_t)))
            over = corner_approach_exceeds(u_in, u_out, speed, drop, ramp, hold, *grid, limit, first)
            assert (over >= 0) == (error > limit)
            stopped = corner_approach_error(u_in, u_out, speed, drop, ramp, hold, *grid, limit)
            assert (stopped > limit) == (error > limit)
            assert stopped <= error


def test_the_servo_response_is_kept_on_disk_and_a_kept_one_is_the_computed_one(tmp_path, monkeypatch):
    """A second process reads the ramp-error response from the cache (no scipy.signal import) and gets
    the bits a computation gives; a damaged file is computed again."""
    import os
    import subprocess
    import sys

    from cnc_gym.motion.planner import error_model

    monkeypatch.setenv("CNC_GYM_CACHE_DIR", str(tmp_path))
    machine = load_machine("vmc-small")
    model = error_model.ServoErrorModel(machine)
    t = np.linspace(0.0, 0.3, 160)
    computed = error_model._compute_ramp_error_response(model, t)
    first = error_model._ramp_error_response(model, t)  # computes and writes
    files = list((tmp_path / "servo").glob("*.npy"))
    assert len(files) == 1 and np.array_equal(first, computed)
    probe = ("import sys, numpy as np\nfrom cnc_gym.machine import load_machine\n"
             "from cnc_gym.motion.planner import error_model as em\n"
             "m = em.ServoErrorModel(load_machine('vmc-small'))\n"
             "out = em._ramp_error_response(m, np.linspace(0.0, 0.3, 160))\n"
             "print('scipy.signal' in sys.modules, out.tobytes().hex())\n")  # fmt: skip
    env = {**os.environ, "CNC_GYM_CACHE_DIR": str(tmp_path)}
    loaded, hexed = subprocess.run([sys.executable, "-c", probe], env=env, capture_output=True, text=True,
                                   check=True).stdout.split()  # fmt: skip
    assert loaded == "False" and bytes.fromhex(hexed) == computed.tobytes()
    files[0].write_bytes(b"not an array")  # damaged: computed again, and the file repaired
    assert np.array_equal(error_model._ramp_error_response(model, t), computed)
    assert np.array_equal(np.load(files[0]), computed)


def test_the_servo_response_cache_stays_bounded(tmp_path, monkeypatch):
    """A full cache folder (a randomised run draws a machine per episode) is read, never grown."""
    from cnc_gym.motion.planner import error_model

    monkeypatch.setenv("CNC_GYM_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(error_model, "MAX_CACHED_RESPONSES", 2)
    t = np.linspace(0.0, 0.3, 40)
    for kv in (30.0, 35.0, 40.0):
        model = error_model.ServoErrorModel(load_machine("vmc-small"))
        model.kv = np.full(3, kv)
        out = error_model._ramp_error_response(model, t)
        assert np.array_equal(out, error_model._compute_ramp_error_response(model, t))
    assert len(list((tmp_path / "servo").iterdir())) == 2
