"""The compiled step: one numba call steps (or resets) every env of a batch, on the state arrays.

Per env (:func:`run_serial` / :func:`run_parallel` over ``_run_env``): the controller's interpolation
periods at the knob (``_reference``, the motion kernel), the servo axes (the LTI plant's compiled step) and
the in-position release, the contour error at every servo sample (the contour meter's kernel), then
``_finish_step``: the statistics, the reward (``_reward_terms``, ``_finish_bonus``), the end of the
episode, and ``_observe``: the look-ahead block, the signals, the observation row and the outputs
(``_write_outputs``). An env flagged for a reset is reset instead (``_reset_episode``). Everything is read
from the program bank and the state rows (:mod:`~cnc_gym.envs.engine.layout`,
:mod:`~cnc_gym.envs.engine.bank`).

The pieces ``reset_modular``, ``finish_modular`` and ``no_motion_modular`` are the same functions entered
one env at a time, for the modular step of a plant without a compiled step
(:meth:`~cnc_gym.envs.engine.batch.FeedrateBatch.step`); :func:`gather_outputs` reads every env's outputs
in one call and :func:`clip_actions` checks and clips the actions.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from cnc_gym.envs.engine.bank import (
    COUNT_MAX_STEPS,
    COUNT_MOTION,
    COUNT_ROWS,
    SCALAR_CFG,
    SCALAR_FINISH_BONUS,
    SCALAR_INV_LENGTH,
    SCALAR_LENGTH,
    SCALAR_START,
    SCALAR_TIME_FRACTION,
    TABLE_SCHEDULE,
    borrowed,
    float_table,
    program_tables,
    view_at,
    work_rows,
)
from cnc_gym.envs.engine.layout import (
    CF_HORIZON,
    CF_IN_POSITION,
    CF_MACHINE,
    CF_MAX_FEED,
    CF_MAX_OVERRIDE,
    CF_PERIOD,
    CF_PLANNER_LEAD,
    CF_PLANNER_REACH,
    CF_TOLERANCE,
    CI_BLOCKS_AT,
    CI_COST,
    CI_FEED_MODE,
    CI_FINISH_OUT,
    CI_OBS,
    CI_OBS_AT,
    CI_OBS_BLOCKS,
    CI_OBS_TAIL,
    CI_PLANNER_OUT,
    CI_POINTS,
    CI_REWARD,
    CI_REWARD_AT,
    CI_TAIL_AT,
    CI_TERMS_OUT,
    CI_TICKS,
    CI_WINDOW,
    CI_WINDOW_AHEAD,
    F_CTRL,
    F_ERROR_MAX,
    F_ERROR_SQ_SUM,
    F_KV_MIN,
    F_LAST_REF,
    F_OUT,
    F_REWARD,
    F_SIGNAL,
    F_VIOLATION_LENGTH,
    F_VIOLATION_TIME,
    I_CTRL,
    I_LAST_SEGMENT,
    I_LINE,
    I_PROGRAM,
    I_RESET,
    I_SAMPLES,
    I_STEPS,
    I_TERMINATED,
    I_TICKS,
    I_TRUNCATED,
    I_VIOLATIONS,
    MACHINE_QUANTITIES,
    N_CONFIG_F,
    OUT_INT,
    OUTPUT_INFO_KEYS,
    REWARD_COLS,
    SIG_ACCEL,
    SIG_DISTANCE_TO_STOP,
    SIG_ERROR_NOW,
    SIG_ERROR_RATIO,
    SIG_ERROR_STEP,
    SIG_FOLLOWING,
    SIG_KNOB,
    SIG_KV_MIN,
    SIG_OVERRIDE,
    SIG_PATH_FRACTION,
    SIG_PLANNER_OVERRIDE,
    SIG_PROGRESS,
    SIG_PROGRESS_DELTA,
    SIG_SPEED,
    SIG_TIME_FRACTION,
    SIG_VIOLATED,
    SIG_VIOLATION_FREE,
    SIG_VIOLATION_LENGTH,
    SIG_VIOLATION_TIME,
    SIGNALS,
    T_CAPPED_SQUARE,
    T_SATURATE,
)
from cnc_gym.motion import kernel as K
from cnc_gym.motion.planner.rule import planner_override  # the one knob rule (the planner's)
from cnc_gym.plant import contour as C
from cnc_gym.plant.servo import settled_env, step_env


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
    sig[SIG_PATH_FRACTION] = st_f[K.S_S] * scalars[SCALAR_INV_LENGTH]
    sig[SIG_DISTANCE_TO_STOP] = ahead[4, 0]
    sig[SIG_VIOLATION_FREE] = 1.0 if sf[e, F_VIOLATION_LENGTH] <= 0.0 else 0.0
    schedule = float_table(bank_f, bank_i, si[e, I_PROGRAM], TABLE_SCHEDULE, 2)
    if schedule.shape[0]:
        sig[SIG_PLANNER_OVERRIDE] = planner_override(schedule, st_f[K.S_S], sig[SIG_SPEED] * 60.0,
                                                     cfg_f[CF_PLANNER_LEAD],
                                                     cfg_f[CF_PLANNER_REACH])  # fmt: skip
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
     counts) = program_tables(bank_f, bank_i, p)  # fmt: skip
    K.reset_state(pt_i, pt_f, dwell_f, counts[COUNT_MOTION], sf[e, F_CTRL : F_CTRL + K.N_STATE_F],
                  si[e, I_CTRL : I_CTRL + K.N_STATE_I])  # fmt: skip
    kv_min = sf[e, F_KV_MIN]
    sf[e, F_SIGNAL:] = 0.0
    sf[e, F_KV_MIN] = kv_min
    for a in range(3):
        sf[e, F_LAST_REF + a] = scalars[SCALAR_START + a]
    si[e, I_CTRL + K.N_STATE_I :] = 0  # the counters and flags (the program stays)
    si[e, I_PROGRAM] = p
    finished = si[e, I_CTRL + K.K_PHASE] == K.PHASE_DONE
    progress = 1.0 if finished else min(sf[e, F_CTRL + K.S_S] / scalars[SCALAR_LENGTH], 1.0)
    sf[e, F_SIGNAL + SIG_PROGRESS] = progress
    sf[e, F_SIGNAL + SIG_TIME_FRACTION] = scalars[SCALAR_TIME_FRACTION]
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


# Inlined into their callers (_reference into _run_env, _run_env into run_serial and run_parallel): a
# separately compiled function links the machine code of everything it calls and LLVM optimises all of it
# again, so each level of calls between the step's entry and the kernels cost seconds of a first run.
@njit(cache=True, nogil=True, inline="always")
def _reference(e, bank_f, bank_i, sf, si, knob, seg_f, pt_f, dwell_f, curve_f, seg_i, pt_i, scalars, out,
               reference, hints, pts) -> None:  # fmt: skip
    """The step's reference positions and segments: the controller's periods at the knob, or the last
    reference held once the program is finished."""
    cfg_f = bank_f[:N_CONFIG_F]
    st_f = sf[e, F_CTRL : F_CTRL + K.N_STATE_F]
    st_i = si[e, I_CTRL : I_CTRL + K.N_STATE_I]
    ticks = reference.shape[0]
    cfg = scalars[SCALAR_CFG : SCALAR_CFG + K.N_CFG]
    if st_i[K.K_PHASE] != K.PHASE_DONE:
        # One call with a typed mode, not one per literal mode: numba would compile the controller twice.
        if bank_i[CI_FEED_MODE]:  # the knob commands the feed (replacing F), 0 … max feed
            mode, override, feed = np.int64(K.MODE_FEED), 1.0, (knob + 1.0) * 0.5 * cfg_f[CF_MAX_FEED] / 60.0
        else:
            mode, override, feed = np.int64(K.MODE_OVERRIDE), (knob + 1.0) * 0.5 * cfg_f[CF_MAX_OVERRIDE], 0.0
        path = K.PathTables(seg_f, seg_i, pt_f, pt_i, dwell_f, curve_f, cfg)
        command = K.Command(mode, override, 1.0, feed, True, False)  # type: ignore[arg-type]  # (int64 mode)
        K.advance_into(path, K.ControllerState(st_f, st_i), command, out, pts)
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
    n_rows = counts[COUNT_ROWS]
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
    progress = 1.0 if finished else min(sf[e, F_CTRL + K.S_S] / scalars[SCALAR_LENGTH], 1.0)
    sig[SIG_PROGRESS_DELTA] = progress - sig[SIG_PROGRESS]
    sig[SIG_PROGRESS] = progress
    sig[SIG_TIME_FRACTION] = scalars[SCALAR_TIME_FRACTION]
    terminated = finished and settled
    sf[e, F_REWARD] = _finish_bonus(e, bank_i, sf, scalars, terminated, _reward_terms(e, bank_f, bank_i, sf))
    si[e, I_TERMINATED] = terminated
    si[e, I_TRUNCATED] = (not terminated) and si[e, I_STEPS] >= counts[COUNT_MAX_STEPS]
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
        row = at + j * REWARD_COLS
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
    bonus = scalars[SCALAR_FINISH_BONUS] if terminated and sf[e, F_VIOLATION_LENGTH] <= 0.0 else 0.0
    sf[e, at] = bonus
    return reward + bonus


@njit(cache=True, nogil=True)
def _no_motion_step(e, bank_f, bank_i, sf, si, obs, ahead) -> None:
    """The step of a program without motion (only modal codes, M30, or nothing): done at once, in 0 s,
    with reward 0 (and the finish bonus where the spec pays one). The terms shown in the info are those
    of the signals as they stand."""
    (seg_f, pt_f, _, _, _, _, scalars, _, pt_i, _, _, _, _, _,
     _) = program_tables(bank_f, bank_i, si[e, I_PROGRAM])  # fmt: skip
    si[e, I_STEPS] += 1
    _reward_terms(e, bank_f, bank_i, sf)
    sf[e, F_REWARD] = _finish_bonus(e, bank_i, sf, scalars, True, 0.0)
    si[e, I_TERMINATED] = 1
    si[e, I_TRUNCATED] = 0
    _observe(e, bank_f, bank_i, sf, si, seg_f, pt_f, pt_i, scalars, ahead, obs)


@njit(cache=True, nogil=True)
def no_motion_modular(e, bank_f, bank_i, sf, si, obs, work_f) -> None:
    _, _, _, _, _, ahead = work_rows(work_f, e, bank_i[CI_TICKS], bank_i[CI_WINDOW], bank_i[CI_POINTS])
    _no_motion_step(e, bank_f, bank_i, sf, si, obs, ahead)


@njit(cache=True, nogil=True, inline="always")
def _run_env(e, bank_f, bank_i, sf, si, plant_x, plant_h, plant_v, lifted, actions, obs, work_f, work_i,
             stepping) -> None:  # fmt: skip
    """One env's part of a batch call: reset it (row flag I_RESET), or step it (if ``stepping``)."""
    if not (stepping or si[e, I_RESET]):
        return
    ticks = bank_i[CI_TICKS]
    out, reference, actual, error, pts, ahead = work_rows(work_f, e, ticks, bank_i[CI_WINDOW],
                                                          bank_i[CI_POINTS])  # fmt: skip
    hints = work_i[e]
    p = si[e, I_PROGRAM]
    (seg_f, pt_f, dwell_f, curve_f, geometry, nurbs_f, scalars, seg_i, pt_i, seg_class, axes, first_back,
     nurbs_i, lines, counts) = program_tables(bank_f, bank_i, p)  # fmt: skip
    if si[e, I_RESET]:
        _reset_plant(e, scalars[SCALAR_START : SCALAR_START + 3], plant_x, plant_h, plant_v)
        _reset_episode(e, bank_f, bank_i, sf, si, obs, ahead)
        return
    knob = actions[e]
    sf[e, F_SIGNAL + SIG_KNOB] = knob
    if counts[COUNT_ROWS] == 0:
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
                       si[e, I_CTRL : I_CTRL + K.N_STATE_I], counts[COUNT_MOTION])  # fmt: skip
    C.measure_kernel(actual, hints, seg_class, axes, geometry, first_back, nurbs_f, nurbs_i,
                     bank_i[CI_WINDOW_AHEAD], error)  # fmt: skip
    _finish_step(e, bank_f, bank_i, sf, si, settled, reference, actual, error, hints, out, s_before, obs,
                 ahead, seg_f, pt_f, dwell_f, scalars, seg_i, pt_i, seg_class, lines, counts)


