"""The LTI servo plant against closed forms and an independent continuous-time simulation.

Notation: v path speed (mm/s), Kv position gain (1/s), f velocity feed-forward fraction, T = 2 ms sample
period. Expected values are derived in each test from the transfer functions, not from the plant code.

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy import signal

from cnc_gym.errors import ConfigError
from cnc_gym.machine import AxisConfig, ControllerConfig, MachineConfig, load_machine
from cnc_gym.plant import ServoPlant
from cnc_gym.plant.servo import MAX_LIFTED_TICKS

PERIOD = 0.002
F5000 = 5000.0 / 60.0  # mm/s


def make_machine(kv=(30.0, 30.0, 30.0), feedforward=0.0, velocity_loop_hz=0.0, damping=0.7,
                 post_filter_s=0.0) -> MachineConfig:  # fmt: skip
    axes = tuple(
        AxisConfig(kv_1_s=k, feedforward=feedforward, velocity_loop_hz=velocity_loop_hz,
                   velocity_loop_damping=damping)
        for k in kv
    )  # fmt: skip
    controller = ControllerConfig(interpolation_period_s=PERIOD, post_filter_s=post_filter_s)
    return MachineConfig(name="test", controller=controller, axes=axes)  # type: ignore[arg-type]


def ramp_reference(speed_xyz, seconds: float) -> np.ndarray:
    """Constant-velocity reference from the origin, one row per sample t = T, 2T, …"""
    t = np.arange(1, round(seconds / PERIOD) + 1) * PERIOD
    return t[:, None] * np.asarray(speed_xyz, dtype=float)[None, :]


def circle_reference(radius: float, speed: float, seconds: float) -> np.ndarray:
    """Analytic constant-speed CCW circle about the origin starting at (R, 0), sampled at t = T, 2T, …"""
    t = np.arange(1, round(seconds / PERIOD) + 1) * PERIOD
    omega = speed / radius
    return np.stack((radius * np.cos(omega * t), radius * np.sin(omega * t), np.zeros_like(t)), axis=1)


# ---------------------------------------------------------------------------------------- following error
def test_p_loop_following_error_on_a_long_line_is_v_over_kv():
    # E/R = s/(s + Kv); a ramp R = v/s² leaves e_ss = lim s→0 s·E = v/Kv = 83.33/30 = 2.7778 mm per axis
    # component. The transient decays as e^(−Kv t): after 1 s it is e^(−30) ≈ 1e−13 of the lag.
    plant = ServoPlant(load_machine("p-loop-30"))
    direction = np.array([3.0, 4.0, 0.0]) / 5.0
    ref = ramp_reference(F5000 * direction, 1.0)
    actual = plant.step(ref)
    lag = ref[-1] - actual[-1]
    np.testing.assert_allclose(lag, F5000 * direction / 30.0, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(plant.following_error[0]), 2.777777777, rtol=1e-8)
    np.testing.assert_allclose(plant.velocity[0], F5000 * direction, rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize("feedforward", [0.3, 0.7, 1.0])
def test_feedforward_reduces_lag_to_one_minus_f(feedforward):
    # X/R = (Kv + f s)/(s + Kv) ⇒ E/R = (1 − f) s/(s + Kv) ⇒ ramp lag (1 − f)·v/Kv. f = 1 tracks exactly.
    kv = 30.0
    plant = ServoPlant(make_machine(kv=(kv,) * 3, feedforward=feedforward))
    ref = ramp_reference((F5000, 0.0, 0.0), 1.0)
    actual = plant.step(ref)
    expected = (1.0 - feedforward) * F5000 / kv
    assert ref[-1, 0] - actual[-1, 0] == pytest.approx(expected, rel=1e-9, abs=1e-9)


def test_velocity_loop_steady_state_lag_and_rest():
    # With a velocity loop V/U = ωn²/(s² + 2ζωn s + ωn²) the steady state still has ẋ = u, so on a ramp
    # Kv·e + f·v = v ⇒ e = (1 − f) v/Kv, the same as the ideal loop (the loop has one integrator).
    kv, ff = 40.0, 0.7
    plant = ServoPlant(make_machine(kv=(kv,) * 3, feedforward=ff, velocity_loop_hz=60.0))
    ref = ramp_reference((F5000, -F5000, 0.0), 1.0)
    actual = plant.step(ref)
    np.testing.assert_allclose(ref[-1] - actual[-1], [(1 - ff) * F5000 / kv, -(1 - ff) * F5000 / kv, 0.0],
                               rtol=1e-7, atol=1e-9)  # fmt: skip
    # Then hold the reference: a type-1 loop comes to rest exactly on it.
    hold = np.repeat(ref[-1:], 1000, axis=0)
    actual = plant.step(hold)
    np.testing.assert_allclose(actual[-1], ref[-1], atol=1e-9)
    np.testing.assert_allclose(plant.velocity[0], 0.0, atol=1e-7)


@pytest.mark.parametrize(
    ("velocity_loop_hz", "feedforward"), [(0.0, 0.0), (0.0, 0.6), (40.0, 0.0), (60.0, 0.7)]
)
def test_matches_independent_continuous_simulation(velocity_loop_hz, feedforward):
    # Independent check of the discretisation: scipy.signal.lsim of the continuous transfer function,
    # with linear interpolation of the input between samples (the plant's first-order hold). The
    # feed-forward uses ṙ, so it enters the numerator:
    #   ideal loop:     X/R = (f s + Kv)/(s + Kv)
    #   velocity loop:  X/R = ωn²(f s + Kv) / (s³ + 2ζωn s² + ωn² s + ωn² Kv)
    kv, zeta = 35.0, 0.7
    rng = np.random.default_rng(1)
    n = 600
    knots = np.cumsum(rng.normal(0.0, 0.3, n))  # an arbitrary piecewise-linear reference, mm
    t = np.arange(n + 1) * PERIOD
    r = np.concatenate(([0.0], knots))
    numerator = [feedforward, kv] if feedforward else [kv]
    if velocity_loop_hz:
        wn = 2 * np.pi * velocity_loop_hz
        system = signal.lti(np.multiply(numerator, wn * wn), [1.0, 2 * zeta * wn, wn * wn, wn * wn * kv])
    else:
        system = signal.lti(numerator, [1.0, kv])
    _, expected, _ = signal.lsim(system, r, t, interp=True)
    plant = ServoPlant(make_machine(kv=(kv,) * 3, feedforward=feedforward, velocity_loop_hz=velocity_loop_hz,
                                    damping=zeta))  # fmt: skip
    ref = np.zeros((n, 3))
    ref[:, 1] = knots
    actual = plant.step(ref)
    np.testing.assert_allclose(actual[:, 1], expected[1:], atol=1e-9 * max(1.0, np.abs(knots).max()))


def test_post_filter_adds_half_its_length_to_the_lag():
    # A moving average over N samples of a ramp equals the ramp delayed by (N − 1)·T/2, so the total lag
    # is v/Kv + v·(N − 1)·T/2. post_filter_s = 0.02 s at T = 2 ms ⇒ N = 10 ⇒ extra 83.33·0.009 = 0.75 mm.
    kv = 30.0
    plant = ServoPlant(make_machine(kv=(kv,) * 3, post_filter_s=0.02))
    assert plant.filter_samples == 10
    ref = ramp_reference((F5000, 0.0, 0.0), 1.5)
    actual = plant.step(ref)
    assert ref[-1, 0] - actual[-1, 0] == pytest.approx(F5000 / kv + F5000 * 9 * PERIOD / 2, rel=1e-9)


# ---------------------------------------------------------------------------------------- circle error
def test_circle_radial_error_p_loop_30():
    # P loop: each axis is a first-order lag; a sinusoid of angular rate ω = v/R keeps amplitude ratio
    # 1/√(1 + (ω/Kv)²), so the circle shrinks by Δr = R(1 − 1/√(1 + (v/(R Kv))²)) ≈ v²/(2 R Kv²).
    # R = 50 mm, F5000 (v = 83.33 mm/s), Kv = 30: v²/(2 R Kv²) = 6944.4/90000 = 0.07716 mm (77 µm);
    # the exact continuous value is 0.076982 mm. The reference (chords of 0.167 mm) sags 0.07 µm.
    plant = ServoPlant(load_machine("p-loop-30"))
    radius = 50.0
    plant.reset([radius, 0.0, 0.0])
    ref = circle_reference(radius, F5000, 8.0)  # > 2 turns; transient e^(−30 t) gone after 1 s
    actual = plant.step(ref)
    steady = actual[round(2.0 / PERIOD) :]
    radial_error = radius - np.hypot(steady[:, 0], steady[:, 1])
    approx = F5000**2 / (2 * radius * 30.0**2)
    assert approx == pytest.approx(0.0772, abs=1e-4)
    assert radial_error.mean() == pytest.approx(approx, rel=0.10)
    exact = radius * (1 - 1 / np.sqrt(1 + (F5000 / (radius * 30.0)) ** 2))
    np.testing.assert_allclose(radial_error, exact, atol=2e-4)  # within 0.2 µm all round
    assert np.ptp(radial_error) < 1e-6  # matched gains: a true circle


def test_circle_with_kv_mismatch_varies_between_bounds():
    # Kvx = 30, Kvy = 33 1/s: each axis is a first-order lag with gain a_i = 1/√(1 + (ω/Kv_i)²) and
    # phase φ_i = atan(ω/Kv_i), so the steady path is (R a_x cos(ωt − φ_x), R a_y sin(ωt − φ_y)): a tilted
    # ellipse. Half the spread of its radius ≈ (v/2)|1/Kvx − 1/Kvy| = 41.67·0.0030303 = 0.1263 mm (§C1).
    kv_x, kv_y, radius = 30.0, 33.0, 50.0
    plant = ServoPlant(make_machine(kv=(kv_x, kv_y, 30.0)))
    plant.reset([radius, 0.0, 0.0])
    ref = circle_reference(radius, F5000, 8.0)
    actual = plant.step(ref)
    t = np.arange(1, len(ref) + 1) * PERIOD
    omega = F5000 / radius
    gain = [1 / np.sqrt(1 + (omega / k) ** 2) for k in (kv_x, kv_y)]
    phase = [np.arctan(omega / k) for k in (kv_x, kv_y)]
    expected = np.stack((radius * gain[0] * np.cos(omega * t - phase[0]),
                         radius * gain[1] * np.sin(omega * t - phase[1])), axis=1)  # fmt: skip
    steady = slice(round(2.0 / PERIOD), None)
    np.testing.assert_allclose(actual[steady, :2], expected[steady], atol=2e-4)
    radial_error = radius - np.hypot(actual[steady, 0], actual[steady, 1])
    half_spread = np.ptp(radial_error) / 2
    assert half_spread == pytest.approx(F5000 / 2 * abs(1 / kv_x - 1 / kv_y), rel=0.10)
    # §C4 lists −196 … +55 µm (radius actual − programmed) for this case.
    assert -radial_error.max() == pytest.approx(-0.196, abs=0.005)
    assert -radial_error.min() == pytest.approx(0.055, abs=0.005)


# ---------------------------------------------------------------------------------------- batching, API
def test_batched_envs_match_single_envs_and_chunking_matches_tick_by_tick():
    machine = load_machine("vmc-small")  # unequal Kv, feed-forward and a velocity loop: all paths used
    rng = np.random.default_rng(7)
    n_envs, n_ticks = 4, 3 * MAX_LIFTED_TICKS + 5  # forces the chunked path
    ref = np.cumsum(rng.normal(0.0, 0.05, (n_envs, n_ticks, 3)), axis=1)
    start = rng.normal(0.0, 1.0, (n_envs, 3))
    batched = ServoPlant(machine, n_envs=n_envs)
    batched.reset(start)  # at rest at the start points
    out = batched.step(ref + start[:, None, :])
    for env in range(n_envs):
        single = ServoPlant(machine)
        single.reset(start[env])
        one_by_one = np.concatenate([single.step(ref[env, k : k + 1] + start[env]) for k in range(n_ticks)])
        np.testing.assert_allclose(out[env], one_by_one, rtol=0, atol=1e-10)
        np.testing.assert_allclose(batched.velocity[env], single.velocity[0], atol=1e-8)
        np.testing.assert_allclose(batched.position[env], single.position[0], atol=1e-10)


def test_reset_rest_and_settled():
    plant = ServoPlant(load_machine("p-loop-30"), n_envs=2)
    plant.reset(np.array([[1.0, 2.0, 3.0], [0.0, 0.0, 0.0]]))
    assert plant.settled(0.001).all()
    # Holding the reset position keeps the axes exactly there.
    out = plant.step(np.repeat(np.array([[[1.0, 2.0, 3.0]], [[0.0, 0.0, 0.0]]]), 5, axis=1))
    np.testing.assert_allclose(out[0], np.tile([1.0, 2.0, 3.0], (5, 1)), rtol=0, atol=1e-12)
    # Env 0 moves 10 mm in X over 0.1 s; env 1 stays.
    move = np.zeros((2, 50, 3))
    move[0] = [1.0, 2.0, 3.0]
    move[0, :, 0] += np.linspace(0.2, 10.0, 50)
    plant.step(move)
    assert plant.settled(0.001).tolist() == [False, True]
    # Hold the end: the error decays as e^(−30 t). From ≈ 6.7 mm (v/Kv with v = 200 mm/s) to 1 µm
    # takes ln(6700)/30 ≈ 0.29 s, so after 0.2 s it is not settled and after 0.5 s it is.
    hold = np.repeat(move[:, -1:, :], 100, axis=1)
    plant.step(hold)
    assert plant.settled(0.001).tolist() == [False, True]
    plant.step(np.repeat(hold[:, -1:, :], 150, axis=1))
    assert plant.settled(0.001).all()
    np.testing.assert_allclose(plant.following_error, 0.0, atol=1e-3)


def test_gsk25i_following_error():
    # P4209 = 245 1/s, P4210 = 0 %: at P1225 = 4000 mm/min the lag is 66.67/245 = 0.2721 mm (§3.1).
    plant = ServoPlant(load_machine("gsk25i"))
    ref = ramp_reference((4000 / 60, 0, 0), 0.3)
    plant.step(ref)
    assert plant.following_error[0, 0] == pytest.approx(0.27211, rel=1e-4)


def test_single_env_shapes_and_bad_input():
    plant = ServoPlant("p-loop-30")
    assert plant.step(np.zeros((5, 3))).shape == (5, 3)
    assert plant.step(np.zeros((1, 5, 3))).shape == (1, 5, 3)
    assert plant.step(np.zeros((0, 3))).shape == (0, 3)
    with pytest.raises(ValueError, match="n_ticks, 3"):
        plant.step(np.zeros((5, 2)))
    with pytest.raises(ValueError, match="finite"):
        plant.step(np.full((2, 3), np.nan))
    with pytest.raises(ValueError, match="finite"):
        plant.reset([np.inf, 0.0, 0.0])
    batched = ServoPlant("p-loop-30", n_envs=3)
    with pytest.raises(ValueError, match="n_envs=3"):
        batched.step(np.zeros((5, 3)))
    with pytest.raises(ValueError):
        ServoPlant("p-loop-30", n_envs=0)
    # A NaN reference is refused before it reaches the state: the plant keeps working.
    np.testing.assert_array_equal(plant.position, 0.0)


def test_other_interpolation_period_keeps_closed_form():
    # The discretisation follows the machine's interpolation period: at T = 1 ms the ramp lag is still v/Kv.
    machine = load_machine("p-loop-30")
    machine = dataclasses.replace(machine, controller=dataclasses.replace(machine.controller,
                                                                          interpolation_period_s=0.001))
    plant = ServoPlant(machine)
    t = np.arange(1, 1001) * 0.001
    ref = np.stack((F5000 * t, 0 * t, 0 * t), axis=1)
    actual = plant.step(ref)
    assert ref[-1, 0] - actual[-1, 0] == pytest.approx(F5000 / 30.0, rel=1e-9)


def test_creeping_reference_is_not_settled():
    # A reference creeping at 0.01 mm/s: the P loop lags 0.01/30 = 0.33 µm and moves at 0.01 mm/s
    # (< Kv·tol = 0.03 mm/s), so only the "reference at rest" condition can tell it is not settled.
    plant = ServoPlant(load_machine("p-loop-30"))
    ref = ramp_reference((0.01, 0.0, 0.0), 1.0)
    plant.step(ref)
    assert np.linalg.norm(plant.following_error) < 1e-3
    assert not plant.settled(1e-3)[0]
    plant.step(np.repeat(ref[-1:], 10, axis=0))
    assert plant.settled(1e-3)[0]


def test_unstable_servo_config_is_a_config_error():
    # Routh-Hurwitz on s³ + 2ζωn s² + ωn² s + ωn² Kv: stable iff Kv < 2ζωn. At 10 Hz, ζ = 0.7:
    # 2·0.7·62.83 = 88 1/s, so Kv = 80 is stable and Kv = 100 is not.
    ServoPlant(make_machine(kv=(80.0, 30.0, 30.0), velocity_loop_hz=10.0))
    with pytest.raises(ConfigError, match=r"axes\.x: the servo loop is unstable"):
        ServoPlant(make_machine(kv=(100.0, 30.0, 30.0), velocity_loop_hz=10.0))
    with pytest.raises(ConfigError, match=r"axes\.y"):
        ServoPlant(make_machine(kv=(80.0, 100.0, 30.0), velocity_loop_hz=10.0))
    # No damping: the velocity loop alone is marginal, any Kv > 0 destabilises it.
    with pytest.raises(ConfigError, match=r"damping = 0\.0"):
        ServoPlant(make_machine(kv=(1.0, 1.0, 1.0), velocity_loop_hz=10.0, damping=0.0))


def test_per_env_kv_scale_equals_a_machine_with_those_gains():
    # Env 1 scales Y's Kv by 1.1 (30 → 33): it must behave exactly like a plant built from a preset
    # with Kv (30, 33, 30), while env 0 stays the plain p-loop-30.
    base = load_machine("p-loop-30")
    rng = np.random.default_rng(5)
    ref = np.cumsum(rng.normal(0.0, 0.1, (2, 40, 3)), axis=1)
    plant = ServoPlant(base, n_envs=2)
    plant.step(ref[:, :7])  # caches a lifted matrix before the change: it must be updated too
    plant.reset(np.zeros(3))
    plant.set_kv_scale([1.0, 1.1, 1.0], env=1)
    np.testing.assert_allclose(plant.kv_1_s, [[30, 30, 30], [30, 33, 30]])
    out = np.concatenate([plant.step(ref[:, k : k + 7]) for k in range(0, 40, 7)], axis=1)
    plain = ServoPlant(base)
    mismatched = ServoPlant(make_machine(kv=(30.0, 33.0, 30.0)))
    np.testing.assert_allclose(out[0], plain.step(ref[0]), atol=1e-12)
    np.testing.assert_allclose(out[1], mismatched.step(ref[1]), atol=1e-12)
    # Setting the same scale everywhere returns to the shared model (and the same results).
    plant.set_kv_scale([1.0, 1.1, 1.0])
    plant.reset(np.zeros(3))
    again = plant.step(ref)
    for env in range(2):
        np.testing.assert_allclose(again[env], ServoPlant(make_machine(kv=(30.0, 33.0, 30.0))).step(ref[env]),
                                   atol=1e-12)  # fmt: skip
    # Construction with per-env scales.
    direct = ServoPlant(base, n_envs=2, kv_scale=[[1.0, 1.0, 1.0], [1.0, 1.1, 1.0]])
    mismatched = ServoPlant(make_machine(kv=(30.0, 33.0, 30.0)))
    expected = np.stack((ServoPlant(base).step(ref[0]), mismatched.step(ref[1])))
    np.testing.assert_allclose(direct.step(ref), expected, atol=1e-12)


def test_bad_kv_scale():
    plant = ServoPlant("p-loop-30", n_envs=2)
    with pytest.raises(ConfigError, match="positive"):
        plant.set_kv_scale([1.0, 0.0, 1.0])
    with pytest.raises(ConfigError, match="positive"):
        plant.set_kv_scale([1.0, np.nan, 1.0], env=0)
    with pytest.raises(ValueError, match="kv_scale"):
        plant.set_kv_scale(np.ones((3, 3)))
    with pytest.raises(ValueError, match="out of range"):
        plant.set_kv_scale(np.ones(3), env=2)
    # A scale that makes a velocity loop unstable is refused like an unstable preset.
    loop = ServoPlant(make_machine(kv=(80.0, 30.0, 30.0), velocity_loop_hz=10.0))
    with pytest.raises(ConfigError, match="unstable"):
        loop.set_kv_scale([1.5, 1.0, 1.0])
