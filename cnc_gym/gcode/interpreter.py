"""The core: check and execute blocks, driven by the dialect's tables, and the coordinate seam.

The language's runner (for the Fanuc family ``lang/fanuc/flow.py``) walks the program with a program
counter; every ordinary block comes here (:meth:`Interpreter.execute`) and is

1. *evaluated*: expression and variable words become numbers (a null variable drops its word);
2. *checked* against the dialect and the modal state: unknown or unbuilt codes, two codes of one modal
   group, a repeated address, a word that means nothing in this block, two owners of the axis words, and
   the dialect's own block checks (:attr:`BlockHooks.checks <cnc_gym.gcode.dialect.BlockHooks.checks>`);
3. *executed* item by item in the dialect's order of execution (``Dialect.execution_order``), each item
   carried out by the callable its :class:`~cnc_gym.gcode.codes.CodeSpec` names in the dialect's action
   registry (``Dialect.actions``).

The core holds no feature: canned cycles, compensation, transforms, calls, NURBS, measurement are actions
and hooks of the dialect, and they see the core only through the :class:`~cnc_gym.gcode.dialect.Seam`
(the state record, the coordinate seam, ``error``). Motion leaves through the output stage
(:class:`~cnc_gym.gcode.canonical.CanonicalMachine`) in machine coordinates.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

from cnc_gym.defaults import INCH_MM, INPUT_UNITS
from cnc_gym.errors import ConfigError, ProgramError, notice_line
from cnc_gym.gcode.canonical import ZERO, CanonicalMachine, MapError, map_arc
from cnc_gym.gcode.codes import CodeSpec, code_name, gkey, round_to
from cnc_gym.gcode.dialect import BlockPlan
from cnc_gym.gcode.program import split_words
from cnc_gym.gcode.settings import FlowOptions, ToolMeasurement, skip_signal_surfaces
from cnc_gym.gcode.setup import apply_setup
from cnc_gym.gcode.state import CompensationState, State
from cnc_gym.toolpath import PLANE_AXES, Plane, SegmentMode, Toolpath, ToolpathBuilder

if TYPE_CHECKING:
    from cnc_gym.gcode.dialect import Dialect, Target, Vec
    from cnc_gym.gcode.program import Block, Program
    from cnc_gym.machine import MachineConfig, SetupConfig

#: Pseudo-spec of an axis-only block: the modal motion.
IMPLICIT_MOTION = CodeSpec("(modal motion)", -1, "motion", None, step="motion")


class Interpreter:
    """Runs one :class:`Program` for one dialect into a :class:`ToolpathBuilder` (the seam's core).

    ``units``: the input unit in force at power-on, ``"mm"`` or ``"inch"`` (a controller parameter; the
    program's own G20/G21 still rules); None: the machine preset's ``power_on_units``, else the dialect's
    power-on code. ``setup``: the operator's work offsets and tool offsets at power-on (:mod:`.setup`);
    ``tool_offsets`` entries are written on top of its tools.
    """

    def __init__(self, program: Program, dialect: Dialect, *, block_skip: frozenset[int] = frozenset(),
                 start: tuple[float, float, float] = (0.0, 0.0, 0.0), machine: MachineConfig | None = None,
                 tool_offsets=None, tool_measurement=None, skip_signal=None,
                 units: str | None = None, setup: SetupConfig | None = None) -> None:  # fmt: skip
        self.dialect = dialect
        language = dialect.language
        # Rotary axes (A/B/C) the machine has: they move with G00/G01 only, in degrees.
        rotary_axes = "" if machine is None else "".join(a for a in machine.rotary_letters
                                                         if a in dialect.other_axes)  # fmt: skip
        builder = ToolpathBuilder(files=(program.file,), rotary_axes=rotary_axes)
        settings = dialect.compensation
        self.state = st = State(
            program=program,
            file=program.file,
            machine=machine,
            tool_measurement=ToolMeasurement.coerce(tool_measurement),
            skip_signal=skip_signal_surfaces(skip_signal, dialect.axes),
            skip_mask=sum(1 << n for n in block_skip),
            builder=builder,
            # (the dialect's error, not this object's: no reference cycle through the output stage)
            out=CanonicalMachine(builder, start, rotary=builder.rotary_origin, error=dialect.error),
            variables=language.variables(dialect),
            comp=CompensationState(settings, settings.new_offsets(tool_offsets)),
        )
        st.rotary_axes = rotary_axes
        st.offsets.g92_shifts_all = dialect.g92_shifts_work_systems
        st.rotary_origin = [0.0] * len(rotary_axes)
        st.increment = dialect.least_increment_mm
        st.feed = dialect.hooks.initial_feed
        # The action registry, checked once: every implemented code names a known action.
        self._actions = dialect.actions
        specs = (*dialect.gcodes.values(), *dialect.mcodes.values(), *dialect.words.values())
        missing = {s.action for s in specs if s.implemented} - set(self._actions)
        if missing:
            raise ValueError(f"dialect {dialect.name} names unknown actions {sorted(missing)}")
        self._motion_action = self._actions["motion"]
        self._evaluate = language.evaluate
        self._order = {name: i for i, name in enumerate(dialect.execution_order)}
        self._checks = dialect.hooks.checks
        self._normalise = dialect.hooks.normalise
        # Words that carry an action (F, S, T, D, H), in the order of execution.
        words = sorted(dialect.words.items(), key=lambda item: self._order[item[1].step])
        self._word_specs = tuple(words)
        self._word_actions = tuple((letter, spec, self._actions[spec.action]) for letter, spec in words)
        self._word_letters = frozenset(dialect.words)
        self._rotary_owner_actions = dialect.rotary_word_actions
        # Codes that give their own words a number format (CodeSpec.address_rules): number → rules.
        self._override_codes = {key / 10: spec.address_rules for key, spec in dialect.gcodes.items()
                                if spec.address_rules}  # fmt: skip
        axes = dialect.axes
        base = self._word_letters | {"O"}
        self._base_words = base
        self._allowed_with_motion = {
            key: base | frozenset(axes) | frozenset(spec.words)
            | (dialect.corner_words if spec.value in (1, 2, 3) else frozenset())
            for key, spec in dialect.gcodes.items() if spec.action == "motion"
        }  # fmt: skip
        for key, spec in dialect.gcodes.items():  # other group-01 modes: G60 as a mode, G06.2
            if spec.group == 1 and key not in self._allowed_with_motion:
                self._allowed_with_motion[key] = base | frozenset(axes) | frozenset(spec.words)
        self._axis_letters = frozenset(axes)
        self._rotary_letters = frozenset(rotary_axes)
        for key, spec in dialect.gcodes.items():  # rotary words belong to G00/G01 blocks only
            if spec.action == "motion" and spec.value in (0, 1):
                self._allowed_with_motion[key] = self._allowed_with_motion[key] | self._rotary_letters
        # The hot path's motion codes by their number as read (G01 → 1.0; another spelling of a code, such as
        # G1.04, takes the general path, which reads it the same way).
        self._motion_by_number = {key / 10: (key, spec) for key, spec in dialect.gcodes.items()
                                  if spec.action == "motion" and spec.implemented}  # fmt: skip
        for key in dialect.power_on:
            spec = dialect.gcodes[key]
            st.modal[spec.group] = key
            if spec.action in dialect.power_on_actions:
                self._actions[spec.action](self, spec, None)
        st.motion_key = next(k for k in dialect.power_on if dialect.gcodes[k].action == "motion")
        if units is None and machine is not None:
            units = machine.power_on_units  # the preset's parameter, below an explicit argument
        if units is not None:
            self._power_on_units(units)
        if setup is not None and not setup.empty:
            apply_setup(self, setup)  # the operator's tables, before the program's first block
            if tool_offsets is not None:  # … and the explicit tables of this run on top
                st.comp.offsets = settings.new_offsets(_with_tables(st.comp.offsets, tool_offsets))
        self.update_modes()

    def _power_on_units(self, units: str) -> None:
        """The input unit in force at power-on (a controller parameter), as if its code had run."""
        roles = self.dialect.roles
        if units not in INPUT_UNITS:
            raise ConfigError(f"units must be 'mm' or 'inch', got {units!r}")
        key = roles.metric if units == "mm" else roles.inch
        if key is None:
            raise ConfigError(f"dialect {self.dialect.name} has no code for {units} input")
        spec = self.dialect.gcodes[key]
        self.state.modal[spec.group] = key
        self._actions[spec.action](self, spec, None)

    # ------------------------------------------------------------------ the run
    def run(self, options: FlowOptions | None = None) -> Toolpath:
        """Run the program (the language's runner: program counter, control flow, calls), then the
        dialect's end-of-program hooks, and build the tool path."""
        st = self.state
        language = self.dialect.language
        for line, level, message, code in st.program.notices:
            st.builder.notice(notice_line(st.program.file, line, message, code, level))
        if language.system_variables is not None:
            st.variables.system = language.system_variables(self)
        try:
            language.runner(self, options or FlowOptions()).run()
        except ProgramError as exc:  # the notes made so far go with the error (a warning may explain it)
            exc.notices = exc.notices or tuple(st.builder.notices)
            raise
        finally:
            # The runner and the system table point back here: drop them so no reference cycle keeps a
            # run's blocks alive after it returns.
            st.flow = None
            st.variables.system = None
        for finish in self.dialect.hooks.finish:
            finish(self)
        return st.builder.build()

    def error(self, message: str, code: str, *, alarm: str | int | None = None) -> ProgramError:
        return self.dialect.error(message, code, alarm=alarm)

    def notice(self, message: str, code: str, *, line: int | None = None) -> None:
        st = self.state
        st.builder.notice(notice_line(st.file, st.out.line if line is None else line, message, code))

    def check_budget(self) -> None:
        runner = self.state.flow
        if runner is not None:
            runner.check_bounds()

    def run_action(self, name: str, spec: CodeSpec | None, values: dict) -> None:
        self._actions[name](self, spec, values)

    # ------------------------------------------------------------------ one block
    def execute(self, block: Block) -> None:
        st = self.state
        hook = st.block_hook
        if hook is not None and hook(self, block):  # G10 L50 parameter input, G06.2 NURBS mode
            return
        if block.assign is not None:
            target, value = block.assign
            evaluate = self._evaluate
            st.variables.write(evaluate(target, st.variables, self.dialect),
                               evaluate(value, st.variables, self.dialect))  # fmt: skip
            return
        if st.pending is not None:  # a chamfer/corner block waits for the next move (corners.py)
            st.pending.before_block(self)
        if block.has_expr:
            gs, ms, values = split_words(self.evaluate_words(block.words))
        else:
            gs, ms, values = block.split()
        if self._normalise is not None:
            gs, ms, values = self._normalise(self, gs, ms, values)
        st.out.line = block.line
        if st.block_listeners:  # active features that count blocks (compensation's look-ahead)
            for listener in st.block_listeners:
                listener(self, values)
        if ms is None and not st.general_path:
            # Hot path: no code, or one group-01 motion code; the other words are axis words, arc words and
            # the words with actions (F, S, T, D, H). Same checks and order as the general path, without
            # building a plan.
            if gs is not None:
                motion = self._motion_by_number.get(gs[0]) if len(gs) == 1 else None
                if motion is None:
                    self._execute_general(gs, (), values, block)
                    return
                key, spec = motion
                st.motion = spec.value  # type: ignore[assignment]
                st.motion_key = key
                st.modal[spec.group] = key
            allowed = self._allowed_with_motion[st.motion_key]
            if not values.keys() <= allowed:
                self._reject_words(values, allowed, None)
            if not self._word_letters.isdisjoint(values):
                for letter, spec, action in self._word_actions:
                    if letter in values:
                        action(self, spec, values)
            self._motion_action(self, None, values)
            return
        self._execute_general(gs or (), ms or (), values, block)

    def _execute_general(self, gs, ms, values: dict[str, float], block: Block) -> None:
        """A block off the hot path: read → check (:meth:`check_block` builds its plan) → execute
        (:meth:`execute_plan`)."""
        self.execute_plan(self.check_block(gs, ms, values), block)

    # ------------------------------------------------------------------ check: a block's plan
    def check_block(self, gs, ms, values: dict[str, float]) -> BlockPlan:
        """The block's codes looked up and checked (unknown or unimplemented codes, one code per modal
        group, who owns the axis words, which words the block may hold) into the plan that
        :meth:`execute_plan` runs; nothing of the state changes here."""
        plan = BlockPlan({}, None, None, [], values)
        self._plan_g_codes(gs, plan)
        if ms:
            self._plan_m_codes(ms, plan)
        # Who owns the axis words: a one-shot code that uses them (G04 X, G10, G52, G92) or the motion;
        # the dialect's block checks may hand them to another code (a pattern taking the cycle's).
        for check in self._checks:
            plan.axis_owner = check(self, plan)
        axis_owner, motion_spec = plan.axis_owner, plan.motion
        if axis_owner is not None and motion_spec is not None and not self._axis_letters.isdisjoint(values):
            raise self.error(f"{axis_owner.name} and {motion_spec.name} both use the axis words of the block",
                             "axis-word-conflict")  # fmt: skip
        if plan.g53 and motion_spec is not None and motion_spec.value not in (0, 1):
            raise self.error(f"G53 positions at rapid; it cannot be combined with {motion_spec.name}",
                             "bad-combination")  # fmt: skip
        allowed = self._allowed_words(plan)
        if not values.keys() <= allowed:
            self._reject_words(values, allowed, axis_owner)
        return plan

    def _plan_g_codes(self, gs, plan: BlockPlan) -> None:
        """The block's G codes into ``plan``: one per modal group, the motion, G53, the axis-word owner."""
        gcodes = self.dialect.gcodes
        by_group, keys, items = plan.by_group, plan.keys, plan.items
        for number in gs:
            key = gkey(number)
            spec = gcodes.get(key)
            if spec is None:
                raise self.error(f"unknown G code {code_name('G', key)}", "unknown-code")
            if not spec.implemented:
                raise self.error(f"{spec.name} is not implemented: {spec.note}", "not-implemented")
            other = by_group.get(spec.group)
            if other is not None:
                raise self.error(f"{other.name} and {spec.name} are both in modal group {spec.group:02d}; "
                                 "one block may hold one code per group", "group-conflict")  # fmt: skip
            by_group[spec.group] = spec
            keys[spec.group] = key
            if spec.action == "motion":
                plan.motion = spec
            elif spec.action == "machine_move":
                plan.g53 = True
            if spec.uses_axes:
                plan.axis_owner = spec
            items.append(spec)

    def _plan_m_codes(self, ms, plan: BlockPlan) -> None:
        """The block's M codes into ``plan``: how many a block may hold, one per M group, machine
        functions."""
        dialect = self.dialect
        if len(ms) > dialect.max_m_per_block:
            raise self.error(f"{len(ms)} M codes in one block (at most {dialect.max_m_per_block})",
                             "too-many-m-codes")  # fmt: skip
        m_seen: dict[str, CodeSpec] = {}
        for number in ms:
            key = gkey(number)
            spec = dialect.mcodes.get(key)
            if spec is None:
                spec = self._machine_function(key)  # or the error of an unknown M code
            if not spec.implemented:
                raise self.error(f"{spec.name} is not implemented: {spec.note}", "not-implemented",
                                 alarm=dialect.addresses["M"].alarm)  # fmt: skip
            for group, members in dialect.m_groups.items():
                if key in members:
                    if group in m_seen:
                        raise self.error(f"{m_seen[group].name} and {spec.name} conflict (both {group} "
                                         "codes)", "group-conflict")  # fmt: skip
                    m_seen[group] = spec
            plan.items.append(spec)

    def _allowed_words(self, plan: BlockPlan) -> frozenset:
        """The addresses the planned block may hold: the base words, the axis words of whoever owns them,
        and the words of each of its codes (the modal motion's when the block has no code of its own)."""
        base = self._base_words
        axis_owner = plan.axis_owner
        modal_item = self.state.modal_item
        if axis_owner is not None:
            allowed = base | self._axis_letters | frozenset(axis_owner.words)
            if axis_owner.action in self._rotary_owner_actions:
                allowed = allowed | self._rotary_letters
        elif plan.g53:
            allowed = base | self._axis_letters | self._rotary_letters
        elif plan.motion is None and modal_item is not None:
            allowed = base | self._axis_letters | frozenset(modal_item.words)
        else:
            motion_key = plan.keys[1] if plan.motion is not None else self.state.motion_key
            allowed = self._allowed_with_motion[motion_key]
        for spec in plan.items:
            if spec.words:
                allowed = allowed | frozenset(spec.words)
        return allowed

    # ------------------------------------------------------------------ execute: run a checked plan
    def execute_plan(self, plan: BlockPlan, block: Block) -> None:
        """Run a plan :meth:`check_block` made: the modal table (raw), then the items (codes, words with
        actions, the modal motion of a block without a code of its own) in the dialect's order."""
        st = self.state
        values = plan.values
        for modal_group, modal_key in plan.keys.items():
            if modal_group > 0:
                st.modal[modal_group] = modal_key
        motion_spec = plan.motion
        if motion_spec is not None:
            st.motion_key = plan.keys[motion_spec.group]
        items = plan.items
        for letter, spec in self._word_specs:
            if letter in values:
                items.append(spec)
        if motion_spec is None and plan.axis_owner is None and not plan.g53:
            modal_item = st.modal_item
            items.append(modal_item if modal_item is not None else IMPLICIT_MOTION)
        order = self._order
        items.sort(key=lambda s: order[s.step])
        st.block_words = block.words
        st.block = block
        st.g53 = plan.g53
        actions = self._actions
        for spec in items:
            actions[spec.action](self, spec, values)
            if st.ended:
                return
        if st.restore_modes:  # G09 lasts one block
            st.restore_modes = False
            self.update_modes()

    def _machine_function(self, key: int) -> CodeSpec:
        """An M code outside the dialect's table: a machine function when the machine preset lists it, or
        when the dialect hands unknown M codes to the machine (``accepts_machine_mcodes``; one it does not
        list either gets a note, and ``machine_functions.strict`` refuses it); else the unknown-code
        error."""
        dialect = self.dialect
        name = code_name("M", key)
        machine = self.state.machine
        own = machine.machine_functions if machine is not None else None
        listed = own.m_codes.get(key // 10) if own is not None and key % 10 == 0 else None
        usual = dialect.machine_mcodes.get(key)
        alarm = dialect.addresses["M"].alarm
        if listed is not None:
            return CodeSpec(name, -1, "machine_function", listed, step="stop")
        if dialect.accepts_machine_mcodes:
            if usual is not None:
                return CodeSpec(name, -1, "machine_function", usual, step="stop")
            if own is None or not own.strict:
                self.notice(f"{name} is not on this machine's M-code list: run as a machine function without "
                            "motion (list it in the machine preset's machine_functions.m_codes, or set "
                            "machine_functions.strict to refuse it)", "machine-function")  # fmt: skip
                return CodeSpec(name, -1, "machine_function", "", step="stop")
            raise self.error(f"unknown M code {name}: not on this machine's M-code list (machine_functions."
                             "strict)", "unknown-code", alarm=alarm)  # fmt: skip
        if usual is not None:
            on = f" (on many machines: {usual})" if usual else ""
            raise self.error(f"{name} is a machine-specific M code{on}: the {dialect.title} dialect does not "
                             "know this machine's M-code list, so it refuses it rather than ignore it (list "
                             "it in the machine preset's machine_functions.m_codes)", "unknown-code",
                             alarm=alarm)  # fmt: skip
        raise self.error(f"unknown M code {name}", "unknown-code", alarm=alarm)

    def _reject_words(self, values: dict[str, float], allowed: frozenset, owner: CodeSpec | None) -> None:
        st = self.state
        for letter in values:
            if letter in allowed:
                continue
            if letter in self._rotary_letters:
                where = f"with {owner.name}" if owner is not None else "in this block"
                raise self.error(f"rotary axis {letter} cannot move {where}: rotary axes move with "
                                 "G00/G01 (and are set by G92, positioned by G53)",
                                 "rotary-axis-context")  # fmt: skip
            if letter in self.dialect.other_axes:
                axes = self.dialect.axes + st.rotary_axes
                hint = (" — rotary axes come from the machine preset's rotary_axes (--machine vmc-4axis "
                        "has A, gsk25i B)" if letter in "ABC" else "")  # fmt: skip
                raise self.error(f"axis {letter} is not on this machine (axes: {axes}){hint}",
                                 "unsupported-axis")  # fmt: skip
            context = f"with {owner.name}" if owner is not None else "in this block"
            raise self.error(f"address {letter} has no meaning {context}", "unused-word")

    def evaluate_words(self, words: Sequence) -> list:
        """Expression words → numbers, with the address's rounding and range rules."""
        dialect = self.dialect
        st = self.state
        evaluate = self._evaluate
        out = []
        overrides = None  # the number formats the block's (literal) G codes give their words
        if self._override_codes:
            for word in words:
                if word[0] == "G" and word[2] is not None and word[1] in self._override_codes:
                    overrides = {**(overrides or {}), **self._override_codes[word[1]]}
        for letter, value, text in words:
            if text is not None:
                out.append((letter, value, text))
                continue
            if value[0] == "deferred":  # a literal only a code's own format accepts (reader.py)
                out.append((letter, self._deferred_word(letter, value, words, overrides), value[2]))
                continue
            rule = overrides[letter] if overrides and letter in overrides else dialect.addresses[letter]
            step = st.increment if rule.unit == "length" else None
            number = evaluate(value, st.variables, dialect, step)
            if number is None:
                continue  # a null variable drops the word
            if rule.unit == "length":
                number = round_to(number, st.increment)
            elif rule.unit == "integer":
                number = float(math.floor(abs(number) + 0.5)) * (1 if number >= 0 else -1)
            elif letter in "GM":
                number = round(number * 10) / 10
            if not rule.low <= number <= rule.high:
                raise self.error(f"{letter}={number:g} is out of range {rule.low:g} to {rule.high:g}",
                                 "value-out-of-range", alarm=rule.alarm)  # fmt: skip
            out.append((letter, number, None))
        return out

    def _deferred_word(self, letter: str, node: tuple, words: Sequence, overrides: dict | None) -> float:
        """A literal the address's own rule rejects (``L2.5``): valid when the block belongs to a code that
        gives the letter its own format: a code of the block, or else the modal canned cycle (a later block
        of a G110 pocket). Otherwise the reader's error (decimal point not allowed) stands."""
        _, value, _, error = node
        if overrides and letter in overrides:
            return value
        gcodes = self.dialect.gcodes
        own = any(w[0] == "G" and w[2] is not None and letter in getattr(gcodes.get(gkey(w[1])), "words", "")
                  for w in words)  # fmt: skip
        spec = self.state.cycle.spec
        modal = spec.address_rules if spec is not None else None
        if not own and modal and letter in modal:
            return value
        raise error

    def word_text(self, letter: str) -> str | None:
        for word in self.state.block_words:
            if word[0] == letter:
                return word[-1]
        return None

    def update_modes(self) -> None:
        st = self.state
        modes = st.path_mode | (SegmentMode.INCH_PROGRAM if st.inch else SegmentMode.NONE)
        system = st.sys_modes  # #3004: (flags added, flags removed)
        if system is not None:
            modes = (modes | system[0]) & ~system[1]
        st.out.modes = modes

    # ------------------------------------------------------------------ the coordinate seam
    # Everything that moves the tool (blocks, cycles, G28, chamfers …) goes through move_linear/move_arc
    # with targets in program coordinates: mm, work coordinates, after G20 conversion and G16 polar
    # conversion, before G51.1/G51/G68 and the offsets. docs/gcode.md "The coordinate seam".

    @property
    def program_position(self) -> Vec:
        """The current position in program coordinates (mm): the inverse of the transforms."""
        st = self.state
        if st.transformed:
            return st.program_point
        m, o = st.out.position, st.offsets.origin
        return (m[0] - o[0], m[1] - o[1], m[2] - o[2])

    def to_machine(self, program) -> Vec:
        """A program point (mm) → machine coordinates through the active chain and the offsets."""
        st = self.state
        chain = st.chain
        w = chain.apply(program) if chain.active else program
        if chain.stages["scaling"] is not None:
            # Scaled results are rounded to the least increment, half up (GSK 25i programming manual §3.2.17,
            # scaling note 7), so a tiny scaled move may become zero (a block without movement).
            step = st.increment * st.scale
            w = tuple(math.floor(c / step + 0.5 + 1e-7) * step for c in w)  # 1e-7: x.5 stored as x.4999…
        o = st.offsets.origin
        return (w[0] + o[0], w[1] + o[1], w[2] + o[2])

    def resolve_target(self, x: float | None, y: float | None, z: float | None) -> Target:
        """A block's axis words (program units, G90/G91, G16 polar) → program target in mm, None where
        the axis is not commanded. Incremental words add to :attr:`program_position`."""
        st = self.state
        s = st.scale
        words = (x, y, z)
        if st.after_g69 and st.incremental and words != (None, None, None):
            raise self.error("the first move after G69 must be absolute (GSK 25i §3.2.18: an incremental one "
                             "does not move correctly)", "incremental-after-g69")  # fmt: skip
        if st.polar is not None:
            return st.polar.resolve(words, st.plane, s, st.incremental, self.program_position)
        if st.incremental:
            p = self.program_position
            return tuple(None if t is None else p[a] + t * s for a, t in enumerate(words))  # type: ignore
        return tuple(None if t is None else t * s for t in words)  # type: ignore[return-value]

    def move_linear(self, rapid: bool, target_program: Target, *, feed: float | None = None) -> None:
        """Rapid (``rapid``) or feed move to ``target_program`` (mm; None = the axis does not move).

        ``feed`` (mm/min) defaults to the modal F; a feed move with no F or F0 is ``missing-feed``.
        Without an active transform an omitted axis keeps its *machine* position; with one, it keeps its
        *program* coordinate (the rotated/scaled axes are coupled).
        """
        st = self.state
        if not rapid:
            if feed is None:
                feed = st.feed
            if not feed:
                raise self.error("G01 needs a feed: no F programmed yet" if feed is None else
                                 "G01 with F0: the feed is zero", "missing-feed")  # fmt: skip
        tx, ty, tz = target_program
        if st.transformed:
            p = st.program_point
            full = (p[0] if tx is None else tx, p[1] if ty is None else ty, p[2] if tz is None else tz)
            if st.capture is not None:  # a chamfer/corner block: geometry only (corners.py)
                st.capture.append(("rapid" if rapid else "line", p, full, None, 0.0, feed))
                return
            st.program_point = full
            target = self.to_machine(full)
            if st.after_g69:
                st.after_g69 = False
                self.set_transform_state()
        else:
            m, o = st.out.position, st.offsets.origin
            target = (m[0] if tx is None else tx + o[0], m[1] if ty is None else ty + o[1],
                      m[2] if tz is None else tz + o[2])  # fmt: skip
        if rapid:
            st.out.straight_traverse(target)
        else:
            st.out.straight_feed(target, feed)  # type: ignore[arg-type]

    def move_arc(self, end_program, center_program, plane: Plane, sweep: float, feed: float) -> None:
        """Arc from :attr:`program_position` to ``end_program`` about ``center_program`` (mm, program
        coordinates; the centre's normal coordinate is ignored), signed ``sweep`` in rad (+ = CCW about the
        plane normal), at ``feed`` mm/min. The chain maps it (:func:`~cnc_gym.gcode.canonical.map_arc`): a
        mirror reverses the direction; unequal scaling gives no ellipse."""
        st = self.state
        if not st.transformed:
            o = st.offsets.origin
            st.out.arc_feed((end_program[0] + o[0], end_program[1] + o[1], end_program[2] + o[2]),
                            (center_program[0] + o[0], center_program[1] + o[1], center_program[2] + o[2]),
                            plane, sweep, feed)  # fmt: skip
            return
        start = st.program_point
        if st.capture is not None:  # a chamfer/corner block: geometry only (corners.py)
            st.capture.append(("arc", start, tuple(end_program), tuple(center_program), sweep, feed))
            return
        try:
            end, center, sweep = map_arc(st.chain, plane, sweep, st.out.position, lambda: (
                self.to_machine(tuple(end_program)),
                self.to_machine(_on_plane(center_program, start, plane))))
        except MapError as exc:
            raise self.error(str(exc), exc.code) from None
        st.program_point = (end_program[0], end_program[1], end_program[2])
        if st.after_g69:
            st.after_g69 = False
            self.set_transform_state()
        st.out.arc_feed(end, center, plane, sweep, feed)

    def set_transform_state(self) -> None:
        """Call after changing ``chain`` or ``polar``: switches between the plain and the transformed
        path. Entering keeps the program position; leaving makes the tool's position the start of the
        next move."""
        st = self.state
        transformed = st.chain.active or st.polar is not None or st.after_g69
        if transformed and not st.transformed:
            st.program_point = self.program_position
        st.transformed = transformed

    def resync_program_position(self) -> None:
        """After a move in machine coordinates (G53) or an origin change while transformed: the program
        position becomes the inverse image of the tool's machine position."""
        st = self.state
        if st.transformed:
            m, o = st.out.position, st.offsets.origin
            w = (m[0] - o[0], m[1] - o[1], m[2] - o[2])
            st.program_point = st.chain.invert(w) if st.chain.active else w


def _with_tables(memory, tables):
    """``memory`` (ToolOffsets) with the entries of ``tables`` (a ``tool_offsets=`` mapping or ToolOffsets)
    written over it."""
    from cnc_gym.gcode.offsets import ToolOffsets

    extra = ToolOffsets.from_mapping(tables, count=memory.count, geometry_limit_mm=memory.geometry_limit_mm,
                                     wear_limit_mm=memory.wear_limit_mm, d_is_diameter=memory.d_is_diameter)
    merged = ToolOffsets.from_mapping(memory)
    for key, table in extra.tables.items():
        for number, value in enumerate(table):
            if value:
                merged.tables[key][number] = value
    return merged


def _on_plane(center, start, plane: Plane) -> Vec:
    """The arc centre with its normal coordinate set to the start's (the centre lies in the start's plane)."""
    w = PLANE_AXES[plane][2]
    out = list(center)
    out[w] = start[w]
    return (out[0], out[1], out[2])


__all__ = ["INCH_MM", "ZERO", "Interpreter"]