#: The compiled step's arrays, in the order it takes them: (what, dtype, dimensions). :func:`describe` packs
#: them into a descriptor, :func:`step_arrays` reads them back in compiled code.
STEP_ARRAYS = (
    ("bank floats", np.float64, 1), ("bank ints", np.int64, 1), ("state floats", np.float64, 2),
    ("state ints", np.int64, 2), ("plant state", np.float64, 3), ("plant history", np.float64, 3),
    ("plant velocity", np.float64, 2), ("lifted matrices", np.float64, 4), ("actions", np.float64, 1),
    ("observations", np.float32, 2), ("float scratch", np.float64, 2), ("int scratch", np.int64, 2),
)  # fmt: skip
_DESCRIBED = 5  # descriptor entries per array: its address, then up to 4 dimensions
_DESCRIPTOR = _DESCRIBED * len(STEP_ARRAYS)


def describe(arrays: tuple[np.ndarray, ...]) -> np.ndarray:
    """The descriptor of the step's ``arrays`` (in :data:`STEP_ARRAYS` order): each one's address and shape,
    int64. :func:`run_serial` takes the descriptor's address (one int) in place of twelve arrays: numba
    unboxes every array argument on every call (a reference-counted record each, made and freed), about
    1.5 µs of a single env's step of 10 µs on this project's 2-core machine. The caller keeps ``arrays``
    and the descriptor alive, unmoved, for as long as it passes the address (the batch holds both)."""
    if len(arrays) != len(STEP_ARRAYS):
        raise ValueError(f"the step takes {len(STEP_ARRAYS)} arrays, got {len(arrays)}")
    descriptor = np.zeros(_DESCRIPTOR, dtype=np.int64)
    for k, (array, (what, dtype, n_dims)) in enumerate(zip(arrays, STEP_ARRAYS, strict=True)):
        if (type(array) is not np.ndarray or array.dtype != dtype or array.ndim != n_dims
                or not array.flags.c_contiguous or not array.flags.aligned):  # fmt: skip
            raise ValueError(f"the step's {what} must be an aligned C-ordered {n_dims}-D "
                             f"{np.dtype(dtype)} numpy array, got {type(array).__name__} "
                             f"{getattr(array, 'shape', '')}")  # fmt: skip
        descriptor[_DESCRIBED * k] = array.ctypes.data
        descriptor[_DESCRIBED * k + 1 : _DESCRIBED * k + 1 + n_dims] = array.shape
    return descriptor


