"""The planner's model of the servo axes: the contour error they make at a path speed, in closed form.

Each axis is the plant's loop ``u = Kv·(r − x) + f·ṙ`` into a velocity loop ``H(s)`` (ideal, or 2nd order
ωn, ζ), so ``X/R = G(s) = H·(Kv + f·s)/(s + H·Kv)``; a post-interpolation moving average multiplies every
axis by the same ``M(jω)``. Three closed forms (the planner's docstring, :mod:`cnc_gym.motion.planner`):
the straight line's lag, the arc's radial error and the corner's transient, tabulated once per machine
(:class:`ServoTables`). The model reads machine parameters only, never the plant.
"""

from __future__ import annotations

import hashlib
import math
import os
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np
from numba import njit

from cnc_gym.machine import MachineConfig
from cnc_gym.toolpath import PLANE_AXES, Plane

#: Speeds are searched in mm/s up to this bound (far above any cutting feed).
SPEED_CEILING_MM_S = 2000.0


class ServoErrorModel:
    """Steady-state contour error of the machine's servo axes as a function of path speed."""

    def __init__(self, machine: MachineConfig) -> None:
        self.machine = machine
        self.period_s = float(machine.controller.interpolation_period_s)
        self.filter_samples = max(1, round(machine.controller.post_filter_s / self.period_s))
        self.kv = np.array(machine.axis_array("kv_1_s"))
        self.ff = np.array(machine.axis_array("feedforward"))
        self.vel_hz = np.array(machine.axis_array("velocity_loop_hz"))
        self.vel_zeta = np.array(machine.axis_array("velocity_loop_damping"))
        # Ramp lag per unit speed of each axis: (1 − f)/Kv, plus the moving average's (N − 1)·T/2.
        self.lag_s = (1.0 - self.ff) / self.kv + (self.filter_samples - 1) * self.period_s / 2.0

    def axis_response(self, omega: np.ndarray) -> np.ndarray:
        """Complex frequency response X/R of each axis at ω (rad/s): shape (3, len(omega))."""
        s = 1j * np.atleast_1d(np.asarray(omega, dtype=float))[None, :]
        wn = 2.0 * np.pi * self.vel_hz[:, None]
        zeta = self.vel_zeta[:, None]
        ideal = self.vel_hz[:, None] <= 0
        h = np.where(ideal, 1.0, wn**2 / (s**2 + 2.0 * zeta * wn * s + wn**2 + (wn == 0)))
        kv, ff = self.kv[:, None], self.ff[:, None]
        g = h * (kv + ff * s) / (s + h * kv)
        n = self.filter_samples
        if n > 1:  # moving average of n samples, common to all axes
            k = np.arange(n)[:, None]
            m = np.exp(-s[0][None, :] * k * self.period_s).mean(axis=0)  # delays e^(-s·kT), s = jω
            g = g * m[None, :]
        return g

    def line_error_per_speed(self, tangent: np.ndarray) -> np.ndarray:
        """Steady contour error per unit speed (mm per mm/s) on straight moves, unit tangents (m, 3)."""
        lag = tangent * self.lag_s[None, :]  # following-error vector per unit speed
        along = np.sum(lag * tangent, axis=1, keepdims=True)
        return np.linalg.norm(lag - along * tangent, axis=1)

    def arc_error(self, speed_mm_s: float | np.ndarray, radius_mm: float, plane: int) -> np.ndarray:
        """Steady contour error (mm) on an arc of ``radius_mm`` in ``plane`` at each speed."""
        speed = np.atleast_1d(np.asarray(speed_mm_s, dtype=float))
        u, v, _ = PLANE_AXES[Plane(int(plane))]
        g = self.axis_response(speed / radius_mm)  # (3, m)
        phase = np.linspace(0.0, 2.0 * np.pi, 73)[:, None]
        x = np.abs(g[u])[None, :] * np.cos(phase + np.angle(g[u])[None, :])
        y = np.abs(g[v])[None, :] * np.sin(phase + np.angle(g[v])[None, :])
        rho = np.hypot(x, y)
        return radius_mm * np.max(np.abs(rho - 1.0), axis=0)

    def arc_speed_cap(self, radius_mm: float, plane: int, error_mm: float) -> float:
        """Largest speed whose steady arc error is at most ``error_mm`` (bisection; error grows with v)."""
        lo, hi = 0.0, SPEED_CEILING_MM_S
        if self.arc_error(hi, radius_mm, plane)[0] <= error_mm:
            return hi
        for _ in range(50):
            mid = 0.5 * (lo + hi)
            if self.arc_error(mid, radius_mm, plane)[0] <= error_mm:
                lo = mid
            else:
                hi = mid
        return lo



