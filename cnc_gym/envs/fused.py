"""The feed-rate task's step as one compiled call over a batch of N episodes, state in arrays.

:class:`FeedrateBatch` holds N episodes of the task (``cnc_gym/Feedrate-v0`` and its vector env): per
env the controller's state, the servo plant's state and the episode's statistics live in rows of a few
arrays (the layout below), and one numba call (:func:`_run_serial` / :func:`_run_parallel`) steps every
env: the controller's interpolation periods, the servo axes, the in-position release, the contour error
at every servo sample, the statistics, the reward, the end of the episode and the observation. Envs
flagged for a reset are reset in the same call instead (Gymnasium's next-step autoreset).

The observation and the reward are declared, not coded: the kernel computes a vector of named per-step
*signals* (:data:`SIGNALS`) and assembles the observation from an :class:`ObservationSpec` (signals,
blocks of look-ahead values, and signals after the blocks, each with a transform, a scale and bounds) and
the reward from a :class:`RewardSpec` (a weighted sum of transformed signals, optionally with a finish bonus
per program, its terms shown in the info). A batch given a :class:`Planner` also evaluates the planner's
override every step, from a schedule table packed with each program. A new env version defines its own
specs (and, if it needs one, adds a signal here) without copying the kernel: Feedrate-v1 and v2 are the
same call as v0 with their specs, the planner and their info keys (:attr:`FeedrateBatch.info_keys`).

Each program is packed once (:class:`PackedProgram`: the controller's limit tables, the contour meter's
tables, the per-program constants) and all programs of a batch are concatenated into one float and one
int array with a directory of offsets (:class:`ProgramBank`), so the kernel takes a dozen arrays whatever
the number of programs, and each env runs the program its row names.

A plant without compiled kernels (``compiled_step = False``; a later physics backend) runs the *modular*
step instead (:meth:`FeedrateBatch.step` with ``fused=False``): the same state arrays, driven through the
:class:`~cnc_gym.motion.Controller` objects (viewing the env's rows), the plant object's batched
``step``/``settled``/``reset`` and the :class:`~cnc_gym.plant.ContourErrorMeter`, with the statistics,
reward and observation from the same compiled functions. It is also the reference the tests hold the
fused step to (the same numbers, exactly).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np
from numba import njit, prange
from numba.core import cgutils, types
from numba.core.imputils import impl_ret_borrowed
from numba.extending import intrinsic
from numba.np.arrayobj import populate_array

from cnc_gym.machine import MachineConfig
from cnc_gym.motion import Controller
from cnc_gym.motion import kernel as K
from cnc_gym.motion.controller import kernel_config
from cnc_gym.motion.limits import PathLimits, build_limits
from cnc_gym.motion.planner.rule import planner_override  # the one knob rule (the planner's)
from cnc_gym.plant import ContourErrorMeter, ServoPlant
from cnc_gym.plant import contour as C
from cnc_gym.plant.servo import settled_env, step_env
from cnc_gym.toolpath import Toolpath

# ----------------------------------------------------------------------------------------------- signals
#: Per-step signals the kernel computes for every env (the observation and the reward are built from them).
SIGNALS = (
    "speed",  # path speed of the reference, mm/s
    "accel",  # tangential acceleration of the reference, mm/s²
    "override",  # override in force (1 before the first period)
    "knob",  # the action, in [-1, 1]
    "following_error",  # ‖reference − actual‖ at the last servo sample, mm
    "contour_error_step",  # largest contour error over the step's servo samples, mm
    "contour_error_now",  # contour error at the last servo sample, mm
    "path_fraction",  # reference arc length × (1 / program length)
    "distance_to_stop",  # to the next mandatory stop, mm (0 once finished)
    "progress",  # p = min(s / L, 1), 1 once the controller has finished
    "progress_delta",  # p − p before the step
    "time_fraction",  # control period / the program's nominal time
    "error_ratio",  # contour_error_step / tolerance
    "violated",  # 1 where contour_error_step > tolerance, else 0
    "violation_length",  # reference path advance over the step's samples with error > tolerance, mm
    "violation_time",  # time of the step's samples with error > tolerance, s
    "violation_free",  # 1 while the episode's violation length is 0, else 0
    "planner_override",  # the deployable planner's override here (the batch's Planner; 0 without one)
    "kv_min",  # the machine's lowest position gain, 1/s (constant: MACHINE_QUANTITIES)
    "kv_mismatch",  # (max Kv − min Kv) / mean Kv of the axes
    "feedforward",  # mean velocity feed-forward fraction of the axes
    "accel_min",  # the lowest axis acceleration, mm/s²
)
(SIG_SPEED, SIG_ACCEL, SIG_OVERRIDE, SIG_KNOB, SIG_FOLLOWING, SIG_ERROR_STEP, SIG_ERROR_NOW,
 SIG_PATH_FRACTION, SIG_DISTANCE_TO_STOP, SIG_PROGRESS, SIG_PROGRESS_DELTA, SIG_TIME_FRACTION,
 SIG_ERROR_RATIO, SIG_VIOLATED, SIG_VIOLATION_LENGTH, SIG_VIOLATION_TIME, SIG_VIOLATION_FREE,
 SIG_PLANNER_OVERRIDE, SIG_KV_MIN, SIG_KV_MISMATCH, SIG_FEEDFORWARD,
 SIG_ACCEL_MIN) = range(len(SIGNALS))  # fmt: skip
#: The machine's own quantities, signals that hold still over an episode (set from the batch's machine).
MACHINE_QUANTITIES = ("kv_min", "kv_mismatch", "feedforward", "accel_min")


def machine_quantities(machine: MachineConfig) -> dict[str, float]:
    """The machine quantities of :data:`MACHINE_QUANTITIES` (Kv in 1/s, accelerations in mm/s²)."""
    kv = np.array(machine.axis_array("kv_1_s"))
    return {"kv_min": float(kv.min()), "kv_mismatch": float((kv.max() - kv.min()) / kv.mean()),
            "feedforward": float(np.mean(machine.axis_array("feedforward"))),
            "accel_min": float(min(machine.axis_array("max_accel_mm_s2")))}  # fmt: skip
#: Rows of the look-ahead block (Controller.lookahead_rows), for observation entries.
LOOKAHEAD_ROWS = ("speed_limit", "curvature", "turn_angle", "programmed_feed")

# ------------------------------------------------------------------------------------- state layout
# Float state, one row per env: the controller's state vector, the signals, then the accumulators.
F_CTRL = 0  # kernel.N_STATE_F columns
F_SIGNAL = K.N_STATE_F  # len(SIGNALS) columns
_F_ACC = F_SIGNAL + len(SIGNALS)
(F_ERROR_MAX, F_ERROR_SQ_SUM, F_REWARD, F_VIOLATION_LENGTH, F_VIOLATION_TIME,
 F_KV_MIN) = range(_F_ACC, _F_ACC + 6)  # fmt: skip
F_LAST_REF = _F_ACC + 6  # x, y, z of the last reference (held while the program is finished)
# The step's outputs, written by the kernel for Python to read in one go: reward, terminated, truncated,
# then the info values in OUTPUT_INFO_KEYS order (integers as floats: exact).
F_OUT = F_LAST_REF + 3
OUTPUT_INFO_KEYS = ("cycle_time_s", "contour_error_mm", "contour_error_max_mm", "contour_error_rms_mm",
                    "tolerance_mm", "violations", "violation_length_mm", "violation_time_s", "cost", "line",
                    "override", "feed_mm_min", "path_s", "progress", "steps")  # fmt: skip
_OUT_INT = tuple(3 + i for i, key in enumerate(OUTPUT_INFO_KEYS) if key in ("violations", "line", "steps"))
N_STATE_F = F_OUT + 3 + len(OUTPUT_INFO_KEYS)
# After them, each batch's own outputs (FeedrateBatch.info_keys): a placeholder for the program's name, then
# where the specs ask for them, the reward terms' values, the finish bonus paid and the planner's override.
F_PROGRAM_NAME = N_STATE_F
# Int state, one row per env: the controller's state vector, then the episode's counters and flags.
I_CTRL = 0  # kernel.N_STATE_I columns
(I_PROGRAM, I_STEPS, I_TICKS, I_VIOLATIONS, I_SAMPLES, I_LAST_SEGMENT, I_LINE, I_TERMINATED, I_TRUNCATED,
 I_RESET) = range(K.N_STATE_I, K.N_STATE_I + 10)  # fmt: skip
N_STATE_I = I_RESET + 1

# --------------------------------------------------------------------------------------- the bank
# Float tables of a program, in bank order, with their column counts; then the int tables.
_FLOAT_TABLES = ("seg_f", "pt_f", "dwell_f", "curve_f", "geometry", "nurbs_f", "scalars", "schedule")
_T_SCHEDULE = 7  # the planner's schedule: (n, 2) rows of path position (mm) and override
_INT_TABLES = ("seg_i", "pt_i", "seg_class", "axes", "first_back", "nurbs_i", "lines", "counts")
# Per-program float scalars: the controller's cfg (6), start point (3), 1 / length, length,
# control period / T, the finish bonus.
_S_CFG, _S_START, _S_INV_LENGTH, _S_LENGTH, _S_TIME_FRACTION, _S_FINISH_BONUS = 0, 6, 9, 10, 11, 12
# Per-program int counts: motion segments, tool path rows, step budget.
_N_MOTION, _N_ROWS, _MAX_STEPS = 0, 1, 2
_DIR_STRIDE = 2 * (len(_FLOAT_TABLES) + len(_INT_TABLES))
# Config (shared by every env), at the start of the bank: floats then ints.
(CF_TOLERANCE, CF_IN_POSITION, CF_MAX_OVERRIDE, CF_MAX_FEED, CF_HORIZON, CF_PERIOD, CF_PLANNER_LEAD,
 CF_MACHINE) = range(8)  # fmt: skip
N_CONFIG_F = CF_MACHINE + len(MACHINE_QUANTITIES)
(CI_TICKS, CI_POINTS, CI_FEED_MODE, CI_WINDOW_AHEAD, CI_WINDOW, CI_OBS, CI_OBS_BLOCKS, CI_REWARD, CI_PROGRAMS,
 CI_OBS_AT, CI_BLOCKS_AT, CI_REWARD_AT, CI_OBS_TAIL, CI_TAIL_AT, CI_COST, CI_TERMS_OUT, CI_FINISH_OUT,
 CI_PLANNER_OUT) = range(18)  # fmt: skip
N_CONFIG_I = 18  # the *_OUT entries: columns of the state row, or -1 where the batch does not output it
# Observation spec rows (floats): per signal entry: signal, scale, low, high; per look-ahead block: row,
# transform, parameter, scale, low, high. Reward spec rows: signal, transform, parameter, weight.
T_NONE, T_SATURATE, T_CAPPED_SQUARE = 0, 1, 2  # transforms: x, xp/(1 + xp), min(x, p)²
_OBS_COLS, _BLOCK_COLS, _REWARD_COLS = 4, 6, 4


@dataclass(frozen=True)
class ObservationSpec:
    """The observation: ``signals`` entries, then ``lookahead`` blocks, then ``tail`` entries, in order.

    A signal entry ``(name, scale, low, high)`` is one of :data:`SIGNALS` (``tail`` entries are signal
    entries too, placed after the blocks); a look-ahead block ``(row, transform, parameter, scale, low,
    high)`` is ``points`` entries, a row of :data:`LOOKAHEAD_ROWS` at each point ahead, ``transform``
    ``"none"`` or ``"saturate"`` (x·p / (1 + x·p)). Each entry is ``clip(transform(x) · scale, low, high)``
    as float32, 0 where NaN.
    """

    signals: tuple[tuple[str, float, float, float], ...]
    lookahead: tuple[tuple[str, str, float, float, float, float], ...]
    points: int
    tail: tuple[tuple[str, float, float, float], ...] = ()

    def tables(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The signal rows (n, 4), the block rows (m, 6) and the tail rows (k, 4) of the kernel."""
        def signal_rows(entries: tuple[tuple[str, float, float, float], ...]) -> np.ndarray:
            rows = [(SIGNALS.index(name), scale, low, high) for name, scale, low, high in entries]
            return np.array(rows, dtype=np.float64).reshape(-1, _OBS_COLS)

        codes = {"none": T_NONE, "saturate": T_SATURATE}
        blocks = [(LOOKAHEAD_ROWS.index(row), codes[transform], param, scale, low, high)
                  for row, transform, param, scale, low, high in self.lookahead]  # fmt: skip
        return (signal_rows(self.signals), np.array(blocks, dtype=np.float64).reshape(-1, _BLOCK_COLS),
                signal_rows(self.tail))  # fmt: skip

    @property
    def size(self) -> int:
        return len(self.signals) + len(self.lookahead) * self.points + len(self.tail)

    def _bounds(self, column: int) -> np.ndarray:
        values = [entry[column] for entry in self.signals]
        for block in self.lookahead:
            values += [block[column + 2]] * self.points
        values += [entry[column] for entry in self.tail]
        return np.array(values, dtype=np.float32)

    @property
    def low(self) -> np.ndarray:
        return self._bounds(2)

    @property
    def high(self) -> np.ndarray:
        return self._bounds(3)