@njit(cache=True, nogil=True, inline="always")
def step_arrays(address):
    """The step's arrays (:data:`STEP_ARRAYS` order) from the address of their descriptor (:func:`describe`),
    as views that count no references."""
    d = view_at(address, (_DESCRIPTOR,), np.int64)
    return (view_at(d[0], (d[1],), np.float64), view_at(d[5], (d[6],), np.int64),
            view_at(d[10], (d[11], d[12]), np.float64),
            view_at(d[15], (d[16], d[17]), np.int64),
            view_at(d[20], (d[21], d[22], d[23]), np.float64),
            view_at(d[25], (d[26], d[27], d[28]), np.float64),
            view_at(d[30], (d[31], d[32]), np.float64),
            view_at(d[35], (d[36], d[37], d[38], d[39]), np.float64),
            view_at(d[40], (d[41],), np.float64),
            view_at(d[45], (d[46], d[47]), np.float32),
            view_at(d[50], (d[51], d[52]), np.float64),
            view_at(d[55], (d[56], d[57]), np.int64))  # fmt: skip


@njit(cache=True, nogil=True)
def run_serial(address, stepping) -> None:
    """Step (or only reset: ``stepping`` False) every env of a batch, one after the other, on the arrays
    described at ``address`` (:func:`describe`)."""
    (bank_f, bank_i, sf, si, plant_x, plant_h, plant_v, lifted, actions, obs, work_f,
     work_i) = step_arrays(address)  # fmt: skip
    for e in range(sf.shape[0]):
        _run_env(e, bank_f, bank_i, sf, si, plant_x, plant_h, plant_v, lifted, actions, obs, work_f, work_i,
                 stepping)


