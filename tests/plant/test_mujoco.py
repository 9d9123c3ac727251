"""The MuJoCo plant against the LTI plant, closed forms and the physics of friction and backlash.

Notation as tests/plant/test_servo.py: v path speed (mm/s), Kv position gain (1/s), f velocity feed-forward,
T = 2 ms sample period. Forces in N, stiffness in N/m unless said; positions in mm.
"""

from __future__ import annotations

import dataclasses
import math
import warnings

import numpy as np
import pytest

from cnc_gym.errors import ConfigError
from cnc_gym.machine import AxisMechanicsConfig, MachineConfig, load_machine, machine_from_dict
from cnc_gym.plant import ServoPlant
from cnc_gym.plant.mujoco import MujocoPlant

PERIOD = 0.002
F5000 = 5000.0 / 60.0  # mm/s


def with_mechanics(machine: MachineConfig | str, timestep_s: float | None = None,
                   **mechanics) -> MachineConfig:  # fmt: skip
    """``machine`` on the MuJoCo backend with ``mechanics`` set on every axis."""
    machine = load_machine(machine)
    axes = machine.plant.axes
    changed = {n: dataclasses.replace(getattr(axes, n), **mechanics) for n in ("x", "y", "z")}
    plant = dataclasses.replace(machine.plant, backend="mujoco", axes=dataclasses.replace(axes, **changed))
    if timestep_s is not None:
        plant = dataclasses.replace(plant, timestep_s=timestep_s)
    return dataclasses.replace(machine, plant=plant)


def rigid(machine: str, **kw) -> MachineConfig:
    """The preset with rigid, frictionless mechanics (what the LTI plant models)."""
    return with_mechanics(machine, coulomb_friction_n=0.0, viscous_damping_n_s_m=0.0,
                          coupling_stiffness_n_um=0.0, backlash_mm=0.0, velocity_integral_time_s=0.0,
                          **kw)  # fmt: skip


def circle(radius: float, speed: float, turns: float) -> np.ndarray:
    """CCW circle about the origin from (R, 0) at constant speed, sampled at t = T, 2T, …"""
    omega = speed / radius
    t = np.arange(1, round(turns * 2 * math.pi / omega / PERIOD) + 1) * PERIOD
    return np.stack((radius * np.cos(omega * t), radius * np.sin(omega * t), np.zeros_like(t)), axis=1)


