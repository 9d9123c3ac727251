"""The batch: N episodes of the feed-rate task in the rows of a few arrays, stepped by one compiled call.

:class:`FeedrateBatch` is what ``cnc_gym/Feedrate-v0`` … v3 and their vector env step: it builds the
program bank from the config and the specs (:mod:`~cnc_gym.envs.engine.bank`,
:mod:`~cnc_gym.envs.engine.specs`), holds the state rows (:mod:`~cnc_gym.envs.engine.layout`) and the plant,
and calls the compiled step (:mod:`~cnc_gym.envs.engine.step`), serial or in numba's threads. It reads the
outputs back as rewards, flags and infos (one dict per env, or one array per key for the vector env).

A plant without compiled kernels (``compiled_step = False``: the MuJoCo plant) runs the *modular* step
instead (:meth:`FeedrateBatch.step` when :attr:`FeedrateBatch.fused` is False): the same state arrays, driven
through the :class:`~cnc_gym.motion.Controller` objects (viewing the env's rows), the plant object's
batched ``step``/``settled``/``reset`` and the :class:`~cnc_gym.plant.ContourErrorMeter`, with the
statistics, reward and observation from the same compiled functions. It is also the reference the tests
hold the compiled step to (the same numbers, exactly).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from cnc_gym.envs.engine.bank import PackedProgram, Planner, ProgramBank, work_rows, work_size
from cnc_gym.envs.engine.episode import KnobRule, run_steps
from cnc_gym.envs.engine.layout import (
    CI_COST,
    CI_FEED_MODE,
    CI_FINISH_OUT,
    CI_OBS,
    CI_OBS_BLOCKS,
    CI_OBS_TAIL,
    CI_PLANNER_OUT,
    CI_POINTS,
    CI_REWARD,
    CI_TERMS_OUT,
    CI_TICKS,
    CI_WINDOW,
    CI_WINDOW_AHEAD,
    F_CTRL,
    F_KV_MIN,
    F_LAST_REF,
    F_OUT,
    F_PROGRAM_NAME,
    F_SIGNAL,
    I_CTRL,
    I_LAST_SEGMENT,
    I_PROGRAM,
    I_RESET,
    MACHINE_QUANTITIES,
    N_CONFIG_I,
    N_STATE_I,
    OUT_INT_KEYS,
    OUTPUT_INFO_KEYS,
    SIG_KNOB,
    SIGNALS,
    machine_quantities,
)
from cnc_gym.envs.engine.specs import ObservationSpec, RewardSpec
from cnc_gym.envs.engine.step import (
    clip_actions,
    describe,
    finish_modular,
    gather_outputs,
    no_motion_modular,
    reset_modular,
    run_parallel,
    run_serial,
)
from cnc_gym.machine import MachineConfig
from cnc_gym.motion import Controller
from cnc_gym.motion import kernel as K
from cnc_gym.plant import ServoPlant
from cnc_gym.toolpath import Toolpath

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
        #: The controller's behaviour revision (:data:`cnc_gym.motion.kernel.CONTROLLER_REVISION`).
        self.controller_revision = int(config.get("controller_revision", K.CONTROLLER_REVISION))
        window = max(int(machine.controller.lookahead_blocks), 2)
        points = int(config["lookahead_points"])
        quantities = machine_quantities(machine)
        config_f = np.array([config["tolerance_mm"], config["in_position_mm"], config["max_override"],
                             config["max_feed_mm_min"], config["lookahead_mm"], self.period_s,
                             0.0 if planner is None else planner.lead_s,
                             0.0 if planner is None else planner.reach_mm,
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
        self._first_info_key = keys[0]
        config_i = np.zeros(N_CONFIG_I, dtype=np.int64)
        config_i[[CI_TICKS, CI_POINTS, CI_FEED_MODE, CI_WINDOW_AHEAD, CI_WINDOW, CI_OBS, CI_OBS_BLOCKS,
                  CI_REWARD, CI_OBS_TAIL, CI_COST, CI_TERMS_OUT, CI_FINISH_OUT, CI_PLANNER_OUT]] = (
            self.ticks, points, int(bool(config["feed_mode"])), 8, window, len(obs_spec.signals),
            len(obs_spec.lookahead), len(reward_spec.terms), len(obs_spec.tail),
            SIGNALS.index(reward_spec.cost), outputs["terms"], outputs["finish"],
            outputs["planner"])  # fmt: skip
        self.bank = ProgramBank(config_f, config_i, obs_spec.tables(), reward_spec.table())
        self.plant = ServoPlant(machine, n_envs=self.n_envs) if plant is None else plant
        #: True: one compiled call steps the batch (the plant's kernels inside it); False: the modular step.
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

    _DERIVED = ("_run", "_entry", "_args", "_descriptor", "_call_args", "_args_bank", "_out_rows",
                "_observation_rows")

    def _derived(self) -> None:
        """What refers into the state arrays or is built from them: the compiled function and its
        arguments, views of the state rows. Rebuilt after a copy, never copied: a copy of a view is no view
        (``copy.deepcopy`` of an env, as the oracle planner makes, must step like the env)."""
        self._run = run_parallel if self.parallel else run_serial
        #: ``self._run``'s machine code for :attr:`_call_args`, called without numba's dispatcher (see
        #: :func:`compiled_entry`); None until the first call with these arrays.
        self._entry: Any = None
        self._args: tuple = ()  # the compiled step's arrays, rebuilt when the bank or the plant changes
        self._descriptor = np.zeros(0, dtype=np.int64)  # their addresses and shapes (step.describe)
        #: What ``self._run`` is called with before ``stepping``: the descriptor's address (run_serial) or
        #: the arrays (run_parallel).
        self._call_args: tuple = ()
        self._args_bank: np.ndarray | None = None
        self._out_rows = [self.state_f[e, F_OUT:] for e in range(self.n_envs)]  # views, read every step
        self._observation_rows = list(self.observations)  # (views too)

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
                                      self.planner, self.controller_revision)  # fmt: skip
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
                                        state=self._controller_state(env),
                                        revision=self.controller_revision)  # fmt: skip
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
        return bool(clip_actions(actions, self.actions))

    def step(self, actions: np.ndarray | None = None) -> None:
        """Step every env (those flagged with I_RESET are reset instead) with ``actions`` (N,), knob values
        already clipped to [-1, 1] (default: what is in :attr:`actions`)."""
        if actions is not None:
            self.actions[:] = actions
        if self.fused:
            self._call(stepping=True)
        else:
            self._modular(None)

    def step_one(self, knob: float) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """Step a batch of one env with the knob value ``knob`` (already in [-1, 1]): Gymnasium's step tuple,
        the observation a copy and the info a :class:`StepInfo` (as :meth:`step` then :meth:`outcome`, with
        less of Python's work in between: the single env's step)."""
        self.actions[0] = knob
        entry = self._entry
        if (entry is not None and self.plant.model_version == self._plant_version
                and self._args_bank is self.bank.floats):  # (the arrays as they were: see _arguments)
            entry(*self._call_args, True)
        else:
            self.step()
        out = self._out_rows[0].tolist()
        info = _new_dict(StepInfo)  # (StepInfo.pending, written out)
        _set_item(info, self._first_info_key, out[3])
        info._outputs = (self.info_keys, out, self._names, self.state_i.item(0, I_PROGRAM))
        return self._observation_rows[0].copy(), out[0], out[1] != 0.0, out[2] != 0.0, info

    def _call(self, stepping: bool) -> None:
        entry = self._entry
        if (entry is not None and self.plant.model_version == self._plant_version
                and self._args_bank is self.bank.floats):  # (the arrays as they were: see _arguments)
            entry(*self._call_args, stepping)
            return
        self._arguments()
        args = self._call_args
        self._run(*args, stepping)  # type: ignore[call-arg]  # (compiles or loads the code for these types)
        self._entry = compiled_entry(self._run, (*args, stepping))

    def _arguments(self) -> tuple:
        """The compiled step's arrays (rebuilt when the plant's gains changed or a program joined the
        bank), and with them their descriptor and :attr:`_call_args`."""
        plant = self.plant
        if plant.model_version != self._plant_version or self._args_bank is not self.bank.floats:
            # gains changed (ServoPlant.set_kv_scale), or a program joined the bank
            self._plant_version = plant.model_version
            self.state_f[:, F_KV_MIN] = plant.kv_min
            self._args_bank = self.bank.floats
            self._entry = None  # (new arrays: their types are checked again on the next call)
            self._args = (self.bank.floats, self.bank.ints, self.state_f, self.state_i, plant._state,
                          plant._history, plant._velocity, plant._lifted4_matrix(self.ticks), self.actions,
                          self.observations, self.work_f, self.work_i)  # fmt: skip
            self._descriptor = describe(self._args)  # (the arrays' addresses: _args keeps them alive)
            address = int(self._descriptor.ctypes.data)
            self._call_args = self._args if self.parallel else (address,)
        return self._args

    def run_rule(self, rule: KnobRule, max_steps: int, *, stop_time_s: float = math.inf,
                 columns: np.ndarray | None = None, rows: np.ndarray | None = None,
                 total: float = 0.0) -> tuple[int, float, int]:  # fmt: skip
        """Step the batch's one env under ``rule`` in one compiled call (:func:`~cnc_gym.envs.engine.episode.
        run_steps`): up to ``max_steps`` steps, the episode's end, or the step whose cycle time reaches
        ``stop_time_s`` (unless it terminated the episode). Row k of ``rows`` gets step k's info values of
        ``columns`` (indices into ``OUTPUT_INFO_KEYS``). Returns ``(steps, total, why)``: ``total`` plus the
        steps' rewards, and why it returned (``episode.RAN``, ``ENDED``, ``STOPPED``, ``NOT_FINITE``).
        Only for a batch of one env stepped by the compiled step (:attr:`fused`)."""
        if not self.fused or self.n_envs != 1:
            raise ValueError("run_rule steps a batch of one env with the compiled step (the LTI plant)")
        columns = np.zeros(0, dtype=np.int64) if columns is None else columns
        if rows is None:
            rows = np.empty((max_steps, len(columns)))
        if rows.shape[0] < max_steps or rows.shape[1] != len(columns):
            raise ValueError(f"rows must have ({max_steps}, {len(columns)}) entries, got {rows.shape}")
        self._arguments()
        address = int(self._descriptor.ctypes.data)
        steps, total, why = run_steps(address, rule.constant, rule.schedule, rule.lead_s, rule.reach_mm,
                                      rule.max_override, int(max_steps), float(stop_time_s), columns, rows,
                                      float(total))  # fmt: skip
        return int(steps), float(total), int(why)

    def _modular(self, reset_only: np.ndarray | None) -> None:
        """The modular step: the Controller, plant and meter objects around the compiled statistics, reward
        and observation (see the module docstring). The step's wiring written a second time, on purpose and
        no more: it is the only step of a plant without compiled kernels (MuJoCo), and the reference the
        tests hold the compiled step to (tests/envs/engine/test_step.py); timings of its parts are
        ``scripts/bench_env.py --profile``'s."""
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
                    no_motion_modular(e, bank_f, bank_i, sf, si, self.observations, self.work_f)
                    continue
                controller = self.controller(e)
                if controller.waiting_in_position and settled[e]:
                    controller.release_in_position()
                error = self.program(e).meter.measure(actual[e], hints[e])
                finish_modular(e, bank_f, bank_i, sf, si, bool(settled[e]), reference[e], actual[e], error,
                               hints[e], rows[e], float(s_before[e]), self.observations,
                               self.work_f)  # fmt: skip
                self._record(e, actual[e], error, rows[e])
        for env in resetting.tolist():
            self.plant.reset(self.program(env).start, env=env)
            reset_modular(env, bank_f, bank_i, sf, si, self.observations, self.work_f)
            self.controller(env)  # the view exists from the reset on

    def _record(self, env: int, actual: np.ndarray, error: np.ndarray, rows: np.ndarray) -> None:
        """Keep the modular step's samples where the fused step leaves them (see :meth:`last_samples`)."""
        rows_of_env = work_rows(self.work_f, env, self.ticks, self._window, self._points)
        out, _, actual_out, error_out, _, _ = rows_of_env
        actual_out[:] = actual
        error_out[:] = error
        out[:, K.O_S] = rows[:, K.O_S]

    def last_samples(self, env: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Actual positions (ticks, 3), contour errors (ticks,) and the reference's arc length (ticks,) at
        the servo samples of env ``env``'s last step (copies)."""
        out, _, actual, error, _, _ = work_rows(self.work_f, env, self.ticks, self._window, self._points)
        return actual.copy(), error.copy(), out[:, K.O_S].copy()

    # ------------------------------------------------------------------------------ info
    def outcome(self, env: int) -> tuple[float, bool, bool, dict[str, Any]]:
        """Reward, terminated, truncated and info of env ``env``'s last step (the info a
        :class:`StepInfo`: its entries are made when it is first used)."""
        out = self._out_rows[env].tolist()
        info = StepInfo.pending(self.info_keys, out, self._names, self.state_i.item(env, I_PROGRAM))
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
        outputs = gather_outputs(self.state_f, self.observations)
        obs, rewards, terminated, truncated, info_f, info_i, ended = outputs
        infos = dict(zip(OUTPUT_INFO_KEYS, info_f, strict=True))
        infos.update(zip(OUT_INT_KEYS, info_i, strict=True))
        infos["program"] = self._names[self.state_i[:, I_PROGRAM]]
        for j, key in enumerate(self.info_keys[len(INFO_KEYS):], start=F_PROGRAM_NAME + 1):
            infos[key] = self.state_f[:, j].copy()  # what the specs add (reward terms, bonus, planner)
        return obs, rewards, terminated, truncated, infos, int(ended)


_new_dict = dict.__new__
_set_item = dict.__setitem__


class StepInfo(dict):
    """A step's info, as :meth:`FeedrateBatch.outcome` makes it: a ``dict`` that makes its entries from the
    step's outputs the first time it is used (read, iterated, measured, printed, compared, copied,
    changed), so that a step whose info is never read never builds it (most of a learner's steps).

    Until then it holds its first entry alone, so that code reading a dict's storage directly sees a
    dict that is not empty (``json``'s encoder then asks for its items). Copies (``dict(info)``,
    ``info.copy()``, ``copy.copy``, ``copy.deepcopy``, pickles) are plain dicts with the same entries.
    Made as a dict is (``StepInfo(...)``), it is an ordinary dict.
    """

    __slots__ = ("_outputs",)

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        self._outputs: tuple | None = None
        dict.__init__(self, *args, **kwargs)

    @classmethod
    def pending(cls, keys: tuple[str, ...], outputs: list, names: np.ndarray, program: int) -> StepInfo:
        """The info of a step whose outputs are ``outputs`` (the env's output row, a copy: reward, flags,
        then the values of ``keys`` in order), with the program name ``names[program]``."""
        info = _new_dict(cls)
        _set_item(info, keys[0], outputs[3])
        info._outputs = (keys, outputs, names, program)
        return info

    def _fill(self) -> None:
        pending = self._outputs
        if pending is not None:
            self._outputs = None
            keys, outputs, names, program = pending
            dict.update(self, zip(keys, outputs[3:], strict=False))  # (lengths match by construction)
            for key in OUT_INT_KEYS:  # (in place: the keys keep their order)
                dict.__setitem__(self, key, int(dict.__getitem__(self, key)))
            dict.__setitem__(self, "program", names[program])

    def __reduce_ex__(self, protocol: Any) -> Any:
        return dict, (self.copy(),)

    __hash__ = None  # (as a dict's)

    def clear(self) -> None:
        self._outputs = None
        dict.clear(self)

    @classmethod
    def fromkeys(cls, iterable: Any, value: Any = None) -> dict:
        return dict.fromkeys(iterable, value)



#: The dict methods a :class:`StepInfo` fills itself (and a StepInfo among the arguments) before: every one
#: that reads, compares, copies or changes the entries.
_FILLING = ("__getitem__", "__setitem__", "__delitem__", "__contains__", "__iter__", "__reversed__",
            "__len__", "__repr__", "__eq__", "__ne__", "__or__", "__ror__", "__ior__", "__sizeof__", "get",
            "keys", "values", "items", "copy", "pop", "popitem", "setdefault", "update")  # fmt: skip


def _filling(name: str) -> Any:
    """``dict``'s method ``name``, called once the info and any StepInfo argument are filled."""
    method = getattr(dict, name)

    def call(self: StepInfo, *args: Any, **kwargs: Any) -> Any:
        self._fill()
        for other in args:
            if isinstance(other, StepInfo):
                other._fill()
        return method(self, *args, **kwargs)

    call.__name__, call.__qualname__, call.__doc__ = name, f"StepInfo.{name}", method.__doc__
    return call


for _name in _FILLING:
    setattr(StepInfo, _name, _filling(_name))


def compiled_entry(dispatcher: Any, args: tuple) -> Any:
    """The machine code that numba's ``dispatcher`` runs for ``args``, as a plain callable: it skips the
    dispatcher's work on every call (typing the arguments, picking the compiled version). Only for
    arguments of exactly these types: the batch passes the same descriptor address (or, to the threaded
    step, the same arrays) every step and asks again when it builds new ones. The dispatcher
    itself where it has no such version (e.g. the code was compiled for other types, or numba's JIT is
    off)."""
    import numba

    overloads = getattr(dispatcher, "overloads", {})
    compiled = overloads.get(tuple(numba.typeof(arg) for arg in args)) if overloads else None
    return dispatcher if compiled is None else compiled.entry_point


#: Info keys of a batch without reward terms, finish bonus or planner (v0's), in the order of
#: :meth:`FeedrateBatch.info`.
INFO_KEYS = (*OUTPUT_INFO_KEYS, "program")


def step_needs_compiling(*, parallel: bool = False) -> bool:
    """Whether this process's first batch step, or its first compiled episode (the baselines' episodes:
    :func:`~cnc_gym.envs.engine.episode.run_steps`), compiles: numba's disk cache holds no machine code for
    this source and CPU (a fresh install, or a kernel changed). Reads the cache's index, compiles nothing."""
    from cnc_gym.numba_cache import needs_compiling

    return needs_compiling([run_parallel if parallel else run_serial, run_steps])
