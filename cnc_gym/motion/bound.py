"""The time-optimal reference: a lower bound on the cycle time of a program, computed with TOPP-RA.

No policy can run a program faster than :func:`time_optimal_bound` says (to within TOPP-RA's
numerical tolerance, see below), whatever it does with the override knob. The bound is the minimum time
of the programmed path under every *static* limit the controller enforces, with jerk and contour
tolerance dropped:

=========================  ========================================================================
cutting moves              time-optimal path parameterization (TOPP-RA, Pham & Pham, IEEE T-RO 2018,
                           with the ``toppra`` package) over every cutting move between two stops:
path speed                 ≤ programmed feed × max override (× 1 on override-locked blocks) and
                           ≤ the controller's static cap of the move: composite clamp P1224,
                           per-axis max feed, curvature limits (centripetal acceleration P1442,
                           chord error P1472, centripetal jerk, floor P1505)
tangential acceleration    each axis's share ``|u_k(s)|·|s̈|`` ≤ its acceleration limit, pointwise
                           (the controller limits tangential acceleration by the axes' limits and the
                           centripetal part separately, by the curvature caps above)
corner smoothing           on the path the controller follows: the blended one where the machine or
                           the program smooths corners (docs/motion.md §6)
junctions                  ≤ the controller's junction limit (corner step P1227 over the change of
                           direction, both neighbours' caps); 0 at every mandatory stop (exact stop,
                           dwell, rapid ↔ cut, tool/spindle change, program end)
rapids                     rest to rest at the rapid rate, rapid acceleration and rapid jerk projected
                           on the move (closed form, :func:`~cnc_gym.motion.limits.rest_to_rest_time`)
dwells                     as programmed (rotary-only moves: their closed-form jerk-limited time)
=========================  ========================================================================

What the bound leaves out, each of which only makes the real controller slower (dropping a limit can
only shorten the least time): jerk on cutting moves, the look-ahead window, the override's slew rate,
in-position waits, the servo's settling at the program end, the interpolation period's sampling, and the
contour tolerance itself. It is therefore a
*lower bound*, not a feasible plan: a policy's ``time_ratio`` (cycle ÷ bound) is at least 1, and how far
above 1 it lies says how much time is left on the table.

With the override mode of the env the path-speed cap is the programmed feed × the machine's
``max_override``; in ``feed`` mode (the agent commands the feed) it is the controller's clamp P1224.

Discretization: TOPP-RA solves on a grid of path positions (every junction plus subdivisions of at
most ``grid_mm`` and 5° of turn, ``max_gridpoints`` in all), with each interval's tangent relaxed to the
most favourable one over the interval (so the grid problem is a relaxation of the continuous one, and its
speeds at the grid points are at least the true optimum's). Between grid points the time is that of the
fastest motion between the two grid speeds under the interval's acceleration and speed cap (ramp up,
cruise, ramp down: :func:`interval_times`), never a constant acceleration over the whole interval, which
over-counts every ramp shorter than an interval: a short cut between two stops (a drilling peck) would
ramp over a whole grid interval at each end and the "bound" would be slower than the controller. On a
line the result is the closed-form trapezoid, on any grid (tests/motion/test_bound.py).

Results are cached in memory and on disk (``$CNC_GYM_CACHE_DIR/bound`` or ``~/.cache/cnc-gym/bound``),
keyed by a hash of the tool path, the machine's parameters, the action mode and :data:`BOUND_VERSION`. A
cache file is checked before it is used (:func:`check_cache_record`: the expected fields and version, its
own key, finite non-negative times that add up, a digest of key and values); a file that fails is computed
again with a one-line notice, so an edited or damaged file never reaches a record.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from cnc_gym.errors import CncGymError
from cnc_gym.machine import MachineConfig
from cnc_gym.motion import kernel as K
from cnc_gym.motion.limits import build_limits, rest_to_rest_time
from cnc_gym.toolpath import Toolpath

#: Bump when the bound's definition or numerics change: it is part of every cache key and record.
BOUND_VERSION = 2

_DEFAULT_GRID_MM = 0.5
_DEFAULT_MAX_GRIDPOINTS = 40_000


@dataclass(frozen=True)
class BoundResult:
    """The time-optimal bound of one program on one machine (seconds)."""

    total_s: float  # the bound: cutting + rapid + dwell
    cutting_s: float  # TOPP-RA time over the cutting moves
    rapid_s: float  # rapids, rest to rest
    dwell_s: float  # dwells and rotary-only moves
    gridpoints: int  # TOPP-RA grid size (0 when there is nothing to cut)
    version: int = BOUND_VERSION

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)


class _ChainPath:
    """The cutting moves as a geometric path for toppra: one unit tangent per grid interval.

    Second derivatives are zero on purpose: toppra's joint-acceleration constraint then bounds each axis's
    share of the *tangential* acceleration, ``|u_k|·|s̈| ≤ A_k`` (the centripetal part is limited by the
    speed caps, as the controller does). toppra evaluates the path only at the grid points it was given;
    the tangent at a grid point is that of the interval starting there.
    """

    def __init__(self, gridpoints: np.ndarray, tangent: np.ndarray) -> None:
        self._grid = gridpoints
        self._tangent = np.vstack((tangent, tangent[-1:]))
        self.dof = 3
        self.path_interval = np.array([gridpoints[0], gridpoints[-1]])

    def __call__(self, positions, order: int = 0) -> np.ndarray:
        s = np.atleast_1d(np.asarray(positions, dtype=float))
        if order == 1:
            index = np.clip(np.searchsorted(self._grid, s, side="right") - 1, 0, len(self._tangent) - 1)
            return self._tangent[index]
        return np.zeros((len(s), 3))  # positions and second derivatives: not needed / zero by design


def speed_cap_constraint(cap: np.ndarray):
    """A toppra linear constraint: path speed ``ṡ ≤ cap[i]`` at grid point i (toppra's ``x = ṡ²``)."""
    from toppra.constraint import LinearConstraint

    class PathSpeedCap(LinearConstraint):
        def __init__(self) -> None:
            super().__init__()
            self.dof = 3
            self._format_string = "    path speed cap per grid point\n"

        def compute_constraint_params(self, path, gridpoints, *args, **kwargs):
            return None, None, None, None, None, None, np.column_stack((np.zeros(len(cap)), cap * cap))

    return PathSpeedCap()


@dataclass(frozen=True)
class _CuttingProblem:
    """The cutting moves on TOPP-RA's grid (coordinate: cutting length, rapids removed)."""

    grid: np.ndarray  # (m + 1,) path positions
    speed: np.ndarray  # (m + 1,) speed cap at each grid point (junction limits, 0 at stops)
    tangent: np.ndarray  # (m, 3) the relaxed tangent of each interval (see _cutting_problem)
    interval_cap: np.ndarray  # (m,) the speed cap inside each interval: its move's cap


def _cutting_problem(tp: Toolpath, limits, machine: MachineConfig, action_mode: str, grid_mm: float,
                     max_gridpoints: int) -> _CuttingProblem | None:  # fmt: skip
    """The grid, caps and tangents of the cutting pieces.

    The coordinate is cutting length (rapids removed). A rapid's ends are mandatory stops, so the cutting
    pieces on either side of it meet at one grid point whose cap is 0.

    Each interval carries one tangent, that of its middle, *relaxed* so that the problem stays a
    relaxation of the true one: on a curved move the tangent turns by ``θ`` (at most 5°) over an interval,
    so every component of the true tangent in it is at least ``|u_k(mid)| − θ/2`` in size; the interval's
    tangent has those components, and each axis's acceleration limit then allows at least as much path
    acceleration as anywhere in the interval. On lines the tangent is exact.
    """
    seg_f, seg_i, pt_f, pt_i = limits.seg_f, limits.seg_i, limits.pt_f, limits.pt_i
    n = len(seg_f)
    cutting = seg_i[:, K.I_RAPID] == 0
    rows = np.flatnonzero(cutting)
    if len(rows) == 0:
        return None
    ctl = machine.controller
    if action_mode == "feed":  # the agent commands the feed: only the clamp P1224 and the caps remain
        target = np.full(n, ctl.max_feed_mm_min / 60.0)
    else:  # override-locked blocks (G63) run at 100 %
        target = seg_f[:, K.F_BASE] * np.where(seg_i[:, K.I_LOCKED] != 0, 1.0, float(ctl.max_override))
    cap = np.minimum(target, seg_f[:, K.F_CAP])
    # Speed allowed at the start of each cutting piece (its limit point q = the piece's index): the
    # junction limit after a cutting piece (never more than the faster side's cap), 0 after a rapid, at the
    # program start and at every mandatory stop.
    after_cut = np.zeros(len(rows), dtype=bool)
    after_cut[1:] = rows[1:] == rows[:-1] + 1
    start = np.minimum(pt_f[rows, K.P_HARD], np.maximum(cap[rows], np.where(after_cut, cap[rows - 1], 0.0)))
    start = np.where(after_cut & (pt_i[rows, K.Q_STOP] == 0), start, 0.0)
    # ... and at its end (the next piece's start, or 0 before a rapid and at the end).
    end = np.zeros(len(rows))
    end[:-1] = np.where(after_cut[1:], start[1:], 0.0)
    length = seg_f[rows, K.F_LEN]
    cut_length = float(np.sum(length))
    h = max(float(grid_mm), cut_length / max(max_gridpoints - 2 * len(rows), 1))
    turn = seg_f[rows, K.F_CURV] * length
    pieces = np.maximum(np.ceil(length / h), np.ceil(turn / math.radians(5.0)))
    # A piece between two stops needs an interior point to move at all.
    pieces = np.maximum(pieces, np.where((start == 0) & (end == 0), 2, 1)).astype(np.int64)
    row_of = np.repeat(np.arange(len(rows)), pieces)
    j = np.arange(len(row_of)) - np.repeat(np.cumsum(pieces) - pieces, pieces)
    frac = j / pieces[row_of]
    cut_start = np.concatenate(([0.0], np.cumsum(length)))[:-1]
    grid = np.concatenate((cut_start[row_of] + frac * length[row_of], [cut_length]))
    speed = np.where(j == 0, start[row_of], cap[rows][row_of])
    speed = np.concatenate((speed, [0.0]))
    # Tangent of each interval at its middle (toolpath arc length).
    s_mid = seg_f[rows[row_of], K.F_S0] + (j + 0.5) / pieces[row_of] * length[row_of]
    _, tangent, _ = (tp if limits.path is None else limits.path).evaluate(s_mid)  # the path followed
    half_turn = 0.5 * (turn / pieces)[row_of]
    tangent = np.sign(tangent) * np.maximum(np.abs(tangent) - half_turn[:, None], 0.0)
    interval_cap = cap[rows][row_of]
    keep = np.concatenate(([True], np.diff(grid) > 0))  # zero-length pieces add nothing
    if not np.all(keep):
        grid, speed = grid[keep], speed[keep]
        tangent, interval_cap = tangent[keep[1:]], interval_cap[keep[1:]]
    return _CuttingProblem(grid, speed, tangent, interval_cap)


def _cutting_time(problem: _CuttingProblem, accel: np.ndarray) -> float:
    import logging

    import toppra
    from toppra.constraint import DiscretizationType, JointAccelerationConstraint

    logging.getLogger("toppra").setLevel(logging.ERROR)
    grid, tangent = problem.grid, problem.tangent
    acceleration = JointAccelerationConstraint(np.asarray(accel, dtype=float),
                                               discretization_scheme=DiscretizationType.Collocation)
    problem_ = toppra.algorithm.TOPPRA([acceleration, speed_cap_constraint(problem.speed)],
                                       _ChainPath(grid, tangent), gridpoints=grid,
                                       solver_wrapper="seidel")  # fmt: skip
    _, sd, _, _ = problem_.compute_parameterization(0.0, 0.0, return_data=True)
    if sd is None or not np.all(np.isfinite(sd)):
        raise CncGymError("time-optimal bound: TOPP-RA found no parameterization of the cutting moves")
    # The path acceleration each interval allows: every axis's share |u_k|·|s̈| within its limit.
    with np.errstate(divide="ignore"):
        path_accel = np.min(np.asarray(accel, dtype=float) / np.abs(tangent), axis=1)
    return float(np.sum(interval_times(np.diff(grid), sd[:-1], sd[1:], path_accel, problem.interval_cap)))


def interval_times(length: np.ndarray, v0: np.ndarray, v1: np.ndarray, accel: np.ndarray,
                   cap: np.ndarray) -> np.ndarray:  # fmt: skip
    """The least time over intervals of ``length`` entered at ``v0`` and left at ``v1`` with path
    acceleration and deceleration at most ``accel`` and speed at most ``cap`` (all per interval).

    The fastest motion accelerates from ``v0``, cruises at the cap if it reaches it and decelerates to
    ``v1`` (``ṡ²`` is the lower envelope of ``v0² + 2·a·s``, ``v1² + 2·a·(L − s)`` and ``cap²``), so any
    motion through the interval that meets these limits and does not exceed ``v0``, ``v1`` at its ends
    takes at least this long. (Integrating constant acceleration from ``v0`` to ``v1`` instead, as the
    TOPP-RA grid suggests, over-counts a ramp that ends inside the interval: a cut between two stops
    would ramp over whole grid intervals.) A cap below an end speed (a junction may allow the faster
    neighbour's cap) is raised to it.
    """
    v0 = np.maximum(v0, 0.0)
    v1 = np.maximum(v1, 0.0)
    x0, x1 = v0 * v0, v1 * v1
    top = np.maximum(cap, np.maximum(v0, v1))
    finite = np.isfinite(accel)
    a = np.where(finite, accel, 1.0)
    # The peak of the two ramps, where v0² + 2·a·s = v1² + 2·a·(L − s); at least both end speeds (a grid
    # step that TOPP-RA's tolerance left a hair steeper than the ramp allows).
    peak = np.sqrt(np.maximum(0.5 * (x0 + x1) + a * length, np.maximum(x0, x1)))
    ramps = np.where(peak <= top, (2.0 * peak - v0 - v1) / a,
                     (2.0 * top - v0 - v1) / a + (length - (2.0 * top * top - x0 - x1) / (2.0 * a)) / top)
    return np.where(finite, ramps, length / np.maximum(top, 1e-300))


def _rapid_and_dwell_time(limits) -> tuple[float, float]:
    seg_f, seg_i = limits.seg_f, limits.seg_i
    rapid = seg_i[:, K.I_RAPID] != 0
    rapid_s = 0.0
    if np.any(rapid):
        rapid_s = float(np.sum(rest_to_rest_time(seg_f[rapid, K.F_LEN], seg_f[rapid, K.F_CAP],
                                                 seg_f[rapid, K.F_ACC], seg_f[rapid, K.F_JERK])))  # fmt: skip
    # The dwell table has one row per dwell (a single row of zeros when there is none).
    return rapid_s, float(np.sum(limits.dwell_f[:, 0]))


def compute_bound(tp: Toolpath, machine: MachineConfig, *, action_mode: str = "override",
                  grid_mm: float = _DEFAULT_GRID_MM,
                  max_gridpoints: int = _DEFAULT_MAX_GRIDPOINTS) -> BoundResult:  # fmt: skip
    """The bound of ``tp`` on ``machine``, computed now (no cache). See the module docstring."""
    if action_mode not in ("override", "feed"):
        raise CncGymError(f"action_mode must be 'override' or 'feed', got {action_mode!r}")
    limits = build_limits(tp, machine)
    rapid_s, dwell_s = _rapid_and_dwell_time(limits)
    problem = _cutting_problem(tp, limits, machine, action_mode, grid_mm, max_gridpoints)
    cutting_s, gridpoints = 0.0, 0
    if problem is not None:
        accel = np.array(machine.axis_array("max_accel_mm_s2"))
        cutting_s, gridpoints = _cutting_time(problem, accel), len(problem.grid)
    return BoundResult(total_s=cutting_s + rapid_s + dwell_s, cutting_s=cutting_s, rapid_s=rapid_s,
                       dwell_s=dwell_s, gridpoints=gridpoints)  # fmt: skip


# ---------------------------------------------------------------------------------------------- cache
def toolpath_digest(tp: Toolpath) -> str:
    """SHA-256 of a tool path's geometry, feeds and modes (what the bound depends on)."""
    h = hashlib.sha256()
    for name in ("kind", "start", "end", "center", "plane", "radius", "start_angle", "sweep", "feed",
                 "dwell_s", "modes", "tool", "spindle_rpm", "length", "rotary_start", "rotary_end"):
        arr = np.ascontiguousarray(getattr(tp, name))
        h.update(name.encode())
        h.update(str(arr.dtype).encode() + str(arr.shape).encode())
        h.update(arr.tobytes())
    h.update(tp.rotary_axes.encode())
    for row in sorted(tp.nurbs):  # NURBS: sampled points stand for the curve
        point, _, _ = tp.nurbs[row].at_length(np.linspace(0.0, float(tp.length[row]), 17))
        h.update(np.ascontiguousarray(point).tobytes())
    return h.hexdigest()


def machine_digest(machine: MachineConfig) -> str:
    """SHA-256 of a machine's parameters (its name, description and source file left out)."""
    text = repr((machine.controller, machine.axes, tuple(sorted(machine.rotary_axes.items()))))
    return hashlib.sha256(text.encode()).hexdigest()


def cache_dir() -> Path:
    """Where bounds are cached: ``$CNC_GYM_CACHE_DIR/bound``, else ``$XDG_CACHE_HOME/cnc-gym/bound``."""
    root = os.environ.get("CNC_GYM_CACHE_DIR")
    if root:
        return Path(root) / "bound"
    xdg = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(xdg) / "cnc-gym" / "bound"


_MEMORY: dict[str, BoundResult] = {}

#: The fields of a cache file besides the result's own: the key it was stored under and a digest of both.
_CACHE_FIELDS = ("key", "digest")
#: Largest cache file read (a result is about 300 bytes).
_MAX_CACHE_BYTES = 4096


#: The layout of a cache file (part of the key: files of an earlier layout are never looked at).
_CACHE_FORMAT = 2


def bound_key(tp: Toolpath, machine: MachineConfig, action_mode: str = "override") -> str:
    """The cache key of a bound: SHA-256 of :data:`BOUND_VERSION`, the cache file layout, the action
    mode, the tool path's digest and the machine's."""
    return hashlib.sha256(
        f"{BOUND_VERSION}:cache-{_CACHE_FORMAT}:{action_mode}:{toolpath_digest(tp)}:"
        f"{machine_digest(machine)}".encode()
    ).hexdigest()


def _cache_digest(key: str, values: dict) -> str:
    """What a cache file's ``digest`` must be: SHA-256 of its key and its values (in the order of
    :class:`BoundResult`), so that a value edited by hand, or a file copied under another key, shows."""
    fields = [f.name for f in dataclasses.fields(BoundResult)]
    text = json.dumps([key, *(values.get(name) for name in fields)], allow_nan=False)
    return hashlib.sha256(text.encode()).hexdigest()


def cache_record(key: str, result: BoundResult) -> dict:
    """The object a cache file holds: the result's fields, its key and their digest."""
    values = result.to_dict()
    return {**values, "key": key, "digest": _cache_digest(key, values)}


def check_cache_record(data: object, key: str) -> BoundResult:
    """The :class:`BoundResult` a cache file's object holds, if it is one for ``key``: an object of
    exactly the expected fields, of :data:`BOUND_VERSION`, stored under ``key``, with finite non-negative
    times whose parts add up to the total and a matching digest. Raises ValueError saying why not."""
    if not isinstance(data, dict):
        raise ValueError(f"not an object but {type(data).__name__}")
    fields = [f.name for f in dataclasses.fields(BoundResult)]
    expected = {*fields, *_CACHE_FIELDS}
    if set(data) != expected:
        odd = sorted(map(str, set(data) ^ expected))[:4]
        raise ValueError(f"not a bound record (fields {', '.join(odd)} missing or unexpected)")
    if type(data["version"]) is not int or data["version"] != BOUND_VERSION:
        raise ValueError(f"bound version {data['version']!r}, expected {BOUND_VERSION}")
    if data["key"] != key:
        raise ValueError("stored under another program or machine")
    times = ("total_s", "cutting_s", "rapid_s", "dwell_s")
    for name in times:
        value = data[name]
        if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value) \
                or value < 0:  # fmt: skip
            raise ValueError(f"{name} is {value!r}, not a finite non-negative number")
    grid = data["gridpoints"]
    if isinstance(grid, bool) or not isinstance(grid, int) or grid < 0:
        raise ValueError(f"gridpoints is {grid!r}, not a non-negative integer")
    parts = data["cutting_s"] + data["rapid_s"] + data["dwell_s"]
    if not math.isclose(data["total_s"], parts, rel_tol=1e-12, abs_tol=1e-12):
        raise ValueError(f"total_s {data['total_s']!r} is not the sum of its parts ({parts!r})")
    if data["digest"] != _cache_digest(key, data):
        raise ValueError("its digest does not match its contents")
    return BoundResult(**{name: data[name] for name in fields})


