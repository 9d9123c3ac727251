"""Check and execute phases: blocks → canonical motion, driven by the dialect's tables.

The core loop (:meth:`Interpreter.run`, carried out by :class:`~cnc_gym.gcode.calls.FlowRunner`) walks the
program with a program counter: GOTO/IF/WHILE, subprograms and macro calls. Each ordinary block is

1. *evaluated*: expression and variable words become numbers (a null variable drops its word, L5136);
2. *checked* against the dialect and the modal state: unknown or not-yet-implemented codes, two codes of
   one modal group (an error: our issue's rule, stricter than the manual's "later one wins", L509), a
   repeated address, a word that means nothing in this block, two owners of the axis words;
3. *executed* item by item in the dialect's order of execution (``Dialect.execution_order``), each item
   carried out by the core action its :class:`~cnc_gym.gcode.dialect.CodeSpec` names.

Motion leaves through :class:`~cnc_gym.gcode.canonical.CanonicalMachine` in machine coordinates.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from cnc_gym.errors import ProgramError
from cnc_gym.gcode import cycles, nurbs
from cnc_gym.gcode.calls import FlowOptions, FlowRunner
from cnc_gym.gcode.canonical import ZERO, CanonicalMachine, OffsetStack, TransformChain
from cnc_gym.gcode.compensation import ToolCompensation
from cnc_gym.gcode.dialect import CodeSpec, code_name, gkey
from cnc_gym.gcode.expressions import _round_to, evaluate
from cnc_gym.gcode.measurement import ToolMeasurement, do_g37, skip_signal_surfaces
from cnc_gym.gcode.reader import split_words
from cnc_gym.gcode.sysvars import SystemVariables
from cnc_gym.gcode.transforms import (
    TRANSFORM_ACTIONS,
    Parameters,
    PendingCorner,
    arm_corner,
    check_coordinate_command,
    check_plane_change,
    corner_motion,
    finish_corner,
    map_arc,
    mark_coordinate_change,
    parameter_block,
)
from cnc_gym.gcode.variables import VariableStore
from cnc_gym.toolpath import PLANE_AXES, Plane, SegmentMode, Toolpath, ToolpathBuilder

if TYPE_CHECKING:
    from cnc_gym.gcode.dialect import Dialect
    from cnc_gym.gcode.reader import Block, Program
    from cnc_gym.machine import MachineConfig

INCH_MM = 25.4
TWO_PI = 2.0 * math.pi
#: In-plane distance below which an arc's end is its start (full circle for I/J/K, 0° arc for R), mm.
SAME_POINT_MM = 1e-7
_IJK = "IJK"
_ARC_WORDS = frozenset("IJKR")
_G60_MODAL = 60  # ``Interpreter.motion`` while G60 is the modal group-01 code (1870#0 MDL = 1)
_PATH_MODES = {
    "exact_stop": SegmentMode.EXACT_STOP,
    "tapping": SegmentMode.OVERRIDE_LOCKED | SegmentMode.TAPPING_MODE,
    "auto_corner": SegmentMode.AUTO_CORNER,
    "cutting": SegmentMode.NONE,
}
# Pseudo-specs for the items a word (not a code) carries.
_WORD_SPECS = {
    "F": CodeSpec("F", -1, "feed", step="feed"),
    "S": CodeSpec("S", -1, "spindle_speed", step="spindle_speed"),
    "T": CodeSpec("T", -1, "tool", step="tool"),
    # D and H select offset numbers before anything of the block uses them (compensation.py).
    "D": CodeSpec("D", -1, "offset_words", step="tool"),
    "H": CodeSpec("H", -1, "offset_words", step="tool"),
}
_IMPLICIT_MOTION = CodeSpec("(modal motion)", -1, "motion", None, step="motion")
_IMPLICIT_CYCLE = CodeSpec("(modal canned cycle)", -1, "cycle", None, step="motion")
_ACTIONS = {
    "motion": "_do_motion", "plane": "_do_plane", "distance": "_do_distance", "units": "_do_units",
    "wcs": "_do_wcs", "path_mode": "_do_path_mode", "dwell": "_do_dwell", "g52": "_do_g52",
    "g92": "_do_g92", "g53": "_do_g53", "record": "_do_nothing", "feed": "_do_feed",
    "spindle_speed": "_do_spindle_speed", "tool": "_do_tool", "tool_change": "_do_tool_change",
    "spindle": "_do_spindle", "coolant": "_do_coolant", "stop": "_do_stop",
    "cutter_comp": "_do_cutter_comp", "length_comp": "_do_length_comp",
    "position_offset": "_do_position_offset",
    "corner_arc": "_do_corner_arc", "offset_words": "_do_offset_words",
    **dict.fromkeys(TRANSFORM_ACTIONS, "_do_transform"), "g09": "_do_g09",
    "subprogram_call": "_do_subprogram_call", "subprogram_return": "_do_subprogram_return",
    "macro_call": "_do_macro_call", "modal_call_cancel": "_do_modal_call_cancel",
    "cycle": "_do_cycle", "cycle_cancel": "_do_cycle_cancel", "pattern": "_do_pattern",
    "rigid_tap": "_do_rigid_tap", "g05": "_do_g05", "nurbs": "_do_nurbs", "g37": "_do_g37",
}  # fmt: skip


def _parameter_hook(interp: Interpreter, block: Block) -> bool:
    """Inside G10 L50 … G11 every block is a parameter block (transforms.py)."""
    parameter_block(interp, block)
    return True


class Interpreter:
    """Runs one :class:`Program` for one dialect into a :class:`ToolpathBuilder`."""

    def __init__(self, program: Program, dialect: Dialect, *, block_skip: frozenset[int] = frozenset(),
                 start: tuple[float, float, float] = (0.0, 0.0, 0.0), machine: MachineConfig | None = None,
                 tool_offsets=None, tool_measurement=None, skip_signal=None) -> None:  # fmt: skip
        self.machine = machine  # reference positions (G27-G30)
        self.tool_measurement = ToolMeasurement.coerce(tool_measurement)  # G37's simulated instrument
        self.skip_signal = skip_signal_surfaces(skip_signal, dialect.axes)  # G31's simulated probe
        self.program = program
        self.dialect = dialect
        self.file = program.file
        self.skip_mask = sum(1 << n for n in block_skip)
        self.variables = VariableStore(dialect)
        # Rotary axes (A/B/C) the machine has: they move with G00/G01 only (L981-L995), in degrees.
        self.rotary_axes = "" if machine is None else "".join(a for a in machine.rotary_letters
                                                              if a in dialect.other_axes)  # fmt: skip
        self.rotary_origin = [0.0] * len(self.rotary_axes)  # program 0 in machine degrees (G92)
        self.builder = ToolpathBuilder(files=(program.file,), rotary_axes=self.rotary_axes)
        self.out = CanonicalMachine(self.builder, start, rotary=self.builder.rotary_origin, error=self.error)
        self.offsets = OffsetStack()
        # Tool compensation (compensation.py): D/H tables (offsets.py), G40-G42, G43/G44/G49, G45-G48.
        self.comp = ToolCompensation(dialect, tool_offsets)
        self.tool_offsets = self.comp.offsets
        # Program-side transforms (G51.1, G51, G68; canonical.py) and G16 polar input (transforms.py).
        # ``_transformed`` is False while none is active: targets are then ``program + origin`` and the
        # program position is ``machine - origin`` (the hot path). While True, ``_program`` holds the
        # program position explicitly (mm, work coordinates) and every target goes through the chain.
        self.chain = TransformChain()
        self.polar = None
        self._transformed = False
        self._program: tuple[float, float, float] = ZERO
        self.rotation_deg = 0.0  # G68 angle in force (for G91 R)
        self.mirror_axes: dict[int, float] = {}  # G51.1: axis → mirror coordinate (mm)
        self.after_g69 = False  # the first move after G69 must be absolute (L2044)
        self.extra_wcs = 0  # G54.1 P number in force (0 = none; #4130)
        self._restore_modes = False  # G09 one-shot exact stop
        self._corner = None  # a chamfer/corner block waiting for the next move (transforms.py)
        self._capture: list | None = None
        self.parameters = Parameters()  # G10 L50 writes; P1051-P1053, P1860-P1862, P1880
        # Blocks in a special mode go to ``_block_hook(interp, block)`` first (True: handled there):
        # G10 L50 parameter input (transforms.py), G06.2 NURBS mode (nurbs.py). One test per block.
        self._block_hook = None
        self.nurbs = nurbs.NurbsState()  # G05 P10000 contour control, the G06.2 curve being read
        # Codes that give their own words a number format (CodeSpec.address_rules): number → rules.
        self._override_codes = {key / 10: spec.address_rules for key, spec in dialect.gcodes.items()
                                if spec.address_rules}  # fmt: skip
        self.g28_intermediate: list[float | None] = [None, None, None]  # G28/G30 point, work coordinates, mm
        self.skip_position: tuple[float, float, float] | None = None  # G31 end (#5061-#5063), mm
        # Modal state. ``modal`` is the raw table (group → code key, for #4001-style reads later); the
        # attributes below are what the actions read.
        self.modal: dict[int, int] = {}
        self.motion = 0
        self.plane = Plane.XY
        self.incremental = False
        self.inch = False
        self.scale = 1.0  # program length unit → mm
        self.increment = dialect.least_increment_mm
        self.feed: float | None = None  # mm/min
        self.spindle_speed = 0.0
        self.spindle_direction = 0
        self.coolant = False
        self.tool = 0
        self.tool_changes = 0
        self.path_mode = SegmentMode.NONE
        self.ended = False
        self._g53 = False
        self._block_words: tuple = ()
        self.stops: list[tuple[int, str]] = []  # (line, "program_stop" | "optional_stop" | "end")
        # Canned cycles (group 09, cycles.py): modal hole data, the machine's cycle parameters.
        self.cycle = cycles.CycleState()
        self.cycle_params = dialect.cycle_params
        self.spindle_orients = 0
        self._block_cycle: int | None = None
        self._order = {name: i for i, name in enumerate(dialect.execution_order)}
        # Action name → method name (a table of names, not bound methods: no reference cycle keeps a run's
        # 100 000 blocks alive after it returns).
        self._actions = _ACTIONS
        missing = {s.action for s in (*dialect.gcodes.values(), *dialect.mcodes.values())
                   if s.implemented} - set(self._actions)  # fmt: skip
        if missing:
            raise ValueError(f"dialect {dialect.name} names unknown actions {sorted(missing)}")
        axes = dialect.axes
        base = frozenset("FSTODH")
        self._allowed_with_motion = {
            key: base | frozenset(axes) | frozenset(spec.words)
            | (dialect.corner_words if spec.value in (1, 2, 3) else frozenset())
            for key, spec in dialect.gcodes.items() if spec.action == "motion"
        }  # fmt: skip
        for key, spec in dialect.gcodes.items():  # other group-01 modes: G60 with 1870#0 MDL = 1, G06.2
            if spec.group == 1 and key not in self._allowed_with_motion:
                self._allowed_with_motion[key] = base | frozenset(axes) | frozenset(spec.words)
        self._axis_letters = frozenset(axes)
        self._rotary_letters = frozenset(self.rotary_axes)
        for key, spec in dialect.gcodes.items():  # rotary words belong to G00/G01 blocks only
            if spec.action == "motion" and spec.value in (0, 1):
                self._allowed_with_motion[key] = self._allowed_with_motion[key] | self._rotary_letters
        self._motion_specs = {key: spec for key, spec in dialect.gcodes.items()
                              if spec.action == "motion" and spec.implemented}  # fmt: skip
        for key in dialect.power_on:
            spec = dialect.gcodes[key]
            self.modal[spec.group] = key
            if spec.action in ("motion", "plane", "distance", "units", "wcs", "path_mode"):
                getattr(self, self._actions[spec.action])(spec)
        self._motion_key = next(k for k in dialect.power_on if dialect.gcodes[k].action == "motion")
        self._update_modes()

    # ------------------------------------------------------------------ core loop
    def run(self, options: FlowOptions | None = None) -> Toolpath:
        """Run the program (the program-counter loop, Macro B flow and calls: calls.FlowRunner)."""
        self.variables.system = SystemVariables(self)
        try:
            FlowRunner(self, options).run()
        finally:
            # The runner and the system table point back here: drop them so no reference cycle keeps a
            # run's blocks alive after it returns.
            self.macro = None
            self.variables.system = None
        if self._corner is not None:
            finish_corner(self)  # a chamfer/corner R in the last move block (transforms.py)
        if self.nurbs.curve is not None:  # the program ended inside a G06.2 curve
            curve = self.nurbs.curve
            raise self.error(f"the program ends before the NURBS curve of line {curve.line} is complete (it "
                             f"needs {curve.rank} knot-only blocks after its control points, L1244)",
                             "nurbs-incomplete").located(self.builder.files[curve.file_index], curve.line)
        self.comp.finish(self.file)  # what the compensation look-ahead still holds
        return self.builder.build()

    @property
    def parameter_input(self) -> bool:
        """Between G10 L50 and G11 (transforms.py): every block is a parameter block."""
        return self._block_hook is _parameter_hook

    @parameter_input.setter
    def parameter_input(self, on: bool) -> None:
        self._block_hook = _parameter_hook if on else None

    def error(self, message: str, code: str, *, alarm: int | None = None) -> ProgramError:
        return self.dialect.error(message, code, alarm=alarm)

    # ------------------------------------------------------------------ one block
    def execute(self, block: Block) -> None:
        hook = self._block_hook
        if hook is not None and hook(self, block):  # G10 L50 parameter input, G06.2 NURBS mode
            return
        if block.assign is not None:
            target, value = block.assign
            self.variables.write(evaluate(target, self.variables, self.dialect),
                                 evaluate(value, self.variables, self.dialect))  # fmt: skip
            return
        if self._corner is not None:  # a chamfer/corner block waits for the next move (transforms.py)
            arm_corner(self)
        if block.has_expr:
            gs, ms, values = split_words(self._evaluate_words(block.words))
        else:
            gs, ms, values = block.gs, block.ms, block.values
        self.out.line = block.line
        if self.comp.stage is not None:  # compensation counts blocks for its look-ahead
            self.comp.stage.begin_block()
            if self.comp.length_restore is not None:  # the tool length vector after G28/G30 (L3897)
                self.comp.restore_length(self, values)

        cycle = self.cycle
        if ms is None and not cycle.code and not cycle.rigid_pending and "D" not in values \
                and "H" not in values and (
                gs is None or (len(gs) == 1 and round(gs[0] * 10) in self._motion_specs)):  # fmt: skip
            # Hot path: no code, or one group-01 motion code; the other words are axis words, arc words,
            # F, S, T, O. Same checks and order as the general path, without building a plan.
            if gs is not None:
                key = round(gs[0] * 10)
                spec = self._motion_specs[key]
                self.motion = spec.value
                self._motion_key = key
                self.modal[spec.group] = key
            allowed = self._allowed_with_motion[self._motion_key]
            if not values.keys() <= allowed:
                self._reject_words(values, allowed, None)
            if "F" in values:
                self._do_feed(None, values)
            if "S" in values:
                self._do_spindle_speed(None, values)
            if "T" in values:
                self._do_tool(None, values)
            self._do_motion(None, values)
            return
        self._execute_general(gs or (), ms or (), values, block)

    def _execute_general(self, gs, ms, values: dict[str, float], block: Block) -> None:
        dialect = self.dialect
        items: list[CodeSpec] = []
        by_group: dict[int, CodeSpec] = {}
        keys: dict[int, int] = {}
        axis_owner: CodeSpec | None = None
        motion_spec: CodeSpec | None = None
        g53 = False
        for number in gs:
            key = gkey(number)
            spec = dialect.gcodes.get(key)
            if spec is None:
                raise self.error(f"unknown G code {code_name('G', key)}", "unknown-code")
            if not spec.implemented:
                raise self.error(f"{spec.name} is not implemented yet: {spec.note}", "not-implemented")
            other = by_group.get(spec.group)
            if other is not None:
                raise self.error(f"{other.name} and {spec.name} are both in modal group {spec.group:02d}; "
                                 "one block may hold one code per group", "group-conflict")  # fmt: skip
            by_group[spec.group] = spec
            keys[spec.group] = key
            if spec.action == "motion":
                motion_spec = spec
            elif spec.action == "g53":
                g53 = True
            if spec.uses_axes:
                axis_owner = spec
            items.append(spec)
        if ms:
            if len(ms) > dialect.max_m_per_block:
                raise self.error(f"{len(ms)} M codes in one block (at most {dialect.max_m_per_block})",
                                 "too-many-m-codes")  # fmt: skip
            m_seen: dict[str, CodeSpec] = {}
            for number in ms:
                key = gkey(number)
                spec = dialect.mcodes.get(key)
                if spec is None:
                    raise self.error(f"unknown M code {code_name('M', key)}", "unknown-code",
                                     alarm=dialect.addresses["M"].alarm)  # fmt: skip
                if not spec.implemented:
                    raise self.error(f"{spec.name} is not implemented yet: {spec.note}", "not-implemented",
                                     alarm=dialect.addresses["M"].alarm)  # fmt: skip
                for group, members in dialect.m_groups.items():
                    if key in members:
                        if group in m_seen:
                            raise self.error(f"{m_seen[group].name} and {spec.name} conflict (both {group} "
                                             "codes)", "group-conflict")  # fmt: skip
                        m_seen[group] = spec
                items.append(spec)

        # Who owns the axis words: a one-shot code that uses them (G04 X, G10, G52, G92) or the motion.
        has_axes = not self._axis_letters.isdisjoint(values)
        if 9 in by_group or self.cycle.code or self.cycle.rigid_pending or axis_owner is not None:
            axis_owner = cycles.check_block(self, by_group, motion_spec, axis_owner, items, values)
        if axis_owner is not None and motion_spec is not None and has_axes:
            raise self.error(f"{axis_owner.name} and {motion_spec.name} both use the axis words of the block",
                             "axis-word-conflict")  # fmt: skip
        if g53 and motion_spec is not None and motion_spec.value not in (0, 1):
            raise self.error(f"G53 positions at rapid; it cannot be combined with {motion_spec.name}",
                             "bad-combination")  # fmt: skip
        base = frozenset("FSTODH")
        if axis_owner is not None:
            allowed = base | self._axis_letters | frozenset(axis_owner.words)
            if axis_owner.action == "g92":
                allowed = allowed | self._rotary_letters
        elif g53:
            allowed = base | self._axis_letters | self._rotary_letters
        elif motion_spec is None and self.cycle.code:
            allowed = base | self._axis_letters | frozenset(cycles.CYCLE_WORDS[self.cycle.code])
        else:
            allowed = self._allowed_with_motion[keys[1] if motion_spec is not None else self._motion_key]
        for spec in items:
            if spec.words:
                allowed = allowed | frozenset(spec.words)
        if not values.keys() <= allowed:
            self._reject_words(values, allowed, axis_owner)

        # Modal table (raw), then the items in the dialect's order of execution.
        for group, key in keys.items():
            if group > 0:
                self.modal[group] = key
        if motion_spec is not None:
            self._motion_key = keys[motion_spec.group]
        for letter in ("F", "S", "T", "D", "H"):
            if letter in values:
                items.append(_WORD_SPECS[letter])
        if motion_spec is None and axis_owner is None and not g53:
            items.append(_IMPLICIT_CYCLE if self.cycle.code else _IMPLICIT_MOTION)
        order = self._order
        items.sort(key=lambda s: order[s.step])
        self._block_words = block.words
        self._g53 = g53
        actions = self._actions
        this = type(self)
        for spec in items:
            getattr(this, actions[spec.action])(self, spec, values)
            if self.ended:
                return
        if self._restore_modes:  # G09 lasts one block
            self._restore_modes = False
            self._update_modes()

    def _reject_words(self, values: dict[str, float], allowed: frozenset, owner: CodeSpec | None) -> None:
        for letter in values:
            if letter in allowed:
                continue
            if letter in self._rotary_letters:
                where = f"with {owner.name}" if owner is not None else "in this block"
                raise self.error(f"rotary axis {letter} cannot move {where}: rotary axes move with "
                                 "G00/G01 (and are set by G92, positioned by G53)",
                                 "rotary-axis-context")  # fmt: skip
            if letter in self.dialect.other_axes:
                axes = self.dialect.axes + self.rotary_axes
                hint = (" — rotary axes come from the machine preset's rotary_axes (the gsk25i preset has B)"
                        if letter in "ABC" else "")  # fmt: skip
                raise self.error(f"axis {letter} is not on this machine (axes: {axes}){hint}",
                                 "unsupported-axis")  # fmt: skip
            context = f"with {owner.name}" if owner is not None else "in this block"
            raise self.error(f"address {letter} has no meaning {context}", "unused-word")

    def _evaluate_words(self, words: tuple) -> list:
        """Expression words → numbers, with the address's rounding and range rules (L5126, L5136)."""
        dialect = self.dialect
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
            step = self.increment if rule.unit == "length" else None
            number = evaluate(value, self.variables, dialect, step)
            if number is None:
                continue  # a null variable drops the word
            if rule.unit == "length":
                number = _round_to(number, self.increment)
            elif rule.unit == "integer":
                number = float(math.floor(abs(number) + 0.5)) * (1 if number >= 0 else -1)
            elif letter in "GM":
                number = round(number * 10) / 10
            if not rule.low <= number <= rule.high:
                raise self.error(f"{letter}={number:g} is out of range {rule.low:g} to {rule.high:g}",
                                 "value-out-of-range", alarm=rule.alarm)  # fmt: skip
            out.append((letter, number, None))
        return out

    def _deferred_word(self, letter: str, node: tuple, words: tuple, overrides: dict | None) -> float:
        """A literal the address's own rule rejects (``L2.5``): valid when the block belongs to a code that
        gives the letter its own format: a code of the block, or else the modal canned cycle (a later block
        of a G110 pocket). Otherwise the reader's error (decimal point not allowed) stands."""
        _, value, _, error = node
        if overrides and letter in overrides:
            return value
        gcodes = self.dialect.gcodes
        own = any(w[0] == "G" and w[2] is not None and letter in getattr(gcodes.get(gkey(w[1])), "words", "")
                  for w in words)  # fmt: skip
        modal = self._override_codes.get(self.cycle.code) if self.cycle.code else None
        if not own and modal and letter in modal:
            return value
        raise error

    # ------------------------------------------------------------------ modal actions
    def _do_nothing(self, spec: CodeSpec, values: dict | None = None) -> None:
        pass

    # Tool compensation (compensation.py).
    def _do_offset_words(self, spec: CodeSpec, values: dict) -> None:
        if spec.name == "D" or "D" not in values:  # D and H are one item when both are in the block
            self.comp.words(self, values)

    def _do_cutter_comp(self, spec: CodeSpec, values: dict) -> None:
        self.comp.cutter(self, spec, values)

    def _do_length_comp(self, spec: CodeSpec, values: dict) -> None:
        self.comp.length(self, spec, values)

    def _do_position_offset(self, spec: CodeSpec, values: dict) -> None:
        self.comp.position_offset(self, spec, values)

    def _do_corner_arc(self, spec: CodeSpec, values: dict) -> None:
        self.comp.corner_arc(self, spec, values)

    def _do_plane(self, spec: CodeSpec, values: dict | None = None) -> None:
        if self.chain.active:
            check_plane_change(self, spec.value)
        if self.comp.side:
            self.comp.check_plane(self, spec.value)
        if spec.value != self.plane:
            mark_coordinate_change(self)  # no chamfer/corner R in the next block (L1633)
        self.plane = spec.value

    def _do_distance(self, spec: CodeSpec, values: dict | None = None) -> None:
        self.incremental = spec.value

    def _do_units(self, spec: CodeSpec, values: dict | None = None) -> None:
        if values is not None and spec.value != self.inch and (
                len(self.builder) or self.offsets.floating is not None or any(self.offsets.local)):
            # L2110, L2127: G20/G21 go at the start, before the work coordinate system is set, and must not
            # switch in the middle of a program (positions and offsets already given would change meaning).
            raise self.error(f"{spec.name}: inch/metric input cannot switch after the program has moved or "
                             "set a coordinate system (give it alone at the start, L2110, L2127)",
                             "units-switch")  # fmt: skip
        self.inch = spec.value
        self.scale = INCH_MM if spec.value else 1.0
        self.increment = self.dialect.least_increment_inch if spec.value else self.dialect.least_increment_mm
        self._update_modes()

    def _do_wcs(self, spec: CodeSpec, values: dict | None = None) -> None:
        if self.chain.active:
            check_coordinate_command(self, spec.name)
        self.offsets.select_wcs(spec.value - 1)
        self.extra_wcs = 0
        self.resync_program_position()
        if values is not None:  # not at power-on
            mark_coordinate_change(self)

    def _do_transform(self, spec: CodeSpec, values: dict) -> None:
        if spec.action in ("g27", "g28", "g29", "g30", "g60"):
            self.comp.before_machine_move()  # cutter compensation is suspended for the reference moves
            if spec.group == 1:  # G60 modal (1870#0 MDL = 1): axis-only blocks position like G60
                self.motion = _G60_MODAL
                self._motion_key = 600
        TRANSFORM_ACTIONS[spec.action](self, spec, values)  # transforms.py

    def _do_g09(self, spec: CodeSpec, values: dict) -> None:
        """G09: exact stop at the end of this block's move only (one-shot)."""
        self.out.modes = self.out.modes | SegmentMode.EXACT_STOP
        self._restore_modes = True

    def _do_path_mode(self, spec: CodeSpec, values: dict | None = None) -> None:
        self.path_mode = _PATH_MODES[spec.value]
        self._update_modes()

    def _update_modes(self) -> None:
        modes = self.path_mode | (SegmentMode.INCH_PROGRAM if self.inch else SegmentMode.NONE)
        system = getattr(self, "_sys_modes", None)  # #3004 (sysvars.py): (flags added, flags removed)
        if system is not None:
            modes = (modes | system[0]) & ~system[1]
        self.out.modes = modes

    # ------------------------------------------------------------------ macro hooks (calls.py)
    def _do_subprogram_call(self, spec: CodeSpec, values: dict) -> None:
        self.macro.subprogram_call(values)

    def _do_subprogram_return(self, spec: CodeSpec, values: dict) -> None:
        self.macro.subprogram_return(values)

    def _do_macro_call(self, spec: CodeSpec, values: dict) -> None:
        self.macro.macro_call_from_variable(spec)

    def _do_modal_call_cancel(self, spec: CodeSpec, values: dict) -> None:
        self.macro.cancel_modal_call()

    # ------------------------------------------------------------------ word actions
    def _do_feed(self, spec: CodeSpec | None, values: dict) -> None:
        self.feed = values["F"] * self.scale  # inch/min → mm/min in G20

    def _do_spindle_speed(self, spec: CodeSpec | None, values: dict) -> None:
        self.spindle_speed = values["S"]
        self.out.spindle_rpm = self.spindle_speed * self.spindle_direction

    def _do_tool(self, spec: CodeSpec | None, values: dict) -> None:
        self.tool = int(values["T"])
        self.out.tool = self.tool

    def _do_tool_change(self, spec: CodeSpec, values: dict) -> None:
        self.tool_changes += 1

    def _do_spindle(self, spec: CodeSpec, values: dict) -> None:
        self.spindle_direction = spec.value
        self.out.spindle_rpm = self.spindle_speed * self.spindle_direction

    def _do_coolant(self, spec: CodeSpec, values: dict) -> None:
        self.coolant = spec.value

    def _do_stop(self, spec: CodeSpec, values: dict) -> None:
        self.stops.append((self.out.line, spec.value))
        if spec.value == "program_stop":
            # M00: the machine stops with an in-position check; a 0 s dwell carries that to the controller.
            self.out.dwell(0.0, SegmentMode.EXACT_STOP)
        elif spec.value == "end":
            self.ended = True
        # M01 (optional stop): the optional-stop switch is off in simulation, so the program runs on.

    # ------------------------------------------------------------------ one-shot actions
    def _word_text(self, letter: str) -> str | None:
        for word in self._block_words:
            if word[0] == letter:
                return word[-1]
        return None

    def _do_dwell(self, spec: CodeSpec, values: dict) -> None:
        """G04: P in ms (integer), X in s; P wins; neither = exact stop (L1305-L1320)."""
        for letter in "YZ":
            if letter in values:
                raise self.error(f"address {letter} has no meaning with G04", "unused-word")
        if "P" in values:
            text = self._word_text("P")
            if text is not None and "." in text:
                raise self.error(f"G04 P{text}: P is in milliseconds and takes no decimal point (use X for "
                                 "seconds)", "decimal-point-not-allowed")  # fmt: skip
            raw = values["P"]
            seconds = round(raw) / 1000.0
        elif "X" in values:
            raw = values["X"]
            seconds = raw
        else:
            self.out.dwell(0.0, SegmentMode.EXACT_STOP)
            return
        if raw < 0:
            raise self.error(f"G04 dwell time {raw:g} is negative", "bad-dwell")
        self.out.dwell(seconds)

    def _do_g52(self, spec: CodeSpec, values: dict) -> None:
        """G52 IP_: local origin at IP in the current work system; IP0 cancels per axis (L1718-L1753).
        The values are a setting, absolute whatever G90/G91 (docs/gcode.md)."""
        if self.chain.active:
            check_coordinate_command(self, "G52", local=True)
        for axis, letter in enumerate(self.dialect.axes):
            if letter in values:
                self.offsets.local[axis] = values[letter] * self.scale
        self.offsets.update()
        self.resync_program_position()
        mark_coordinate_change(self)

    def _do_g92(self, spec: CodeSpec, values: dict) -> None:
        """G92 IP_: the current position gets coordinates IP in a floating system (L1670-L1716)."""
        if self.chain.active:
            check_coordinate_command(self, "G92")
        position = self.out.position
        for axis, letter in enumerate(self.dialect.axes):
            if letter in values:
                self.offsets.set_floating(axis, position[axis], values[letter] * self.scale)
        for axis, letter in enumerate(self.rotary_axes):  # degrees: G20/G21 do not scale them
            if letter in values:
                self.rotary_origin[axis] = self.out.rotary[axis] - values[letter]
        self.offsets.update()
        self.resync_program_position()
        mark_coordinate_change(self)

    def _do_g37(self, spec: CodeSpec, values: dict) -> None:
        self.comp.before_machine_move()
        do_g37(self, spec, values)  # measurement.py

    # ------------------------------------------------------------------ NURBS (nurbs.py)
    def _do_g05(self, spec: CodeSpec, values: dict) -> None:
        nurbs.do_g05(self, spec, values)

    def _do_nurbs(self, spec: CodeSpec, values: dict) -> None:
        nurbs.start(self, spec, values)

    # ------------------------------------------------------------------ canned cycles (cycles.py)
    def _do_cycle(self, spec: CodeSpec, values: dict) -> None:
        cycles.cycle_block(self, None if spec is _IMPLICIT_CYCLE else spec.value, values)

    def _do_cycle_cancel(self, spec: CodeSpec, values: dict) -> None:
        cycles.cancel(self)

    def _do_pattern(self, spec: CodeSpec, values: dict) -> None:
        cycles.pattern_block(self, spec.value, values, self._block_cycle)

    def _do_rigid_tap(self, spec: CodeSpec, values: dict) -> None:
        cycles.rigid_tap(self)

    # ------------------------------------------------------------------ motion
    def _do_motion(self, spec: CodeSpec | None = None, values: dict | None = None) -> None:
        if spec is not None and spec.value is not None:
            self.motion = spec.value
            if self._g53:
                return  # G53 makes this block's move (a rapid in machine coordinates)
        if values is None:
            return  # power-on
        x = values.get("X")
        y = values.get("Y")
        z = values.get("Z")
        motion = self.motion
        if self._rotary_letters and not self._rotary_letters.isdisjoint(values):
            return self._rotary_motion(motion, x, y, z, values)
        if self._corner is not None or ",L" in values or ",R" in values:
            return corner_motion(self, motion, x, y, z, values)  # chamfer / corner R (transforms.py)
        if motion >= 2:
            if motion == _G60_MODAL:  # G60 in force as a group-01 mode (1870#0 MDL = 1, transforms.py)
                if x is not None or y is not None or z is not None:
                    self._do_transform(self.dialect.gcodes[600], values)
                return
            if x is None and y is None and z is None and not _ARC_WORDS.intersection(values):
                return  # no geometry in the block: the arc mode is only (re)selected
            return self._arc(motion, x, y, z, values)
        if x is None and y is None and z is None:
            return  # a motion code with no axis words only sets the mode (L938)
        if self._transformed:
            self.move_linear(motion == 0, self.resolve_target(x, y, z))
            return
        pos = self.out.position
        s = self.scale
        if self.incremental:
            target = (pos[0] if x is None else pos[0] + x * s, pos[1] if y is None else pos[1] + y * s,
                      pos[2] if z is None else pos[2] + z * s)  # fmt: skip
        else:
            o = self.offsets.origin
            target = (pos[0] if x is None else x * s + o[0], pos[1] if y is None else y * s + o[1],
                      pos[2] if z is None else z * s + o[2])  # fmt: skip
        if motion == 0:
            self.out.straight_traverse(target)
        else:
            feed = self.feed
            if not feed:
                raise self.error("G01 needs a feed: no F programmed yet" if feed is None else
                                 "G01 with F0: the feed is zero", "missing-feed")  # fmt: skip
            self.out.straight_feed(target, feed)

    def _rotary_motion(self, motion: int, x, y, z, values: dict) -> None:
        """A G00/G01 block with rotary axis words (L981-L995): the rotary axes move linearly with the XYZ
        move (or alone). F is the rate along the composite vector, degrees counted as mm (inch in G20):
        the tool path carries the angles, ``Toolpath.path_feed`` the resulting XYZ feed."""
        if isinstance(self._corner, PendingCorner) or ",L" in values or ",R" in values:
            raise self.error("chamfer/corner rounding cannot join a block that moves a rotary axis",
                             "rotary-axis-context")  # fmt: skip
        if self.comp.side:
            raise self.error("a rotary axis cannot move in cutter compensation mode (G41/G42): cancel it "
                             "with G40 first", "rotary-axis-context")  # fmt: skip
        start = self.out.rotary
        target = list(start)
        for axis, letter in enumerate(self.rotary_axes):
            value = values.get(letter)
            if value is not None:
                target[axis] = start[axis] + value if self.incremental else value + self.rotary_origin[axis]
        self.out.rotary_next = tuple(target)
        if x is None and y is None and z is None:
            if motion == 1 and not self.feed:
                raise self.error("G01 needs a feed: no F programmed yet" if self.feed is None else
                                 "G01 with F0: the feed is zero", "missing-feed")  # fmt: skip
            position = self.out.position
            if motion == 0:
                self.out.straight_traverse(position)
            else:
                self.out.straight_feed(position, self.feed)
            return
        self.move_linear(motion == 0, self.resolve_target(x, y, z))

    def _do_g53(self, spec: CodeSpec, values: dict) -> None:
        """G53 IP_: rapid to machine coordinates; one-shot; ignored in G91 (L1656)."""
        if self.chain.stages["rotation"] is not None:
            check_coordinate_command(self, "G53", local=True)  # "G52 to G59" in G68 mode (L2041)
        if self.incremental:
            return
        self.comp.before_machine_move()
        pos = self.out.position
        s = self.scale
        target = tuple(pos[a] if letter not in values else values[letter] * s
                       for a, letter in enumerate(self.dialect.axes))  # fmt: skip
        if not self._rotary_letters.isdisjoint(values):
            current = self.out.rotary
            self.out.rotary_next = tuple(values.get(letter, current[a])
                                         for a, letter in enumerate(self.rotary_axes))  # fmt: skip
        self.out.straight_traverse(target)  # type: ignore[arg-type]
        self.resync_program_position()

    def _arc(self, motion: int, x, y, z, values: dict) -> None:
        """G02/G03 in the selected plane, I/J/K (incremental, L1025) or R (R wins, L510; R<0 > 180°)."""
        name = "G02" if motion == 2 else "G03"
        feed = self.feed
        if not feed:
            if feed is None:
                raise self.error(f"{name} needs a feed: no F programmed yet", "missing-feed")
            raise self.error(f"{name} with F0: zero feed is not allowed on an arc", "zero-feed")
        plane = self.plane
        u, v, w = PLANE_AXES[plane]
        s = self.scale
        transformed = self._transformed
        if transformed:
            # Geometry in program coordinates; move_arc maps it through the chain.
            if self.polar is not None and "R" not in values:
                raise self.error(f"{name} in polar mode (G16) needs R (L1849)", "polar-arc-needs-r")
            pos = self._program
            end = [pos[a] if t is None else t for a, t in enumerate(self.resolve_target(x, y, z))]
        elif self.incremental:
            pos = self.out.position
            end = [pos[0] if x is None else pos[0] + x * s, pos[1] if y is None else pos[1] + y * s,
                   pos[2] if z is None else pos[2] + z * s]  # fmt: skip
        else:
            pos = self.out.position
            o = self.offsets.origin
            end = [pos[0] if x is None else x * s + o[0], pos[1] if y is None else y * s + o[1],
                   pos[2] if z is None else z * s + o[2]]  # fmt: skip
        du = end[u] - pos[u]
        dv = end[v] - pos[v]
        chord = math.hypot(du, dv)
        ccw = motion == 3
        tol = self.dialect.arc_radius_tolerance_mm
        center = [0.0, 0.0, 0.0]
        center[w] = pos[w]
        if "R" in values:
            radius = values["R"] * s
            if chord < SAME_POINT_MM:
                if abs(end[w] - pos[w]) > SAME_POINT_MM:
                    raise self.error(f"{name} with R: end point equals start in the plane, so the arc is 0° "
                                     "and cannot carry a helical move (use I/J/K for a full turn)",
                                     "arc-impossible")  # fmt: skip
                return  # "G02 R;": a 0° arc, the tool does not move (L1036)
            if radius == 0:
                raise self.error(f"{name} with R0", "arc-impossible")
            half = chord / 2.0
            r_abs = abs(radius)
            if half > r_abs:
                if half - r_abs > max(tol, 1e-9):
                    raise self.error(f"{name}: R{abs(radius) / s:g} is too small for the chord of "
                                     f"{chord / s:.4f} (need |R| >= {half / s:.4f})",
                                     "arc-impossible")  # fmt: skip
                h = 0.0
            else:
                h = math.sqrt(r_abs * r_abs - half * half)
            # Centre on the left of the chord for a CCW minor arc; right for CW; flipped for R < 0.
            side = (1.0 if ccw else -1.0) * (1.0 if radius > 0 else -1.0)
            nu, nv = -dv / chord, du / chord
            center[u] = pos[u] + du / 2.0 + side * h * nu
            center[v] = pos[v] + dv / 2.0 + side * h * nv
            r_start = math.hypot(pos[u] - center[u], pos[v] - center[v])
            full = False
        else:
            letter_u, letter_v, letter_w = _IJK[u], _IJK[v], _IJK[w]
            if letter_w in values:
                raise self.error(f"{name}: {letter_w} is not an axis of the {plane.name} plane (use "
                                 f"{letter_u}/{letter_v}, or select the plane with G17/G18/G19)",
                                 "arc-bad-offset")  # fmt: skip
            if letter_u not in values and letter_v not in values:
                raise self.error(f"{name} needs R or a centre {letter_u}/{letter_v} in the {plane.name} "
                                 "plane",
                                 "arc-missing-center")  # fmt: skip
            center[u] = pos[u] + values.get(letter_u, 0.0) * s
            center[v] = pos[v] + values.get(letter_v, 0.0) * s
            r_start = math.hypot(pos[u] - center[u], pos[v] - center[v])
            if r_start < SAME_POINT_MM:
                raise self.error(f"{name}: the centre is the start point (radius 0)", "arc-impossible")
            full = chord < SAME_POINT_MM
            if full:
                end[u], end[v] = pos[u], pos[v]
            else:
                r_end = math.hypot(end[u] - center[u], end[v] - center[v])
                if tol > 0 and abs(r_end - r_start) > tol:
                    raise self.error(f"{name}: radius at the start {r_start / s:.4f} and at the end "
                                     f"{r_end / s:.4f} differ by {abs(r_end - r_start) / s:.4f}, more than "
                                     f"the tolerance {tol:g} mm (P1810)", "arc-radius-mismatch")  # fmt: skip
                if r_end < SAME_POINT_MM:
                    raise self.error(f"{name}: the centre is the end point", "arc-impossible")
                # Within tolerance: keep the centre and the radius, move the end point radially onto the
                # circle (at most the tolerance away from the programmed one). docs/gcode.md.
                k = r_start / r_end
                end[u] = center[u] + (end[u] - center[u]) * k
                end[v] = center[v] + (end[v] - center[v]) * k
        a0 = math.atan2(pos[v] - center[v], pos[u] - center[u])
        if full:
            sweep = TWO_PI if ccw else -TWO_PI
        else:
            a1 = math.atan2(end[v] - center[v], end[u] - center[u])
            sweep = (a1 - a0) % TWO_PI if ccw else -((a0 - a1) % TWO_PI)
            if "R" in values and h == 0.0:
                sweep = math.pi if ccw else -math.pi
        del r_start
        if transformed:
            self.move_arc((end[0], end[1], end[2]), (center[0], center[1], center[2]), plane, sweep, feed)
        else:
            self.out.arc_feed((end[0], end[1], end[2]), (center[0], center[1], center[2]), plane, sweep, feed)

    # ------------------------------------------------------------------ the coordinate seam
    # Everything that moves the tool (blocks, cycles, G28, chamfers …) goes through move_linear/move_arc
    # with targets in program coordinates: mm, work coordinates, after G20 conversion and G16 polar
    # conversion, before G51.1/G51/G68 and the offsets. docs/gcode.md "The coordinate seam".

    @property
    def program_position(self) -> tuple[float, float, float]:
        """The current position in program coordinates (mm): the inverse of the transforms."""
        if self._transformed:
            return self._program
        m, o = self.out.position, self.offsets.origin
        return (m[0] - o[0], m[1] - o[1], m[2] - o[2])

    def to_machine(self, program) -> tuple[float, float, float]:
        """A program point (mm) → machine coordinates through the active chain and the offsets."""
        w = self.chain.apply(program) if self.chain.active else program
        if self.chain.stages["scaling"] is not None:
            # L1966 (G51 note 7): scaled results are rounded to the least increment, half up, so a tiny
            # scaled move may become zero (a block without movement).
            step = self.increment * self.scale
            w = tuple(math.floor(c / step + 0.5 + 1e-7) * step for c in w)  # 1e-7: x.5 stored as x.4999…
        o = self.offsets.origin
        return (w[0] + o[0], w[1] + o[1], w[2] + o[2])

    def resolve_target(self, x: float | None, y: float | None, z: float | None,
                       ) -> tuple[float | None, float | None, float | None]:  # fmt: skip
        """A block's axis words (program units, G90/G91, G16 polar) → program target in mm, None where
        the axis is not commanded. Incremental words add to :attr:`program_position`."""
        s = self.scale
        words = (x, y, z)
        if self.after_g69 and self.incremental and words != (None, None, None):
            raise self.error("the first move after G69 must be absolute (L2044: an incremental one does not "
                             "move correctly)", "incremental-after-g69")  # fmt: skip
        if self.polar is not None:
            return self.polar.resolve(self, words)
        if self.incremental:
            p = self.program_position
            return tuple(None if t is None else p[a] + t * s for a, t in enumerate(words))  # type: ignore
        return tuple(None if t is None else t * s for t in words)  # type: ignore[return-value]

    def move_linear(self, rapid: bool, target_program, *, feed: float | None = None) -> None:
        """Rapid (``rapid``) or feed move to ``target_program`` (mm; None = the axis does not move).

        ``feed`` (mm/min) defaults to the modal F; a feed move with no F or F0 is ``missing-feed``.
        Without an active transform an omitted axis keeps its *machine* position (L1550); with one, it
        keeps its *program* coordinate (the rotated/scaled axes are coupled).
        """
        if not rapid:
            if feed is None:
                feed = self.feed
            if not feed:
                raise self.error("G01 needs a feed: no F programmed yet" if feed is None else
                                 "G01 with F0: the feed is zero", "missing-feed")  # fmt: skip
        tx, ty, tz = target_program
        if self._transformed:
            p = self._program
            full = (p[0] if tx is None else tx, p[1] if ty is None else ty, p[2] if tz is None else tz)
            if self._capture is not None:  # a chamfer/corner block: geometry only (transforms.py)
                self._capture.append(("rapid" if rapid else "line", p, full, None, 0.0, feed))
                return
            self._program = full
            target = self.to_machine(full)
            if self.after_g69:
                self.after_g69 = False
                self.set_transform_state()
        else:
            m, o = self.out.position, self.offsets.origin
            target = (m[0] if tx is None else tx + o[0], m[1] if ty is None else ty + o[1],
                      m[2] if tz is None else tz + o[2])  # fmt: skip
        if rapid:
            self.out.straight_traverse(target)
        else:
            self.out.straight_feed(target, feed)

    def move_arc(self, end_program, center_program, plane: Plane, sweep: float, feed: float) -> None:
        """Arc from :attr:`program_position` to ``end_program`` about ``center_program`` (mm, program
        coordinates; the centre's normal coordinate is ignored), signed ``sweep`` in rad (+ = CCW about the
        plane normal), at ``feed`` mm/min. The chain maps it (transforms.map_arc): a mirror reverses the
        direction; unequal scaling gives no ellipse (L1936)."""
        if not self._transformed:
            o = self.offsets.origin
            self.out.arc_feed((end_program[0] + o[0], end_program[1] + o[1], end_program[2] + o[2]),
                              (center_program[0] + o[0], center_program[1] + o[1], center_program[2] + o[2]),
                              plane, sweep, feed)  # fmt: skip
            return
        start = self._program
        if self._capture is not None:  # a chamfer/corner block: geometry only (transforms.py)
            self._capture.append(("arc", start, tuple(end_program), tuple(center_program), sweep, feed))
            return
        end, center, sweep = map_arc(self, start, tuple(end_program), tuple(center_program), plane, sweep)
        self._program = tuple(end_program)  # type: ignore[assignment]
        if self.after_g69:
            self.after_g69 = False
            self.set_transform_state()
        self.out.arc_feed(end, center, plane, sweep, feed)

    def set_transform_state(self) -> None:
        """Call after changing ``chain`` or ``polar``: switches between the plain and the transformed
        path. Entering keeps the program position; leaving makes the tool's position the start of the
        next move (L1932, L1843)."""
        transformed = self.chain.active or self.polar is not None or self.after_g69
        if transformed and not self._transformed:
            self._program = self.program_position
        self._transformed = transformed

    def resync_program_position(self) -> None:
        """After a move in machine coordinates (G53) or an origin change while transformed: the program
        position becomes the inverse image of the tool's machine position."""
        if self._transformed:
            m, o = self.out.position, self.offsets.origin
            w = (m[0] - o[0], m[1] - o[1], m[2] - o[2])
            self._program = self.chain.invert(w) if self.chain.active else w
