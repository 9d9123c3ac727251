"""The program bank: every program of a batch packed into one float and one int array, and the compiled
accessors that read it.

Each program is packed once (:class:`PackedProgram`: the controller's limit tables, the contour meter's
tables, the per-program constants, the planner's schedule) and all programs of a batch are concatenated,
after the config and the spec rows, into one float and one int array with a directory of offsets
(:class:`ProgramBank`), so the compiled step takes a dozen arrays whatever the number of programs, and each
env runs the program its state row names. :func:`program_tables` gives views of a program's tables,
:func:`work_rows` views of an env's scratch row; :func:`borrowed`, :func:`view_at` and :func:`matrix` are the
view helpers they and the step are built on (no reference counting, no layout checks).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numba import njit
from numba.core import cgutils, types
from numba.core.imputils import impl_ret_borrowed
from numba.extending import intrinsic
from numba.np.arrayobj import populate_array

from cnc_gym.envs.engine.layout import (
    CI_BLOCKS_AT,
    CI_OBS_AT,
    CI_PROGRAMS,
    CI_REWARD_AT,
    CI_TAIL_AT,
    N_CONFIG_I,
)
from cnc_gym.machine import MachineConfig
from cnc_gym.motion import kernel as K
from cnc_gym.motion.controller import kernel_config
from cnc_gym.motion.limits import PathLimits, build_limits
from cnc_gym.plant import ContourErrorMeter
from cnc_gym.plant import contour as C
from cnc_gym.toolpath import Toolpath

# Float tables of a program, in bank order, with their column counts; then the int tables.
FLOAT_TABLES = ("seg_f", "pt_f", "dwell_f", "curve_f", "geometry", "nurbs_f", "scalars", "schedule")
TABLE_SCHEDULE = 7  # the planner's schedule: (n, 2) rows of path position (mm) and override
INT_TABLES = ("seg_i", "pt_i", "seg_class", "axes", "first_back", "nurbs_i", "lines", "counts")
# Per-program float scalars: the controller's cfg (kernel.N_CFG entries), start point (3), 1 / length,
# length, control period / T, the finish bonus.
SCALAR_CFG = 0
SCALAR_START = SCALAR_CFG + K.N_CFG
SCALAR_INV_LENGTH, SCALAR_LENGTH, SCALAR_TIME_FRACTION, SCALAR_FINISH_BONUS = range(SCALAR_START + 3,
                                                                                   SCALAR_START + 7)
# Per-program int counts: motion segments, tool path rows, step budget.
COUNT_MOTION, COUNT_ROWS, COUNT_MAX_STEPS = 0, 1, 2
# Directory entries per program: (offset, rows) of each table.
DIR_STRIDE = 2 * (len(FLOAT_TABLES) + len(INT_TABLES))


@dataclass(frozen=True)
class PackedProgram:
    """One program ready for the kernel: its controller limits, contour meter and constants."""

    name: str
    toolpath: Toolpath
    limits: PathLimits
    meter: ContourErrorMeter
    floats: tuple[np.ndarray, ...]  # in FLOAT_TABLES order
    ints: tuple[np.ndarray, ...]  # in INT_TABLES order
    start: np.ndarray  # (3,) where the episode starts (the first point, or the origin)
    length_mm: float  # total path length (at least 1e-9)
    max_episode_steps: int

    @classmethod
    def build(cls, name: str, toolpath: Toolpath, machine: MachineConfig, window_back_mm: float,
              time_fraction: float, max_episode_steps: int, rapids_behind: bool = True,
              finish_bonus: float = 0.0, planner: Planner | None = None,
              controller_revision: int = K.CONTROLLER_REVISION) -> PackedProgram:  # fmt: skip
        limits = build_limits(toolpath, machine)
        # The window reaches back over the largest possible lag (max feed / Kv) so that on short-segment
        # programs the actual point is never measured against the wrong segment.
        meter = ContourErrorMeter(toolpath, window_back_mm=window_back_mm, rapids_behind=rapids_behind)
        start = toolpath.start[0].astype(np.float64) if len(toolpath) else np.zeros(3)
        length = max(toolpath.total_length, 1e-9)
        constants = [1.0 / length, length, time_fraction, finish_bonus]
        scalars = np.concatenate((kernel_config(machine, limits, controller_revision), start, constants))
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

    #: Reaction lead, s: the override is the schedule's smallest over the stretch covered in this time ...
    lead_s: float
    #: ... and this much farther, mm.
    reach_mm: float

    def schedule_table(self, toolpath: Toolpath, machine: MachineConfig, limits: PathLimits) -> np.ndarray:
        """(n, 2) rows of path position (mm, ascending) and the override scheduled from there on."""
        ...


class ProgramBank:
    """The config, the observation and reward tables and every program's tables in one float and one int
    array (see :func:`program_tables`); rebuilt when a program is added."""

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
        n_head_i = N_CONFIG_I + DIR_STRIDE * len(self.programs)
        floats, ints = list(head_f), []
        directory = np.zeros((len(self.programs), DIR_STRIDE), dtype=np.int64)
        at_f, at_i = n_head_f, n_head_i
        for p, program in enumerate(self.programs):
            for t, table in enumerate(program.floats):
                directory[p, 2 * t : 2 * t + 2] = (at_f, table.shape[0])
                floats.append(np.ascontiguousarray(table, dtype=np.float64).ravel())
                at_f += floats[-1].size
            base = 2 * len(FLOAT_TABLES)
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


@intrinsic
def borrowed(typingctx, array):
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
def view_at(typingctx, address, shape, dtype):
    """The C-ordered array of ``dtype`` (a numpy scalar type, e.g. ``np.float64``) and ``shape`` (a tuple of
    ints) whose data starts at ``address`` (an int: a numpy array's ``ctypes.data``), counting no references,
    as :func:`borrowed` makes. What a compiled call needs to step on arrays it is not passed as arrays (numba
    unboxes each array argument on every call: see :func:`~cnc_gym.envs.engine.step.describe`). Only for
    memory the caller keeps alive, of that type and shape, for the whole call."""
    if not (isinstance(address, types.Integer) and isinstance(shape, types.UniTuple)
            and isinstance(shape.dtype, types.Integer) and isinstance(dtype, types.NumberClass)):  # fmt: skip
        return None
    n_dims = shape.count
    view_type = types.Array(dtype.dtype, n_dims, "C")

    def codegen(context, builder, signature, args):
        address_value, shape_value, _ = args
        view = context.make_array(view_type)(context, builder)
        intp = context.get_value_type(types.intp)
        data_type = context.get_data_type(dtype.dtype)
        itemsize = context.get_constant(types.intp, context.get_abi_sizeof(data_type))
        dims = [context.cast(builder, builder.extract_value(shape_value, i), shape.dtype, types.intp)
                for i in range(n_dims)]  # fmt: skip
        strides = [itemsize]
        for dim in reversed(dims[1:]):  # C order: the last axis is contiguous
            strides.insert(0, builder.mul(strides[0], dim))
        data = builder.inttoptr(context.cast(builder, address_value, signature.args[0], types.intp),
                                data_type.as_pointer())  # fmt: skip
        populate_array(view, data=data, shape=cgutils.pack_array(builder, dims, ty=intp),
                       strides=cgutils.pack_array(builder, strides, ty=intp), itemsize=itemsize, meminfo=None,
                       parent=None)  # fmt: skip
        return view._getvalue()

    return view_type(address, shape, dtype), codegen


@intrinsic
def matrix(typingctx, flat, start, rows, cols):
    """The (rows, cols) C-ordered view of ``flat[start : start + rows·cols]`` (a 1-D C array), which the
    caller guarantees to be in range. ``reshape`` does the same through a call into numba's C helper that
    checks the layout, some 20 times per env step."""
    if not (isinstance(flat, types.Array) and flat.ndim == 1 and flat.layout == "C"):
        return None
    view_type = types.Array(flat.dtype, 2, "C")

    def codegen(context, builder, signature, args):
        flat_value, start_value, rows_value, cols_value = args
        source = context.make_array(flat)(context, builder, value=flat_value)
        view = context.make_array(view_type)(context, builder)
        intp = context.get_value_type(types.intp)
        first = context.cast(builder, start_value, signature.args[1], types.intp)
        n_rows = context.cast(builder, rows_value, signature.args[2], types.intp)
        n_cols = context.cast(builder, cols_value, signature.args[3], types.intp)
        itemsize = context.get_constant(types.intp, context.get_abi_sizeof(context.get_data_type(flat.dtype)))
        shape = cgutils.pack_array(builder, [n_rows, n_cols], ty=intp)
        strides = cgutils.pack_array(builder, [builder.mul(n_cols, itemsize), itemsize], ty=intp)
        populate_array(view, data=builder.gep(source.data, [first]), shape=shape, strides=strides,
                       itemsize=itemsize, meminfo=source.meminfo, parent=source.parent)  # fmt: skip
        return impl_ret_borrowed(context, builder, view_type, view._getvalue())

    return view_type(flat, start, rows, cols), codegen


@njit(cache=True, nogil=True, inline="always")
def float_table(bank_f, bank_i, p, t, n_cols):
    at = N_CONFIG_I + p * DIR_STRIDE + 2 * t
    return matrix(bank_f, bank_i[at], bank_i[at + 1], n_cols)


@njit(cache=True, nogil=True, inline="always")
def float_column(bank_f, bank_i, p, t):
    at = N_CONFIG_I + p * DIR_STRIDE + 2 * t
    return bank_f[bank_i[at] : bank_i[at] + bank_i[at + 1]]


@njit(cache=True, nogil=True, inline="always")
def int_table(bank_f, bank_i, p, t, n_cols):
    at = N_CONFIG_I + p * DIR_STRIDE + 2 * (len(FLOAT_TABLES) + t)
    return matrix(bank_i, bank_i[at], bank_i[at + 1], n_cols)


@njit(cache=True, nogil=True, inline="always")
def int_column(bank_f, bank_i, p, t):
    at = N_CONFIG_I + p * DIR_STRIDE + 2 * (len(FLOAT_TABLES) + t)
    return bank_i[bank_i[at] : bank_i[at] + bank_i[at + 1]]


@njit(cache=True, nogil=True)
def program_tables(bank_f, bank_i, p):
    """Views of program p's tables (see FLOAT_TABLES, INT_TABLES). A call, not inlined: its fifteen views
    inlined into each of the step's functions that reads a program cost numba seconds of compiling each."""
    seg_f = float_table(bank_f, bank_i, p, 0, K.N_SEG_F)
    pt_f = float_table(bank_f, bank_i, p, 1, K.N_PT_F)
    dwell_f = float_table(bank_f, bank_i, p, 2, 5)
    curve_f = float_table(bank_f, bank_i, p, 3, 6)
    geometry = float_table(bank_f, bank_i, p, 4, C.N_GEOMETRY)
    nurbs_f = float_column(bank_f, bank_i, p, 5)
    scalars = float_column(bank_f, bank_i, p, 6)
    seg_i = int_table(bank_f, bank_i, p, 0, K.N_SEG_I)
    pt_i = int_table(bank_f, bank_i, p, 1, K.N_PT_I)
    seg_class = int_column(bank_f, bank_i, p, 2)
    axes = int_table(bank_f, bank_i, p, 3, 3)
    first_back = int_column(bank_f, bank_i, p, 4)
    nurbs_i = int_table(bank_f, bank_i, p, 5, 5)
    lines = int_column(bank_f, bank_i, p, 6)
    counts = int_column(bank_f, bank_i, p, 7)
    return (seg_f, pt_f, dwell_f, curve_f, geometry, nurbs_f, scalars, seg_i, pt_i, seg_class, axes,
            first_back, nurbs_i, lines, counts)  # fmt: skip


@njit(cache=True, nogil=True, inline="always")
def work_rows(work_f, e, ticks, window, points):
    """Env e's scratch rows: controller output (ticks, N_OUT), reference and actual (ticks, 3), contour error
    (ticks,), the controller's point buffer (window + 2, 3) and the look-ahead block (5, points)."""
    row = work_f[e]
    at = 0
    out = matrix(row, at, ticks, K.N_OUT)
    at += ticks * K.N_OUT
    reference = matrix(row, at, ticks, 3)
    at += 3 * ticks
    actual = matrix(row, at, ticks, 3)
    at += 3 * ticks
    error = row[at : at + ticks]
    at += ticks
    pts = matrix(row, at, window + 2, 3)
    at += 3 * (window + 2)
    ahead = matrix(row, at, 5, points)
    return out, reference, actual, error, pts, ahead


def work_size(ticks: int, window: int, points: int) -> int:
    """Floats of one env's scratch row (see :func:`work_rows`)."""
    return ticks * K.N_OUT + 7 * ticks + 3 * (window + 2) + 5 * points


def _dependencies() -> None:
    from cnc_gym.envs.engine import layout
    from cnc_gym.numba_cache import refresh_on_change

    refresh_on_change(__name__, [layout, K, C])


_dependencies()  # the accessors read the layout's and the kernels' table widths: drop them when they change