@dataclass(frozen=True)
class RewardSpec:
    """The reward: ``Σ weight · transform(signal)`` over ``terms`` of ``(signal name, transform,
    parameter, weight)`` (transforms ``"linear"``: x; ``"capped_square"``: min(x, p)²), summed in order.

    ``term_keys``: the info key of each term's value (empty: the terms are not in the info). ``finish_key``:
    when set, the step that ends the episode by termination with a violation length of 0 also pays the
    program's finish bonus (:meth:`FeedrateBatch.add_program`), shown in the info under this key. ``cost``:
    the signal that is ``info["cost"]``.
    """

    terms: tuple[tuple[str, str, float, float], ...]
    term_keys: tuple[str, ...] = ()
    finish_key: str | None = None
    cost: str = "violated"

    def __post_init__(self) -> None:
        if self.term_keys and len(self.term_keys) != len(self.terms):
            raise ValueError("RewardSpec: one term key per term")

    def table(self) -> np.ndarray:
        codes = {"linear": T_NONE, "capped_square": T_CAPPED_SQUARE}
        rows = [(SIGNALS.index(name), codes[transform], param, weight) for name, transform, param, weight
                in self.terms]  # fmt: skip
        return np.array(rows, dtype=np.float64).reshape(-1, _REWARD_COLS)


@dataclass(frozen=True)
class PackedProgram:
    """One program ready for the kernel: its controller limits, contour meter and constants."""

    name: str
    toolpath: Toolpath
    limits: PathLimits
    meter: ContourErrorMeter
    floats: tuple[np.ndarray, ...]  # in _FLOAT_TABLES order
    ints: tuple[np.ndarray, ...]  # in _INT_TABLES order
    start: np.ndarray  # (3,) where the episode starts (the first point, or the origin)
    length_mm: float  # total path length (at least 1e-9)
    max_episode_steps: int

    @classmethod
    def build(cls, name: str, toolpath: Toolpath, machine: MachineConfig, window_back_mm: float,
              time_fraction: float, max_episode_steps: int, rapids_behind: bool = True,
              finish_bonus: float = 0.0, planner: Planner | None = None) -> PackedProgram:  # fmt: skip
        limits = build_limits(toolpath, machine)
        # The window reaches back over the largest possible lag (max feed / Kv) so that on short-segment
        # programs the actual point is never measured against the wrong segment.
        meter = ContourErrorMeter(toolpath, window_back_mm=window_back_mm, rapids_behind=rapids_behind)
        start = toolpath.start[0].astype(np.float64) if len(toolpath) else np.zeros(3)
        length = max(toolpath.total_length, 1e-9)
        constants = [1.0 / length, length, time_fraction, finish_bonus]
        scalars = np.concatenate((kernel_config(machine, limits), start, constants))
        t = meter.tables
        n_rows = len(toolpath)
        schedule = np.zeros((0, 2)) if planner is None else planner.schedule_table(toolpath, machine, limits)
        floats = (limits.seg_f, limits.pt_f, limits.dwell_f, limits.curve_f, t.geometry, t.nurbs_f, scalars,
                  schedule)  # fmt: skip
        counts = np.array([limits.seg_f.shape[0], n_rows, max_episode_steps])
        ints = (limits.seg_i, limits.pt_i, t.seg_class, t.axes, t.first_back, t.nurbs_i,
                np.asarray(toolpath.line, dtype=np.int64), counts)  # fmt: skip
        return cls(name, toolpath, limits, meter, floats, ints, start, length, int(max_episode_steps))


