"""The deployable feed planner: a motion-stage service that schedules the feed override along a program.

*Deployable* means it uses only what a real controller or CAM system knows: the program, the machine
parameters (axis limits, the controller's static speed and junction limits) and its own model of the
servo axes. It never runs the env or the plant, so it could run inside a controller's look-ahead. It
costs about 12 µs of CPU per segment on average over the benchmark's test split
(``scripts/bench_planner_versions.py``; docs/benchmark.md); a schedule is computed once per program and
machine and kept (:class:`SchedulePlanner`). Versions: 3 is the live one, 2 and 1 are frozen for the env
ids that publish them (:mod:`.service`).

Its users: the ``classical`` baseline policy (:mod:`cnc_gym.policies.classical`), the env's planner
observation entry and its ``residual`` action mode (:mod:`cnc_gym.envs.planner_prior`); the oracle
(:mod:`cnc_gym.policies.oracle`) starts from its error model and scan.

=====================  ========================================================================
:mod:`.error_model`    the servo error model and its tables (step 1 below)
:mod:`.schedule`       caps, the jerk-limited scan and the schedule (steps 2 and 3),
                       :class:`SchedulePlanner`
:mod:`.rule`           the knob rule (step 4), compiled once for every user, and the reaction lead
=====================  ========================================================================

How the schedule is built:

1. **Servo error model** (:class:`~.error_model.ServoErrorModel`). Each axis is the plant's loop
   ``u = Kv·(r − x) + f·ṙ`` into a velocity loop ``H(s)`` (ideal, or 2nd order ωn, ζ), so
   ``X/R = G(s) = H·(Kv + f·s)/(s + H·Kv)``; a post-interpolation moving average multiplies every axis by
   the same ``M(jω)``. Three closed forms, tabulated once per machine (:class:`~.error_model.ServoTables`):

   * *straight line at speed v*: each axis lags by ``(1 − f_k)·v_k/Kv_k``; unequal lags (gain mismatch)
     push the tool sideways, linear in v;
   * *arc of radius R at speed v* (ω = v/R): the contour error is ``R·max_t |ρ(t) − 1|`` with ρ the
     actual radius over R, ``R·F(ω)`` with F tabulated over ω (for a matched P loop with feed-forward f,
     ``(1 − f²)·v²·κ/(2·Kv²)``);
   * *corner at speed v*: the tangent jumps from ``u_in`` to ``u_out``, so each axis's reference velocity
     steps by ``v·(u_out,k − u_in,k)``; the following error answers with the loop's ramp-error response
     ``E_k(t)`` (the step response of ``(1 − G_k(s))/s``, tabulated), and the actual point is
     ``v·(t·u_out − L∘u_in − (u_out − u_in)∘E(t))``, L the steady lags. Its largest distance from the two
     legs of the corner, over t, is ``v·c(u_in, u_out)``: linear in v.

2. **Speed caps** along the path, each the largest v whose predicted error is at most
   ``margin × tolerance``: per cutting move (line lag, arc or NURBS curvature, and the controller's own
   static cap and programmed feed × max override), per junction (the corner model, and the controller's
   junction limit), and for chains of short G01 moves the arc model at the *chain curvature*: the net
   change of direction over a window of the path, divided by its length (the turns of sharp corners, which
   the corner model covers, left out; the net change rather than the sum of turns, so that the
   direction noise of rounded CAM coordinates cancels).
3. **Bidirectional jerk-limited scan** (compiled): backward (deceleration feasibility) and forward
   (acceleration) passes with the path acceleration A, jerk J and the override slew rate, using the
   jerk-limited S-curve reach ``(v − v0)(v + v0)² = J·L²`` (acceleration capped at A).
4. **The knob rule** (:func:`~.rule.planner_override`): at path position s the knob is the smallest
   scheduled override ``v_sched/F`` over the stretch the controller covers in its reaction lead (two
   control periods + 10 ms at the current speed, :func:`~.rule.reaction_lead_s`), clipped to
   ``[0, max_override]``; on rapids the knob is at ``max_override`` (no contour error is measured there).
   Version 3 bakes a second anticipation into the schedule, at the scheduled speed (so that a slow actual
   speed cannot shorten it): where the override must fall faster than its slew allows (at a change of
   programmed feed the same speed is another override) it starts falling earlier, and each node asks for
   the lowest override of the next 20 ms (:class:`~.schedule.PlanSettings`). Versions 1 and 2 look
   0.5 mm farther instead, which at a few mm/s is tenths of a second of crawl before every slow stretch.

Boundary records: the input is the tool path, the machine and (optionally) the controller's static tables
(:class:`~cnc_gym.motion.limits.PathLimits`); the output is a :class:`~.schedule.Schedule` (path
positions, caps, speeds, overrides, and the (n, 2) ``table`` the compiled rule reads).
"""

from cnc_gym.motion.planner.error_model import (
    SPEED_CEILING_MM_S,
    ServoErrorModel,
    ServoTables,
    arc_caps,
    corner_error_per_speed,
    servo_tables,
)
from cnc_gym.motion.planner.record import Schedule
from cnc_gym.motion.planner.rule import override_at, planner_override, reaction_lead_s, rule_reach_mm
from cnc_gym.motion.planner.schedule import MARGIN, bidirectional_scan, plan_schedule
from cnc_gym.motion.planner.service import PLANNER_VERSION, PLANNERS, SchedulePlanner, planner_version

__all__ = ["MARGIN", "PLANNERS", "PLANNER_VERSION", "SPEED_CEILING_MM_S", "Schedule", "SchedulePlanner",
           "ServoErrorModel", "ServoTables", "arc_caps", "bidirectional_scan", "corner_error_per_speed",
           "override_at", "plan_schedule", "planner_override", "planner_version", "reaction_lead_s",
           "rule_reach_mm",
           "servo_tables"]
