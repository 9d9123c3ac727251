"""The program bank (:mod:`cnc_gym.envs.engine.bank`): the compiled accessors read back what was packed,
the view helpers are the arrays' own memory, and a program outside an env's set joins the bank once.
"""

from __future__ import annotations

import numpy as np
from random_gcode import bench_program

from cnc_gym.envs.engine.bank import (
    FLOAT_TABLES,
    INT_TABLES,
    TABLE_SCHEDULE,
    float_table,
    program_tables,
    work_rows,
    work_size,
)
from cnc_gym.envs.feedrate_v1 import FeedrateEnvV1
from cnc_gym.envs.vector import FeedrateVectorEnv


def test_the_accessors_read_back_every_packed_table():
    # Three programs (one of NURBS curves: its NURBS tables are not empty) packed into one bank with the
    # planner's schedules; through the directory, every table of every program reads back as it was packed.
    env = FeedrateEnvV1(programs=["circle", "star", bench_program("nurbs")])
    batch = env._batch
    slots = [env.program_slot(batch, choice) for choice in range(3)]
    assert slots == [0, 1, 2] and len(batch.bank.programs) == 3
    bank_f, bank_i = batch.bank.floats, batch.bank.ints
    order = [*range(TABLE_SCHEDULE), *range(len(INT_TABLES))]  # program_tables: floats but the schedule, ints
    names = [*FLOAT_TABLES[:TABLE_SCHEDULE], *INT_TABLES]
    for p, program in enumerate(batch.bank.programs):
        views = program_tables(bank_f, bank_i, p)
        assert len(views) == len(names)
        for view, name, t in zip(views, names, order, strict=True):
            packed = (program.floats if name in FLOAT_TABLES else program.ints)[t]
            np.testing.assert_array_equal(view.ravel(), np.ravel(packed), err_msg=f"program {p}: {name}")
            assert view.ndim == np.ndim(packed) or np.ndim(packed) == 1, name
        schedule = float_table(bank_f, bank_i, p, TABLE_SCHEDULE, 2)
        assert schedule.shape[0] > 0
        np.testing.assert_array_equal(schedule, program.floats[TABLE_SCHEDULE])
    assert batch.bank.programs[2].floats[FLOAT_TABLES.index("nurbs_f")].size > 0


def test_the_scratch_rows_tile_an_env_row_without_overlap():
    ticks, window, points = 5, 8, 4
    work = np.zeros((2, work_size(ticks, window, points)))
    views = work_rows(work, 1, ticks, window, points)
    shapes = [v.shape for v in views]
    assert shapes[1:] == [(ticks, 3), (ticks, 3), (ticks,), (window + 2, 3), (5, points)]
    for k, view in enumerate(views):
        view[...] = k + 1
    # every float of row 1 belongs to exactly one view (in order), row 0 is untouched
    expected = np.concatenate([np.full(v.size, k + 1.0) for k, v in enumerate(views)])
    np.testing.assert_array_equal(work[1], expected)
    assert not work[0].any()


def test_a_program_outside_the_set_joins_the_bank():
    # reset(options={"program": text}) on the vector env: the program is packed once and every env runs it.
    envs = FeedrateVectorEnv(2, programs=["circle"])
    text = "G90 G21\nG01 X5.0 F1200.0\nM30\n"
    _, infos = envs.reset(seed=0, options={"program": text})
    assert all(name.startswith("text-") for name in infos["program"])
    assert len(envs.batch.bank.programs) == 1  # packed on first use, once for both envs
    for _ in range(5):
        *_, infos = envs.step(np.zeros((2, 1), dtype=np.float32))
    np.testing.assert_array_equal(infos["path_s"], infos["path_s"][0])


def test_borrowed_and_matrix_views_are_the_arrays_own_memory():
    # The batch call's two view helpers: a borrowed array (no reference count) and a direct (rows, cols)
    # view of a stretch of a flat table are the same memory as the array they come from, read and written.
    from numba import njit

    from cnc_gym.envs.engine.bank import borrowed, matrix

    @njit
    def fill(flat, start, rows, cols):
        view = matrix(borrowed(flat), start, rows, cols)
        for i in range(rows):
            for j in range(cols):
                view[i, j] += 100.0 * i + j
        return matrix(flat, start, rows, cols).sum()

    flat = np.arange(40, dtype=np.float64)
    expected = flat.copy()
    expected[7:19] += (100.0 * np.arange(3)[:, None] + np.arange(4)).ravel()
    total = fill(flat, 7, 3, 4)
    np.testing.assert_array_equal(flat, expected)
    assert total == expected[7:19].sum()


def test_view_at_is_the_arrays_own_memory_in_any_shape():
    # The view the single env's step reads its arrays through (from their addresses): the same memory,
    # in the array's C order, for each dtype and number of dimensions the step uses.
    from numba import njit

    from cnc_gym.envs.engine.bank import view_at

    @njit
    def bump_2d(address, rows, cols):
        view = view_at(address, (rows, cols), np.float32)
        for i in range(rows):
            for j in range(cols):
                view[i, j] += 10 * i + j
        return view[rows - 1, cols - 1]

    @njit
    def bump_4d(address, a, b, c, d):
        view = view_at(address, (a, b, c, d), np.int64)
        view[a - 1, b - 1, c - 1, d - 1] += 1000
        view[0, 0, 1, 0] += 7
        return view.sum()

    table = np.arange(12, dtype=np.float32).reshape(3, 4)
    expected = table + (10 * np.arange(3)[:, None] + np.arange(4)).astype(np.float32)
    assert bump_2d(table.ctypes.data, 3, 4) == expected[2, 3]
    np.testing.assert_array_equal(table, expected)
    block = np.arange(2 * 1 * 3 * 5, dtype=np.int64).reshape(2, 1, 3, 5)
    expected_block = block.copy()
    expected_block[1, 0, 2, 4] += 1000
    expected_block[0, 0, 1, 0] += 7
    assert bump_4d(block.ctypes.data, *block.shape) == expected_block.sum()
    np.testing.assert_array_equal(block, expected_block)