class Planner(Protocol):
    """What the compiled step needs of a planner whose override it evaluates every step (the signal
    ``planner_override``): a schedule per program, and how far ahead it looks."""

    #: Reaction lead, s: the override is the schedule's smallest over the stretch covered in this time.
    lead_s: float

    def schedule_table(self, toolpath: Toolpath, machine: MachineConfig, limits: PathLimits) -> np.ndarray:
        """(n, 2) rows of path position (mm, ascending) and the override scheduled from there on."""
        ...


class ProgramBank:
    """The config, the observation and reward tables and every program's tables in one float and one int
    array (see :func:`_program`); rebuilt when a program is added."""

    def __init__(self, config_f: np.ndarray, config_i: np.ndarray,
                 obs_tables: tuple[np.ndarray, np.ndarray, np.ndarray],
                 reward_table: np.ndarray) -> None:  # fmt: skip
        self.config_f, self.config_i = config_f, config_i
        self.obs_table, self.block_table, self.tail_table = obs_tables
        self.reward_table = reward_table
        self.programs: list[PackedProgram] = []
        self.floats = np.zeros(0)
        self.ints = np.zeros(0, dtype=np.int64)

    def add(self, program: PackedProgram) -> int:
        self.programs.append(program)
        self._pack()
        return len(self.programs) - 1

    def _pack(self) -> None:
        head_f = [self.config_f, self.obs_table.ravel(), self.block_table.ravel(), self.reward_table.ravel(),
                  self.tail_table.ravel()]  # fmt: skip
        n_head_f = sum(len(x) for x in head_f)
        n_head_i = N_CONFIG_I + _DIR_STRIDE * len(self.programs)
        floats, ints = list(head_f), []
        directory = np.zeros((len(self.programs), _DIR_STRIDE), dtype=np.int64)
        at_f, at_i = n_head_f, n_head_i
        for p, program in enumerate(self.programs):
            for t, table in enumerate(program.floats):
                directory[p, 2 * t : 2 * t + 2] = (at_f, table.shape[0])
                floats.append(np.ascontiguousarray(table, dtype=np.float64).ravel())
                at_f += floats[-1].size
            base = 2 * len(_FLOAT_TABLES)
            for t, table in enumerate(program.ints):
                directory[p, base + 2 * t : base + 2 * t + 2] = (at_i, table.shape[0])
                ints.append(np.ascontiguousarray(table, dtype=np.int64).ravel())
                at_i += ints[-1].size
        config_i = self.config_i.copy()
        config_i[CI_PROGRAMS] = len(self.programs)
        config_i[CI_OBS_AT] = len(self.config_f)
        config_i[CI_BLOCKS_AT] = config_i[CI_OBS_AT] + self.obs_table.size
        config_i[CI_REWARD_AT] = config_i[CI_BLOCKS_AT] + self.block_table.size
        config_i[CI_TAIL_AT] = config_i[CI_REWARD_AT] + self.reward_table.size
        self.floats = np.concatenate(floats)
        self.ints = np.concatenate([config_i, directory.ravel(), *ints])


# ------------------------------------------------------------------------------------ compiled parts
@intrinsic
def _borrowed(typingctx, array):
    """``array`` as a view that counts no references (no meminfo), for the length of one compiled call.

    numba counts references to an array's buffer with atomic increments and decrements, and it does so for
    every view and every array argument of every compiled call: a step of one env made some 250 of them
    (a fifth of its time, measured with perf), for buffers that outlive the call anyway. Views of a
    borrowed array, and the calls that take them, skip the count (numba's own ``carray`` views are made the
    same way). Only for arrays the caller holds for the whole call, and never returned."""
    if not isinstance(array, types.Array):
        return None

    def codegen(context, builder, signature, args):
        source = context.make_array(array)(context, builder, value=args[0])
        view = context.make_array(array)(context, builder)
        for field in ("shape", "strides", "data", "itemsize", "nitems"):
            setattr(view, field, getattr(source, field))
        view.meminfo = cgutils.get_null_value(view.meminfo.type)
        view.parent = cgutils.get_null_value(view.parent.type)
        return view._getvalue()

    return array(array), codegen


@intrinsic
def _matrix(typingctx, flat, start, rows, cols):
    """The (rows, cols) C-ordered view of ``flat[start : start + rows·cols]`` (a 1-D C array), which the
    caller guarantees to be in range. ``reshape`` does the same through a call into numba's C helper that
    checks the layout, some 20 times per env step."""
    if not (isinstance(flat, types.Array) and flat.ndim == 1 and flat.layout == "C"):
        return None
    matrix = types.Array(flat.dtype, 2, "C")

    def codegen(context, builder, signature, args):
        flat_value, start_value, rows_value, cols_value = args
        source = context.make_array(flat)(context, builder, value=flat_value)
        view = context.make_array(matrix)(context, builder)
        intp = context.get_value_type(types.intp)
        first = context.cast(builder, start_value, signature.args[1], types.intp)
        n_rows = context.cast(builder, rows_value, signature.args[2], types.intp)
        n_cols = context.cast(builder, cols_value, signature.args[3], types.intp)
        itemsize = context.get_constant(types.intp, context.get_abi_sizeof(context.get_data_type(flat.dtype)))
        shape = cgutils.pack_array(builder, [n_rows, n_cols], ty=intp)
        strides = cgutils.pack_array(builder, [builder.mul(n_cols, itemsize), itemsize], ty=intp)
        populate_array(view, data=builder.gep(source.data, [first]), shape=shape, strides=strides,
                       itemsize=itemsize, meminfo=source.meminfo, parent=source.parent)  # fmt: skip
        return impl_ret_borrowed(context, builder, matrix, view._getvalue())

    return matrix(flat, start, rows, cols), codegen


@njit(cache=True, nogil=True, inline="always")
def _float_table(bank_f, bank_i, p, t, n_cols):
    at = N_CONFIG_I + p * _DIR_STRIDE + 2 * t
    return _matrix(bank_f, bank_i[at], bank_i[at + 1], n_cols)


@njit(cache=True, nogil=True, inline="always")
def _float_column(bank_f, bank_i, p, t):
    at = N_CONFIG_I + p * _DIR_STRIDE + 2 * t
    return bank_f[bank_i[at] : bank_i[at] + bank_i[at + 1]]


@njit(cache=True, nogil=True, inline="always")
def _int_table(bank_f, bank_i, p, t, n_cols):
    at = N_CONFIG_I + p * _DIR_STRIDE + 2 * (len(_FLOAT_TABLES) + t)
    return _matrix(bank_i, bank_i[at], bank_i[at + 1], n_cols)


@njit(cache=True, nogil=True, inline="always")
def _int_column(bank_f, bank_i, p, t):
    at = N_CONFIG_I + p * _DIR_STRIDE + 2 * (len(_FLOAT_TABLES) + t)
    return bank_i[bank_i[at] : bank_i[at] + bank_i[at + 1]]


@njit(cache=True, nogil=True, inline="always")
def _program(bank_f, bank_i, p):
    """Views of program p's tables (see _FLOAT_TABLES, _INT_TABLES)."""
    seg_f = _float_table(bank_f, bank_i, p, 0, K.N_SEG_F)
    pt_f = _float_table(bank_f, bank_i, p, 1, K.N_PT_F)
    dwell_f = _float_table(bank_f, bank_i, p, 2, 5)
    curve_f = _float_table(bank_f, bank_i, p, 3, 6)
    geometry = _float_table(bank_f, bank_i, p, 4, C.N_GEOMETRY)
    nurbs_f = _float_column(bank_f, bank_i, p, 5)
    scalars = _float_column(bank_f, bank_i, p, 6)
    seg_i = _int_table(bank_f, bank_i, p, 0, K.N_SEG_I)
    pt_i = _int_table(bank_f, bank_i, p, 1, K.N_PT_I)
    seg_class = _int_column(bank_f, bank_i, p, 2)
    axes = _int_table(bank_f, bank_i, p, 3, 3)
    first_back = _int_column(bank_f, bank_i, p, 4)
    nurbs_i = _int_table(bank_f, bank_i, p, 5, 5)
    lines = _int_column(bank_f, bank_i, p, 6)
    counts = _int_column(bank_f, bank_i, p, 7)
    return (seg_f, pt_f, dwell_f, curve_f, geometry, nurbs_f, scalars, seg_i, pt_i, seg_class, axes,
            first_back, nurbs_i, lines, counts)  # fmt: skip