# ------------------------------------------------------------------------------------ tabulated model
@dataclass(frozen=True)
class ServoTables:
    """The servo error model of one machine, tabulated once for the planner's per-segment work."""

    lag_s: np.ndarray  # (3,) steady lag per unit speed, s
    arc_omega: np.ndarray  # (m,) ω grid, rad/s
    arc_error: np.ndarray  # (3 planes, m) steady arc error per mm of radius, non-decreasing in ω
    ramp_t: np.ndarray  # (k,) time grid, s
    ramp_error: np.ndarray  # (3, k) E_k(t): following error after a unit velocity step, s (→ lag_s)


def _ramp_error_response(model: ServoErrorModel, t: np.ndarray) -> np.ndarray:
    """E_k(t) of every axis (:func:`_compute_ramp_error_response`), kept on disk: computing it imports
    ``scipy.signal``, which costs a fresh process about a second, the rest of the planner's tables a few
    ms. The file holds the very array computed (``.npy``, no pickle) under a key of everything it depends
    on (the loop parameters, the time grid, the SciPy version), so a hit gives the same bits a computation
    would; a file that cannot be read, or is not the array its key names, is computed again."""
    key = _response_key(model, t)
    path = response_cache_dir() / f"{key}.npy"
    try:
        with path.open("rb") as fh:
            cached = np.load(fh, allow_pickle=False)
        if cached.shape == (3, len(t)) and cached.dtype == np.float64 and np.all(np.isfinite(cached)):
            return cached
    except (OSError, ValueError, EOFError):
        pass
    out = _compute_ramp_error_response(model, t)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        if sum(1 for _ in os.scandir(path.parent)) >= MAX_CACHED_RESPONSES:
            return out  # (domain randomisation draws a machine per episode: the folder stays bounded)
        tmp = path.with_suffix(f".{os.getpid()}.tmp")
        with tmp.open("wb") as fh:
            np.save(fh, out, allow_pickle=False)
        os.replace(tmp, path)
    except OSError:  # a read-only or full disk: the next process computes it again
        pass
    return out


#: Files the response cache folder holds at most (about 4 KB each): the presets' and a user's machines, not
#: every machine a randomised training run draws.
MAX_CACHED_RESPONSES = 256


def response_cache_dir() -> Path:
    """Where the servo responses are kept: ``$CNC_GYM_CACHE_DIR/servo``, else
    ``$XDG_CACHE_HOME/cnc-gym/servo`` (beside the bounds, :func:`cnc_gym.motion.bound.cache_dir`)."""
    root = os.environ.get("CNC_GYM_CACHE_DIR")
    if root:
        return Path(root) / "servo"
    xdg = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(xdg) / "cnc-gym" / "servo"


def _response_key(model: ServoErrorModel, t: np.ndarray) -> str:
    from importlib.metadata import version

    h = hashlib.sha256(f"ramp-error-1:scipy-{version('scipy')}:".encode())
    for arr in (model.kv, model.ff, model.vel_hz, model.vel_zeta, t):
        h.update(np.ascontiguousarray(arr, dtype=np.float64).tobytes())
    h.update(f"{model.filter_samples}:{model.period_s!r}".encode())
    return h.hexdigest()


def _compute_ramp_error_response(model: ServoErrorModel, t: np.ndarray) -> np.ndarray:
    """E_k(t) of every axis: the step response of (1 − G_k(s))/s, then the moving average if any."""
    from scipy import signal

    out = np.zeros((3, len(t)))
    for k in range(3):
        kv, ff = float(model.kv[k]), float(model.ff[k])
        if model.vel_hz[k] > 0:  # (1 − G)/s = (D − f·ωn²)/(s·D + Kv·ωn²), D = s² + 2ζωn·s + ωn²
            wn = 2.0 * math.pi * float(model.vel_hz[k])
            zeta = float(model.vel_zeta[k])
            num = [1.0, 2.0 * zeta * wn, wn * wn * (1.0 - ff)]
            den = [1.0, 2.0 * zeta * wn, wn * wn, kv * wn * wn]
        else:  # (1 − f)/(s + Kv)
            num, den = [1.0 - ff], [1.0, kv]
        _, out[k] = signal.step(signal.TransferFunction(num, den), T=t)
    n = model.filter_samples
    if n > 1:  # error = (r − M r) + M(r − G r): the average's own lag plus the averaged servo error
        dt = model.period_s
        ramp = t.copy()
        shifted = [np.interp(t - i * dt, t, ramp, left=0.0) for i in range(n)]
        own = ramp - np.mean(shifted, axis=0)
        servo = np.mean([[np.interp(t - i * dt, t, out[k], left=0.0) for i in range(n)] for k in range(3)],
                        axis=1)  # fmt: skip
        out = own[None, :] + servo
    return out


