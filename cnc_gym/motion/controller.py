"""The controller: look-ahead, jerk-limited (S-curve) feed profile and real-time override.

``Controller(toolpath, machine)`` precomputes every static limit once (:mod:`cnc_gym.motion.limits`);
``advance(n_ticks, override=...)`` then produces the reference position every interpolation period,
one compiled loop per call (:mod:`cnc_gym.motion.kernel`). The algorithm and its guarantees are
described in ``docs/motion.md``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from cnc_gym.errors import CncGymError
from cnc_gym.machine import MachineConfig
from cnc_gym.motion import kernel as K
from cnc_gym.motion.limits import PathLimits, build_limits, rest_to_rest_position
from cnc_gym.toolpath import SegmentKind, Toolpath


class ActionError(CncGymError, ValueError):
    """A bad argument to the controller (NaN or out-of-range override or feed, negative tick count)."""


@dataclass(slots=True)
class MotionChunk:
    """Reference output of one :meth:`Controller.advance` call: one row per interpolation period.

    ==========  ========  =======================================================================
    time_s      (n,)      time at the end of each period, s (from program start)
    position    (n, 3)    reference position, machine coordinates, mm
    path_s      (n,)      arc length along the tool path, mm
    speed       (n,)      path speed, mm/s
    accel       (n,)      tangential acceleration, mm/s^2
    jerk        (n,)      tangential jerk applied during the period, mm/s^3
    segment     (n,)      index of the toolpath segment (a dwell's index while dwelling)
    cutting     (n,)      True on lines and arcs, False on rapids and dwells
    rotary      (n, k)    rotary axes' reference, machine degrees, in ``toolpath.rotary_axes`` order
                          (None on a tool path without rotary axes)
    ==========  ========  =======================================================================
    """

    time_s: np.ndarray
    position: np.ndarray
    path_s: np.ndarray
    speed: np.ndarray
    accel: np.ndarray
    jerk: np.ndarray
    segment: np.ndarray
    cutting: np.ndarray
    rotary: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.time_s)


@dataclass(slots=True)
class LookaheadFeatures:
    """The path ahead in ``n`` equal arc-length bins of ``horizon / n`` mm from the current position.

    ======================  =====  ===============================================================
    speed_limit_mm_s        (n,)   the controller's static limit at 100 % override: min over the bin
                                   of programmed feed, axis/curvature/chord caps and junction limits
                                   inside it; 0 where the bin holds a mandatory stop or lies past the
                                   program end
    curvature_1_mm          (n,)   largest curvature in the bin
    turn_angle_rad          (n,)   largest junction turning angle in the bin (0 if none)
    programmed_feed_mm_s    (n,)   programmed path feed (rapid rate on rapids) at the bin's far end;
                                   0 past the program end
    distance_to_stop_mm     float  distance to the next mandatory stop (exact stop, dwell, rapid,
                                   program end)
    ======================  =====  ===============================================================
    """

    speed_limit_mm_s: np.ndarray
    curvature_1_mm: np.ndarray
    turn_angle_rad: np.ndarray
    programmed_feed_mm_s: np.ndarray
    distance_to_stop_mm: float


class Controller:
    """Simulated CNC controller for one tool path on one machine.

    Look-ahead over ``machine.controller.lookahead_blocks`` motion blocks, speed limits from programmed
    feed × override (clamped), per-axis velocity/acceleration/jerk projected on the path, curvature,
    chord error, corner steps, exact stops, rapids, dwells and program end; a jerk-limited profile that
    reacts to the override in real time and never violates a geometric limit. ``advance`` returns a
    :class:`MotionChunk`; ``lookahead`` returns :class:`LookaheadFeatures` for observations.
    """

    def __init__(self, toolpath: Toolpath, machine: MachineConfig, in_position_check: bool = True, *,
                 limits: PathLimits | None = None,
                 state: tuple[np.ndarray, np.ndarray] | None = None,
                 revision: int = K.CONTROLLER_REVISION) -> None:  # fmt: skip
        """``revision``: the controller's behaviour revision (``kernel.CONTROLLER_REVISION``, the live
        one; env ids published before a fix keep theirs). ``limits``: the tool path's :func:`build_limits`
        on ``machine`` if already built (they are the expensive part). ``state``: the ``(float, int)``
        state vectors (``kernel.N_STATE_F``, ``kernel.N_STATE_I``) to run on, e.g. one env's rows of a
        batch, taken as they are (their owner resets them); by default the controller's own, reset."""
        self.toolpath = toolpath
        #: Hold the reference at every in-position stop until :meth:`release_in_position` (see
        #: ``docs/motion.md``); False runs straight on from every stop once the reference is at rest.
        self.in_position_check = bool(in_position_check)
        self.machine = machine
        ctl = machine.controller
        self.dt = float(ctl.interpolation_period_s)
        self.max_override = float(ctl.max_override)
        self.limits: PathLimits = build_limits(toolpath, machine) if limits is None else limits
        self._n_seg = self.limits.seg_f.shape[0]
        self.revision = controller_revision(revision)
        self._cfg = kernel_config(machine, self.limits, self.revision)
        lim = self.limits
        #: The kernel's record of the path's tables (fixed for the controller's life), as the plain tuple
        #: kernel.advance_rows takes from Python.
        self._path = tuple(K.PathTables(lim.seg_f, lim.seg_i, lim.pt_f, lim.pt_i, lim.dwell_f, lim.curve_f,
                                        self._cfg))  # fmt: skip
        self._scratch = np.zeros((int(self._cfg[1]) + 2, 3))
        own_state = state is None
        if state is None:
            state = (np.zeros(K.N_STATE_F), np.zeros(K.N_STATE_I, dtype=np.int64))
        self._st_f: np.ndarray = state[0]
        self._st_i: np.ndarray = state[1]
        # Rotary axes: each period's angles follow from its row (linear in path_s on a move, the hold's own
        # jerk-limited profile on a rotary-only move, counted in periods since the hold began).
        self._rotary = None
        if toolpath.rotary_axes:
            holds = self.limits.rotary_holds
            self._rotary = {int(row): tuple(profile) for row, *profile in holds}
        self._hold = (-1, 0)  # (toolpath row of the rotary-only move under way, periods so far)
        if own_state:
            self.reset()
        else:
            self._last_position = self._rest_position_now()

    # ------------------------------------------------------------------ state
    def use_state(self, state: tuple[np.ndarray, np.ndarray]) -> None:
        """Run on the ``(float, int)`` state vectors ``state`` from now on, their values taken as the
        controller's state (e.g. the rows of a batch's state arrays after the batch was copied)."""
        self._st_f, self._st_i = state

    def reset(self) -> None:
        """Back to the program start: t = 0, at rest, override 100 %."""
        lim = self.limits
        K.reset_state(lim.pt_i, lim.pt_f, lim.dwell_f, self._n_seg, self._st_f, self._st_i)
        self._last_position = self._rest_position_now()
        self._hold = (-1, 0)

    def _rest_position_now(self) -> np.ndarray:
        if self._n_seg:
            out = np.zeros((1, K.N_OUT))
            k = int(self._st_i[K.K_SEG])
            lim = self.limits
            K._position(lim.seg_f, lim.seg_i, lim.curve_f, k, self._st_f[K.S_S], out, 0)
            return out[0, 1:4].copy()
        return self.limits.rest_position.copy()

    @property
    def finished(self) -> bool:
        """True once the reference is at rest at the program end, released from its in-position wait, and
        every dwell is done."""
        return bool(self._st_i[K.K_PHASE] == K.PHASE_DONE)

    @property
    def waiting_in_position(self) -> bool:
        """True while the reference rests on a stop with an in-position check and waits for
        :meth:`release_in_position` (time runs on, speed 0)."""
        return bool(self._st_i[K.K_PHASE] == K.PHASE_WAIT)

    def release_in_position(self) -> None:
        """The axes are in position: end the wait (the next period goes on with the stop's dwells, the next
        block, or finishes the program). Does nothing when not waiting."""
        if self._st_i[K.K_PHASE] == K.PHASE_WAIT:
            lim = self.limits
            K.release_wait(lim.pt_i, lim.dwell_f, self._st_f, self._st_i, self._n_seg)

    @property
    def time_s(self) -> float:
        return float(self._st_f[K.S_T])

    @property
    def path_s(self) -> float:
        return float(self._st_f[K.S_S])

    @property
    def speed(self) -> float:
        return float(self._st_f[K.S_V])

    @property
    def accel(self) -> float:
        return float(self._st_f[K.S_A])

    @property
    def override_applied(self) -> float:
        """The override in force. It starts at the first commanded override after reset (1.0 before any
        advance) and then follows the command at ``override_slew_per_s``."""
        ov = float(self._st_f[K.S_OV])
        return 1.0 if ov < 0 else ov

    @property
    def segment_index(self) -> int:
        """Toolpath index of the segment the reference is on (a dwell's index while dwelling)."""
        return int(K.segment_index(self.limits.seg_i, self.limits.dwell_f, self._st_i))

    @property
    def position(self) -> np.ndarray:
        """Current reference position, mm."""
        return self._last_position.copy()

    # ------------------------------------------------------------------ stepping
    def advance(
        self,
        n_ticks: int,
        override: float | None = None,
        rapid_override: float = 1.0,
        *,
        feed_mm_min: float | None = None,
    ) -> MotionChunk:
        """Run ``n_ticks`` interpolation periods with the override at ``override`` (0..max_override)
        or, in 'feed' action mode, with ``feed_mm_min`` commanded instead of F × override (still clamped by
        every limit). ``rapid_override`` (0..1) scales rapids. Returns the reference of these periods."""
        chunk = _chunk(self.advance_rows(n_ticks, override, rapid_override, feed_mm_min=feed_mm_min))
        if self._rotary is not None:
            chunk.rotary = self._rotary_reference(chunk)
        return chunk

    def advance_rows(
        self,
        n_ticks: int,
        override: float | None = None,
        rapid_override: float = 1.0,
        *,
        feed_mm_min: float | None = None,
    ) -> np.ndarray:
        """:meth:`advance` without the :class:`MotionChunk`: the kernel's rows (n, ``kernel.N_OUT``), columns
        ``kernel.O_T``, ``O_X..O_Z``, ``O_S``, ``O_V``, ``O_A``, ``O_J``, ``O_SEG`` (float), ``O_CUT`` — for
        hot loops such as the env's step (no rotary reference)."""
        # Fast path for the common call (plain int and floats in range); anything else is validated below.
        if (type(n_ticks) is int and n_ticks >= 0 and feed_mm_min is None and type(override) is float
                and 0.0 <= override <= self.max_override and rapid_override == 1.0):  # fmt: skip
            return self._advance_raw(n_ticks, override)
        if isinstance(n_ticks, bool) or not isinstance(n_ticks, int | np.integer) or n_ticks < 0:
            raise ActionError(f"n_ticks must be a non-negative integer, got {n_ticks!r}")
        if feed_mm_min is not None:
            if override is not None:
                raise ActionError("give either override or feed_mm_min, not both")
            feed = _finite(feed_mm_min, "feed_mm_min")
            if feed < 0:
                raise ActionError(f"feed_mm_min must not be negative, got {feed_mm_min!r}")
            mode, ratio, feed_mm_s = K.MODE_FEED, 1.0, feed / 60.0
        else:
            ratio = 1.0 if override is None else _finite(override, "override")
            if not 0.0 <= ratio <= self.max_override:
                raise ActionError(f"override must be within 0..{self.max_override:g}, got {override!r}")
            mode, feed_mm_s = K.MODE_OVERRIDE, 0.0
        rapid = _finite(rapid_override, "rapid_override")
        if not 0.0 <= rapid <= 1.0:
            raise ActionError(f"rapid_override must be within 0..1, got {rapid_override!r}")
        return self._advance_raw(int(n_ticks), ratio, rapid, mode, feed_mm_s)

    def _advance_raw(self, n_ticks: int, ratio: float, rapid: float = 1.0, mode: int = K.MODE_OVERRIDE,
                     feed_mm_s: float = 0.0, stop_when_done: bool = False,
                     wait: bool = True) -> np.ndarray:  # fmt: skip
        # a kernel.Command and a kernel.ControllerState, as plain tuples (see kernel.advance_rows)
        command = (mode, ratio, rapid, feed_mm_s, wait and self.in_position_check, stop_when_done)
        out = K.advance_rows(self._path, (self._st_f, self._st_i), command, n_ticks, self._scratch)
        if len(out):
            self._last_position = out[-1, K.O_X : K.O_Z + 1].copy()
        return out

    def run_to_end(
        self, override: float = 1.0, max_ticks: int = 50_000_000, chunk: int = 4096
    ) -> MotionChunk:
        """Advance at a constant override until the program is finished; the run (and the controller's
        clock) stops on the period at which it finished (for tests, scripts and baselines). With no servo
        to wait for, the reference goes on from every stop once at rest (no in-position wait; a wait
        already begun is released)."""
        ratio = _finite(override, "override")
        if not 0.0 <= ratio <= self.max_override:
            raise ActionError(f"override must be within 0..{self.max_override:g}, got {override!r}")
        parts = []
        done = 0
        self.release_in_position()
        while not self.finished:
            if done >= max_ticks:
                raise CncGymError(f"program did not finish within {max_ticks} interpolation periods")
            parts.append(self._advance_raw(chunk, ratio, stop_when_done=True, wait=False))
            done += chunk
        out = np.concatenate(parts) if parts else np.zeros((0, K.N_OUT))
        result = _chunk(out)
        if self._rotary is not None:
            result.rotary = self._rotary_reference(result)
        return result

    def _rotary_reference(self, chunk: MotionChunk) -> np.ndarray:
        """The rotary axes' angles at the end of each period of ``chunk`` (call once per chunk, in order)."""
        tp = self.toolpath
        rows = chunk.segment
        assert tp.rotary_start is not None and tp.rotary_end is not None and self._rotary is not None
        start, end = tp.rotary_start[rows], tp.rotary_end[rows]
        length = tp.length[rows]
        # On a move: the share of the row's XYZ length covered (the axes move linearly with the row).
        share = np.divide(chunk.path_s - tp.s_start[rows], length, out=np.ones(len(rows)), where=length > 0)
        share = np.clip(share, 0.0, 1.0)
        hold_row, done = self._hold
        # The reference only moves forward, so a rotary-only row's periods are contiguous in the chunk.
        for row in np.unique(rows).tolist():
            profile = self._rotary.get(row)
            if profile is None:
                continue
            at = np.flatnonzero(rows == row)
            first = done if row == hold_row else 0
            periods = first + np.arange(1, len(at) + 1)
            _seconds, travel, speed, accel, jerk = profile
            share[at] = rest_to_rest_position(periods * self.dt, travel, speed, accel, jerk) / travel
            hold_row, done = row, int(periods[-1])
        self._hold = (hold_row, done)
        return start + (end - start) * share[:, None]

    # ------------------------------------------------------------------ observations
    def lookahead(self, horizon_mm: float, n_points: int) -> LookaheadFeatures:
        """Features of the path ahead of the current position (see :class:`LookaheadFeatures`)."""
        horizon = _finite(horizon_mm, "horizon_mm")
        if horizon <= 0:
            raise ActionError(f"horizon_mm must be positive, got {horizon_mm!r}")
        if isinstance(n_points, bool) or not isinstance(n_points, int | np.integer) or n_points < 1:
            raise ActionError(f"n_points must be a positive integer, got {n_points!r}")
        out = self.lookahead_rows(horizon, int(n_points))
        return LookaheadFeatures(out[0], out[1], out[2], out[3], float(out[4, 0]))

    def lookahead_rows(self, horizon_mm: float, n_points: int) -> np.ndarray:
        """:meth:`lookahead` without checks or the record, for hot loops that validated their arguments
        once: rows speed limit, curvature, turn angle, programmed feed, and [distance to stop, …], (5, n)."""
        lim = self.limits
        done = self._st_i[K.K_PHASE] == K.PHASE_DONE
        return K.lookahead_kernel(lim.seg_f, lim.seg_i, lim.pt_f, lim.pt_i, int(self._st_i[K.K_SEG]),
                                  float(self._st_f[K.S_S]), bool(done), horizon_mm, n_points)  # fmt: skip

    # ------------------------------------------------------------------ introspection (tests, planners)
    def segment_limits(self) -> dict[str, np.ndarray]:
        """Static per-motion-segment limits (mm, s): toolpath index, cap, base speed, accel, jerk."""
        f, i = self.limits.seg_f, self.limits.seg_i
        return {"index": i[:, K.I_TP].copy(), "cap_mm_s": f[:, K.F_CAP].copy(),
                "base_mm_s": f[:, K.F_BASE].copy(), "accel_mm_s2": f[:, K.F_ACC].copy(),
                "jerk_mm_s3": f[:, K.F_JERK].copy(), "s_start": f[:, K.F_S0].copy(),
                "length": f[:, K.F_LEN].copy()}  # fmt: skip

    def junction_limits(self) -> dict[str, np.ndarray]:
        """Static per-point limits: arc length, hard speed limit (0 = mandatory stop), turning angle."""
        f, i = self.limits.pt_f, self.limits.pt_i
        return {"s": f[:, K.P_S].copy(), "limit_mm_s": f[:, K.P_HARD].copy(),
                "stop": i[:, K.Q_STOP].astype(bool), "turn_rad": f[:, K.P_TURN].copy()}  # fmt: skip

    @property
    def cutting_kinds(self) -> tuple[int, int]:
        return (int(SegmentKind.LINE), int(SegmentKind.ARC))