@njit(cache=True, nogil=True, inline="always")
def _work(work_f, e, ticks, window, points):
    """Env e's scratch rows: controller output (ticks, N_OUT), reference and actual (ticks, 3), contour error
    (ticks,), the controller's point buffer (window + 2, 3) and the look-ahead block (5, points)."""
    row = work_f[e]
    at = 0
    out = _matrix(row, at, ticks, K.N_OUT)
    at += ticks * K.N_OUT
    reference = _matrix(row, at, ticks, 3)
    at += 3 * ticks
    actual = _matrix(row, at, ticks, 3)
    at += 3 * ticks
    error = row[at : at + ticks]
    at += ticks
    pts = _matrix(row, at, window + 2, 3)
    at += 3 * (window + 2)
    ahead = _matrix(row, at, 5, points)
    return out, reference, actual, error, pts, ahead


def work_size(ticks: int, window: int, points: int) -> int:
    """Floats of one env's scratch row (see :func:`_work`)."""
    return ticks * K.N_OUT + 7 * ticks + 3 * (window + 2) + 5 * points


@njit(cache=True, nogil=True)
def _observe(e, bank_f, bank_i, sf, si, seg_f, pt_f, pt_i, scalars, ahead, obs) -> None:
    """The look-ahead block, the observation signals, the observation row and the outputs of env e."""
    cfg_f = bank_f[:N_CONFIG_F]
    st_f = sf[e, F_CTRL : F_CTRL + K.N_STATE_F]
    st_i = si[e, I_CTRL : I_CTRL + K.N_STATE_I]
    done = st_i[K.K_PHASE] == K.PHASE_DONE
    K.lookahead_into(seg_f, pt_f, pt_i, st_i[K.K_SEG], st_f[K.S_S], done, cfg_f[CF_HORIZON], ahead)
    sig = sf[e, F_SIGNAL : F_SIGNAL + len(SIGNALS)]
    sig[SIG_SPEED] = st_f[K.S_V]
    sig[SIG_ACCEL] = st_f[K.S_A]
    sig[SIG_OVERRIDE] = 1.0 if st_f[K.S_OV] < 0.0 else st_f[K.S_OV]
    sig[SIG_PATH_FRACTION] = st_f[K.S_S] * scalars[_S_INV_LENGTH]
    sig[SIG_DISTANCE_TO_STOP] = ahead[4, 0]
    sig[SIG_VIOLATION_FREE] = 1.0 if sf[e, F_VIOLATION_LENGTH] <= 0.0 else 0.0
    schedule = _float_table(bank_f, bank_i, si[e, I_PROGRAM], _T_SCHEDULE, 2)
    if schedule.shape[0]:
        sig[SIG_PLANNER_OVERRIDE] = planner_override(schedule, st_f[K.S_S], sig[SIG_SPEED] * 60.0,
                                                     cfg_f[CF_PLANNER_LEAD])  # fmt: skip
    row = bank_f[bank_i[CI_OBS_AT] :]
    n_signals = bank_i[CI_OBS]
    for i in range(n_signals):
        x = sig[int(row[4 * i])] * row[4 * i + 1]
        obs[e, i] = _clip(x, row[4 * i + 2], row[4 * i + 3])
    block = bank_f[bank_i[CI_BLOCKS_AT] :]
    n_points = ahead.shape[1]
    at = n_signals
    for b in range(bank_i[CI_OBS_BLOCKS]):
        values = ahead[int(block[6 * b])]
        saturate = int(block[6 * b + 1]) == T_SATURATE
        param, scale, low, high = block[6 * b + 2], block[6 * b + 3], block[6 * b + 4], block[6 * b + 5]
        for j in range(n_points):
            x = values[j]
            if saturate:
                kl = x * param
                x = kl / (kl + 1.0)
            obs[e, at + j] = _clip(x * scale, low, high)
        at += n_points
    row = bank_f[bank_i[CI_TAIL_AT] :]
    for i in range(bank_i[CI_OBS_TAIL]):
        x = sig[int(row[4 * i])] * row[4 * i + 1]
        obs[e, at + i] = _clip(x, row[4 * i + 2], row[4 * i + 3])
    _write_outputs(e, bank_f, bank_i, sf, si)


@njit(cache=True, nogil=True, inline="always")
def _clip(x, low, high):
    """An observation entry: NaN from upstream becomes 0 (it would poison a policy), then clipped."""
    if x != x:
        x = 0.0
    return min(max(x, low), high)


@njit(cache=True, nogil=True)
def _write_outputs(e, bank_f, bank_i, sf, si) -> None:
    """The step's outputs block of env e (see F_OUT), from its state."""
    out = sf[e, F_OUT:]
    samples = si[e, I_SAMPLES]
    out[0] = sf[e, F_REWARD]
    out[1] = si[e, I_TERMINATED]
    out[2] = si[e, I_TRUNCATED]
    out[3] = si[e, I_TICKS] * bank_f[CF_PERIOD]
    out[4] = sf[e, F_SIGNAL + SIG_ERROR_STEP]
    out[5] = sf[e, F_ERROR_MAX]
    out[6] = math.sqrt(sf[e, F_ERROR_SQ_SUM] / samples) if samples else 0.0
    out[7] = bank_f[CF_TOLERANCE]
    out[8] = si[e, I_VIOLATIONS]
    out[9] = sf[e, F_VIOLATION_LENGTH]
    out[10] = sf[e, F_VIOLATION_TIME]
    out[11] = sf[e, F_SIGNAL + bank_i[CI_COST]]
    out[12] = si[e, I_LINE]
    out[13] = sf[e, F_SIGNAL + SIG_OVERRIDE]
    out[14] = sf[e, F_SIGNAL + SIG_SPEED] * 60.0
    out[15] = sf[e, F_CTRL + K.S_S]
    out[16] = sf[e, F_SIGNAL + SIG_PROGRESS]
    out[17] = si[e, I_STEPS]
    if bank_i[CI_PLANNER_OUT] >= 0:
        sf[e, bank_i[CI_PLANNER_OUT]] = sf[e, F_SIGNAL + SIG_PLANNER_OVERRIDE]


@njit(cache=True, nogil=True)
def _line_of(si, e, seg_i, dwell_f, lines) -> None:
    row = K.segment_index(seg_i, dwell_f, si[e, I_CTRL : I_CTRL + K.N_STATE_I])
    si[e, I_LINE] = lines[min(max(row, 0), lines.shape[0] - 1)] if lines.shape[0] else 0


@njit(cache=True, nogil=True)
def _reset_episode(e, bank_f, bank_i, sf, si, obs, ahead) -> None:
    """Env e at the start of its program (row I_PROGRAM): controller state, counters and signals, the
    observation. The plant is reset by the caller (compiled, or through the plant object)."""
    p = si[e, I_PROGRAM]
    (seg_f, pt_f, dwell_f, _, _, _, scalars, seg_i, pt_i, _, _, _, _, lines,
     counts) = _program(bank_f, bank_i, p)  # fmt: skip
    K.reset_state(pt_i, pt_f, dwell_f, counts[_N_MOTION], sf[e, F_CTRL : F_CTRL + K.N_STATE_F],
                  si[e, I_CTRL : I_CTRL + K.N_STATE_I])  # fmt: skip
    kv_min = sf[e, F_KV_MIN]
    sf[e, F_SIGNAL:] = 0.0
    sf[e, F_KV_MIN] = kv_min
    for a in range(3):
        sf[e, F_LAST_REF + a] = scalars[_S_START + a]
    si[e, I_CTRL + K.N_STATE_I :] = 0  # the counters and flags (the program stays)
    si[e, I_PROGRAM] = p
    finished = si[e, I_CTRL + K.K_PHASE] == K.PHASE_DONE
    progress = 1.0 if finished else min(sf[e, F_CTRL + K.S_S] / scalars[_S_LENGTH], 1.0)
    sf[e, F_SIGNAL + SIG_PROGRESS] = progress
    sf[e, F_SIGNAL + SIG_TIME_FRACTION] = scalars[_S_TIME_FRACTION]
    for k in range(len(MACHINE_QUANTITIES)):
        sf[e, F_SIGNAL + SIG_KV_MIN + k] = bank_f[CF_MACHINE + k]
    _line_of(si, e, seg_i, dwell_f, lines)
    _observe(e, bank_f, bank_i, sf, si, seg_f, pt_f, pt_i, scalars, ahead, obs)


