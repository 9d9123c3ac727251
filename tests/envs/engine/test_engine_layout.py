"""The engine's data layout (:mod:`cnc_gym.envs.engine.layout`): its columns tile the state rows, the
outputs and the config head without overlap, and the names the step relies on line up.

(Named ``test_engine_layout`` because pytest needs unique test module names: ``tests/gcode/test_layout.py``.
That the engine's modules import one another in one direction is checked in tests/test_package_layout.py.)
"""

from __future__ import annotations

from cnc_gym.envs.engine import layout as L
from cnc_gym.motion import kernel as K


def test_every_signal_has_its_index_constant():
    short = {"following_error": "FOLLOWING", "contour_error_step": "ERROR_STEP",
             "contour_error_now": "ERROR_NOW"}  # fmt: skip
    for index, name in enumerate(L.SIGNALS):
        assert getattr(L, "SIG_" + short.get(name, name.upper())) == index, name


def test_the_machine_quantities_are_consecutive_signals_from_kv_min():
    # the step copies them from the config head in one loop: SIG_KV_MIN + k ← CF_MACHINE + k
    for k, name in enumerate(L.MACHINE_QUANTITIES):
        assert L.SIGNALS[L.SIG_KV_MIN + k] == name
    assert L.CF_MACHINE + len(L.MACHINE_QUANTITIES) == L.N_CONFIG_F


def test_the_float_state_row_is_tiled_in_order():
    blocks = [(L.F_CTRL, K.N_STATE_F), (L.F_SIGNAL, len(L.SIGNALS)), (L.F_ERROR_MAX, 1),
              (L.F_ERROR_SQ_SUM, 1), (L.F_REWARD, 1), (L.F_VIOLATION_LENGTH, 1), (L.F_VIOLATION_TIME, 1),
              (L.F_KV_MIN, 1), (L.F_LAST_REF, 3), (L.F_OUT, 3 + len(L.OUTPUT_INFO_KEYS))]  # fmt: skip
    at = 0
    for start, width in blocks:
        assert start == at
        at += width
    assert at == L.N_STATE_F == L.F_PROGRAM_NAME


def test_the_int_state_row_follows_the_controller_state():
    flags = [L.I_PROGRAM, L.I_STEPS, L.I_TICKS, L.I_VIOLATIONS, L.I_SAMPLES, L.I_LAST_SEGMENT, L.I_LINE,
             L.I_TERMINATED, L.I_TRUNCATED, L.I_RESET]  # fmt: skip
    assert L.I_CTRL == 0 and flags == list(range(K.N_STATE_I, K.N_STATE_I + len(flags)))
    assert flags[-1] + 1 == L.N_STATE_I


def test_the_integer_outputs_are_the_counters():
    assert L.OUT_INT_KEYS == ("violations", "line", "steps")
    assert [L.OUTPUT_INFO_KEYS[i - 3] for i in L.OUT_INT] == list(L.OUT_INT_KEYS)


def test_config_columns_are_distinct_and_in_range():
    floats = [getattr(L, n) for n in dir(L) if n.startswith("CF_")]
    ints = [getattr(L, n) for n in dir(L) if n.startswith("CI_")]
    assert sorted(floats) == list(range(len(floats))) and max(floats) < L.N_CONFIG_F
    assert sorted(ints) == list(range(L.N_CONFIG_I))