@lru_cache(maxsize=256)  # (a randomised training run plans on a few dozen machines)
def servo_tables(machine: MachineConfig) -> ServoTables:
    """:class:`ServoTables` of ``machine`` (cached: machines are frozen and hashable)."""
    model = ServoErrorModel(machine)
    omega = np.geomspace(1e-2, 2e4, 400)
    arc = np.zeros((3, len(omega)))
    for plane in range(3):  # error per mm of radius: the radius only scales the circle
        arc[plane] = np.maximum.accumulate(model.arc_error(omega, 1.0, plane))
    horizon = 8.0 / float(np.min(model.kv)) + model.filter_samples * model.period_s
    t = np.linspace(0.0, horizon, 160)
    return ServoTables(lag_s=model.lag_s.copy(), arc_omega=omega, arc_error=arc, ramp_t=t,
                       ramp_error=_ramp_error_response(model, t))  # fmt: skip


def arc_caps(tables: ServoTables, radius_mm: np.ndarray, plane: np.ndarray, error_mm: float) -> np.ndarray:
    """Largest speed on arcs of ``radius_mm`` (in ``plane``) whose steady error is ≤ ``error_mm``."""
    radius = np.asarray(radius_mm, dtype=float)
    caps = np.full(radius.shape, SPEED_CEILING_MM_S)
    for p in np.unique(plane):
        sel = plane == p
        per_mm = error_mm / radius[sel]
        table = tables.arc_error[int(p)]
        omega = np.interp(per_mm, table, tables.arc_omega, right=tables.arc_omega[-1])
        # Below the table the error grows at least linearly with ω: scaling down linearly is safe.
        small = per_mm < table[0]
        omega = np.where(small, tables.arc_omega[0] * per_mm / max(table[0], 1e-300), omega)
        caps[sel] = np.where(per_mm >= table[-1], SPEED_CEILING_MM_S, omega * radius[sel])
    return caps


def corner_error_per_speed(tables: ServoTables, u_in: np.ndarray, u_out: np.ndarray) -> np.ndarray:
    """c(u_in, u_out) per junction (mm per mm/s): the corner model of the module docstring, (m,)."""
    return _corner_errors(np.ascontiguousarray(u_in, dtype=np.float64),
                          np.ascontiguousarray(u_out, dtype=np.float64), tables.ramp_t,
                          np.ascontiguousarray(tables.ramp_error.T), tables.lag_s)  # fmt: skip


@njit(cache=True)
def _corner_errors(u_in: np.ndarray, u_out: np.ndarray, t: np.ndarray, e: np.ndarray,
                   lag: np.ndarray) -> np.ndarray:  # fmt: skip
    """For each corner, max over t of the distance of y(t) = t·b − lag∘a − (b − a)∘E(t) from the two legs
    {−α·a} and {β·b} (α, β ≥ 0): the actual point per unit speed, the corner at the origin."""
    m = u_in.shape[0]
    out = np.zeros(m)
    y = np.zeros(3)
    for j in range(m):
        worst = 0.0
        for k in range(t.shape[0]):
            along_in = 0.0
            along_out = 0.0
            for c in range(3):
                y[c] = t[k] * u_out[j, c] - lag[c] * u_in[j, c] - (u_out[j, c] - u_in[j, c]) * e[k, c]
                along_in += y[c] * u_in[j, c]
                along_out += y[c] * u_out[j, c]
            along_in = min(along_in, 0.0)  # nearest point of the incoming leg
            along_out = max(along_out, 0.0)  # ... and of the outgoing leg
            d_in = 0.0
            d_out = 0.0
            for c in range(3):
                d_in += (y[c] - along_in * u_in[j, c]) ** 2
                d_out += (y[c] - along_out * u_out[j, c]) ** 2
            d = math.sqrt(min(d_in, d_out))
            if d > worst:
                worst = d
        out[j] = worst
    return out