@njit(cache=True, nogil=True)
def _reset_plant(e, start, plant_x, plant_h, plant_v) -> None:
    """ServoPlant.reset of one env: at rest at ``start``, the reference history there too."""
    for a in range(3):
        for j in range(plant_x.shape[1]):
            plant_x[a, j, e] = 0.0
        plant_x[a, 0, e] = start[a]
        for j in range(plant_h.shape[1]):
            plant_h[a, j, e] = start[a]
        plant_v[a, e] = 0.0


@njit(cache=True, nogil=True)
def _reference(e, bank_f, bank_i, sf, si, knob, seg_f, pt_f, dwell_f, curve_f, seg_i, pt_i, scalars, out,
               reference, hints, pts) -> None:  # fmt: skip
    """The step's reference positions and segments: the controller's periods at the knob, or the last
    reference held once the program is finished."""
    cfg_f = bank_f[:N_CONFIG_F]
    st_f = sf[e, F_CTRL : F_CTRL + K.N_STATE_F]
    st_i = si[e, I_CTRL : I_CTRL + K.N_STATE_I]
    ticks = reference.shape[0]
    cfg = scalars[_S_CFG : _S_CFG + 6]
    if st_i[K.K_PHASE] != K.PHASE_DONE:
        # One call with a typed mode, not one per literal mode: numba would compile the controller twice.
        if bank_i[CI_FEED_MODE]:  # the knob commands the feed (replacing F), 0 … max feed
            mode, override, feed = np.int64(1), 1.0, (knob + 1.0) * 0.5 * cfg_f[CF_MAX_FEED] / 60.0
        else:
            mode, override, feed = np.int64(0), (knob + 1.0) * 0.5 * cfg_f[CF_MAX_OVERRIDE], 0.0
        K.advance_into(seg_f, seg_i, pt_f, pt_i, dwell_f, curve_f, cfg, st_f, st_i, mode, override, 1.0, feed,
                       pts, out, False, True)  # fmt: skip
        for t in range(ticks):
            for a in range(3):
                reference[t, a] = out[t, K.O_X + a]
            hints[t] = int(out[t, K.O_SEG])
        si[e, I_LAST_SEGMENT] = hints[ticks - 1]
        for a in range(3):
            sf[e, F_LAST_REF + a] = reference[ticks - 1, a]
    else:  # settling at the end: the reference rests at the last point
        for t in range(ticks):
            for a in range(3):
                reference[t, a] = sf[e, F_LAST_REF + a]
            hints[t] = si[e, I_LAST_SEGMENT]
            out[t, K.O_S] = sf[e, F_CTRL + K.S_S]


@njit(cache=True, nogil=True)
def _finish_step(e, bank_f, bank_i, sf, si, settled, reference, actual, error, hints, out, s_before, obs,
                 ahead, seg_f, pt_f, dwell_f, scalars, seg_i, pt_i, seg_class, lines,
                 counts) -> None:  # fmt: skip
    """After the plant and the contour meter: statistics, reward, end of episode and observation of env e
    (on the tables of its program)."""
    cfg_f = bank_f[:N_CONFIG_F]
    tolerance = cfg_f[CF_TOLERANCE]
    ticks = error.shape[0]
    n_rows = counts[_N_ROWS]
    sig = sf[e, F_SIGNAL : F_SIGNAL + len(SIGNALS)]
    e_max = 0.0
    sum_sq = 0.0
    n_cut = 0
    violation_length = 0.0
    n_over = 0
    s_prev = s_before
    for t in range(ticks):
        x = error[t]
        sum_sq += x * x
        if x > e_max:
            e_max = x
        h = hints[t]
        # The meter gives 0 where the reference is on a rapid or dwell, so the sum of squares over all
        # samples is the sum over cutting samples; only the count needs the cutting test.
        if 0 <= h < n_rows and C.is_cutting(seg_class[h]):
            n_cut += 1
        if x > tolerance:  # per servo sample: the reference's path advance and time while over tolerance
            violation_length += out[t, K.O_S] - s_prev
            n_over += 1
        s_prev = out[t, K.O_S]
    violation_time = n_over * cfg_f[CF_PERIOD]
    dx = reference[ticks - 1, 0] - actual[ticks - 1, 0]
    dy = reference[ticks - 1, 1] - actual[ticks - 1, 1]
    dz = reference[ticks - 1, 2] - actual[ticks - 1, 2]
    si[e, I_TICKS] += ticks
    si[e, I_STEPS] += 1
    if n_cut:
        sf[e, F_ERROR_SQ_SUM] += sum_sq
        si[e, I_SAMPLES] += n_cut
    if e_max > sf[e, F_ERROR_MAX]:
        sf[e, F_ERROR_MAX] = e_max
    violated = e_max > tolerance
    si[e, I_VIOLATIONS] += violated
    sf[e, F_VIOLATION_LENGTH] += violation_length
    sf[e, F_VIOLATION_TIME] += violation_time
    sig[SIG_FOLLOWING] = math.sqrt(dx * dx + dy * dy + dz * dz)
    sig[SIG_ERROR_STEP] = e_max
    sig[SIG_ERROR_NOW] = error[ticks - 1]
    sig[SIG_ERROR_RATIO] = e_max / tolerance
    sig[SIG_VIOLATED] = 1.0 if violated else 0.0
    sig[SIG_VIOLATION_LENGTH] = violation_length
    sig[SIG_VIOLATION_TIME] = violation_time
    finished = si[e, I_CTRL + K.K_PHASE] == K.PHASE_DONE
    progress = 1.0 if finished else min(sf[e, F_CTRL + K.S_S] / scalars[_S_LENGTH], 1.0)
    sig[SIG_PROGRESS_DELTA] = progress - sig[SIG_PROGRESS]
    sig[SIG_PROGRESS] = progress
    sig[SIG_TIME_FRACTION] = scalars[_S_TIME_FRACTION]
    terminated = finished and settled
    sf[e, F_REWARD] = _finish_bonus(e, bank_i, sf, scalars, terminated, _reward_terms(e, bank_f, bank_i, sf))
    si[e, I_TERMINATED] = terminated
    si[e, I_TRUNCATED] = (not terminated) and si[e, I_STEPS] >= counts[_MAX_STEPS]
    _line_of(si, e, seg_i, dwell_f, lines)
    _observe(e, bank_f, bank_i, sf, si, seg_f, pt_f, pt_i, scalars, ahead, obs)


@njit(cache=True, nogil=True, inline="always")
def _reward_terms(e, bank_f, bank_i, sf):
    """The reward's terms, ``weight · transform(signal)`` in the spec's order: their sum, each written to
    the outputs where the batch shows them."""
    sig = sf[e, F_SIGNAL : F_SIGNAL + len(SIGNALS)]
    terms_out = bank_i[CI_TERMS_OUT]
    reward = 0.0
    at = bank_i[CI_REWARD_AT]
    for j in range(bank_i[CI_REWARD]):
        row = at + j * _REWARD_COLS
        x = sig[int(bank_f[row])]
        if int(bank_f[row + 1]) == T_CAPPED_SQUARE:
            x = min(x, bank_f[row + 2])
            term = bank_f[row + 3] * x * x
        else:
            term = bank_f[row + 3] * x
        reward += term
        if terms_out >= 0:
            sf[e, terms_out + j] = term
    return reward


@njit(cache=True, nogil=True, inline="always")
def _finish_bonus(e, bank_i, sf, scalars, terminated, reward):
    """``reward`` with the program's finish bonus where the spec pays one and the episode has just
    terminated with a violation length of 0 (the bonus paid, or 0, written to the outputs)."""
    at = bank_i[CI_FINISH_OUT]
    if at < 0:
        return reward
    bonus = scalars[_S_FINISH_BONUS] if terminated and sf[e, F_VIOLATION_LENGTH] <= 0.0 else 0.0
    sf[e, at] = bonus
    return reward + bonus