def run_circle(plant, radius=50.0, speed=F5000, turns=2.0):
    """(reference angle in degrees, radial error in µm) over the last turn."""
    ref = circle(radius, speed, turns)
    plant.reset(ref[0] * 0 + [radius, 0, 0])
    actual = plant.step(ref)
    last = slice(len(ref) // 2, None)
    angle = np.degrees(np.arctan2(ref[last, 1], ref[last, 0])) % 360
    return angle, (np.hypot(actual[last, 0], actual[last, 1]) - radius) * 1e3


def near(angle: np.ndarray, centre: float, width: float) -> np.ndarray:
    return np.abs((angle - centre + 180) % 360 - 180) < width


# ------------------------------------------------------------------------------------- against the LTI plant
def test_p_loop_30_circle_matches_the_lti_plant_and_the_closed_form():
    # Steady radial error of a P loop on a circle: R(1 − 1/√(1 + (v/(R·Kv))²)) = 76.98 µm (≈ v²/(2R·Kv²)
    # = 77.2 µm); the LTI plant gives 77.03 µm. The issue asks for 5 %; the MuJoCo plant is within 0.5 %
    # (its ideal velocity loop follows the command with a time constant of 1/8 of a physics step).
    closed_form = 50 * (1 - 1 / math.sqrt(1 + (F5000 / (50 * 30)) ** 2)) * 1e3
    machine = rigid("p-loop-30")
    _, lti = run_circle(ServoPlant(machine))
    _, mj = run_circle(MujocoPlant(machine))
    assert np.ptp(mj) < 1e-3  # constant round the circle
    assert mj.mean() == pytest.approx(lti.mean(), rel=0.005)
    assert -mj.mean() == pytest.approx(closed_form, rel=0.005)
    assert -mj.mean() == pytest.approx(77.0, rel=0.05)


def test_lagged_velocity_loop_matches_the_lti_plant_to_second_order():
    # vmc-small: Kv 40/38/45, f 0.7, 60 Hz ζ 0.7 velocity loop. The whole trajectory (start from rest
    # into a full-speed circle, two turns) agrees with the LTI plant's exact discretisation, and halving
    # the physics step divides the difference by about 4 (second order).
    ref = circle(50.0, F5000, 2.0)
    errors = []
    for timestep in (0.001, 0.0005):
        machine = rigid("vmc-small", timestep_s=timestep)
        lti, mj = ServoPlant(machine), MujocoPlant(machine)
        for p in (lti, mj):
            p.reset([50.0, 0, 0])
        errors.append(np.abs(mj.step(ref) - lti.step(ref)).max())
    assert errors[1] < 1e-3  # mm: under 1 µm, on a 33 µm band of radial error
    assert 3.0 < errors[0] / errors[1] < 5.0


@pytest.mark.parametrize("preset", ["p-loop-30", "vmc-small"])
def test_ramp_lag_is_the_closed_form(preset):
    # A ramp leaves (1 − f)·v/Kv of lag in every axis (type-1 loop): 2.7778 mm on p-loop-30, 0.3·83.33/40 =
    # 0.625 mm on vmc-small's X.
    machine = rigid(preset)
    kv, f = machine.axes[0].kv_1_s, machine.axes[0].feedforward
    t = np.arange(1, 1001) * PERIOD
    ref = np.stack((F5000 * t, 0 * t, 0 * t), axis=1)
    plant = MujocoPlant(machine)
    actual = plant.step(ref)
    assert ref[-1, 0] - actual[-1, 0] == pytest.approx((1 - f) * F5000 / kv, rel=1e-7)
    np.testing.assert_allclose(plant.following_error[0], ref[-1] - actual[-1], atol=1e-12)


@pytest.mark.parametrize("preset", ["p-loop-30", "vmc-small"])
def test_step_response_matches_the_lti_plant(preset):
    machine = rigid(preset)
    ref = np.zeros((400, 3))
    ref[:, 1] = 1.0
    lti, mj = ServoPlant(machine).step(ref), MujocoPlant(machine).step(ref)
    np.testing.assert_allclose(mj, lti, atol=2e-3)  # mm, on a 1 mm step
    assert mj[-1, 1] == pytest.approx(1.0, abs=1e-6)


# ------------------------------------------------------------------------------------------ friction
# The P-loop friction tests build such machines on purpose.
P_LOOP_FRICTION = pytest.mark.filterwarnings("ignore:.*with a P velocity loop the Coulomb friction")


def _glitch_machine(friction_n: float, integral_s: float) -> MachineConfig:
    return with_mechanics(rigid("vmc-small"), coulomb_friction_n=friction_n,
                          velocity_integral_time_s=integral_s)  # fmt: skip


def _friction_deviation(friction_n: float, integral_s: float):
    """(angle, radial error with friction − without, µm, the plant) on a circle R50 F5000."""
    angle, base = run_circle(MujocoPlant(_glitch_machine(0.0, integral_s)))
    plant = MujocoPlant(_glitch_machine(friction_n, integral_s))
    _, with_friction = run_circle(plant)
    return angle, with_friction - base, plant


@P_LOOP_FRICTION
def test_coulomb_friction_with_a_p_velocity_loop_offsets_by_friction_over_loop_stiffness():
    # The estimate. The P velocity loop makes a force Kp·(u − v) with u = Kv·e (plus feed-forward), so
    # holding a friction force F needs a following error F/(Kp·Kv): the loop is a spring of stiffness
    # K = Kp·Kv (Kp = m·ωn/(2ζ)). On the circle an axis's friction force flips at its reversal (X at 0° and
    # 180°, Y at 90° and 270°): there the reversing axis is radial, and its friction offset F/K (which
    # points against its motion, so it changes sign there) is all radial. The radial error at a reversal
    # therefore differs from the friction-free circle's by F/K of the reversing axis.
    friction = 100.0
    angle, deviation, plant = _friction_deviation(friction, 0.0)
    stiffness = plant.loop_stiffness_n_m[0]  # N/m per axis
    for axis, reversals in ((0, (0, 180)), (1, (90, 270))):
        estimate_um = friction / stiffness[axis] * 1e6
        for centre in reversals:
            peak = np.abs(deviation[near(angle, centre, 5)]).max()
            assert peak == pytest.approx(estimate_um, rel=0.05)


def test_quadrant_glitches_appear_at_the_four_reversals_only_and_grow_with_friction():
    # With a PI velocity loop (reset time 10 ms) the integral takes the friction over, so the error is a
    # spike right after each axis reversal (a quadrant glitch) and vanishes between them. Its size is
    # bounded by the P loop's F/K (the integral only shortens it): the spike reaches about half of F/K
    # before the integral catches up. It grows with the friction, slightly less than in proportion (twice
    # the friction gives 1.9 times the spike: the axis sticks a little longer at the reversal).
    peaks = {}
    for friction in (60.0, 120.0):
        angle, deviation, plant = _friction_deviation(friction, 0.01)
        stiffness = plant.loop_stiffness_n_m[0]
        peaks[friction] = []
        for axis, centre in ((0, 0), (1, 90), (0, 180), (1, 270)):
            window = (angle >= centre) & near(angle, centre + 5, 5)  # within 10° after the reversal
            peak = np.abs(deviation[window]).max()
            bound_um = friction / stiffness[axis] * 1e6
            assert 0.3 * bound_um < peak < bound_um
            peaks[friction].append(peak)
        away = np.ones_like(angle, dtype=bool)
        for centre in (0, 90, 180, 270):
            away &= ~((angle >= centre - 2) & near(angle, centre + 14, 16))  # from 2° before to 30° after
        assert np.abs(deviation[away]).max() < 0.01 * min(peaks[friction])
    ratios = np.array(peaks[120.0]) / np.array(peaks[60.0])
    assert np.all((ratios > 1.8) & (ratios < 2.05))


@P_LOOP_FRICTION
def test_friction_holds_an_axis_against_a_smaller_force():
    # MuJoCo's frictionloss is dry friction: with a 200 N friction force and a loop that can only push
    # with Kp·Kv·e (a 10 µm move of a P loop with K = 3.2 N/µm: at most 32 N) the table stays put, but
    # for a creep of about half a micrometre in a second (MuJoCo's friction is a stiff soft constraint; real
    # guides show a few µm of such pre-sliding displacement). Without friction it goes the whole 10 µm.
    ref = np.zeros((500, 3))
    ref[:, 0] = 0.010
    held = MujocoPlant(_glitch_machine(200.0, 0.0)).step(ref)
    free = MujocoPlant(_glitch_machine(0.0, 0.0)).step(ref)
    assert abs(held[-1, 0]) < 1e-3
    assert free[-1, 0] == pytest.approx(0.010, abs=1e-6)


# ------------------------------------------------------------------------------------------ backlash
def test_backlash_at_a_reversal_lags_by_the_dead_band():
    # A semi-closed axis (encoder on the motor) with a dead band b between motor and load and guideway
    # friction F: moving forward the motor drags the load at the far side of the gap, load − motor =
    # −(b/2 + F/k); after the reversal it pushes from the other side, +(b/2 + F/k). The load's position
    # jumps by b + 2F/k relative to the motor (the motor follows the reference as before: the PI loop
    # takes the friction over), so the tool's following error changes by that much across the reversal.
    friction, stiffness_n_um = 120.0, 180.0
    results = {}
    for backlash in (0.0, 0.01, 0.02):
        machine = with_mechanics("vmc-small-mujoco", coulomb_friction_n=friction, viscous_damping_n_s_m=0.0,
                                 coupling_stiffness_n_um=stiffness_n_um, backlash_mm=backlash)  # fmt: skip
        plant = MujocoPlant(machine)
        t = np.arange(1, 1001) * PERIOD
        x = np.where(t < 1.0, t, 2.0 - t) * (1000.0 / 60.0)  # F1000 out and back
        ref = np.stack((x, 0 * t, 0 * t), axis=1)
        plant.step(ref[:450])
        gap_forward = (plant.position - plant.motor_position)[0, 0]
        error_forward = plant.following_error[0, 0]
        plant.step(ref[450:])
        gap_back = (plant.position - plant.motor_position)[0, 0]
        error_back = plant.following_error[0, 0]
        expected = backlash + 2 * friction / (stiffness_n_um * 1e6) * 1e3  # mm
        assert gap_back - gap_forward == pytest.approx(expected, rel=0.02)
        assert error_forward + error_back == pytest.approx(0.0, abs=1e-4)  # the same lag either way
        results[backlash] = error_forward
    # The tool lags half the dead band more on each side: b more across a reversal.
    assert results[0.02] - results[0.0] == pytest.approx(0.01, rel=0.02)


def test_load_feedback_takes_the_compliance_out_of_the_steady_lag():
    # A full-closed loop (linear scale) measures the load: its ramp lag is (1 − f)v/Kv on the load
    # whatever the spring's deflection; a semi-closed one adds the deflection F/k on the load.
    friction, stiffness_n_um = 150.0, 100.0
    lags = {}
    for feedback in ("load", "motor"):
        machine = with_mechanics("vmc-small-mujoco", coulomb_friction_n=friction, viscous_damping_n_s_m=0.0,
                                 coupling_stiffness_n_um=stiffness_n_um, backlash_mm=0.0,
                                 position_feedback=feedback)  # fmt: skip
        t = np.arange(1, 751) * PERIOD
        ref = np.stack((F5000 * t, 0 * t, 0 * t), axis=1)
        plant = MujocoPlant(machine)
        lags[feedback] = (ref[-1] - plant.step(ref)[-1])[0]
    ideal = 0.3 * F5000 / 40
    assert lags["load"] == pytest.approx(ideal, abs=1e-5)
    assert lags["motor"] - ideal == pytest.approx(friction / (stiffness_n_um * 1e6) * 1e3, rel=0.02)


# ------------------------------------------------------------------------------------- interface
def test_batched_envs_are_independent_machines():
    machine = load_machine("vmc-small-mujoco")
    rng = np.random.default_rng(3)
    refs = np.cumsum(rng.normal(0, 0.05, size=(3, 200, 3)), axis=1)
    batched = MujocoPlant(machine, n_envs=3)
    out = np.concatenate([batched.step(refs[:, :120]), batched.step(refs[:, 120:])], axis=1)
    for e in range(3):
        single = MujocoPlant(machine)
        np.testing.assert_allclose(out[e], single.step(refs[e]), atol=1e-9)


def test_resetting_one_env_leaves_the_others_running():
    machine = load_machine("vmc-small-mujoco")
    ref = np.repeat(circle(20.0, F5000, 0.3)[None], 2, axis=0)
    batched, single = MujocoPlant(machine, n_envs=2), MujocoPlant(machine)
    for p in (batched, single):
        p.reset(np.array([20.0, 0, 0]))
    half = ref.shape[1] // 2
    batched.step(ref[:, :half])
    single.step(ref[0, :half])
    batched.reset(np.array([1.0, 2.0, 3.0]), env=1)
    np.testing.assert_allclose(batched.position[1], [1, 2, 3])
    np.testing.assert_allclose(batched.step(ref[:, half:])[0], single.step(ref[0, half:]), atol=1e-9)
    assert batched.kv_min.shape == (2,) and batched.compiled_step is False
    with pytest.raises(ValueError):
        batched.reset(np.zeros(3), env=2)


def test_per_env_kv_scale_equals_a_machine_with_those_gains():
    machine = rigid("vmc-small")
    scale = np.array([[1.0, 1.0, 1.0], [0.8, 1.1, 0.9]])
    plant = MujocoPlant(machine, n_envs=2, kv_scale=scale)
    ref = np.repeat(circle(20.0, F5000, 0.5)[None], 2, axis=0)
    plant.reset(np.array([20.0, 0, 0]))
    out = plant.step(ref)
    axes = tuple(dataclasses.replace(a, kv_1_s=a.kv_1_s * s)
                 for a, s in zip(machine.axes, scale[1], strict=True))  # fmt: skip
    other = MujocoPlant(dataclasses.replace(machine, axes=axes))
    other.reset(np.array([20.0, 0, 0]))
    np.testing.assert_allclose(out[1], other.step(ref[1]), atol=1e-9)
    np.testing.assert_allclose(plant.kv_1_s, scale * np.array(machine.axis_array("kv_1_s")))
    assert plant.model_version == 1
    with pytest.raises(ConfigError):
        plant.set_kv_scale(np.array([0.0, 1, 1]), env=0)
    with pytest.raises(ValueError):
        plant.set_kv_scale(np.ones(3), env=5)


def test_reset_settled_and_bad_input():
    plant = MujocoPlant("vmc-small-mujoco")
    plant.reset(np.array([1.0, 2.0, 3.0]))
    assert plant.settled(0.01).all()
    np.testing.assert_allclose(plant.position[0], [1, 2, 3])
    ref = np.tile([5.0, 2.0, 3.0], (10, 1))
    plant.step(ref)
    assert not plant.settled(0.01).any()  # 4 mm away after 20 ms
    plant.step(np.tile([5.0, 2.0, 3.0], (500, 1)))
    assert plant.settled(0.01).all()
    assert plant.step(np.zeros((0, 3))).shape == (0, 3)
    for bad in (np.full((2, 3), np.nan), np.zeros((2, 2)), np.zeros((1, 2, 3, 1))):
        with pytest.raises(ValueError):
            plant.step(bad)
    with pytest.raises(ValueError):
        plant.reset(np.array([np.inf, 0, 0]))
    with pytest.raises(ValueError):
        MujocoPlant("vmc-small-mujoco", n_envs=2).step(np.zeros((3, 3)))


def test_friction_on_a_p_velocity_loop_beyond_the_in_position_width_is_warned():
    # vmc-small's X: K = Kp·Kv = 3.23 N/µm, so 100 N of friction can hold it 31 µm off (> 10 µm).
    with pytest.warns(UserWarning, match=r"P velocity loop .*: x 0.0309 mm \(100 N\), y 0.0195 mm") as caught:
        MujocoPlant(_glitch_machine(100.0, 0.0))
    assert len(caught) == 1
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        MujocoPlant(_glitch_machine(100.0, 0.01))  # a PI loop: no warning
        MujocoPlant(_glitch_machine(20.0, 0.0))  # 6 µm: within the width


def test_a_diverged_simulation_is_an_error_not_motion(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # MuJoCo logs its warning to MUJOCO_LOG.TXT in the working folder
    plant = MujocoPlant("vmc-small-mujoco")
    plant.data.qvel[0] = np.nan  # what an exploding simulation leaves; MuJoCo then resets it
    with pytest.raises(ConfigError, match="diverged"):
        plant.step(np.zeros((5, 3)))


def test_unstable_or_too_coarse_mechanics_are_config_errors():
    with pytest.raises(ConfigError, match="unstable"):  # a reset time far below the current loop's lag
        MujocoPlant(with_mechanics("vmc-small", velocity_integral_time_s=1e-4))
    with pytest.raises(ConfigError, match="too coarse"):  # 1e6 N/µm on 100 kg: a 16 kHz resonance
        MujocoPlant(with_mechanics("vmc-small", coupling_stiffness_n_um=1e6))


def test_the_plant_section_is_validated():
    def problem(plant: dict) -> str:
        with pytest.raises(ConfigError) as info:
            machine_from_dict({"plant": plant}, "m.yaml")
        return str(info.value)

    assert "plant.backend must be one of lti, mujoco" in problem({"backend": "bullet"})
    assert "plant.timestep_s must be the interpolation period" in problem({"timestep_s": 0.0007})
    assert "unknown key plant.axes.x.mass" in problem({"axes": {"x": {"mass": 3}}})
    assert "plant.axes.y.backlash_mm needs coupling_stiffness_n_um" in problem(
        {"axes": {"y": {"backlash_mm": 0.01}}})
    assert "plant.axes.z.coulomb_friction_n must be" in problem({"axes": {"z": {"coulomb_friction_n": -1}}})
    assert "position_feedback must be one of motor, load" in problem(
        {"axes": {"x": {"position_feedback": "x"}}})
    assert isinstance(AxisMechanicsConfig().load_mass_kg, float)


def test_vmc_small_mujoco_keeps_vmc_small_gains():
    small, mujoco = load_machine("vmc-small"), load_machine("vmc-small-mujoco")
    assert mujoco.plant.backend == "mujoco"
    assert mujoco.axes == small.axes and mujoco.controller == small.controller
    plant = MujocoPlant(mujoco)
    np.testing.assert_allclose(plant.axis_mass_kg, [562, 962, 612], atol=0.01)  # Y carries the table