# ----------------------------------------------------------------------- planner version 2's models
# servo_tables, arc_caps and corner_error_per_speed above are also planner version 1's (frozen, see
# planner/v1.py): add models below, never change those.
@dataclass(frozen=True)
class ApproachTables:
    """What the corner-with-approach model needs beyond :class:`ServoTables`: the cumulative excess lag.

    A velocity step of −Δv along the incoming tangent τ seconds before a corner leaves axis k behind
    its constant-speed state by ``Δv·(L_k − E_k(τ))`` (the loop's ramp-error response E_k tends to its
    steady lag L_k); a linear deceleration ramp of duration T that ended τ ago leaves
    ``Δv·(C_k(τ + T) − C_k(τ))/T``, with ``C_k(τ) = ∫₀^τ (L_k − E_k)``, tabulated here on ``ramp_t``.
    """

    excess_integral: np.ndarray  # (k, 3) C_k on ServoTables.ramp_t, s²
    ramp_error: np.ndarray  # (k, 3) E_k, time-major (ServoTables.ramp_error transposed), s


@lru_cache(maxsize=256)
def approach_tables(machine: MachineConfig) -> ApproachTables:
    """:class:`ApproachTables` of ``machine`` (cached, like :func:`servo_tables`)."""
    tables = servo_tables(machine)
    e = np.ascontiguousarray(tables.ramp_error.T)
    gap = np.maximum(tables.lag_s[None, :] - e, 0.0)  # L − E ≥ 0 (E rises to L; overshoot counts as 0)
    dt = np.diff(tables.ramp_t)
    c = np.zeros_like(gap)
    c[1:] = np.cumsum(0.5 * (gap[1:] + gap[:-1]) * dt[:, None], axis=0)
    return ApproachTables(excess_integral=c, ramp_error=e)


@njit(cache=True, inline="always")
def _on_row(table: np.ndarray, row: int, w: float, c: int) -> float:
    """Column ``c`` of a table on the uniform time grid at grid row ``row`` plus ``w`` of the next: linear
    between rows, held at the first row before the grid (row −1) and at the last beyond it."""
    if row < 0:
        return table[0, c]
    if row >= table.shape[0] - 1:
        return table[table.shape[0] - 1, c]
    return table[row, c] * (1.0 - w) + table[row + 1, c] * w


@njit(cache=True)  # (not inlined: its two callers would each compile the whole of it again)
def _approach_error_at(k: int, u_in: np.ndarray, u_out: np.ndarray, speed: float, drop: float, ramp_s: float,
                       hold_s: float, t: np.ndarray, e: np.ndarray, c_int: np.ndarray,
                       lag: np.ndarray) -> float:  # fmt: skip
    """The error of :func:`corner_approach_error` at time ``t[k]`` after the corner.

    The planner's innermost loop, so written out in scalars: each time's place on the grid (row and
    weight) is found once for the three axes' look-ups (:func:`_on_row`).
    """
    tk = t[k]
    i0, i1, i2 = u_in[0], u_in[1], u_in[2]
    o0, o1, o2 = u_out[0], u_out[1], u_out[2]
    y0 = speed * (tk * o0 - lag[0] * i0 - (o0 - i0) * e[k, 0])
    y1 = speed * (tk * o1 - lag[1] * i1 - (o1 - i1) * e[k, 1])
    y2 = speed * (tk * o2 - lag[2] * i2 - (o2 - i2) * e[k, 2])
    if drop > 0.0:
        n = t.shape[0]
        step = t[1] - t[0]
        tau = tk + hold_s
        row, w = -1, 0.0  # the grid place of τ: row −1 before the grid, n − 1 beyond it
        if tau > 0.0:
            f = tau / step
            row = int(f)
            if row >= n - 1:
                row = n - 1
            else:
                w = f - row
        row_end, w_end = row, w  # ... and of τ + T
        if ramp_s > 0.0:
            row_end, w_end = -1, 0.0
            if tau + ramp_s > 0.0:
                f = (tau + ramp_s) / step
                row_end = int(f)
                if row_end >= n - 1:
                    row_end = n - 1
                else:
                    w_end = f - row_end
        x0 = x1 = x2 = 0.0
        for a in range(3):
            if ramp_s > 0.0:  # the ramp's mean excess lag: (C(τ + T) − C(τ))/T
                x = (_on_row(c_int, row_end, w_end, a) - _on_row(c_int, row, w, a)) / ramp_s
            else:  # a step: L − E(τ)
                x = max(lag[a] - _on_row(e, row, w, a), 0.0)
            if a == 0:
                x0 = x
            elif a == 1:
                x1 = x
            else:
                x2 = x
        y0 -= drop * x0 * i0
        y1 -= drop * x1 * i1
        y2 -= drop * x2 * i2
    along_in = min(0.0 + y0 * i0 + y1 * i1 + y2 * i2, 0.0)  # nearest point of the incoming leg
    along_out = max(0.0 + y0 * o0 + y1 * o1 + y2 * o2, 0.0)  # ... and of the outgoing leg
    g0, g1, g2 = y0 - along_in * i0, y1 - along_in * i1, y2 - along_in * i2
    d_in = 0.0 + g0 * g0 + g1 * g1 + g2 * g2
    g0, g1, g2 = y0 - along_out * o0, y1 - along_out * o1, y2 - along_out * o2
    d_out = 0.0 + g0 * g0 + g1 * g1 + g2 * g2
    return math.sqrt(min(d_in, d_out))