def _stderr_notice(message: str) -> None:
    import sys

    print(message, file=sys.stderr)


def time_optimal_bound(tp: Toolpath, machine: MachineConfig, *, action_mode: str = "override",
                       cache: bool = True, notice=_stderr_notice) -> BoundResult:  # fmt: skip
    """The bound of ``tp`` on ``machine`` (cached by tool path and machine hash; see the module docstring).

    A cache file is used only when :func:`check_cache_record` accepts it; anything else (not JSON, not an
    object, another version or key, a time that is not a finite non-negative number, a total that is not
    the sum of its parts, a digest that does not match) is computed again and rewritten, and ``notice``
    gets one line saying which file and why (default: printed on stderr). A file that cannot be read or
    written is ignored silently (the bound is computed again). The cache is a convenience, not a trust
    boundary: what it saves is only ever a recomputation.
    """
    key = bound_key(tp, machine, action_mode)
    if cache and key in _MEMORY:
        return _MEMORY[key]
    path = cache_dir() / f"{key}.json"
    if cache:
        try:
            with path.open("rb") as fh:
                raw = fh.read(_MAX_CACHE_BYTES + 1)
        except OSError:
            raw = None
        if raw is not None:
            try:
                if len(raw) > _MAX_CACHE_BYTES:
                    raise ValueError(f"larger than {_MAX_CACHE_BYTES} bytes")
                data = json.loads(raw, parse_constant=_refuse_constant)
                result = check_cache_record(data, key)
            except (ValueError, RecursionError) as exc:
                if notice is not None:
                    why = str(exc).splitlines()[0][:160] if str(exc) else type(exc).__name__
                    notice(f"cnc-gym: bound cache {path}: {why}; computing the bound again")
            else:
                _MEMORY[key] = result
                return result
    result = compute_bound(tp, machine, action_mode=action_mode)
    if not all(math.isfinite(v) and v >= 0 for v in (result.total_s, result.cutting_s, result.rapid_s,
                                                       result.dwell_s)):  # fmt: skip
        raise CncGymError(f"time-optimal bound: not a finite time ({result.total_s!r} s)")
    if cache:
        _MEMORY[key] = result
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            tmp = path.with_suffix(f".{os.getpid()}.tmp")
            tmp.write_text(json.dumps(cache_record(key, result), allow_nan=False))
            tmp.replace(path)
        except OSError:
            pass
    return result


def _refuse_constant(name: str) -> float:
    raise ValueError(f"holds {name}, not a number")
