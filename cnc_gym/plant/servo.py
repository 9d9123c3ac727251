"""The fast servo backend: a discrete-time LTI model of every axis, batched over axes and environments.

Model of one axis (continuous time; ``r`` is the reference, ``x`` the actual position)::

    velocity command   u = Kv·(r − x) + f·ṙ                (P position loop + velocity feed-forward f)
    ideal velocity loop (velocity_loop_hz = 0):   ẋ = u     ⇒  X/R = (Kv + f·s)/(s + Kv)
    2nd-order velocity loop (ωn = 2π·velocity_loop_hz, ζ = velocity_loop_damping):
        V/U = ωn² / (s² + 2ζωn·s + ωn²),   ẋ = V

State per axis: ``[x, ẋ, ẍ]`` (the ideal loop uses only ``x``; the other two stay zero).

How the reference reaches the loop. The interpolator produces one reference sample every interpolation
period T. The optional post-interpolation acc/dec filter (``controller.post_filter_s``) is a moving
average over N = round(post_filter_s/T) samples. Between samples the drive interpolates the (filtered)
reference linearly (first-order hold — what a drive's fine interpolator does), so over each period the
reference is a ramp and its derivative, used by the feed-forward, is the backward difference
(r_k − r_{k−1})/T. The discretisation is exact for that input: one matrix exponential of the system
augmented with ``r`` and ``ṙ`` (``expm``). A consequence worth knowing: a ramp input gives exactly the
continuous-time lag (1 − f)·v/Kv, with no extra half-sample delay that a zero-order hold would add.

Vectorisation: for a given number of ticks n the recursion is lifted into one matrix per axis that maps
``[state (3), raw reference history (H ≥ N), new references (n)]`` to ``[actual x_1..x_n, state_n,
ẋ_n]``; a step is that matrix-vector product for every (axis, env), done in place on the state by
one numba-compiled loop (:func:`_step_kernel`: ~1 µs for 5 ticks of one env, where the numpy batched
matmul it replaced spent ~5 µs in call overhead; compiled on first use, cached on disk). The per-env
step (:func:`step_env`) and settle test (:func:`settled_env`) are what the env's fused step calls too.
Discrete models and lifted matrices are computed once per process for a machine's axes and a block
length n (n up to ``MAX_LIFTED_TICKS``; longer steps are done in chunks), so N envs of one machine
share them. With per-env Kv (``set_kv_scale``) there is one lifted matrix per (axis, env).
"""

from __future__ import annotations

import functools
import math

import numpy as np
from numba import njit
from scipy.linalg import expm

from cnc_gym.errors import ConfigError
from cnc_gym.machine import AXIS_NAMES, DEFAULT_MACHINE, MachineConfig, load_machine

#: Longest block of ticks handled by one lifted matrix; longer steps are split into chunks.
MAX_LIFTED_TICKS = 64
_N_STATES = 3  # x, ẋ, ẍ


