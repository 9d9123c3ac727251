"""The oracle: a simulate-and-correct feed schedule that tunes itself on the exact env, named as an oracle.

It starts from the servo model's schedule, then *runs copies of the env* (the exact controller and plant)
and corrects the schedule where the simulated contour error exceeds its target. No real controller or CAM
system can do that (it would need the machine's exact future), so its results are an **oracle**: an
upper reference for what a feed schedule can reach on this simulator, not a deployable baseline. The
deployable planner is :class:`cnc_gym.policies.classical.ClassicalPlanner`.

Planning runs whole episodes, several times: on a terminal (stderr a TTY) it shows a progress bar while it
plans, before the episode's own bar, and prints nothing otherwise.

How the schedule is built (once per program, machine and control period, cached):

1. **Servo error model** (the deployable planner's, :class:`~cnc_gym.motion.planner.ServoErrorModel`).
   Each axis is the plant's loop (``cnc_gym.plant``): ``u = Kv·(r − x) + f·ṙ`` into a velocity loop
   ``H(s)`` (ideal, or 2nd order ωn, ζ), so ``X/R = G(s) = H·(Kv + f·s)/(s + H·Kv)``; the
   post-interpolation moving average multiplies every axis by the same ``M(jω)``. Two steady states give
   closed forms:

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
import sys
import warnings
from typing import Any

import numpy as np

from cnc_gym.machine import MachineConfig
from cnc_gym.motion.planner import (
    SPEED_CEILING_MM_S,
    Schedule,
    ServoErrorModel,
    bidirectional_scan,
    override_at,
)
from cnc_gym.motion.planner.rule import REACH_MM_V1
from cnc_gym.policies.base import override_action
from cnc_gym.policies.classical import knob_setup
from cnc_gym.rollout import play
from cnc_gym.toolpath import SegmentKind, Toolpath


class OraclePlanner:
    """Simulate-and-correct feed schedule as a feed-override policy, named ``oracle``.

    ``margin`` is the fraction of the contour tolerance the schedule aims at; ``refine_iterations`` the
    number of simulate-and-correct rounds (0 = model only); ``reaction_time_s`` how far ahead (in time)
    the knob anticipates the schedule; ``progress`` shows a planning bar (None: when stderr is a TTY);
    ``plans_on_nominal``: the ``nominal-oracle`` (the same planner, told to simulate an env of the
    nominal machine, :attr:`nominal_env`, which the benchmark builds on tracks whose plant differs).
    See the module docstring for the method.
    """

    deterministic = True

    def __init__(
        self,
        margin: float = 0.85,
        refine_iterations: int = 12,
        reaction_time_s: float | None = None,
        grid_mm: float | None = None,
        min_override: float = 0.05,
        raise_rounds: int = 3,
        progress: bool | None = None,
        plans_on_nominal: bool = False,
    ) -> None:
        self.name = "nominal-oracle" if plans_on_nominal else "oracle"
        self.plans_on_nominal = bool(plans_on_nominal)
        #: An env of the same program on the nominal machine: set, the schedule is planned by simulating
        #: it and then run open loop on the env ``reset`` gets (``nominal-oracle``: simulation with the
        #: wrong model). None: the env ``reset`` gets is simulated (the oracle).
        self.nominal_env: Any = None
        self.progress = progress
        self._bar: Any = None
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
        base, toolpath, machine, period = knob_setup(self, env)
        if self.nominal_env is not None:  # plan on the nominal machine's env, run on ``env``
            self.nominal_env.reset(seed=0)
            base = self.nominal_env.unwrapped
            toolpath, machine = base.toolpath, base.machine
        key = (id(toolpath), machine, period, self.margin, self.refine_iterations, self.raise_rounds)
        cached = self._cache.get(key)
        if cached is not None and cached[0] is toolpath:
            self.schedule = cached[1]
            return
        show = sys.stderr.isatty() if self.progress is None else bool(self.progress)
        if show:
            from tqdm import tqdm

            rounds = self.refine_iterations + 1 + self.raise_rounds
            name = str(getattr(base, "program_name", "program"))
            self._bar = tqdm(total=rounds, desc=f"oracle: planning {name}", file=sys.stderr, leave=False,
                             bar_format="{desc}: {percentage:3.0f}%|{bar}| {elapsed}")  # fmt: skip
        try:
            self.schedule = self.plan(toolpath, machine, env=base)
        finally:
            if self._bar is not None:
                self._bar.close()
                self._bar = None
        self._cache[key] = (toolpath, self.schedule)  # keeps the toolpath alive so its id stays unique

    def act(self, observation: np.ndarray, info: dict[str, Any]) -> np.ndarray:
        return override_action(self.override_at(float(info.get("path_s", 0.0)), info), self._max_override)

    # ------------------------------------------------------------------ schedule
    def override_at(self, path_s: float, info: dict[str, Any] | None = None) -> float:
        """Knob value at path position ``path_s``: smallest scheduled override over the reaction window."""
        return override_at(self.schedule, path_s, float((info or {}).get("feed_mm_min", 0.0)), self._lead_s,
                           REACH_MM_V1)

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
            run = self._simulate(env)
            if run is None:  # env could not be copied: model-only schedule
                return schedule
            path_s, error, speed = run
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
            new_run = self._simulate(env)
            if new_run is None:  # (the env was copied before: it can be copied again)
                break
            new_path_s, new_error, _ = new_run
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
        cap = np.full(len(seg), SPEED_CEILING_MM_S)
        is_arc = toolpath.kind[seg] == SegmentKind.ARC
        if np.any(~is_arc):
            _, tangent, curvature = toolpath.evaluate(s[~is_arc])
            per_speed = model.line_error_per_speed(tangent)
            line_cap = np.where(per_speed > 1e-12, target / np.maximum(per_speed, 1e-12), SPEED_CEILING_MM_S)
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
        finite_cap = np.where(np.isfinite(cap), cap, SPEED_CEILING_MM_S)
        speed = bidirectional_scan(s, finite_cap, accel, jerk)
        override = np.full(len(s), self._max_override)
        fed = cutting & (feed_mm_s > 0)
        override[fed] = np.clip(speed[fed] / feed_mm_s[fed], 0.0, self._max_override)
        return Schedule(s=s, cap_mm_s=cap.copy(), speed_mm_s=speed, override=override)

    def _simulate(self, env: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """Run a copy of the (just reset) env with the current schedule.

        Returns per control step: path position (mm), contour error (mm) and path speed (mm/s); None when
        the env cannot be copied.
        """
        # Tool paths are immutable and may be large: share them instead of copying.
        memo: dict[int, Any] = {}
        for toolpath in [getattr(env, "toolpath", None), *(tp for _, tp in getattr(env, "_programs", []))]:
            if toolpath is not None:
                memo[id(toolpath)] = toolpath
        try:
            sim = copy.deepcopy(env, memo)
        except Exception as exc:  # an env that cannot be copied: fall back to the model-only schedule
            warnings.warn(f"oracle planner: cannot copy the env to refine the schedule ({exc}); "
                          "using the servo model alone", RuntimeWarning, stacklevel=3)  # fmt: skip
            return None
        positions: list[float] = []
        errors: list[float] = []
        speeds: list[float] = []
        bar = self._bar
        done = bar.n if bar is not None else 0

        def record(steps: int, reward: float, terminated: bool, truncated: bool,
                   info: dict[str, Any]) -> None:  # fmt: skip
            positions.append(float(info.get("path_s", 0.0)))
            errors.append(float(info.get("contour_error_mm", 0.0)))
            speeds.append(float(info.get("feed_mm_min", 0.0)) / 60.0)
            if bar is not None and (steps - 1) % 500 == 0 and not (terminated or truncated):
                bar.n = min(done + float(info.get("progress", 0.0)), bar.total)  # a round moves it ≤ 1 unit
                bar.refresh()

        # The copy was just reset: the schedule's episode from its first step (no observation yet).
        play(sim, self, None, {}, record)
        if bar is not None:
            bar.n = min(int(done) + 1, bar.total)
            bar.refresh()
        return np.asarray(positions), np.asarray(errors), np.asarray(speeds)
