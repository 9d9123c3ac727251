"""The MuJoCo servo backend: the LTI plant's loops driving the machine's mechanics, batched over envs.

The same interface as :class:`~cnc_gym.plant.servo.ServoPlant` (``reset``, ``step``, ``settled``,
``set_kv_scale``, ``position``, ``velocity``, ``reference``, ``following_error``), so the env, the runner
and the benchmark take either. The machine (:mod:`cnc_gym.plant.mjcf`) is built from the preset's
``plant`` section: masses, guideway viscous and Coulomb friction, and per axis an optional motor–load
spring-damper with an optional dead band (backlash).

The servo law, per axis, computed at every physics step (``plant.timestep_s``, a whole fraction of the
interpolation period) and applied through the axis's actuator on the motor side::

    reference     r(t): the (post-filtered) samples joined linearly (first-order hold), ṙ = Δr/T
    position loop u = Kv·(r − x_fb) + f·ṙ                   x_fb: motor (semi-closed) or load (scale)
    velocity loop F* = Kp·(u − v_motor + I/Tn),  İ = u − v_motor   (I only with a PI loop, Tn > 0)
      velocity_loop_hz > 0:  the force F follows F* through the current loop's first-order lag τ
                             (integrated exactly; a ``motor`` actuator applies it), Kp = m·ωn/(2ζ),
                             τ = 1/(2ζωn)
      velocity_loop_hz = 0:  F = F* at once with Kp = m/(timestep/8) (a ``general`` actuator whose bias
                             −Kp·v MuJoCo integrates implicitly): the velocity follows u within an eighth
                             of a step

Where in the step the law is evaluated is chosen for second-order accuracy (see :func:`_servo_law`).
``m`` is the axis's whole moving mass along its direction (taken from the compiled model's mass matrix:
the Y drive moves the saddle and the table). On a rigid axis without friction the force is m·ẍ, so the
closed loop is the LTI plant's exactly: ẍ' = ωn²(u − ẋ) − 2ζωn·ẍ (velocity_loop_hz > 0) or ẋ = u
(ideal). Friction, compliance and backlash are what the LTI plant cannot show: the contour error is
measured on the load side (the table and the head), where the tool cuts.

Every env is a copy of the machine in one MuJoCo model, so one ``mj_step`` advances all of them and the
servo law is one compiled loop (numba) over (env, axis) per physics step.
"""

from __future__ import annotations

import math
import warnings

import mujoco
import numpy as np
from numba import njit

from cnc_gym.errors import ConfigError
from cnc_gym.machine import AXIS_NAMES, DEFAULT_MACHINE, MachineConfig
from cnc_gym.plant.mjcf import axis_names, machine_mjcf
from cnc_gym.plant.servo import checked_kv_scale, plant_machine, reference_rows

_M_PER_MM = 1e-3
#: MuJoCo's warnings of a state that is no longer finite (it then resets the simulation).
_DIVERGED = tuple(getattr(mujoco.mjtWarning, f"mjWARN_BAD{what}") for what in ("QACC", "QVEL", "QPOS"))
#: Largest |λ|·timestep allowed for the fastest mode (the coupling's resonance, the velocity loop): the
#: explicit parts of the step are stable up to 2 and within 5 % of the true frequency up to 1.
MAX_OMEGA_TIMESTEP = 1.0


# Columns of the per-axis parameters (3, _N_PAR) and of the address array (n_envs, 3, 3) of _servo_law.
_FF, _KP, _INV_TN, _LAG_DECAY, _LAG_MEAN, _LAGGED, _N_PAR = range(7)
_FB_Q, _FB_V, _MOTOR_V = range(3)