def controller_revision(revision: int) -> int:
    """``revision`` checked: 1 or 2 (:data:`cnc_gym.motion.kernel.CONTROLLER_REVISION`), else a ValueError."""
    if isinstance(revision, bool) or revision not in range(1, K.CONTROLLER_REVISION + 1):
        raise ValueError(f"unknown controller revision {revision!r} (known: 1 to {K.CONTROLLER_REVISION})")
    return int(revision)


def kernel_config(machine: MachineConfig, limits: PathLimits,
                  revision: int = K.CONTROLLER_REVISION) -> np.ndarray:  # fmt: skip
    """The kernel's ``cfg`` of a tool path on a machine: [dt, window blocks, override slew per s, rest x, y,
    z, controller revision]. The window counts motion segments (a NURBS piece as one); without look-ahead
    every block ends at rest anyway, and 2 keeps the pieces of one NURBS block flowing (the window end is
    never the next junction)."""
    ctl = machine.controller
    window = max(int(ctl.lookahead_blocks), 2)
    return np.array([ctl.interpolation_period_s, window, ctl.override_slew_per_s, *limits.rest_position,
                     controller_revision(revision)], dtype=np.float64)  # fmt: skip


def _chunk(out: np.ndarray) -> MotionChunk:
    return MotionChunk(
        time_s=out[:, K.O_T],
        position=out[:, K.O_X : K.O_Z + 1],
        path_s=out[:, K.O_S],
        speed=out[:, K.O_V],
        accel=out[:, K.O_A],
        jerk=out[:, K.O_J],
        segment=out[:, K.O_SEG].astype(np.int64),
        cutting=out[:, K.O_CUT] > 0.5,
    )


def _finite(value: object, name: str) -> float:
    try:
        x = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ActionError(f"{name} must be a number, got {value!r}") from None
    if not math.isfinite(x):
        raise ActionError(f"{name} must be finite, got {value!r}")
    return x