@njit(cache=True, nogil=True, parallel=True)
def run_parallel(bank_f, bank_i, sf, si, plant_x, plant_h, plant_v, lifted, actions, obs, work_f, work_i,
                 stepping) -> None:  # fmt: skip
    bank_f, bank_i, sf, si = borrowed(bank_f), borrowed(bank_i), borrowed(sf), borrowed(si)  # type: ignore[call-arg]
    plant_x, plant_h, plant_v = borrowed(plant_x), borrowed(plant_h), borrowed(plant_v)
    lifted, actions, obs = borrowed(lifted), borrowed(actions), borrowed(obs)
    work_f, work_i = borrowed(work_f), borrowed(work_i)
    for i in prange(sf.shape[0]):
        e = np.int64(i)  # (prange's index may be unsigned; signed and unsigned would unify to float)
        _run_env(e, bank_f, bank_i, sf, si, plant_x, plant_h, plant_v, lifted, actions, obs, work_f, work_i,
                 stepping)


@njit(cache=True, nogil=True)
def clip_actions(actions, out) -> bool:
    """``out`` = ``actions`` (N,) clipped to [-1, 1]; False (``out`` untouched) if one is not finite."""
    for e in range(actions.shape[0]):
        if not math.isfinite(actions[e]):
            return False
    for e in range(actions.shape[0]):
        out[e] = min(max(actions[e], -1.0), 1.0)
    return True