@njit(cache=True, nogil=True)
def _servo_law(qpos, qvel, qacc, adr, kv, par, state, filtered, k, alpha, period, timestep, ctrl):
    """The actuators' commands of every (env, axis) for one physics step of servo sample ``k`` (the
    reference ramps from ``filtered[:, k]`` to ``filtered[:, k + 1]``; ``alpha`` = the step's middle as a
    fraction of the sample). ``state[e, a]`` = [velocity-loop integral, current-loop force], updated.

    Where in the step the loop is evaluated makes MuJoCo's semi-implicit Euler step second-order accurate
    (checked against the LTI plant's exact discretisation: the error falls with the square of the step):

    - ideal velocity loop: the velocity command at the middle of the step (reference there, feedback
      position predicted from its velocity); the implicitly integrated velocity feedback makes it the
      step's velocity, so the position advances by the midpoint rule.
    - lagged velocity loop: the reference at the middle of the step against the position and the motor
      velocity (brought half a step on with the last acceleration); the current loop's lag integrated
      exactly for that command, the actuator applying its mean over the step. The trajectory this gives
      is the continuous one half a step late, which :meth:`MujocoPlant.step` takes back when it reports
      positions.
    """
    half = 0.5 * timestep
    for e in range(filtered.shape[0]):
        for a in range(3):
            r_start = filtered[e, k, a]
            dr = filtered[e, k + 1, a] - r_start
            vel = adr[e, a, _MOTOR_V]
            lagged = par[a, _LAGGED] > 0
            position = qpos[adr[e, a, _FB_Q]]
            if lagged:
                v = qvel[vel] + half * qacc[vel]
            else:
                v = qvel[vel]
                position += half * qvel[adr[e, a, _FB_V]]
            u = kv[e, a] * (r_start + alpha * dr - position) + par[a, _FF] * dr / period
            w = u + state[e, a, 0] * par[a, _INV_TN]
            state[e, a, 0] += (u - v) * timestep
            if lagged:
                target = par[a, _KP] * (w - v)
                start = state[e, a, 1]
                ctrl[e * 3 + a] = target + (start - target) * par[a, _LAG_MEAN]
                state[e, a, 1] = target + (start - target) * par[a, _LAG_DECAY]
            else:
                ctrl[e * 3 + a] = w


def _loop_matrix(kv: float, kp: float, tau: float, inv_tn: float, m_motor: float,
                 m_load: float, stiffness: float, damping: float, viscous: float, load_feedback: bool,
                 lagged: bool) -> np.ndarray:  # fmt: skip
    """The linear closed loop of one axis (no friction, no backlash; reference 0) as ẋ = A x.

    States: motor position and velocity, load position and velocity, force F (lagged loop), integral I.
    A rigid axis (stiffness 0) is one mass: the load states copy the motor's.
    """
    rigid = stiffness == 0
    a = np.zeros((6, 6))
    xm, vm, xl, vl, f, i = range(6)
    fb = xl if load_feedback and not rigid else xm
    # u = −Kv·x_fb;  F* = Kp·(u − v_m + I/Tn)
    fstar = np.zeros(6)
    fstar[fb] -= kp * kv
    fstar[vm] -= kp
    fstar[i] += kp * inv_tn
    if lagged:
        a[f] = (fstar - np.eye(6)[f]) / tau
        force = np.eye(6)[f]
    else:
        force = fstar
    a[i, fb] -= kv
    a[i, vm] -= 1.0
    a[xm, vm] = 1.0
    if rigid:
        a[vm] = (force - viscous * np.eye(6)[vm]) / (m_motor + m_load)
        a[xl], a[vl] = a[xm], a[vm]
    else:
        spring = stiffness * (np.eye(6)[xl] - np.eye(6)[xm]) + damping * (np.eye(6)[vl] - np.eye(6)[vm])
        a[vm] = (force + spring) / m_motor
        a[xl, vl] = 1.0
        a[vl] = (-spring - viscous * np.eye(6)[vl]) / m_load
    used = [xm, vm] + ([] if rigid else [xl, vl]) + ([f] if lagged else []) + ([i] if inv_tn > 0 else [])
    return a[np.ix_(used, used)]


