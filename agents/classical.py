"""The classical baseline: a tolerance-aware look-ahead feed schedule, used as an override policy.

How the schedule is built (once per program and machine, cached):

1. **Servo error model** (:class:`ServoErrorModel`). Each axis is the plant's loop (``cnc_gym.plant``):
   ``u = Kv·(r − x) + f·ṙ`` into a velocity loop ``H(s)`` (ideal, or 2nd order ωn, ζ), so
   ``X/R = G(s) = H·(Kv + f·s)/(s + H·Kv)``; the post-interpolation moving average multiplies every axis
   by the same ``M(jω)``. Two steady states give closed forms:

   * *straight line at speed v* — each axis lags by ``(1 − f_k)·v_k/Kv_k`` (ramp error of the loop, ``H(0)
     = 1``). Equal lags only move the tool along the line; unequal ones (gain mismatch, unequal
     feed-forward) push it sideways: contour error = component of the lag vector normal to the tangent,
     linear in v.
   * *arc of radius R at speed v* (ω = v/R) — axis u answers ``R·|G_u(jω)|·cos(ωt + φ_u)``, axis v likewise;
     the contour error is ``R·max_t |ρ(t) − 1|`` with ρ the actual radius over R. For a P loop with
     feed-forward f and matched axes this is ``R(1 − |G|) ≈ (1 − f²)·v²·κ/(2·Kv²)``, since
     ``|G|² = (Kv² + f²ω²)/(Kv² + ω²)``.

   The speed cap is the largest v whose predicted error stays within ``margin × tolerance``.
2. **Refinement against the real controller and plant.** Corners and transients have no useful closed
   form (their error depends on the controller's corner speed, jerk and the loop's transient), so the
   planner simulates the episode exactly as the env will run it (a copy of the env, same control period,
   same policy function), finds the control steps whose contour error exceeds the target, lowers the cap
   on the stretch of path behind each one (by the ratio target/error), rebuilds the schedule and
   repeats until no step exceeds the target.
3. **Bidirectional jerk-limited scan.** The cap is turned into a reachable speed schedule: backward
   (deceleration feasibility) and forward (acceleration) passes with the path acceleration A, jerk J
   and the override slew rate, using the jerk-limited S-curve reach ``(v − v0)(v + v0)² = J·L²`` (accel
   capped at A). The pass keeps one "anchor" (the last binding point); this is exact because a profile
   that keeps accelerating from an anchor always reaches at least what a restart from a later point
   would.
4. **As a policy**: at path position s the knob is set to the smallest scheduled override
   ``v_sched/F`` over the stretch the controller covers in its reaction time, clipped to
   ``[0, max_override]``. Where geometry allows (straight lines, gentle curves) that is above 100 %,
   which is how the planner beats every constant override that stays within tolerance.
"""

from __future__ import annotations

import copy
import math
import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np

from agents.base import override_action, require_override_mode
from cnc_gym.machine import MachineConfig
from cnc_gym.toolpath import PLANE_AXES, Plane, SegmentKind, Toolpath

# Speeds are searched in mm/s up to this bound (far above any cutting feed).
_SPEED_CEILING_MM_S = 2000.0


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
            m = np.exp(-1j * s[0][None, :] * k * self.period_s).mean(axis=0)
            g = g * m[None, :]
        return g

    def line_error_per_speed(self, tangent: np.ndarray) -> np.ndarray:
        """Steady contour error per unit speed (mm per mm/s) on straight moves, unit tangents (m, 3)."""
        lag = tangent * self.lag_s[None, :]  # following-error vector per unit speed
        along = np.sum(lag * tangent, axis=1, keepdims=True)
        return np.linalg.norm(lag - along * tangent, axis=1)

    def arc_error(self, speed_mm_s: np.ndarray, radius_mm: float, plane: int) -> np.ndarray:
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
        lo, hi = 0.0, _SPEED_CEILING_MM_S
        if self.arc_error(hi, radius_mm, plane)[0] <= error_mm:
            return hi
        for _ in range(50):
            mid = 0.5 * (lo + hi)
            if self.arc_error(mid, radius_mm, plane)[0] <= error_mm:
                lo = mid
            else:
                hi = mid
        return lo


