"""The engine's data layout: the per-step signals, the state rows, the step's outputs and the config head.

Everything the compiled step reads or writes is a column of a few arrays; this module names the columns,
and nothing else (no code that steps). One row per env:

- the float state (``state_f``): the controller's state vector (``F_CTRL``), the signals (``F_SIGNAL``,
  :data:`SIGNALS`), the episode's accumulators, the last reference point, then the step's outputs
  (``F_OUT``: reward, terminated, truncated and the info values of :data:`OUTPUT_INFO_KEYS`), then each
  batch's own outputs from ``F_PROGRAM_NAME`` on;
- the int state (``state_i``): the controller's state vector (``I_CTRL``), then the episode's counters and
  flags (``I_PROGRAM`` … ``I_RESET``).

The program bank (:mod:`cnc_gym.envs.engine.bank`) starts with the batch's config: ``CF_*`` floats and
``CI_*`` ints, then the observation and reward spec rows (``*_COLS`` columns, ``T_*`` transform codes).
"""

from __future__ import annotations

import numpy as np

from cnc_gym.machine import MachineConfig
from cnc_gym.motion import kernel as K

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
#: Columns of the outputs (from F_OUT) that hold integers, and their info keys.
OUT_INT = tuple(3 + i for i, key in enumerate(OUTPUT_INFO_KEYS) if key in ("violations", "line", "steps"))
OUT_INT_KEYS = tuple(OUTPUT_INFO_KEYS[i - 3] for i in OUT_INT)
N_STATE_F = F_OUT + 3 + len(OUTPUT_INFO_KEYS)
# After them, each batch's own outputs (FeedrateBatch.info_keys): a placeholder for the program's name, then
# where the specs ask for them, the reward terms' values, the finish bonus paid and the planner's override.
F_PROGRAM_NAME = N_STATE_F
# Int state, one row per env: the controller's state vector, then the episode's counters and flags.
I_CTRL = 0  # kernel.N_STATE_I columns
(I_PROGRAM, I_STEPS, I_TICKS, I_VIOLATIONS, I_SAMPLES, I_LAST_SEGMENT, I_LINE, I_TERMINATED, I_TRUNCATED,
 I_RESET) = range(K.N_STATE_I, K.N_STATE_I + 10)  # fmt: skip
N_STATE_I = I_RESET + 1

# ------------------------------------------------------------------------------------- config head
# Config (shared by every env), at the start of the bank: floats then ints.
(CF_TOLERANCE, CF_IN_POSITION, CF_MAX_OVERRIDE, CF_MAX_FEED, CF_HORIZON, CF_PERIOD, CF_PLANNER_LEAD,
 CF_PLANNER_REACH, CF_MACHINE) = range(9)  # fmt: skip
N_CONFIG_F = CF_MACHINE + len(MACHINE_QUANTITIES)
(CI_TICKS, CI_POINTS, CI_FEED_MODE, CI_WINDOW_AHEAD, CI_WINDOW, CI_OBS, CI_OBS_BLOCKS, CI_REWARD, CI_PROGRAMS,
 CI_OBS_AT, CI_BLOCKS_AT, CI_REWARD_AT, CI_OBS_TAIL, CI_TAIL_AT, CI_COST, CI_TERMS_OUT, CI_FINISH_OUT,
 CI_PLANNER_OUT) = range(18)  # fmt: skip
N_CONFIG_I = 18  # the *_OUT entries: columns of the state row, or -1 where the batch does not output it
# Observation spec rows (floats): per signal entry: signal, scale, low, high; per look-ahead block: row,
# transform, parameter, scale, low, high. Reward spec rows: signal, transform, parameter, weight.
T_NONE, T_SATURATE, T_CAPPED_SQUARE = 0, 1, 2  # transforms: x, xp/(1 + xp), min(x, p)²
OBS_COLS, BLOCK_COLS, REWARD_COLS = 4, 6, 4