class MujocoPlant:
    """Servo axes X, Y, Z of ``n_envs`` machines simulated by MuJoCo: reference positions in, load-side
    (tool) positions out. Constructor and methods as :class:`~cnc_gym.plant.servo.ServoPlant`.

    Attributes (all ``(n_envs, 3)``, mm and mm/s): ``position`` and ``velocity`` (load side: the tool
    relative to the table), ``motor_position`` (what a semi-closed loop measures), ``following_error``
    (raw reference − load position), ``reference`` (last raw reference). ``model`` and ``data`` are the
    MuJoCo objects (SI units; joint coordinates are the machine coordinates in metres).

    ``compiled_step`` is False: the env steps this plant through its methods (the modular step), not
    inside its own compiled step; ``model_version`` counts gain changes, as ServoPlant's.
    """

    compiled_step = False

    def __init__(
        self,
        machine: MachineConfig | str = DEFAULT_MACHINE,
        n_envs: int = 1,
        kv_scale: np.ndarray | None = None,
    ) -> None:
        self.machine, self.n_envs = machine, n_envs = plant_machine(machine, n_envs)
        ctrl = machine.controller
        self.period_s = float(ctrl.interpolation_period_s)
        self.timestep_s = float(machine.plant.timestep_s)
        self.substeps = max(1, round(self.period_s / self.timestep_s))
        self.filter_samples = max(1, round(ctrl.post_filter_s / self.period_s))
        self._n_hist = max(self.filter_samples, 2)
        self.model = mujoco.MjModel.from_xml_string(machine_mjcf(machine, self.n_envs))
        self.data = mujoco.MjData(self.model)
        self._index_model()
        self._tune_drives()
        mujoco.mj_resetData(self.model, self.data)
        self._base_kv = np.array(machine.axis_array("kv_1_s"))
        self._kv_scale = np.ones((self.n_envs, 3))
        self._kv = self._base_kv * self._kv_scale
        self.model_version = 0
        self._check_loops(np.ones(3))
        self._warn_friction_without_integral()
        self._state = np.zeros((self.n_envs, 3, 2))  # velocity-loop integral, current-loop force
        self._diverged = 0  # MuJoCo's count of non-finite states so far
        self._history = np.zeros((self.n_envs, self._n_hist, 3))  # raw references, metres
        if kv_scale is not None:
            self.set_kv_scale(kv_scale)
        self.reset(np.zeros(3))

    # ------------------------------------------------------------------ model
    def _index_model(self) -> None:
        """Address arrays (n_envs, 3) of the load and motor coordinates and of the feedback position."""
        m = self.model
        shape = (self.n_envs, 3)
        self._load_q, self._load_v = np.zeros(shape, np.int64), np.zeros(shape, np.int64)
        self._motor_q, self._motor_v = np.zeros(shape, np.int64), np.zeros(shape, np.int64)
        self._fb_q, self._fb_v = np.zeros(shape, np.int64), np.zeros(shape, np.int64)
        self._actuator = np.zeros(shape, np.int64)
        for e in range(self.n_envs):
            for a in range(3):
                mech = self.machine.plant.axes.axis(a)
                names = axis_names(e, a, mech)
                load = m.joint(names.load_joint)
                motor = m.joint(names.motor_joint or names.load_joint)
                self._load_q[e, a], self._load_v[e, a] = load.qposadr[0], load.dofadr[0]
                self._motor_q[e, a], self._motor_v[e, a] = motor.qposadr[0], motor.dofadr[0]
                on_load = mech.position_feedback == "load"
                self._fb_q[e, a] = self._load_q[e, a] if on_load else self._motor_q[e, a]
                self._fb_v[e, a] = self._load_v[e, a] if on_load else self._motor_v[e, a]
                self._actuator[e, a] = m.actuator(names.actuator).id
        self._adr = np.stack((self._fb_q, self._fb_v, self._motor_v), axis=-1)
        if not np.array_equal(self._actuator.ravel(), np.arange(3 * self.n_envs)):
            raise AssertionError("actuators must be ordered env by env, X Y Z")  # the MJCF builder's order

    def _tune_drives(self) -> None:
        """Velocity-loop gain and current-loop lag of every axis from its compiled moving mass."""
        m, d = self.model, self.data
        mujoco.mj_forward(m, d)
        full = np.zeros((m.nv, m.nv))
        mujoco.mj_fullM(m, d, full)
        self.axis_mass_kg = np.zeros(3)  # whole moving mass along each axis (motor side included)
        self.motor_mass_kg = np.zeros(3)
        self.load_mass_kg = np.zeros(3)
        for a in range(3):
            lv, mv = self._load_v[0, a], self._motor_v[0, a]
            self.load_mass_kg[a] = full[lv, lv]
            self.motor_mass_kg[a] = full[mv, mv] if mv != lv else 0.0
            self.axis_mass_kg[a] = self.load_mass_kg[a] + self.motor_mass_kg[a]
        self._kp = np.zeros(3)
        self._tau = np.zeros(3)
        self._lagged = np.zeros(3, dtype=np.bool_)
        self._inv_tn = np.zeros(3)
        for a, servo in enumerate(self.machine.axes):
            mass = self.axis_mass_kg[a]
            tn = self.machine.plant.axes.axis(a).velocity_integral_time_s
            self._inv_tn[a] = 1.0 / tn if tn > 0 else 0.0
            if servo.velocity_loop_hz > 0:
                wn = 2.0 * math.pi * servo.velocity_loop_hz
                zeta = servo.velocity_loop_damping
                self._kp[a] = mass * wn / (2.0 * zeta)
                self._tau[a] = 1.0 / (2.0 * zeta * wn)
                self._lagged[a] = True
            else:  # the velocity follows u with a time constant of 1/8 of a physics step
                self._kp[a] = mass / (self.timestep_s / 8)
        ratio = np.divide(self.timestep_s, self._tau, out=np.full(3, np.inf), where=self._tau > 0)
        self._lag_decay = np.exp(-ratio)
        lag_mean = np.where(self._lagged, (1.0 - self._lag_decay) / ratio, 0.0)
        self._par = np.zeros((3, _N_PAR))
        self._par[:, _FF] = self.machine.axis_array("feedforward")
        self._par[:, _KP], self._par[:, _INV_TN] = self._kp, self._inv_tn
        self._par[:, _LAG_DECAY], self._par[:, _LAG_MEAN] = self._lag_decay, lag_mean
        self._par[:, _LAGGED] = self._lagged
        # Positions are reported half a step back on lagged axes (see _servo_law).
        self._report_shift_s = np.where(self._lagged, 0.5 * self.timestep_s, 0.0)
        for e in range(self.n_envs):
            for a in range(3):
                i = self._actuator[e, a]
                if not self._lagged[a]:
                    m.actuator_gainprm[i, 0] = self._kp[a]
                    m.actuator_biasprm[i, 2] = -self._kp[a]

    def _check_loops(self, scale: np.ndarray) -> None:
        """ConfigError if an axis's linear closed loop (Kv × ``scale``) is unstable or too fast for the
        physics timestep."""
        source = self.machine.source
        for a, (name, servo) in enumerate(zip(AXIS_NAMES, self.machine.axes, strict=True)):
            mech = self.machine.plant.axes.axis(a)
            kv = servo.kv_1_s * float(scale[a])
            k = mech.coupling_stiffness_n_um * 1e6
            matrix = _loop_matrix(kv, self._kp[a], self._tau[a], self._inv_tn[a],
                                  self.motor_mass_kg[a] if k else self.axis_mass_kg[a],
                                  self.load_mass_kg[a] if k else 0.0, k, mech.coupling_damping_n_s_m,
                                  mech.viscous_damping_n_s_m, mech.position_feedback == "load",
                                  bool(self._lagged[a]))  # fmt: skip
            poles = np.linalg.eigvals(matrix)
            if poles.real.max() >= 0:
                raise ConfigError(
                    f"{source}: plant.axes.{name}: the MuJoCo servo loop is unstable (kv_1_s = {kv:g}, "
                    f"velocity_loop_hz = {servo.velocity_loop_hz:g}, velocity_integral_time_s = "
                    f"{mech.velocity_integral_time_s:g}, coupling_stiffness_n_um = "
                    f"{mech.coupling_stiffness_n_um:g}, position_feedback = {mech.position_feedback})"
                )
            fastest = [abs(servo.velocity_loop_hz) * 2 * math.pi]
            if k:
                fastest.append(math.sqrt(k * (1 / self.motor_mass_kg[a] + 1 / self.load_mass_kg[a])))
            omega = max(fastest)
            if omega * self.timestep_s > MAX_OMEGA_TIMESTEP:
                raise ConfigError(
                    f"{source}: plant.timestep_s {self.timestep_s:g} s is too coarse for axis {name}: its "
                    f"fastest mode is {omega / (2 * math.pi):.4g} Hz; use at most "
                    f"{MAX_OMEGA_TIMESTEP / omega:.3g} s (a whole fraction of the interpolation period)"
                )

    def _warn_friction_without_integral(self) -> None:
        """A P velocity loop holds a Coulomb friction F only with a following error F/(Kp·Kv): an axis can
        stop that far from its target, and beyond the in-position width the controller never releases it
        (the episode then ends at its step budget). Real drives integrate (a PI loop): say so, once."""
        width = self.machine.controller.in_position_mm * _M_PER_MM
        held = []
        for a, name in enumerate(AXIS_NAMES):
            mech = self.machine.plant.axes.axis(a)
            offset = mech.coulomb_friction_n / (self._kp[a] * self._kv[0, a])
            if mech.velocity_integral_time_s == 0 and offset > width:
                held.append(f"{name} {offset / _M_PER_MM:.3g} mm ({mech.coulomb_friction_n:g} N)")
        if held:
            warnings.warn(
                f"{self.machine.source}: plant.axes: with a P velocity loop the Coulomb friction can hold an "
                f"axis this far from its target: {', '.join(held)}, beyond in_position_mm "
                f"({width / _M_PER_MM:g}), so the controller may never see it in position; a PI loop "
                "(velocity_integral_time_s) removes the offset", stacklevel=3)

    # ------------------------------------------------------------------ gains
    @property
    def kv_1_s(self) -> np.ndarray:
        """Position gains in force, (n_envs, 3), 1/s."""
        return self._kv.copy()

    @property
    def loop_stiffness_n_m(self) -> np.ndarray:
        """(n_envs, 3) N/m: the force a P velocity loop makes per metre of following error at rest,
        Kp·Kv: a Coulomb friction F offsets the axis by F/(Kp·Kv) (the integral of a PI loop removes
        the offset, not the spike at a reversal)."""
        return self._kp * self._kv

    def set_kv_scale(self, kv_scale: np.ndarray, env: int | None = None) -> None:
        """Multiply the preset's per-axis Kv by ``kv_scale``, as :meth:`ServoPlant.set_kv_scale`."""
        new_scale = checked_kv_scale(kv_scale, self._kv_scale, env)
        for row in np.unique(new_scale, axis=0):
            self._check_loops(row)
        self._kv_scale = new_scale
        self._kv = self._base_kv * new_scale
        self.model_version += 1

    @property
    def kv_min(self) -> np.ndarray:
        """(n_envs,) each env's lowest position gain, 1/s."""
        return self._kv.min(axis=1)

    # ------------------------------------------------------------------ public API
    def reset(self, position: np.ndarray, env: int | None = None) -> None:
        """Every axis at rest at ``position`` ((n_envs, 3) or (3,), mm), motor and load alike (a backlash
        gap is centred), the drives' states cleared; the reference history too. With ``env``, only that
        env (``position`` (3,)); the other machines in the model are left as they are."""
        envs = np.arange(self.n_envs) if env is None else np.array([int(env)])
        if envs.min() < 0 or envs.max() >= self.n_envs:
            raise ValueError(f"env {env} out of range 0..{self.n_envs - 1}")
        pos = np.broadcast_to(np.asarray(position, dtype=float), (len(envs), 3))
        if not np.all(np.isfinite(pos)):
            raise ValueError("plant reset position must be finite")
        d, pos_m = self.data, pos * _M_PER_MM
        d.qpos[self._load_q[envs]] = pos_m
        d.qpos[self._motor_q[envs]] = pos_m
        for dofs in (self._load_v[envs], self._motor_v[envs]):
            d.qvel[dofs] = d.qacc[dofs] = d.qacc_warmstart[dofs] = d.qfrc_applied[dofs] = 0.0
        d.ctrl[self._actuator[envs].ravel()] = 0.0
        self._state[envs] = 0.0
        self._history[envs] = pos_m[:, None, :]

    def step(self, reference: np.ndarray) -> np.ndarray:
        """Advance by one sample per reference row and return the load-side positions (mm), same shape.

        ``reference`` is (n_envs, n_ticks, 3), or (n_ticks, 3) when ``n_envs == 1`` (mm).
        """
        ref, squeeze = reference_rows(reference, self.n_envs)
        n_ticks = ref.shape[1]
        if n_ticks == 0:
            return ref[0].copy() if squeeze else ref.copy()
        if not np.isfinite(ref.sum()):
            raise ValueError("reference positions must be finite")
        # Raw history then the new samples; the filtered reference r_j is the mean of the N raws ending at j.
        raw = np.concatenate((self._history, ref * _M_PER_MM), axis=1)
        n_filter = self.filter_samples
        cum = np.concatenate((np.zeros((self.n_envs, 1, 3)), np.cumsum(raw, axis=1)), axis=1)
        ends = np.arange(self._n_hist - 1, self._n_hist + n_ticks) + 1
        filtered = (cum[:, ends] - cum[:, ends - n_filter]) / n_filter  # r_0 (last old) .. r_n
        self._history = raw[:, -self._n_hist :].copy()
        actual = np.empty((self.n_envs, n_ticks, 3))
        m, d = self.model, self.data
        qpos, qvel, qacc, ctrl = d.qpos, d.qvel, d.qacc, d.ctrl
        h, n_sub, period = self.timestep_s, self.substeps, self.period_s
        adr, kv, par, state = self._adr, self._kv, self._par, self._state
        middles = [(j + 0.5) / n_sub for j in range(n_sub)]  # each physics step's middle, in the sample
        for k in range(n_ticks):
            for middle in middles:
                _servo_law(qpos, qvel, qacc, adr, kv, par, state, filtered, k, middle, period, h, ctrl)
                mujoco.mj_step(m, d)
            actual[:, k] = qpos[self._load_q] - self._report_shift_s * qvel[self._load_v]
        bad = sum(d.warning[w].number for w in _DIVERGED)
        if bad != self._diverged or not np.all(np.isfinite(actual)):
            # MuJoCo resets a simulation whose state is no longer finite (and counts it): say so, never
            # return the reset state as motion.
            self._diverged = bad
            raise ConfigError(f"{self.machine.source}: the MuJoCo plant diverged: its mechanics (plant "
                              "section) cannot follow this reference at this timestep")  # fmt: skip
        actual *= 1.0 / _M_PER_MM
        return actual[0] if squeeze else actual

    @property
    def position(self) -> np.ndarray:
        """Load-side (tool) position (n_envs, 3), mm."""
        return self._now(self._load_q, self._load_v) / _M_PER_MM

    def _now(self, q_adr: np.ndarray, v_adr: np.ndarray) -> np.ndarray:
        """Positions (m) at the current sample time (see :func:`_servo_law`)."""
        return self.data.qpos[q_adr] - self._report_shift_s * self.data.qvel[v_adr]

    @property
    def motor_position(self) -> np.ndarray:
        """Motor-side position (n_envs, 3), mm (the load's on a rigid axis)."""
        return self._now(self._motor_q, self._motor_v) / _M_PER_MM

    @property
    def velocity(self) -> np.ndarray:
        """Load-side velocity (n_envs, 3), mm/s."""
        return self.data.qvel[self._load_v] / _M_PER_MM

    @property
    def reference(self) -> np.ndarray:
        """Last raw (unfiltered) reference (n_envs, 3), mm."""
        return self._history[:, -1, :] / _M_PER_MM

    @property
    def following_error(self) -> np.ndarray:
        """Raw reference − load position at the last sample (n_envs, 3), mm."""
        return self.reference - self.position

    def settled(self, tolerance_mm: float) -> np.ndarray:
        """(n_envs,) bool: at rest within ``tolerance_mm`` of the last reference, as the controller sees it.

        As :meth:`ServoPlant.settled`, on the position the loop measures (the motor's on a semi-closed
        axis: a load resting anywhere in its backlash gap is in position, as on the machine) and the
        motor's speed.
        """
        tol = float(tolerance_mm) * _M_PER_MM
        hist = self._history
        ref_at_rest = np.all(hist == hist[:, -1:, :], axis=(1, 2))
        err = hist[:, -1, :] - self._now(self._fb_q, self._fb_v)
        close = np.einsum("ea,ea->e", err, err) <= tol * tol
        speed = self.data.qvel[self._motor_v]
        slow = np.einsum("ea,ea->e", speed, speed) <= (self._kv.min(axis=1) * tol) ** 2
        return ref_at_rest & close & slow