@njit(cache=True, nogil=True)
def _no_motion_step(e, bank_f, bank_i, sf, si, obs, ahead) -> None:
    """The step of a program without motion (only modal codes, M30, or nothing): done at once, in 0 s,
    with reward 0 (and the finish bonus where the spec pays one). The terms shown in the info are those
    of the signals as they stand."""
    (seg_f, pt_f, _, _, _, _, scalars, _, pt_i, _, _, _, _, _, _) = _program(bank_f, bank_i, si[e, I_PROGRAM])
    si[e, I_STEPS] += 1
    _reward_terms(e, bank_f, bank_i, sf)
    sf[e, F_REWARD] = _finish_bonus(e, bank_i, sf, scalars, True, 0.0)
    si[e, I_TERMINATED] = 1
    si[e, I_TRUNCATED] = 0
    _observe(e, bank_f, bank_i, sf, si, seg_f, pt_f, pt_i, scalars, ahead, obs)


@njit(cache=True, nogil=True)
def _no_motion_modular(e, bank_f, bank_i, sf, si, obs, work_f) -> None:
    _, _, _, _, _, ahead = _work(work_f, e, bank_i[CI_TICKS], bank_i[CI_WINDOW], bank_i[CI_POINTS])
    _no_motion_step(e, bank_f, bank_i, sf, si, obs, ahead)


@njit(cache=True, nogil=True)
def _run_env(e, bank_f, bank_i, sf, si, plant_x, plant_h, plant_v, lifted, actions, obs, work_f, work_i,
             stepping) -> None:  # fmt: skip
    """One env's part of a batch call: reset it (row flag I_RESET), or step it (if ``stepping``)."""
    if not (stepping or si[e, I_RESET]):
        return
    ticks = bank_i[CI_TICKS]
    out, reference, actual, error, pts, ahead = _work(work_f, e, ticks, bank_i[CI_WINDOW], bank_i[CI_POINTS])
    hints = work_i[e]
    p = si[e, I_PROGRAM]
    (seg_f, pt_f, dwell_f, curve_f, geometry, nurbs_f, scalars, seg_i, pt_i, seg_class, axes, first_back,
     nurbs_i, lines, counts) = _program(bank_f, bank_i, p)  # fmt: skip
    if si[e, I_RESET]:
        _reset_plant(e, scalars[_S_START : _S_START + 3], plant_x, plant_h, plant_v)
        _reset_episode(e, bank_f, bank_i, sf, si, obs, ahead)
        return
    knob = actions[e]
    sf[e, F_SIGNAL + SIG_KNOB] = knob
    if counts[_N_ROWS] == 0:
        _no_motion_step(e, bank_f, bank_i, sf, si, obs, ahead)
        return
    s_before = sf[e, F_CTRL + K.S_S]
    _reference(e, bank_f, bank_i, sf, si, knob, seg_f, pt_f, dwell_f, curve_f, seg_i, pt_i, scalars, out,
               reference, hints, pts)  # fmt: skip
    step_env(lifted, plant_x, plant_h, plant_v, e, reference, actual)
    # In-position check (P1471), once per control step: the controller holds the reference on an exact stop,
    # a rapid end or start, or the program end until the servo is settled there.
    settled = settled_env(plant_x, plant_h, plant_v, e, bank_f[CF_IN_POSITION], sf[e, F_KV_MIN])
    if settled and si[e, I_CTRL + K.K_PHASE] == K.PHASE_WAIT:
        K.release_wait(pt_i, dwell_f, sf[e, F_CTRL : F_CTRL + K.N_STATE_F],
                       si[e, I_CTRL : I_CTRL + K.N_STATE_I], counts[_N_MOTION])  # fmt: skip
    C.measure_kernel(actual, hints, seg_class, axes, geometry, first_back, nurbs_f, nurbs_i,
                     bank_i[CI_WINDOW_AHEAD], error)  # fmt: skip
    _finish_step(e, bank_f, bank_i, sf, si, settled, reference, actual, error, hints, out, s_before, obs,
                 ahead, seg_f, pt_f, dwell_f, scalars, seg_i, pt_i, seg_class, lines, counts)


@njit(cache=True, nogil=True)
def _run_serial(bank_f, bank_i, sf, si, plant_x, plant_h, plant_v, lifted, actions, obs, work_f, work_i,
                stepping) -> None:  # fmt: skip
    bank_f, bank_i, sf, si = _borrowed(bank_f), _borrowed(bank_i), _borrowed(sf), _borrowed(si)
    plant_x, plant_h, plant_v = _borrowed(plant_x), _borrowed(plant_h), _borrowed(plant_v)
    lifted, actions, obs = _borrowed(lifted), _borrowed(actions), _borrowed(obs)
    work_f, work_i = _borrowed(work_f), _borrowed(work_i)
    for e in range(sf.shape[0]):
        _run_env(e, bank_f, bank_i, sf, si, plant_x, plant_h, plant_v, lifted, actions, obs, work_f, work_i,
                 stepping)


@njit(cache=True, nogil=True, parallel=True)
def _run_parallel(bank_f, bank_i, sf, si, plant_x, plant_h, plant_v, lifted, actions, obs, work_f, work_i,
                  stepping) -> None:  # fmt: skip
    bank_f, bank_i, sf, si = _borrowed(bank_f), _borrowed(bank_i), _borrowed(sf), _borrowed(si)
    plant_x, plant_h, plant_v = _borrowed(plant_x), _borrowed(plant_h), _borrowed(plant_v)
    lifted, actions, obs = _borrowed(lifted), _borrowed(actions), _borrowed(obs)
    work_f, work_i = _borrowed(work_f), _borrowed(work_i)
    for i in prange(sf.shape[0]):
        e = np.int64(i)  # (prange's index may be unsigned; signed and unsigned would unify to float)
        _run_env(e, bank_f, bank_i, sf, si, plant_x, plant_h, plant_v, lifted, actions, obs, work_f, work_i,
                 stepping)


@njit(cache=True, nogil=True)
def _clip_actions(actions, out) -> bool:
    """``out`` = ``actions`` (N,) clipped to [-1, 1]; False (``out`` untouched) if one is not finite."""
    for e in range(actions.shape[0]):
        if not math.isfinite(actions[e]):
            return False
    for e in range(actions.shape[0]):
        out[e] = min(max(actions[e], -1.0), 1.0)
    return True


@njit(cache=True, nogil=True)
def _finish_modular(e, bank_f, bank_i, sf, si, settled, reference, actual, error, hints, out, s_before, obs,
                    work_f) -> None:  # fmt: skip
    _, _, _, _, _, ahead = _work(work_f, e, bank_i[CI_TICKS], bank_i[CI_WINDOW], bank_i[CI_POINTS])
    (seg_f, pt_f, dwell_f, _, _, _, scalars, seg_i, pt_i, seg_class, _, _, _, lines,
     counts) = _program(bank_f, bank_i, si[e, I_PROGRAM])  # fmt: skip
    _finish_step(e, bank_f, bank_i, sf, si, settled, reference, actual, error, hints, out, s_before, obs,
                 ahead, seg_f, pt_f, dwell_f, scalars, seg_i, pt_i, seg_class, lines, counts)


@njit(cache=True, nogil=True)
def _reset_modular(e, bank_f, bank_i, sf, si, obs, work_f) -> None:
    _, _, _, _, _, ahead = _work(work_f, e, bank_i[CI_TICKS], bank_i[CI_WINDOW], bank_i[CI_POINTS])
    _reset_episode(e, bank_f, bank_i, sf, si, obs, ahead)


# ------------------------------------------------------------------------------------------ the batch
#: Batches of at least this many envs step in numba's threads by default, where numba has at least
#: PARALLEL_MIN_THREADS threads (on two cores, shared, the threads' hand-offs cost more than they save).
PARALLEL_MIN_ENVS = 16
PARALLEL_MIN_THREADS = 4