def _ramp_length(v0: float, v: float, accel: float, jerk: float) -> float:
    """Path length of the jerk-limited S-curve from ``v0`` to ``v`` (both at zero acceleration)."""
    dv = v - v0
    if dv <= 0:
        return 0.0
    t = 2.0 * math.sqrt(dv / jerk) if dv <= accel * accel / jerk else dv / accel + accel / jerk
    return 0.5 * (v0 + v) * t


def jerk_limited_reach(v0: float, distance_mm: float, accel: float, jerk: float) -> float:
    """Highest speed reachable from ``v0`` (at zero acceleration) within ``distance_mm``.

    S-curve with jerk ``jerk`` and acceleration capped at ``accel``: a change Δv ≤ A²/J takes
    T = 2·√(Δv/J) over L = (v0 + v)·√(Δv/J), i.e. ``(v − v0)(v + v0)² = J·L²`` (solved by Newton in
    w = v + v0 from the right, where the cubic is increasing and convex); a larger change takes
    T = Δv/A + A/J over L = (v0 + v)/2·T, a quadratic in v.
    """
    if distance_mm <= 0:
        return v0
    dv_full = accel * accel / jerk
    if distance_mm > _ramp_length(v0, v0 + dv_full, accel, jerk):
        b = dv_full  # v² + (A²/J)·v + (v0·A²/J − v0² − 2·A·L) = 0
        c = v0 * dv_full - v0 * v0 - 2.0 * accel * distance_mm
        return 0.5 * (-b + math.sqrt(b * b - 4.0 * c))
    target = jerk * distance_mm * distance_mm
    w = 2.0 * v0 + dv_full
    for _ in range(60):
        f = (w - 2.0 * v0) * w * w - target
        step = f / (w * (3.0 * w - 4.0 * v0))
        w -= step
        if abs(step) < 1e-9 * max(w, 1.0):
            break
    return max(w - v0, v0)


def bidirectional_scan(s: np.ndarray, cap: np.ndarray, accel: float | np.ndarray, jerk: float) -> np.ndarray:
    """Largest speed profile ≤ ``cap`` whose rises and falls are reachable under (A, J).

    Backward pass (can we slow down in time for every later cap?) then forward pass (can we speed up
    that fast?). Each pass keeps one anchor, the last point where the cap itself was binding; ``accel``
    may vary along the path (one value per point; the anchor's applies to the ramp leaving it).
    """
    out = np.array(cap, dtype=float)
    accel_at = np.broadcast_to(np.asarray(accel, dtype=float), out.shape)
    for order in (range(len(s) - 1, -1, -1), range(len(s))):
        anchor_s, anchor_v, anchor_a = None, 0.0, 0.0
        for i in order:
            if anchor_s is not None:
                distance = abs(anchor_s - s[i])
                # Cheap test first: is the cap itself reachable from the anchor?
                if _ramp_length(anchor_v, out[i], anchor_a, jerk) > distance:
                    out[i] = jerk_limited_reach(anchor_v, distance, anchor_a, jerk)
                    continue
            anchor_s, anchor_v, anchor_a = s[i], out[i], float(accel_at[i])
    return out


@dataclass
class Schedule:
    """The planner's result for one program: override to command at each path position."""

    s: np.ndarray  # grid of path positions, mm
    cap_mm_s: np.ndarray  # tolerance speed cap (after refinement)
    speed_mm_s: np.ndarray  # scheduled (reachable) speed
    override: np.ndarray  # speed / programmed feed, clipped to [0, max_override]; max_override on rapids
    iterations: int = 0
    predicted_violations: int = 0