@njit(cache=True, nogil=True)
def finish_modular(e, bank_f, bank_i, sf, si, settled, reference, actual, error, hints, out, s_before, obs,
                   work_f) -> None:  # fmt: skip
    _, _, _, _, _, ahead = work_rows(work_f, e, bank_i[CI_TICKS], bank_i[CI_WINDOW], bank_i[CI_POINTS])
    (seg_f, pt_f, dwell_f, _, _, _, scalars, seg_i, pt_i, seg_class, _, _, _, lines,
     counts) = program_tables(bank_f, bank_i, si[e, I_PROGRAM])  # fmt: skip
    _finish_step(e, bank_f, bank_i, sf, si, settled, reference, actual, error, hints, out, s_before, obs,
                 ahead, seg_f, pt_f, dwell_f, scalars, seg_i, pt_i, seg_class, lines, counts)


@njit(cache=True, nogil=True)
def reset_modular(e, bank_f, bank_i, sf, si, obs, work_f) -> None:
    _, _, _, _, _, ahead = work_rows(work_f, e, bank_i[CI_TICKS], bank_i[CI_WINDOW], bank_i[CI_POINTS])
    _reset_episode(e, bank_f, bank_i, sf, si, obs, ahead)


@njit(cache=True, nogil=True)
def gather_outputs(sf, observations):
    """Fresh output arrays of a batch step (see FeedrateBatch.gather) from the envs' output blocks: info
    rows in OUTPUT_INFO_KEYS order (the integer ones as int64), one column per env."""
    n = sf.shape[0]
    obs = observations.copy()
    rewards = np.empty(n)
    terminated = np.empty(n, dtype=np.bool_)
    truncated = np.empty(n, dtype=np.bool_)
    n_info = len(OUTPUT_INFO_KEYS)
    info_f = np.empty((n_info, n))
    info_i = np.empty((len(OUT_INT), n), dtype=np.int64)
    ended = 0
    for e in range(n):
        out = sf[e, F_OUT:]
        rewards[e] = out[0]
        terminated[e] = out[1] != 0.0
        truncated[e] = out[2] != 0.0
        ended += terminated[e] or truncated[e]
        for k in range(n_info):
            info_f[k, e] = out[3 + k]
        for j in range(len(OUT_INT)):
            info_i[j, e] = int(out[OUT_INT[j]])
    return obs, rewards, terminated, truncated, info_f, info_i, ended


def _dependencies() -> None:
    from cnc_gym.envs.engine import bank, layout
    from cnc_gym.motion.planner import rule
    from cnc_gym.numba_cache import refresh_on_change
    from cnc_gym.plant import servo
    from cnc_gym.toolpath import nearest

    refresh_on_change(__name__, [layout, bank, K, servo, C, nearest, rule])


_dependencies()  # the step links the bank's accessors and the controller, plant and meter kernels, and reads
# the layout's columns: drop it when one of them changes