@njit(cache=True)
def corner_error_unit(u_in: np.ndarray, u_out: np.ndarray, t: np.ndarray, e: np.ndarray,
                      lag: np.ndarray) -> float:  # fmt: skip
    """:func:`corner_approach_error` at unit speed with no approach (``drop = 0``): the constant-speed
    corner's error per mm/s. The same operations, in a loop of its own (the planner calls it for every
    junction and window)."""
    i0, i1, i2 = u_in[0], u_in[1], u_in[2]
    o0, o1, o2 = u_out[0], u_out[1], u_out[2]
    l0, l1, l2 = lag[0], lag[1], lag[2]
    worst = 0.0
    for k in range(t.shape[0]):
        tk = t[k]
        y0 = 1.0 * (tk * o0 - l0 * i0 - (o0 - i0) * e[k, 0])
        y1 = 1.0 * (tk * o1 - l1 * i1 - (o1 - i1) * e[k, 1])
        y2 = 1.0 * (tk * o2 - l2 * i2 - (o2 - i2) * e[k, 2])
        along_in = min(0.0 + y0 * i0 + y1 * i1 + y2 * i2, 0.0)
        along_out = max(0.0 + y0 * o0 + y1 * o1 + y2 * o2, 0.0)
        g0, g1, g2 = y0 - along_in * i0, y1 - along_in * i1, y2 - along_in * i2
        d_in = 0.0 + g0 * g0 + g1 * g1 + g2 * g2
        g0, g1, g2 = y0 - along_out * o0, y1 - along_out * o1, y2 - along_out * o2
        d_out = 0.0 + g0 * g0 + g1 * g1 + g2 * g2
        d = math.sqrt(min(d_in, d_out))
        if d > worst:
            worst = d
    return worst


@njit(cache=True)
def corner_approach_error(u_in: np.ndarray, u_out: np.ndarray, speed: float, drop: float, ramp_s: float,
                          hold_s: float, t: np.ndarray, e: np.ndarray, c_int: np.ndarray,
                          lag: np.ndarray, stop_above: float = np.inf) -> float:  # fmt: skip
    """Largest contour error (mm) of a corner (unit tangents ``u_in`` → ``u_out``) taken at ``speed`` after
    slowing down by ``drop`` (mm/s) along ``u_in``: a linear ramp of ``ramp_s`` seconds that ended
    ``hold_s`` seconds before the corner (:class:`ApproachTables`). With ``drop = 0`` it is the
    constant-speed corner model (``speed × corner_error_per_speed``).

    The servo axes are linear, so the tool's deviation is the constant-speed corner's,
    ``v·(t·u_out − L∘u_in − (u_out − u_in)∘E(t))``, plus the excess lag the faster approach left along
    ``u_in``, still decaying after the corner; the error is its distance from the corner's two legs.

    ``stop_above``: return as soon as the error passes it (a value above it, not the maximum): what a
    caller that only compares the error with a budget needs, at a fraction of the cost when it fails.
    """
    worst = 0.0
    for k in range(t.shape[0]):
        d = _approach_error_at(k, u_in, u_out, speed, drop, ramp_s, hold_s, t, e, c_int, lag)
        if d > worst:
            worst = d
            if worst > stop_above:
                break
    return worst


@njit(cache=True)
def corner_approach_exceeds(u_in: np.ndarray, u_out: np.ndarray, speed: float, drop: float, ramp_s: float,
                            hold_s: float, t: np.ndarray, e: np.ndarray, c_int: np.ndarray, lag: np.ndarray,
                            limit: float, first: int) -> int:  # fmt: skip
    """Whether :func:`corner_approach_error` passes ``limit``: the index of a time on ``t`` where it does,
    or −1 when it never does. The scan starts at ``first`` and wraps round: a search over holds passes
    the previous hold's index, where a too-short hold usually fails again at once."""
    n = t.shape[0]
    for j in range(n):
        k = first + j if first + j < n else first + j - n
        if _approach_error_at(k, u_in, u_out, speed, drop, ramp_s, hold_s, t, e, c_int, lag) > limit:
            return k
    return -1