class ClassicalPlanner:
    """Tolerance-aware look-ahead feed schedule as a feed-override policy.

    ``margin`` is the fraction of the contour tolerance the schedule aims at; ``refine_iterations`` the
    number of simulate-and-correct rounds (0 = model only); ``reaction_time_s`` how far ahead (in time)
    the knob anticipates the schedule. See the module docstring for the method.
    """

    def __init__(
        self,
        margin: float = 0.85,
        refine_iterations: int = 12,
        reaction_time_s: float | None = None,
        grid_mm: float | None = None,
        min_override: float = 0.05,
        raise_rounds: int = 3,
    ) -> None:
        self.name = "classical"
        self.margin = float(margin)
        self.refine_iterations = int(refine_iterations)
        self.reaction_time_s = reaction_time_s
        self.grid_mm = grid_mm
        self.min_override = float(min_override)
        self.raise_rounds = int(raise_rounds)
        self._cache: dict[tuple, tuple[Toolpath, Schedule]] = {}
        self.schedule: Schedule | None = None
        self._max_override = 2.0
        self._lead_s = 0.03

    # ------------------------------------------------------------------ policy protocol
    def reset(self, env: Any) -> None:
        require_override_mode(env, self.name)
        base = env.unwrapped
        toolpath: Toolpath = base.toolpath
        machine: MachineConfig = base.machine
        period = float(getattr(base, "control_period_s", 0.01))
        self._max_override = float(machine.controller.max_override)
        self._lead_s = self.reaction_time_s if self.reaction_time_s is not None else 2.0 * period + 0.01
        key = (id(toolpath), machine, period, self.margin, self.refine_iterations, self.raise_rounds)
        cached = self._cache.get(key)
        if cached is not None and cached[0] is toolpath:
            self.schedule = cached[1]
            return
        self.schedule = self.plan(toolpath, machine, env=base)
        self._cache[key] = (toolpath, self.schedule)  # keeps the toolpath alive so its id stays unique

    def act(self, observation: np.ndarray, info: dict[str, Any]) -> np.ndarray:
        return override_action(self.override_at(float(info.get("path_s", 0.0)), info), self._max_override)

    # ------------------------------------------------------------------ schedule
    def override_at(self, path_s: float, info: dict[str, Any] | None = None) -> float:
        """Knob value at path position ``path_s``: smallest scheduled override over the reaction window."""
        sched = self.schedule
        if sched is None:
            raise RuntimeError("ClassicalPlanner.reset(env) must be called before act()")
        speed = max(float((info or {}).get("feed_mm_min", 0.0)) / 60.0, 1.0)
        lo = np.searchsorted(sched.s, path_s, side="right") - 1
        hi = np.searchsorted(sched.s, path_s + speed * self._lead_s + 0.5, side="right")
        lo = min(max(lo, 0), len(sched.s) - 1)
        return float(np.min(sched.override[lo : max(hi, lo + 1)]))

    def plan(self, toolpath: Toolpath, machine: MachineConfig, env: Any = None) -> Schedule:
        """Build (and, given an env to copy, refine by simulation) the schedule for one program."""
        if not len(toolpath):  # a program without motion: nothing to schedule (the env ends it at once)
            one = np.ones(1)
            return Schedule(s=np.zeros(1), cap_mm_s=np.full(1, np.inf), speed_mm_s=0 * one, override=one)
        model = ServoErrorModel(machine)
        tolerance = float(machine.controller.contour_tolerance_mm)
        target = self.margin * tolerance
        s, seg = self._grid(toolpath)
        kind = toolpath.kind[seg]
        cutting = (kind == SegmentKind.LINE) | (kind == SegmentKind.ARC) | (kind == SegmentKind.NURBS)
        feed_mm_s = np.where(cutting, np.nan_to_num(toolpath.path_feed[seg], nan=0.0) / 60.0, 0.0)
        cap = np.full(len(s), np.inf)
        cap[cutting] = self._model_cap(toolpath, seg[cutting], s[cutting], model, target)
        # No need to go beyond what the knob can ask for.
        cap = np.minimum(cap, np.where(cutting, feed_mm_s * self._max_override, np.inf))
        accel = min(machine.axis_array("max_accel_mm_s2"))
        jerk = min(machine.axis_array("max_jerk_mm_s3"))
        # The applied override follows the knob at a limited slew: that bounds speed changes too.
        slew_accel = float(machine.controller.override_slew_per_s) * feed_mm_s
        accel_eff = np.where(cutting & (feed_mm_s > 0), np.minimum(accel, slew_accel), accel)
        accel_eff = np.maximum(accel_eff, 1e-3)
        schedule = self._schedule(s, cap, cutting, feed_mm_s, accel_eff, jerk)
        self.schedule = schedule
        if env is None or self.refine_iterations <= 0:
            return schedule
        # Offending places of the previous round: (path position, error, speed). Every round lowers the
        # cap below the speed actually run at an offending place, so a place whose error did not drop
        # does not depend on the feed (a transient the feed does not drive);
        # lowering the cap there again would only cost time.
        floor = np.where(cutting, self.min_override * feed_mm_s, 0.0)
        model_cap = cap.copy()
        previous: list[tuple[float, float, float]] = []
        unresponsive: list[float] = []
        # Every schedule returned has been simulated: the last round only measures.
        for iteration in range(1, self.refine_iterations + 2):
            path_s, error, speed = self._simulate(env)
            if path_s is None:  # env could not be copied: model-only schedule
                return schedule
            schedule.iterations = iteration
            schedule.predicted_violations = int(np.sum(error > tolerance))
            offending = []
            for k in np.flatnonzero(error > target):
                where, err = float(path_s[k]), float(error[k])
                if any(abs(where - u) < 0.5 for u in unresponsive):
                    continue
                before = [(e, v) for (w, e, v) in previous if abs(w - where) < 0.5]
                if before and err > 0.99 * max(e for e, _ in before):
                    unresponsive.append(where)
                    continue
                offending.append((k, where, err))
            previous = [
                (float(path_s[k]), float(error[k]), float(speed[k])) for k in np.flatnonzero(error > target)
            ]
            if not offending or iteration > self.refine_iterations:
                break
            # Lower the cap on the stretch behind each offending step (the error builds up over the
            # servo's settling distance) to the speed actually run there times target/error (a little
            # less, to converge quickly). The speed actually run, not the schedule's: the controller may
            # already go slower than asked (its own corner limit), and only going below that helps.
            # Overlapping stretches take the smallest ratio (never a product of ratios). The floor
            # keeps the knob from stalling the program where the feed is not the cause.
            order = np.argsort(path_s, kind="stable")
            run_speed = np.interp(s, path_s[order], speed[order])
            ratio = np.ones(len(s))
            for k, where, err in offending:
                back = max(2.0, 4.0 * float(speed[k]) * float(np.max(1.0 / model.kv)))
                window = (s >= where - back) & (s <= where + 1.0)
                ratio[window] = np.minimum(ratio[window], max(0.3, 0.95 * target / err))
            lowered = (ratio < 1.0) & cutting
            new_cap = np.maximum(np.minimum(run_speed, schedule.speed_mm_s) * ratio, floor)
            cap[lowered] = np.minimum(cap[lowered], new_cap[lowered])
            schedule = self._schedule(s, cap, cutting, feed_mm_s, accel_eff, jerk)
            schedule.iterations = iteration
            self.schedule = schedule
        if offending:  # not converged: keep the most careful schedule
            return schedule
        reach_mm = max(2.0, 4.0 * float(np.max(schedule.speed_mm_s)) * float(np.max(1.0 / model.kv)))
        limits = (model_cap, cutting, feed_mm_s, accel_eff, jerk)
        return self._raise(env, schedule, (path_s, error), limits, target, tolerance, unresponsive, reach_mm)

    def _raise(self, env, schedule, run, limits, target, tolerance, unresponsive, reach_mm) -> Schedule:
        """Give back speed where the simulated error stayed well below the target.

        The lowering rounds overshoot (each aims a little below the target, and a corner's cut spreads
        over the whole stretch before it). For every grid point, the worst error over the stretch it
        influences (the next ``reach_mm``) is looked up in the last simulated run; where it is under
        70 % of the target the cap is raised by up to 25 % (√ of the headroom: error grows at least
        linearly with speed), never above the servo model's cap. The raised schedule is simulated and
        kept only if no step exceeds the target (apart from spots known not to depend on the feed).
        """
        model_cap, cutting, feed_mm_s, accel, jerk = limits
        s = schedule.s
        spacing = float(np.median(np.diff(s))) if len(s) > 1 else 1.0
        width = max(1, int(np.ceil(reach_mm / spacing)))
        path_s, error = run
        for _ in range(self.raise_rounds):
            cell = np.clip(np.searchsorted(s, path_s, side="right") - 1, 0, len(s) - 1)
            err_cell = np.zeros(len(s))
            np.maximum.at(err_cell, cell, error)
            windows = np.lib.stride_tricks.sliding_window_view(np.pad(err_cell, (0, width)), width + 1)
            ahead = windows.max(axis=1)
            headroom = cutting & (ahead < 0.7 * target) & np.isfinite(schedule.cap_mm_s)
            if not np.any(headroom):
                break
            factor = np.minimum(1.25, np.sqrt(0.9 * target / np.maximum(ahead, 1e-9)))
            cap = schedule.cap_mm_s.copy()
            cap[headroom] = np.minimum(model_cap[headroom], cap[headroom] * factor[headroom])
            candidate = self._schedule(s, cap, cutting, feed_mm_s, accel, jerk)
            candidate.iterations = schedule.iterations + 1
            self.schedule = candidate
            new_path_s, new_error, _ = self._simulate(env)
            over = new_path_s[new_error > target]
            if any(not any(abs(w - u) < 0.5 for u in unresponsive) for w in over):
                self.schedule = schedule  # too far: keep the last schedule that passed
                break
            candidate.predicted_violations = int(np.sum(new_error > tolerance))
            schedule, path_s, error = candidate, new_path_s, new_error
        self.schedule = schedule
        return schedule

    def _grid(self, toolpath: Toolpath) -> tuple[np.ndarray, np.ndarray]:
        total = toolpath.total_length
        spacing = self.grid_mm or float(np.clip(total / 4000.0, 0.05, 0.5))
        s = np.unique(np.concatenate((np.arange(0.0, total, spacing), toolpath.s_start)))
        seg = toolpath.segment_at(s)
        return s, seg

    def _model_cap(self, toolpath: Toolpath, seg: np.ndarray, s: np.ndarray, model: ServoErrorModel,
                   target: float) -> np.ndarray:  # fmt: skip
        cap = np.full(len(seg), _SPEED_CEILING_MM_S)
        is_arc = toolpath.kind[seg] == SegmentKind.ARC
        if np.any(~is_arc):
            _, tangent, curvature = toolpath.evaluate(s[~is_arc])
            per_speed = model.line_error_per_speed(tangent)
            line_cap = np.where(per_speed > 1e-12, target / np.maximum(per_speed, 1e-12), _SPEED_CEILING_MM_S)
            # Curved non-arc segments (NURBS): the arc model at the local radius 1/κ, taken in the XY
            # plane, on radii rounded to 2 % steps so the bisection runs once per step.
            curved = curvature > 1e-9
            if np.any(curved):
                radius = np.exp(np.round(np.log(1.0 / curvature[curved]) / 0.02) * 0.02)
                caps = {r: model.arc_speed_cap(float(r), 0, target) for r in np.unique(radius)}
                line_cap[curved] = np.minimum(line_cap[curved], [caps[r] for r in radius])
            cap[~is_arc] = line_cap
        for index in np.unique(seg[is_arc]):
            value = model.arc_speed_cap(float(toolpath.radius[index]), int(toolpath.plane[index]), target)
            cap[seg == index] = value
        return cap

    def _schedule(self, s, cap, cutting, feed_mm_s, accel, jerk) -> Schedule:
        finite_cap = np.where(np.isfinite(cap), cap, _SPEED_CEILING_MM_S)
        speed = bidirectional_scan(s, finite_cap, accel, jerk)
        override = np.full(len(s), self._max_override)
        fed = cutting & (feed_mm_s > 0)
        override[fed] = np.clip(speed[fed] / feed_mm_s[fed], 0.0, self._max_override)
        return Schedule(s=s, cap_mm_s=cap.copy(), speed_mm_s=speed, override=override)

    def _simulate(self, env: Any) -> tuple[np.ndarray | None, np.ndarray | None, np.ndarray | None]:
        """Run a copy of the (just reset) env with the current schedule.

        Returns per control step: path position (mm), contour error (mm) and path speed (mm/s).
        """
        # Tool paths are immutable and may be large: share them instead of copying.
        memo: dict[int, Any] = {}
        for toolpath in [getattr(env, "toolpath", None), *(tp for _, tp in getattr(env, "_programs", []))]:
            if toolpath is not None:
                memo[id(toolpath)] = toolpath
        try:
            sim = copy.deepcopy(env, memo)
        except Exception as exc:  # an env that cannot be copied: fall back to the model-only schedule
            warnings.warn(f"classical planner: cannot copy the env to refine the schedule ({exc}); "
                          "using the servo model alone", RuntimeWarning, stacklevel=3)  # fmt: skip
            return None, None, None
        info: dict[str, Any] = {}
        observation = None
        positions, errors, speeds = [], [], []
        for _ in range(10_000_000):
            _, _, terminated, truncated, info = sim.step(self.act(observation, info))
            positions.append(float(info.get("path_s", 0.0)))
            errors.append(float(info.get("contour_error_mm", 0.0)))
            speeds.append(float(info.get("feed_mm_min", 0.0)) / 60.0)
            if terminated or truncated:
                break
        return np.asarray(positions), np.asarray(errors), np.asarray(speeds)