class FeedrateBatch:
    """N episodes of the feed-rate task, stepped by one compiled call (see the module docstring).

    ``config`` keys: ``ticks_per_step``, ``tolerance_mm``, ``in_position_mm``, ``max_override``,
    ``max_feed_mm_min``, ``lookahead_mm``, ``lookahead_points``, ``feed_mode`` (bool), ``window_back_mm``,
    optionally ``contour_rapids_behind`` (bool, default True: the meter's rule, :class:`ContourErrorMeter`).
    ``parallel``: step the envs in numba's threads (None: from :data:`PARALLEL_MIN_ENVS` envs on, when
    numba has at least :data:`PARALLEL_MIN_THREADS` threads). ``plant``: the plant backend (default: the
    LTI :class:`ServoPlant`; one whose ``compiled_step`` is False runs the modular step). ``planner``: a
    :class:`Planner` whose override is the signal ``planner_override`` and the info's ``planner_override``
    (default: none, the signal 0).
    """

    def __init__(self, n_envs: int, machine: MachineConfig, config: dict[str, Any], obs_spec: ObservationSpec,
                 reward_spec: RewardSpec, *, parallel: bool | None = None, plant: Any | None = None,
                 planner: Planner | None = None) -> None:  # fmt: skip
        import numba

        self.n_envs = int(n_envs)
        self.machine = machine
        self.config = dict(config)
        self.planner = planner
        self.ticks = int(config["ticks_per_step"])
        self.period_s = float(machine.controller.interpolation_period_s)
        self.window_back_mm = float(config["window_back_mm"])
        self.rapids_behind = bool(config.get("contour_rapids_behind", True))
        window = max(int(machine.controller.lookahead_blocks), 2)
        points = int(config["lookahead_points"])
        quantities = machine_quantities(machine)
        config_f = np.array([config["tolerance_mm"], config["in_position_mm"], config["max_override"],
                             config["max_feed_mm_min"], config["lookahead_mm"], self.period_s,
                             0.0 if planner is None else planner.lead_s,
                             *(quantities[q] for q in MACHINE_QUANTITIES)])  # fmt: skip
        # The info: v0's keys and the program, then what the specs add (see F_PROGRAM_NAME).
        keys = [*OUTPUT_INFO_KEYS, "program"]
        column = F_PROGRAM_NAME + 1
        outputs = {"terms": -1, "finish": -1, "planner": -1}
        if reward_spec.term_keys:
            outputs["terms"], column = column, column + len(reward_spec.terms)
            keys += reward_spec.term_keys
        if reward_spec.finish_key is not None:
            outputs["finish"], column = column, column + 1
            keys.append(reward_spec.finish_key)
        if planner is not None:
            outputs["planner"], column = column, column + 1
            keys.append("planner_override")
        #: The keys of :meth:`info`, in order.
        self.info_keys = tuple(keys)
        config_i = np.zeros(N_CONFIG_I, dtype=np.int64)
        config_i[[CI_TICKS, CI_POINTS, CI_FEED_MODE, CI_WINDOW_AHEAD, CI_WINDOW, CI_OBS, CI_OBS_BLOCKS,
                  CI_REWARD, CI_OBS_TAIL, CI_COST, CI_TERMS_OUT, CI_FINISH_OUT, CI_PLANNER_OUT]] = (
            self.ticks, points, int(bool(config["feed_mode"])), 8, window, len(obs_spec.signals),
            len(obs_spec.lookahead), len(reward_spec.terms), len(obs_spec.tail),
            SIGNALS.index(reward_spec.cost), outputs["terms"], outputs["finish"],
            outputs["planner"])  # fmt: skip
        self.bank = ProgramBank(config_f, config_i, obs_spec.tables(), reward_spec.table())
        self.plant = ServoPlant(machine, n_envs=self.n_envs) if plant is None else plant
        self.fused = bool(getattr(self.plant, "compiled_step", False))
        if parallel is None:
            threads = numba.config.NUMBA_NUM_THREADS  # type: ignore[attr-defined]
            parallel = self.n_envs >= PARALLEL_MIN_ENVS and threads >= PARALLEL_MIN_THREADS
        self.parallel = bool(parallel)
        # State (see the layout constants) and scratch.
        self.state_f = np.zeros((self.n_envs, column))
        self.state_i = np.zeros((self.n_envs, N_STATE_I), dtype=np.int64)
        self._plant_version = -1  # the plant's gains are read into the state before the first call
        self.observations = np.zeros((self.n_envs, obs_spec.size), dtype=np.float32)
        self.actions = np.zeros(self.n_envs)
        self.work_f = np.zeros((self.n_envs, work_size(self.ticks, window, points)))
        self.work_i = np.zeros((self.n_envs, self.ticks), dtype=np.int64)
        self._window, self._points = window, points
        self._names = np.empty(0, dtype=object)  # program names by bank index, for the infos
        self._controllers: list[dict[int, Controller]] = [{} for _ in range(self.n_envs)]
        self._derived()

    _DERIVED = ("_run", "_args", "_args_bank", "_out_rows")

    def _derived(self) -> None:
        """What refers into the state arrays or is built from them: the compiled function and its
        arguments, views of the state rows. Rebuilt after a copy, never copied: a copy of a view is no view
        (``copy.deepcopy`` of an env, as the oracle planner makes, must step like the env)."""
        self._run = _run_parallel if self.parallel else _run_serial
        self._args: tuple = ()  # the compiled call's arrays, rebuilt when the bank or the plant changes
        self._args_bank: np.ndarray | None = None
        self._out_rows = [self.state_f[e, F_OUT:] for e in range(self.n_envs)]  # views, read every step

    def _controller_state(self, env: int) -> tuple[np.ndarray, np.ndarray]:
        """Env ``env``'s controller state vectors: views of its rows of the state arrays."""
        return (self.state_f[env, F_CTRL : F_CTRL + K.N_STATE_F],
                self.state_i[env, I_CTRL : I_CTRL + K.N_STATE_I])  # fmt: skip

    def __getstate__(self) -> dict[str, Any]:
        return {key: value for key, value in vars(self).items() if key not in self._DERIVED}

    def __setstate__(self, state: dict[str, Any]) -> None:
        vars(self).update(state)
        self._derived()
        for env, controllers in enumerate(self._controllers):  # their state vectors came as copies
            for controller in controllers.values():
                controller.use_state(self._controller_state(env))

    # ------------------------------------------------------------------------------ programs
    def add_program(self, name: str, toolpath: Toolpath, time_fraction: float, max_episode_steps: int,
                    finish_bonus: float = 0.0) -> int:  # fmt: skip
        """Pack a program into the bank (``finish_bonus``: what a violation-free finish pays where the
        reward spec has a ``finish_key``; the batch's planner plans it); returns its index."""
        program = PackedProgram.build(name, toolpath, self.machine, self.window_back_mm, time_fraction,
                                      max_episode_steps, self.rapids_behind, finish_bonus,
                                      self.planner)  # fmt: skip
        index = self.bank.add(program)
        self._names = np.array([p.name for p in self.bank.programs] + [None], dtype=object)[:-1]
        return index

    def find_program(self, name: str, toolpath: Toolpath) -> int | None:
        """The bank index of a program already packed (same name, same tool path object), else None."""
        for index, program in enumerate(self.bank.programs):
            if program.name == name and program.toolpath is toolpath:
                return index
        return None

    def program(self, env: int) -> PackedProgram:
        return self.bank.programs[int(self.state_i[env, I_PROGRAM])]

    def controller(self, env: int) -> Controller:
        """A :class:`Controller` on env ``env``'s current program, viewing the env's state (live)."""
        p = int(self.state_i[env, I_PROGRAM])
        controllers = self._controllers[env]
        if p not in controllers:
            program = self.bank.programs[p]
            controllers[p] = Controller(program.toolpath, self.machine, limits=program.limits,
                                        state=self._controller_state(env))  # fmt: skip
        return controllers[p]

    # ------------------------------------------------------------------------------ stepping
    def reset(self, envs: list[int], programs: list[int]) -> None:
        """Reset ``envs`` onto ``programs`` (indices into the bank) now; the others are left as they are."""
        for env, program in zip(envs, programs, strict=True):
            self.state_i[env, I_PROGRAM] = program
            self.state_i[env, I_RESET] = 1
        if self.fused:
            self._call(stepping=False)
        else:
            self._modular(np.asarray(envs, dtype=np.int64))

    def set_actions(self, actions: np.ndarray) -> bool:
        """Put ``actions`` ((N,) float64) clipped to [-1, 1] in :attr:`actions`; False (nothing changed) if
        one is not finite."""
        return bool(_clip_actions(actions, self.actions))

    def step(self, actions: np.ndarray | None = None) -> None:
        """Step every env (those flagged with I_RESET are reset instead) with ``actions`` (N,), knob values
        already clipped to [-1, 1] (default: what is in :attr:`actions`)."""
        if actions is not None:
            self.actions[:] = actions
        if self.fused:
            self._call(stepping=True)
        else:
            self._modular(None)

    def _call(self, stepping: bool) -> None:
        plant = self.plant
        if plant.model_version != self._plant_version or self._args_bank is not self.bank.floats:
            # gains changed (ServoPlant.set_kv_scale), or a program joined the bank
            self._plant_version = plant.model_version
            self.state_f[:, F_KV_MIN] = plant.kv_min
            self._args_bank = self.bank.floats
            self._args = (self.bank.floats, self.bank.ints, self.state_f, self.state_i, plant._state,
                          plant._history, plant._velocity, plant._lifted4_matrix(self.ticks), self.actions,
                          self.observations, self.work_f, self.work_i)  # fmt: skip
        self._run(*self._args, stepping)  # type: ignore[call-arg]

    def _modular(self, reset_only: np.ndarray | None) -> None:
        """The step through the Controller, plant and meter objects (see the module docstring)."""
        bank_f, bank_i = self.bank.floats, self.bank.ints
        sf, si = self.state_f, self.state_i
        resetting = np.flatnonzero(si[:, I_RESET]) if reset_only is None else reset_only
        if reset_only is None:
            ticks = self.ticks
            reference = np.empty((self.n_envs, ticks, 3))
            hints = np.zeros((self.n_envs, ticks), dtype=np.int64)
            rows = np.zeros((self.n_envs, ticks, K.N_OUT))
            s_before = sf[:, F_CTRL + K.S_S].copy()
            feed_mode = bool(self.config["feed_mode"])
            no_motion = np.zeros(self.n_envs, dtype=bool)
            for e in range(self.n_envs):
                knob = float(self.actions[e])
                sf[e, F_SIGNAL + SIG_KNOB] = knob
                controller = self.controller(e)
                no_motion[e] = not si[e, I_RESET] and len(self.program(e).toolpath) == 0
                if si[e, I_RESET] or no_motion[e]:
                    reference[e] = sf[e, F_LAST_REF : F_LAST_REF + 3]
                elif not controller.finished:
                    if feed_mode:
                        out = controller.advance_rows(ticks, feed_mm_min=(knob + 1.0) * 0.5 * self.config[
                            "max_feed_mm_min"])  # fmt: skip
                    else:
                        out = controller.advance_rows(ticks, override=(knob + 1.0) * 0.5 * self.config[
                            "max_override"])  # fmt: skip
                    rows[e] = out
                    reference[e] = out[:, K.O_X : K.O_Z + 1]
                    hints[e] = out[:, K.O_SEG].astype(np.int64)
                    si[e, I_LAST_SEGMENT] = hints[e, -1]
                    sf[e, F_LAST_REF : F_LAST_REF + 3] = reference[e, -1]
                else:  # settling at the end: the reference rests at the last point
                    reference[e] = sf[e, F_LAST_REF : F_LAST_REF + 3]
                    hints[e] = si[e, I_LAST_SEGMENT]
                    rows[e, :, K.O_S] = sf[e, F_CTRL + K.S_S]
            actual = self.plant.step(reference)
            settled = self.plant.settled(self.config["in_position_mm"])
            for e in range(self.n_envs):
                if si[e, I_RESET]:
                    continue
                if no_motion[e]:  # (its plant was stepped at rest, where it stays)
                    _no_motion_modular(e, bank_f, bank_i, sf, si, self.observations, self.work_f)
                    continue
                controller = self.controller(e)
                if controller.waiting_in_position and settled[e]:
                    controller.release_in_position()
                error = self.program(e).meter.measure(actual[e], hints[e])
                _finish_modular(e, bank_f, bank_i, sf, si, bool(settled[e]), reference[e], actual[e], error,
                                hints[e], rows[e], float(s_before[e]), self.observations,
                                self.work_f)  # fmt: skip
                self._record(e, actual[e], error, rows[e])
        for e in resetting:
            program = self.program(int(e))
            self.plant.reset(program.start, env=int(e))
            _reset_modular(int(e), bank_f, bank_i, sf, si, self.observations, self.work_f)
            self.controller(int(e))  # the view exists from the reset on

    def _record(self, env: int, actual: np.ndarray, error: np.ndarray, rows: np.ndarray) -> None:
        """Keep the modular step's samples where the fused step leaves them (see :meth:`last_samples`)."""
        out, _, actual_out, error_out, _, _ = _work(self.work_f, env, self.ticks, self._window, self._points)
        actual_out[:] = actual
        error_out[:] = error
        out[:, K.O_S] = rows[:, K.O_S]

    def last_samples(self, env: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Actual positions (ticks, 3), contour errors (ticks,) and the reference's arc length (ticks,) at
        the servo samples of env ``env``'s last step (copies)."""
        out, _, actual, error, _, _ = _work(self.work_f, env, self.ticks, self._window, self._points)
        return actual.copy(), error.copy(), out[:, K.O_S].copy()

    # ------------------------------------------------------------------------------ info
    def outcome(self, env: int) -> tuple[float, bool, bool, dict[str, Any]]:
        """Reward, terminated, truncated and info of env ``env``'s last step."""
        out = self._out_rows[env].tolist()
        for i in _OUT_INT:
            out[i] = int(out[i])
        out[F_PROGRAM_NAME - F_OUT] = self._names[int(self.state_i[env, I_PROGRAM])]
        info = dict(zip(self.info_keys, out[3:], strict=False))  # (the lengths match by construction)
        return out[0], out[1] != 0.0, out[2] != 0.0, info

    def info(self, env: int) -> dict[str, Any]:
        """The env's info dict (see FeedrateEnv's docstring)."""
        return self.outcome(env)[3]

    def infos(self) -> dict[str, np.ndarray]:
        """Every env's info as one (N,) array per key (``program`` an object array)."""
        return self.gather()[4]

    def gather(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, np.ndarray], int]:
        """The last step's observations, rewards, terminated and truncated flags, infos (as
        :meth:`infos`) and the number of envs whose episode ended: fresh arrays, from one compiled call."""
        obs, rewards, terminated, truncated, info_f, info_i, ended = _gather(self.state_f, self.observations)
        infos = dict(zip(OUTPUT_INFO_KEYS, info_f, strict=True))
        infos.update(zip(_OUT_INT_KEYS, info_i, strict=True))
        infos["program"] = self._names[self.state_i[:, I_PROGRAM]]
        return obs, rewards, terminated, truncated, infos, int(ended)


