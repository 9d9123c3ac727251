"""The program bank (:mod:`cnc_gym.envs.engine.bank`): the compiled accessors read back what was packed,
the view helpers are the arrays' own memory, and a program outside an env's set joins the bank once.
"""

from __future__ import annotations

import numpy as np

from cnc_gym.envs.vector import FeedrateVectorEnv


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