def axis_discrete_model(
    kv_1_s: float,
    feedforward: float,
    velocity_loop_hz: float,
    velocity_loop_damping: float,
    period_s: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Exact discretisation of one axis for a piecewise-linear reference.

    Returns ``(A, B_prev, B_cur, C_vel, D_vel)`` with

        z_k = A z_{k−1} + B_prev r_{k−1} + B_cur r_k        (z = [x, ẋ, ẍ])
        ẋ_k = C_vel · z_k + D_vel · [r_{k−1}, r_k]          (velocity at the sample, left limit)
    """
    kv, ff, period = float(kv_1_s), float(feedforward), float(period_s)
    # Augmented continuous system q = [x, ẋ, ẍ, r, ṙ]: q̇ = M q, with r ramping and ṙ constant over a period.
    m = np.zeros((5, 5))
    m[3, 4] = 1.0  # ṙ drives r
    if velocity_loop_hz > 0:
        wn = 2.0 * np.pi * float(velocity_loop_hz)
        zeta = float(velocity_loop_damping)
        m[0, 1] = 1.0
        m[1, 2] = 1.0
        # ẍ' = ωn²·(u − ẋ) − 2ζωn·ẍ,  u = Kv (r − x) + f ṙ
        m[2] = [-wn * wn * kv, -wn * wn, -2.0 * zeta * wn, wn * wn * kv, wn * wn * ff]
        c_vel = np.array([0.0, 1.0, 0.0])
        d_vel = np.zeros(2)
    else:
        m[0] = [-kv, 0.0, 0.0, kv, ff]
        c_vel = np.array([-kv, 0.0, 0.0])
        d_vel = np.array([-ff / period, kv + ff / period])
    e = expm(m * period)
    a = e[:3, :3]
    g_r, g_d = e[:3, 3], e[:3, 4]
    # ṙ over period k is (r_k − r_{k−1})/T.
    b_prev = g_r - g_d / period
    b_cur = g_d / period
    return a, b_prev, b_cur, c_vel, d_vel


@njit(cache=True, nogil=True)
def step_env(lifted, state, history, velocity, env, reference, actual) -> None:
    """One block of ticks of env ``env``, in place: for every axis the lifted matrix times
    ``[state (3), raw history (H), new references (n)]`` (see :meth:`ServoPlant._lift_models`).

    ``lifted`` (3, 1 or E, n + 4, 3 + H + n) (the env's own matrices, or one shared); ``state`` (3, 3, E),
    ``history`` (3, H, E), ``velocity`` (3, E) are updated; ``reference`` (n, 3) in, ``actual`` (n, 3)
    out. The caller checks that the references are finite. Shared by :meth:`ServoPlant.step` and the
    env's fused step, so both give the same numbers.
    """
    n_ticks = reference.shape[0]
    n_hist = history.shape[1]
    matrix_env = env if lifted.shape[1] > 1 else 0
    for a in range(3):
        matrix = lifted[a, matrix_env]
        z0 = state[a, 0, env]
        z1 = state[a, 1, env]
        z2 = state[a, 2, env]
        for row in range(n_ticks + _N_STATES + 1):
            # The columns in order (state, history, references): the same sums as one dot product.
            acc = matrix[row, 0] * z0
            acc += matrix[row, 1] * z1
            acc += matrix[row, 2] * z2
            for j in range(n_hist):
                acc += matrix[row, _N_STATES + j] * history[a, j, env]
            for j in range(n_ticks):
                acc += matrix[row, _N_STATES + n_hist + j] * reference[j, a]
            if row < n_ticks:
                actual[row, a] = acc
            elif row < n_ticks + _N_STATES:
                state[a, row - n_ticks, env] = acc
            else:
                velocity[a, env] = acc
        # Keep the last H raw references (older history shifts forward when fewer than H are new).
        keep = n_hist - n_ticks
        for j in range(n_hist):
            if j < keep:
                history[a, j, env] = history[a, j + n_ticks, env]
            else:
                history[a, j, env] = reference[j - keep, a]


@njit(cache=True, nogil=True)
def settled_env(state, history, velocity, env, tolerance_mm, kv_min) -> bool:
    """:meth:`ServoPlant.settled` of one env (``kv_min``: the env's lowest position gain)."""
    n_hist = history.shape[1]
    for a in range(3):
        last = history[a, n_hist - 1, env]
        for j in range(n_hist - 1):
            if history[a, j, env] != last:
                return False
    err2 = 0.0
    speed2 = 0.0
    for a in range(3):
        e = history[a, n_hist - 1, env] - state[a, 0, env]
        err2 += e * e
        speed2 += velocity[a, env] * velocity[a, env]
    slow = kv_min * tolerance_mm
    return err2 <= tolerance_mm * tolerance_mm and speed2 <= slow * slow


@njit(cache=True, nogil=True)
def _all_finite(reference) -> bool:
    total = 0.0
    for x in reference.ravel():
        total += x
    return math.isfinite(total)


@njit(cache=True, nogil=True)
def _step_kernel(lifted, state, history, velocity, reference, actual) -> bool:
    """One block of ticks for every env (:func:`step_env`); ``reference`` (E, n, 3) in, ``actual`` (E, n,
    3) out. Returns False, touching nothing, if a reference is not finite."""
    if not _all_finite(reference):
        return False
    for e in range(reference.shape[0]):
        step_env(lifted, state, history, velocity, e, reference[e], actual[e])
    return True


AxisKey = tuple[float, float, float, float, float]  # kv_1_s, feedforward, velocity_loop_hz, damping, period_s


@functools.lru_cache(maxsize=256)
def _discrete_model(kv: float, feedforward: float, velocity_loop_hz: float, damping: float,
                    period_s: float) -> tuple[tuple[np.ndarray, ...], float]:  # fmt: skip
    """:func:`axis_discrete_model` (read-only arrays) and the spectral radius of its state matrix, once per
    process and parameter set: N envs of one machine share them (no matrix exponential per env)."""
    model = axis_discrete_model(kv, feedforward, velocity_loop_hz, damping, period_s)
    for array in model:
        array.flags.writeable = False
    used = _N_STATES if velocity_loop_hz > 0 else 1  # the ideal loop has the state x only
    return model, float(np.abs(np.linalg.eigvals(model[0][:used, :used])).max())


@functools.lru_cache(maxsize=256)
def _lifted_axes(models: tuple[AxisKey, ...], n_hist: int, n_filter: int, n_ticks: int) -> np.ndarray:
    """The lifted matrices of :meth:`ServoPlant._lift_models`, shared by every plant (never written).

    H ≥ N raw references are carried; the filtered reference r_j is the mean of raw_{j−N+1}..raw_j.
    """
    n_cols = _N_STATES + n_hist + n_ticks
    # Filtered reference r_j (j = 0..n) as rows over the raw columns: mean of the N raws ending at j.
    filt = np.zeros((n_ticks + 1, n_cols))
    for j in range(n_ticks + 1):
        last_col = _N_STATES + n_hist - 1 + j  # column of raw_j
        filt[j, last_col - n_filter + 1 : last_col + 1] = 1.0 / n_filter
    out = np.zeros((3, n_ticks + _N_STATES + 1, n_cols))
    for axis, key in enumerate(models):
        a, b_prev, b_cur, c_vel, d_vel = _discrete_model(*key)[0]
        z = np.zeros((_N_STATES, n_cols))
        z[:, :_N_STATES] = np.eye(_N_STATES)
        for k in range(1, n_ticks + 1):
            z = a @ z + np.outer(b_prev, filt[k - 1]) + np.outer(b_cur, filt[k])
            out[axis, k - 1] = z[0]
        out[axis, n_ticks : n_ticks + _N_STATES] = z
        out[axis, -1] = c_vel @ z + d_vel[0] * filt[n_ticks - 1] + d_vel[1] * filt[n_ticks]
    return out


def plant_machine(machine: MachineConfig | str, n_envs: int) -> tuple[MachineConfig, int]:
    """A plant's machine (a preset name is loaded) and number of envs (at least 1), for every backend."""
    if isinstance(machine, str):
        machine = load_machine(machine)
    if int(n_envs) < 1:
        raise ValueError(f"n_envs must be at least 1, got {n_envs}")
    return machine, int(n_envs)


def checked_kv_scale(kv_scale: np.ndarray, current: np.ndarray, env: int | None) -> np.ndarray:
    """The per-env Kv multipliers ((n_envs, 3)) after ``set_kv_scale(kv_scale, env)`` from ``current``:
    ``kv_scale`` (3,) or (n_envs, 3) for all envs, or (3,) for one ``env``. A wrong shape or env is a
    ValueError, a multiplier that is not positive and finite a ConfigError."""
    n_envs = current.shape[0]
    scale = np.asarray(kv_scale, dtype=float)
    new_scale = current.copy()
    if env is None:
        scale = np.broadcast_to(scale, (n_envs, 3)) if scale.ndim <= 1 else scale
        if scale.shape != (n_envs, 3):
            raise ValueError(f"kv_scale must be (3,) or (n_envs={n_envs}, 3), got {scale.shape}")
        new_scale[:] = scale
    else:
        if scale.shape != (3,):
            raise ValueError(f"kv_scale for one env must be (3,), got {scale.shape}")
        if not 0 <= env < n_envs:
            raise ValueError(f"env {env} out of range 0..{n_envs - 1}")
        new_scale[env] = scale
    if not np.all(np.isfinite(scale)) or np.any(scale <= 0):
        raise ConfigError(f"kv_scale must be positive and finite, got {kv_scale!r}")
    return new_scale


def reference_rows(reference: np.ndarray, n_envs: int) -> tuple[np.ndarray, bool]:
    """A plant step's reference as float64 (n_envs, n_ticks, 3), and whether it came as (n_ticks, 3) (one
    env); ValueError on any other shape."""
    ref = reference
    if type(ref) is not np.ndarray or ref.dtype != np.float64:
        ref = np.asarray(reference, dtype=np.float64)
    squeeze = ref.ndim == 2
    if squeeze:
        if n_envs != 1:
            raise ValueError(f"reference must be (n_envs={n_envs}, n_ticks, 3), got {ref.shape}")
        ref = ref[None]
    if ref.ndim != 3 or ref.shape[0] != n_envs or ref.shape[2] != 3:
        raise ValueError(f"reference must be (n_envs={n_envs}, n_ticks, 3), got {ref.shape}")
    return ref, squeeze


class ServoPlant:
    """Servo axes X, Y, Z of ``n_envs`` machines: reference positions in, actual positions out.

    ``machine`` is a :class:`~cnc_gym.machine.MachineConfig` (or a preset name). One sample per
    interpolation period (``machine.controller.interpolation_period_s``). Per-axis Kv, feed-forward
    and velocity loop come from ``machine.axes``; unequal Kv between axes is the gain mismatch.
    ``kv_scale`` ((3,) or (n_envs, 3), default all 1) multiplies each env's per-axis Kv, e.g. for
    randomising the mismatch per episode (see :meth:`set_kv_scale`). See the module docstring for the model.

    Attributes (all ``(n_envs, 3)``, mm and mm/s): ``position``, ``velocity``, ``following_error``
    (raw reference − actual at the last sample), ``reference`` (last raw reference).

    The plant interface the env relies on (any backend provides it): ``n_envs``, ``reset(position,
    env=None)``, ``step(reference (n_envs, n, 3)) → actual``, ``settled(tolerance) → (n_envs,) bool``.
    This backend also has ``compiled_step``: its state arrays (``_state``, ``_history``, ``_velocity``,
    with :func:`step_env` and :func:`settled_env`) can be stepped inside the env's fused kernel.
    """

    #: The env's fused kernel may step this plant's arrays directly (see the class docstring).
    compiled_step = True

    def __init__(
        self,
        machine: MachineConfig | str = DEFAULT_MACHINE,
        n_envs: int = 1,
        kv_scale: np.ndarray | None = None,
    ) -> None:
        self.machine, self.n_envs = machine, n_envs = plant_machine(machine, n_envs)
        self.period_s = float(machine.controller.interpolation_period_s)
        self.filter_samples = max(1, round(machine.controller.post_filter_s / self.period_s))
        # Raw references kept: the filter window, and at least two so settled() can see a moving reference.
        self._n_hist = max(self.filter_samples, 2)
        self._base_kv = np.array(machine.axis_array("kv_1_s"))
        # Shared mode: one model per axis for all envs, lifted (3, rows, cols). Per-env mode (after a
        # kv_scale that differs between envs): lifted (3, n_envs, rows, cols).
        self._kv_scale = np.ones((self.n_envs, 3))
        self._shared_models = self._axis_models(np.ones(3))
        self._env_models: list[tuple[AxisKey, ...]] | None = None
        self._lifted: dict[int, np.ndarray] = {}
        self._lifted4: dict[int, np.ndarray] = {}  # the same as (3, 1 or n_envs, rows, cols), for the kernel
        #: Counts changes of the gains (set_kv_scale), for callers that keep values derived from them.
        self.model_version = 0
        # Internal layout is axis-major so that one batched matmul over axes serves every env.
        self._state = np.zeros((3, _N_STATES, self.n_envs))
        self._history = np.zeros((3, self._n_hist, self.n_envs))  # last raw references
        self._velocity = np.zeros((3, self.n_envs))
        if kv_scale is not None:
            self.set_kv_scale(kv_scale)
        self.reset(np.zeros(3))

    # ------------------------------------------------------------------ models
    @property
    def kv_1_s(self) -> np.ndarray:
        """Position gains in force, (n_envs, 3), 1/s."""
        return self._base_kv * self._kv_scale

    def _axis_models(self, scale: np.ndarray) -> tuple[AxisKey, ...]:
        """X, Y, Z with Kv multiplied by ``scale`` (3,), as the keys of their discrete models (the models
        are computed once per process and key: :func:`_discrete_model`); unstable loops are refused."""
        keys = []
        for name, axis, factor in zip(AXIS_NAMES, self.machine.axes, scale, strict=True):
            kv = axis.kv_1_s * float(factor)
            key = (float(kv), float(axis.feedforward), float(axis.velocity_loop_hz),
                   float(axis.velocity_loop_damping), self.period_s)  # fmt: skip
            if _discrete_model(*key)[1] >= 1.0:
                # Routh-Hurwitz on s³ + 2ζωn s² + ωn² s + ωn² Kv: stable iff Kv < 2ζωn.
                raise ConfigError(
                    f"{self.machine.source}: axes.{name}: the servo loop is unstable (kv_1_s = {kv:g}, "
                    f"velocity_loop_hz = {axis.velocity_loop_hz}, damping = {axis.velocity_loop_damping}); "
                    "a velocity loop needs kv_1_s < 2·damping·2π·velocity_loop_hz"
                )
            keys.append(key)
        return tuple(keys)

    def set_kv_scale(self, kv_scale: np.ndarray, env: int | None = None) -> None:
        """Multiply the preset's per-axis Kv by ``kv_scale``: (3,) or (n_envs, 3) for all envs, or (3,)
        for one ``env``. Takes effect from the next step; the state is kept. Cached lifted matrices are
        rebuilt for the envs that change (a few ms per env), so call it at resets, not every step.
        """
        new_scale = checked_kv_scale(kv_scale, self._kv_scale, env)
        envs: list[int] = list(range(self.n_envs)) if env is None else [env]
        self._lifted4.clear()
        self.model_version += 1
        if np.all(new_scale == new_scale[0]):
            # Every env alike again: back to one shared model per axis.
            self._shared_models = self._axis_models(new_scale[0])
            self._env_models = None
            self._lifted.clear()
        else:
            if self._env_models is None:
                self._env_models = [self._shared_models for _ in range(self.n_envs)]
                self._lifted = {
                    n: np.repeat(lifted[:, None], self.n_envs, axis=1) for n, lifted in self._lifted.items()
                }
            changed = [e for e in envs if not np.array_equal(new_scale[e], self._kv_scale[e])]
            for e in changed:
                self._env_models[e] = self._axis_models(new_scale[e])
                for n_ticks, lifted in self._lifted.items():
                    lifted[:, e] = self._lift_models(self._env_models[e], n_ticks)
        self._kv_scale = new_scale

    # ------------------------------------------------------------------ lifted matrices
    def _lifted_matrix(self, n_ticks: int) -> np.ndarray:
        cached = self._lifted.get(n_ticks)
        if cached is not None:
            return cached
        if self._env_models is None:
            lifted = self._lift_models(self._shared_models, n_ticks)
        else:
            lifted = np.stack([self._lift_models(models, n_ticks) for models in self._env_models], axis=1)
        self._lifted[n_ticks] = lifted
        return lifted

    def _lifted4_matrix(self, n_ticks: int) -> np.ndarray:
        cached = self._lifted4.get(n_ticks)
        if cached is None:
            cached = self._lifted_matrix(n_ticks)
            if cached.ndim == 3:  # shared model: one matrix per axis for every env
                cached = cached[:, None]
            self._lifted4[n_ticks] = cached
        return cached

    def _lift_models(self, models: tuple[AxisKey, ...], n_ticks: int) -> np.ndarray:
        """(3, n + 3 + 1, 3 + H + n): [z_0, raw_{1−H}..raw_0, raw_1..raw_n] → [x_1..x_n, z_n, ẋ_n]
        (:func:`_lifted_axes`, computed once per process for a machine's axes and a block length)."""
        return _lifted_axes(models, self._n_hist, self.filter_samples, n_ticks)

    # ------------------------------------------------------------------ public API
    def reset(self, position: np.ndarray, env: int | None = None) -> None:
        """Put every axis at rest at ``position`` ((n_envs, 3) or (3,)); the reference history too. With
        ``env``, only that env (``position`` (3,))."""
        envs = slice(None) if env is None else slice(int(env), int(env) + 1)
        n = self.n_envs if env is None else 1
        pos = np.broadcast_to(np.asarray(position, dtype=float), (n, 3))
        if not np.all(np.isfinite(pos)):
            raise ValueError("plant reset position must be finite")
        self._state[:, :, envs] = 0.0
        self._state[:, 0, envs] = pos.T
        self._history[:, :, envs] = pos.T[:, None, :]
        self._velocity[:, envs] = 0.0

    def step(self, reference: np.ndarray) -> np.ndarray:
        """Advance by one sample per reference row and return the actual positions, same shape.

        ``reference`` is (n_envs, n_ticks, 3), or (n_ticks, 3) when ``n_envs == 1``.
        """
        ref = reference
        if (type(ref) is np.ndarray and ref.dtype == np.float64 and ref.ndim == 3
                and ref.shape[0] == self.n_envs and ref.shape[2] == 3
                and 0 < ref.shape[1] <= MAX_LIFTED_TICKS):  # fmt: skip
            # The usual call (the env's): one block, no conversions.
            actual = np.empty(ref.shape)
            if not _step_kernel(self._lifted4_matrix(ref.shape[1]), self._state, self._history,
                                self._velocity, ref, actual):  # fmt: skip
                raise ValueError("reference positions must be finite")
            return actual
        ref, squeeze = reference_rows(reference, self.n_envs)
        n_ticks = ref.shape[1]
        if n_ticks == 0:
            return ref[0].copy() if squeeze else ref.copy()
        if n_ticks > MAX_LIFTED_TICKS and not np.isfinite(ref.sum()):  # the kernel checks one block
            raise ValueError("reference positions must be finite")
        actual = np.empty((self.n_envs, n_ticks, 3))
        for i in range(0, n_ticks, MAX_LIFTED_TICKS):
            block = ref[:, i : i + MAX_LIFTED_TICKS]
            lifted = self._lifted4_matrix(block.shape[1])
            if not _step_kernel(lifted, self._state, self._history, self._velocity, block,
                                actual[:, i : i + MAX_LIFTED_TICKS]):  # fmt: skip
                raise ValueError("reference positions must be finite")
        return actual[0] if squeeze else actual

    @property
    def position(self) -> np.ndarray:
        """Actual position (n_envs, 3), mm."""
        return self._state[:, 0, :].T.copy()

    @property
    def velocity(self) -> np.ndarray:
        """Actual velocity (n_envs, 3), mm/s."""
        return self._velocity.T.copy()

    @property
    def reference(self) -> np.ndarray:
        """Last raw (unfiltered) reference (n_envs, 3), mm."""
        return self._history[:, -1, :].T.copy()

    @property
    def following_error(self) -> np.ndarray:
        """Raw reference − actual at the last sample (n_envs, 3), mm."""
        return (self._history[:, -1, :] - self._state[:, 0, :]).T

    def settled(self, tolerance_mm: float) -> np.ndarray:
        """(n_envs,) bool: at rest within ``tolerance_mm`` of the last reference.

        True where the reference has stopped (the last raw references — the whole filter window, and
        at least two — are equal), the Euclidean following error is within the tolerance, and the speed
        is at most min(Kv)·tolerance — the speed a P loop has that far from its target, so a settling
        axis passes and one that is still crossing the band does not.
        """
        out = np.empty(self.n_envs, dtype=bool)
        _settled_kernel(self._state, self._history, self._velocity, float(tolerance_mm), self.kv_min, out)
        return out

    @property
    def kv_min(self) -> np.ndarray:
        """Lowest position gain of each env, (n_envs,), 1/s (the settle test's speed bound)."""
        return self.kv_1_s.min(axis=1)


@njit(cache=True, nogil=True)
def _settled_kernel(state, history, velocity, tolerance_mm, kv_min, out) -> None:
    for e in range(out.shape[0]):
        out[e] = settled_env(state, history, velocity, e, tolerance_mm, kv_min[e])