_OUT_INT_KEYS = tuple(OUTPUT_INFO_KEYS[i - 3] for i in _OUT_INT)


@njit(cache=True, nogil=True)
def _gather(sf, observations):
    """Fresh output arrays of a batch step (see FeedrateBatch.gather) from the envs' output blocks: info
    rows in OUTPUT_INFO_KEYS order (the integer ones as int64), one column per env."""
    n = sf.shape[0]
    obs = observations.copy()
    rewards = np.empty(n)
    terminated = np.empty(n, dtype=np.bool_)
    truncated = np.empty(n, dtype=np.bool_)
    n_info = len(OUTPUT_INFO_KEYS)
    info_f = np.empty((n_info, n))
    info_i = np.empty((len(_OUT_INT), n), dtype=np.int64)
    ended = 0
    for e in range(n):
        out = sf[e, F_OUT:]
        rewards[e] = out[0]
        terminated[e] = out[1] != 0.0
        truncated[e] = out[2] != 0.0
        ended += terminated[e] or truncated[e]
        for k in range(n_info):
            info_f[k, e] = out[3 + k]
        for j in range(len(_OUT_INT)):
            info_i[j, e] = int(out[_OUT_INT[j]])
    return obs, rewards, terminated, truncated, info_f, info_i, ended


#: Info keys of a batch without reward terms, finish bonus or planner (v0's), in the order of
#: :meth:`FeedrateBatch.info`.
INFO_KEYS = (*OUTPUT_INFO_KEYS, "program")


def step_needs_compiling(*, parallel: bool = False) -> bool:
    """Whether this process's first batch step compiles the fused step: numba's disk cache holds none for
    this source and CPU (a fresh install, or a kernel changed). Reads the cache's index, compiles nothing."""
    from cnc_gym.numba_cache import needs_compiling

    return needs_compiling([_run_parallel if parallel else _run_serial])


def _dependencies() -> None:
    from cnc_gym.motion.planner import rule
    from cnc_gym.numba_cache import refresh_on_change
    from cnc_gym.plant import servo
    from cnc_gym.toolpath import nearest

    refresh_on_change(__name__, [K, servo, C, nearest, rule])


_dependencies()  # the compiled step links the controller, plant and meter kernels: drop it when they change
