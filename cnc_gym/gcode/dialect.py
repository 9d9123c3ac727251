"""The contract between the interpreter core and a dialect: the :class:`Dialect` record and the
:class:`Seam` through which a dialect's actions and hooks see the core.

A :class:`Dialect` is a frozen record of everything that differs between controllers:

* **tables** — which G and M codes exist (:class:`~cnc_gym.gcode.codes.CodeSpec`: modal group, the
  action that carries it out and its argument, its step in the order of execution, the words it gives a
  meaning to), power-on codes, the order of execution, per-address number formats, expression functions,
  variable ranges, the map from our stable error codes to the controller's alarm numbers, limits;
* **an action registry** (:attr:`Dialect.actions`) — action name → callable ``(core, spec, values)``.
  The Fanuc family's registry (``lang/fanuc``) is the default; a dialect extends it with its own
  (``{**fanuc.ACTIONS, "pocket": pockets.pocket}``) or replaces an entry;
* **a cycle library** (:attr:`Dialect.cycles`) — canned-cycle kind → :class:`CycleKind`, one function per
  kind with its step list; the code tables map G81, G83 … onto kinds;
* **language components** (:class:`Language`) — lexer (the reader), expression evaluator, variable model,
  system variables, control flow and call convention (the runner);
* **block hooks** (:class:`BlockHooks`) — the G-per-block policy and word normalisers, block checks, the
  arc rule, the initial feed;
* **settings** — the machine parameters the features read (``settings.py``).

The core (``interpreter.py``) reads only these. Adding a controller means adding a folder under
``cnc_gym/gcode/dialects/`` and registering it in :data:`DIALECT_MODULES`, never touching the core;
docs/dialects.md walks through it.

**Roles.** Where the core or a feature needs a particular code (the one that cancels canned cycles, the
modal macro call, the NURBS mode …) it asks :attr:`Dialect.roles`, which is derived from the tables by
action, never a literal GSK number.
"""

from __future__ import annotations

import importlib
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any, Protocol

from cnc_gym.errors import ConfigError, ProgramError
from cnc_gym.gcode.codes import AddressRule, CodeSpec, code_name, gkey
from cnc_gym.gcode.settings import CompensationSettings, CycleParameters, MacroCalls, NurbsParameters

if TYPE_CHECKING:
    from cnc_gym.gcode.program import Block, Program
    from cnc_gym.gcode.settings import FlowOptions
    from cnc_gym.gcode.state import State, Variables
    from cnc_gym.toolpath import Plane

__all__ = ["DIALECT_MODULES", "Action", "AddressRule", "BlockHooks", "BlockPlan", "CodeSpec", "CycleKind",
           "Dialect", "Hole", "Language", "MacroCalls", "Roles", "Seam", "code_name", "get_dialect", "gkey"]

Vec = tuple[float, float, float]
Target = tuple[float | None, float | None, float | None]


class Seam(Protocol):
    """What an action or hook may use of the core: the dialect, the state record, and the coordinate
    seam. Program coordinates are mm, work coordinates, after G20 conversion and polar input, before
    the program-side transforms (G51.1, G51, G68) and the offsets; docs/gcode.md "The coordinate seam"."""

    dialect: Dialect
    state: State

    def error(self, message: str, code: str, *, alarm: str | int | None = None) -> ProgramError:
        """A ProgramError with the dialect's alarm number for ``code``, or for the condition ``alarm``
        names (:meth:`Dialect.error`); file and line added later."""
        ...

    def notice(self, message: str, code: str, *, line: int | None = None) -> None:
        """A one-line note about the current block (or ``line`` of the running file) for the user
        (``FILE:LINE: note: message [code]``, on the tool path's ``notices``): something the controller does
        without an alarm that the user should know (words it does not use, text it does not run, a setting
        the program seems to need)."""
        ...

    @property
    def program_position(self) -> Vec:
        """The current position in program coordinates."""
        ...

    def resolve_target(self, x: float | None, y: float | None, z: float | None) -> Target:
        """A block's axis words (program units, G90/G91, polar) → program target, None = not commanded."""
        ...

    def move_linear(self, rapid: bool, target_program: Target, *, feed: float | None = None) -> None:
        """Rapid or feed move to a program target (``feed`` defaults to the modal F)."""
        ...

    def move_arc(self, end_program: Vec, center_program: Vec, plane: Plane, sweep: float,
                 feed: float) -> None:  # fmt: skip
        """Arc from the program position about ``center_program``, signed ``sweep`` (rad, + = CCW)."""
        ...

    def to_machine(self, program: Vec) -> Vec:
        """A program point → machine coordinates through the transforms and offsets."""
        ...

    def resync_program_position(self) -> None:
        """After a move in machine coordinates or an origin change: re-derive the program position."""
        ...

    def set_transform_state(self) -> None:
        """After changing the transform chain or polar mode."""
        ...

    def update_modes(self) -> None:
        """Recompute the segment flags after a path mode, unit or run-control change."""
        ...

    def word_text(self, letter: str) -> str | None:
        """The literal digits of the block's ``letter`` word (None: absent or an expression)."""
        ...

    def evaluate_words(self, words: Sequence) -> list:
        """Expression words of a block → numbers, with each address's rounding and range rules."""
        ...

    def execute(self, block: Block) -> None:
        """Check and execute one ordinary block (the runner's entry into the core)."""
        ...

    def run_action(self, name: str, spec: CodeSpec | None, values: dict[str, float]) -> None:
        """Carry out the dialect's action ``name`` (a feature re-entering another, e.g. the modal motion)."""
        ...

    def check_budget(self) -> None:
        """The run's CPU-time and tool-path bounds (``max_seconds``, ``max_segments``): a feature that makes
        many moves from one block (a cycle over a hole pattern, a NURBS curve) checks them between moves."""
        ...


#: An action: ``action(core, spec, values)`` carries out one item of a block (a code, or a word such as F);
#: ``values`` are the block's words (address → number, in program units). The actions a dialect runs at
#: power-on get ``values`` None; the motion action gets ``spec`` None for an axis-only block.
Action = Callable[..., None]


@dataclass(slots=True)
class BlockPlan:
    """One block after its codes are looked up, as the block checks see it (:attr:`BlockHooks.checks`).

    ``by_group``: modal group → the block's code of that group; ``motion``: the block's motion code (or
    None); ``axis_owner``: the one-shot code that takes the axis words (G04 X, G92 …) or None; ``items``:
    the codes to execute (a check may remove one it takes over); ``values``: the block's words; ``keys``:
    modal group → the key of the block's code of that group; ``g53``: the block holds G53. The
    interpreter's check phase builds it (``Interpreter.check_block``) and its execute phase runs it.
    """

    by_group: dict[int, CodeSpec]
    motion: CodeSpec | None
    axis_owner: CodeSpec | None
    items: list[CodeSpec]
    values: dict[str, float]
    keys: dict[int, int] = field(default_factory=dict)
    g53: bool = False


@dataclass
class Hole:
    """One hole of a canned cycle, in program coordinates (mm) along the drilling axis ``w``.

    ``hole`` is the hole position (its drilling-axis coordinate unused); ``initial``, ``r_level`` and
    ``bottom`` are the levels; ``retract`` the return level (initial for G98, R for G99); ``shift`` the
    G76/G87 shift vector and ``shift_feed`` its feed (None: rapid); ``values`` the block's words;
    ``repeats`` (K) and ``holes`` (of a hole pattern) how many times the block makes this hole's steps in
    all, for the bound on one block's moves (``cycles.limit``).
    """

    spec: CodeSpec
    hole: Vec
    w: int
    initial: float
    r_level: float
    bottom: float
    return_initial: bool
    feed: float
    q: float
    dwell_s: float
    params: CycleParameters
    spindle: int
    rigid: bool
    shift: Vec = (0.0, 0.0, 0.0)
    shift_feed: float | None = None
    values: dict = field(default_factory=dict)
    repeats: int = 1
    holes: int = 1


@dataclass(frozen=True)
class CycleKind:
    """One kind of canned cycle in the dialect's cycle library: the steps of one hole and how the modal
    cycle treats the kind.

    ``steps(core, hole)`` returns the hole's steps (``lang/fanuc/cycles.py`` lists the step tuples).
    ``pecking``: Q is the peck depth (required, alarm 45; stored only by a drilling block). ``tapping``:
    +1 right-hand, -1 left-hand tapping (M29 rigid tapping applies). ``shifting``: a G76/G87-style shift
    at the bottom (Q or the I/J vector). ``special``: a pocket/boss cycle (XY plane only, its own words,
    no hole patterns). ``back_boring``: the bottom may lie above R (G87 back boring).
    """

    name: str
    steps: Callable[[Seam, Hole], list]
    pecking: bool = False
    tapping: int = 0
    shifting: bool = False
    special: bool = False
    back_boring: bool = False


@dataclass(frozen=True)
class BlockHooks:
    """Per-block rules a dialect sets (the Fanuc family's defaults in ``lang/fanuc``).

    ``normalise(core, gs, ms, values) -> (gs, ms, values)``: runs before the block's codes are looked up;
    the G-per-block policy (e.g. only the last G code of a block counts) and word normalisers (e.g. U/V/W
    as incremental X/Y/Z) go here. None: the block is taken as written.
    ``checks``: ``check(core, plan) -> axis owner``, run on every block that takes the general path (codes
    other than one motion code, or a feature that asks for it); the canned-cycle rules are one.
    ``arc(core, motion, x, y, z, values)``: G02/G03 geometry → the move (the Fanuc family's I/J/K and R
    rules by default).
    ``initial_feed``: the feed in force at power-on (mm/min), None: none (a feed move before F is an error).
    ``finish``: ``finish(core)`` at the end of the program, in order (a chamfer still waiting, a NURBS curve
    not complete, what the compensation look-ahead still holds).
    """

    normalise: Callable[[Seam, Any, Any, dict], tuple] | None = None
    checks: tuple[Callable[[Seam, BlockPlan], CodeSpec | None], ...] = ()
    arc: Callable[..., None] | None = None
    initial_feed: float | None = None
    finish: tuple[Callable[[Seam], None], ...] = ()


class ProgramReader(Protocol):
    max_blocks: int  # most blocks a program text may hold (the run's max_blocks)

    def read(self, text: str, file: str = "<program>") -> Program: ...


class Runner(Protocol):
    def run(self) -> None: ...

    def check_bounds(self) -> None:
        """Raise ``time-budget`` / ``segment-budget`` when the run is over its CPU-time or tool-path bound."""
        ...


@dataclass(frozen=True)
class Language:
    """The language family's components (the Fanuc family: ``lang/fanuc``).

    ``reader(dialect, macro_calls)``: the lexer/block reader, text → :class:`~cnc_gym.gcode.program.Program`.
    ``evaluate(node, variables, dialect, round_step)``: the value of an expression node the reader made.
    ``variables(dialect)``: a fresh variable store; ``system_variables(core)``: its system-variable table
    (None: the language has none). ``runner(core, options)``: the program-counter loop with the
    language's control flow and call convention.
    ``hint(text) -> str | None``: on a syntax error, a hint when the line looks like another language's
    syntax (``;`` comments, LinuxCNC O-words …); None: no hint.
    """

    name: str
    reader: Callable[[Dialect, MacroCalls | None], ProgramReader]
    evaluate: Callable[..., float | None]
    variables: Callable[[Dialect], Variables]
    system_variables: Callable[[Seam], Any] | None
    runner: Callable[[Seam, FlowOptions], Runner]
    hint: Callable[[str], str | None] | None = None


@dataclass(frozen=True)
class Roles:
    """The codes that play a special part, found in the dialect's tables by their action (never literal
    numbers in the core or the features). Each is a table key, or None where the dialect has no such code.

    ``cycle_cancel`` (G80) and ``cycle_group``; ``return_initial``/``return_r`` (G98/G99, action
    ``cycle_return``) and their group; ``macro_call`` (G65, one-shot) and ``modal_call`` (G66) with
    ``modal_call_cancel`` (G67) and their group; ``nurbs`` (G06.2); ``modal_positioning`` (G60 as a
    group-01 mode); ``arcs`` (G02/G03: the motion codes with values 2 and 3); ``incremental`` (G91) and
    its group; ``parameter_input_end`` (G11); ``inch`` and ``metric`` (G20/G21, action ``units``);
    ``cutter_cancel`` (G40) and its group; ``contour_control`` (G05, high-precision contour control).
    """

    cycle_cancel: int | None = None
    cycle_group: int | None = None
    return_initial: int | None = None
    return_r: int | None = None
    return_group: int | None = None
    macro_call: int | None = None
    modal_call: int | None = None
    modal_call_cancel: int | None = None
    modal_call_group: int | None = None
    nurbs: int | None = None
    modal_positioning: int | None = None
    arcs: frozenset[int] = frozenset()
    incremental: int | None = None
    distance_group: int | None = None
    parameter_input_end: int | None = None
    inch: int | None = None
    metric: int | None = None
    cutter_cancel: int | None = None
    cutter_group: int | None = None
    contour_control: int | None = None

    @classmethod
    def from_tables(cls, gcodes: Mapping[int, CodeSpec]) -> Roles:
        def find(action: str, value: object = None, *,
                 modal: bool | None = None) -> tuple[int | None, int | None]:  # fmt: skip
            for key, spec in sorted(gcodes.items()):
                if spec.action != action or (value is not None and spec.value != value):
                    continue
                if modal is not None and (spec.group != 0) != modal:
                    continue
                return key, spec.group
            return None, None

        cancel, cycle_group = find("cycle_cancel")
        initial, return_group = find("cycle_return", "initial")
        r_key, _ = find("cycle_return", "r")
        macro, _ = find("macro_call", modal=False)
        modal, modal_group = find("macro_call", modal=True)
        modal_cancel, _ = find("modal_call_cancel")
        nurbs, _ = find("nurbs")
        positioning, group = find("single_direction")
        incremental, distance_group = find("distance", True)
        parameter_end, _ = find("parameter_input_end")
        inch, _ = find("units", True)
        metric, _ = find("units", False)
        cutter_cancel, cutter_group = find("cutter_comp", 0)
        contour, _ = find("contour_control")
        arcs = frozenset(k for k, s in gcodes.items() if s.action == "motion" and s.value in (2, 3))
        return cls(cancel, cycle_group, initial, r_key, return_group, macro, modal, modal_cancel, modal_group,
                   nurbs, positioning if group == 1 else None, arcs, incremental, distance_group,
                   parameter_end, inch, metric, cutter_cancel, cutter_group, contour)  # fmt: skip


def _no_language(*args, **kwargs):
    raise ConfigError("this dialect has no language components")


_NONE = Language("none", _no_language, _no_language, _no_language, None, _no_language)


@dataclass(frozen=True)
class Dialect:
    """Everything controller-specific the interpreter core needs. See the module docstring."""

    name: str
    title: str
    gcodes: Mapping[int, CodeSpec]
    mcodes: Mapping[int, CodeSpec]
    #: Keys of the G codes active at power-on (one per modal group).
    power_on: tuple[int, ...]
    #: Order of execution of the items in one block: step names (docs/gcode.md "Order of execution").
    execution_order: tuple[str, ...]
    addresses: Mapping[str, AddressRule]
    #: Words (not codes) that carry an action, each as a pseudo code: ``{"F": CodeSpec("F", -1, "feed",
    #: step="feed"), …}``. Axis words always go to the motion or the code that owns them.
    words: Mapping[str, CodeSpec] = field(default_factory=dict)
    #: The action registry: action name → callable ``(core, spec, values)`` (module docstring).
    actions: Mapping[str, Action] = field(default_factory=dict)
    #: The canned-cycle library: cycle kind (a cycle code's ``value``) → :class:`CycleKind`.
    cycles: Mapping[str, CycleKind] = field(default_factory=dict)
    language: Language = _NONE
    hooks: BlockHooks = field(default_factory=BlockHooks)
    #: Actions run at power-on for the power-on codes (the rest only enter the modal table).
    power_on_actions: frozenset[str] = frozenset({"motion", "plane", "distance", "units", "wcs", "path_mode"})
    #: Actions besides G00/G01 whose block may carry rotary axis words (G92 sets, G53 positions them).
    rotary_word_actions: frozenset[str] = frozenset({"floating_origin", "machine_move"})
    #: Linear axes of the machine, in order; the toolpath is XYZ.
    axes: str = "XYZ"
    #: Other axis letters the controller knows: A/B/C are rotary axes where the machine preset has them
    #: (``rotary_axes``), the rest are rejected by name (``unsupported-axis``).
    other_axes: str = "ABCUVW"
    #: Expression functions: name → (number of arguments, function on floats).
    functions: Mapping[str, tuple[int, Callable[..., float]]] = field(default_factory=dict)
    #: Stable error code → controller alarm number (the ``alarm=`` of ProgramError). A key may also be a
    #: *condition*, ``"<code>/<what>"``, where the controller numbers one case of a code apart (GSK:
    #: ``"cycle-argument/special-plane"`` 227 beside ``"cycle-argument"`` 61); the family's checks name
    #: conditions, never numbers, so a dialect prints only its own numbers (:meth:`error`).
    alarms: Mapping[str, int] = field(default_factory=dict)
    #: ``#3000 = n`` stops with alarm ``user_alarm_base + n`` (GSK 25i and Fanuc: 3000); None: no number.
    user_alarm_base: int | None = None
    #: A number without a decimal point is in mm/inch/s (True, GSK 1800#0 DPI = 1) or in least increments.
    integer_is_unit: bool = True
    #: The controller parameter that switches to calculator-type input (a number without a decimal point
    #: in mm/inch/s: ``integer_is_unit``), as its manual names it (Fanuc "parameter 3401#0 DPI"); "": the
    #: dialect has no such setting. :func:`calculator_input` makes the variant.
    calculator_input_parameter: str = ""
    #: Least input increment in mm (G21) and inch (G20); literals are truncated to it, variables rounded.
    least_increment_mm: float = 0.0001
    least_increment_inch: float = 0.0001
    #: Largest start/end radius difference of an I/J/K arc, mm (GSK P1810); 0 disables the check.
    arc_radius_tolerance_mm: float = 0.01
    #: The controller's parameter that holds that tolerance, as its manual names it ("P1810", "parameter
    #: 3410"), cited in the arc error; "" where the manual names none.
    arc_tolerance_parameter: str = ""
    #: A dwell P with a decimal point (G04 P1.5, a cycle's P1.5) is in seconds (Haas: "P10. is 10 seconds,
    #: P10 10 milliseconds"); False: refused (``decimal-point-not-allowed``, P is in ms).
    dwell_p_decimal_seconds: bool = False
    #: G codes (table keys) that take their block's comment as an argument (Haas G47: the text to engrave):
    #: the reader keeps the comment on such a block (``Block.comment``).
    comment_codes: frozenset[int] = frozenset()
    #: Abbreviated macro words the reader writes out (Fanuc: ``WH`` → ``WHILE``, ``SQ`` → ``SQRT`` …;
    #: ``lang/fanuc/abbreviations.py``); empty: none.
    macro_abbreviations: Mapping[str, str] = field(default_factory=dict)
    #: The control has an external work offset (G10 L2 P0) added to every work system: a setup may set it
    #: (``EXT``).
    external_work_offset: bool = False
    #: The manual whose sections the Fanuc family's messages cite ("GSK 25i": the family was written from
    #: it); "": the dialect's own manual numbers its sections otherwise, and those messages cite none.
    family_manual: str = ""
    #: G92 shifts every work coordinate system by one vector, which stays across G54-G59 (Fanuc 0i); False:
    #: G92 sets a floating system that replaces them until the next G54-G59 (GSK 25i §3.2.13).
    g92_shifts_work_systems: bool = False
    max_words_per_block: int = 32
    #: Longest literal word, address letter included (GSK alarm 13 "A UNIT CHARACTER STRING EXCEEDS 16");
    #: words holding an expression are not limited.
    max_word_length: int = 16
    max_m_per_block: int = 3
    #: M-code groups (codes of one group may not share a block): group name → M keys.
    m_groups: Mapping[str, frozenset[int]] = field(default_factory=dict)
    #: M codes the machine builder defines (the Fanuc-family range M10-M89 …): key → what the code usually
    #: does on such machines ("" if nothing). Refused by name, unless ``accepts_machine_mcodes``.
    machine_mcodes: Mapping[int, str] = field(default_factory=dict)
    #: An M code that is not in ``mcodes`` is a machine function the control hands to the machine (run
    #: without motion, listed on the tool path), as a Fanuc control does; one outside ``machine_mcodes`` and
    #: the machine preset's list gets a note, and a preset's ``machine_functions.strict`` refuses it. False:
    #: only the preset's list is accepted, every other unknown M code is refused.
    accepts_machine_mcodes: bool = False
    #: Bracket nesting limit in expressions (GSK: 5, functions' brackets included).
    max_bracket_depth: int = 5
    #: Macro statement keywords (IF, THEN, GOTO, WHILE, DO, END) the reader recognises.
    keywords: frozenset[str] = frozenset()
    #: Logical operators allowed between comparisons in IF/WHILE conditions (Fanuc: AND, OR); empty: one
    #: comparison per condition (GSK 25i).
    condition_operators: frozenset[str] = frozenset()
    #: Characters that may stand for the O address of a program number (Fanuc ``:1234``).
    program_number_marks: str = "O"
    #: Variables that exist, as (first, last) ranges; the rest of ``system_variables`` is rejected by name.
    variables: tuple[tuple[int, int], ...] = ((1, 33), (100, 199), (500, 999))
    system_variables: tuple[tuple[int, int], ...] = ()
    #: Chamfer / corner-rounding words of G01-G03 blocks (GSK: ``,L`` and ``,R``; Fanuc: ``,C``, ``,R``).
    corner_words: frozenset[str] = frozenset()
    #: Canned-cycle machine parameters (G73/G83 d, G76/G87 shift direction, rigid tapping limits).
    cycle_params: CycleParameters = field(default_factory=CycleParameters)
    #: Macro and subprogram calls by G, M and T codes (the controller's parameter settings).
    macro_calls: MacroCalls = field(default_factory=MacroCalls)
    #: Nesting limits: subprogram (M98) levels and macro (G65/G66/G-M code) levels below the main program.
    max_subprogram_nesting: int = 4
    max_macro_nesting: int = 4
    #: DO-END nesting per program level.
    max_loop_nesting: int = 3
    #: Tool compensation parameters: tool length type A/B, start-up type A/B, D radius/diameter (offsets.py).
    compensation: CompensationSettings = field(default_factory=CompensationSettings)
    #: NURBS parameters (P1404, P1405, P1407, P1493-P1495).
    nurbs_params: NurbsParameters = field(default_factory=NurbsParameters)
    #: G60 modal in group 01 (GSK 1870#0 MDL = 1) instead of one-shot (0, the standard setting).
    g60_modal: bool = False
    #: The R of a parameter-input block (G10 L50 … G11): a raw integer with its own range (GSK: 8 digits,
    #: a bit parameter's eight binary digits), wider than the R address's. None: the R address rule.
    parameter_input_r: AddressRule | None = None
    #: Controller parameters the features read, by meaning → parameter number (G10 L50 writes them):
    #: ``reference_2``-``reference_4`` (per axis), ``rotation_angle``, ``scale``, ``scale_axis``,
    #: ``positioning_overrun`` (per axis), ``measure_feed``, ``measure_decel``, ``measure_band``.
    parameter_numbers: Mapping[str, int] = field(default_factory=dict)
    #: Parameters whose raw value is range-checked when written: number → largest magnitude.
    parameter_ranges: Mapping[int, int] = field(default_factory=dict)
    #: The dialect's own parameters: a record its folder declares and only its own features read (Syntec's
    #: peck-tapping type, polar-angle sign …); the core and the language families never read it.
    options: Any = None
    #: Whether a dialect that is listed but not built yet (raises on use).
    implemented: bool = True
    #: The codes that play a special part (derived from the tables, see :class:`Roles`).
    roles: Roles = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        # 1870#0 MDL = 1: G60 is a modal code of group 01 (ended by G00-G03), not a one-shot code.
        key = gkey(60)
        spec = self.gcodes.get(key)
        if self.g60_modal and spec is not None and spec.group != 1:
            object.__setattr__(self, "gcodes", {**self.gcodes, key: replace(spec, group=1)})
        object.__setattr__(self, "roles", Roles.from_tables(self.gcodes))

    def cite(self, section: str) -> str:
        """``GSK 25i §3.2.19`` for a family message that cites the family's manual, or "" where this
        dialect's manual is another (its sections would be wrong there)."""
        return f"{self.family_manual} {section}" if self.family_manual else ""

    def alarm(self, code: str, condition: str | int | None = None) -> int | None:
        """The alarm number of an error: the number of ``condition`` when one is named (a key of
        :attr:`alarms`, none when this dialect has no number for it; an int is a dialect's own number,
        passed by its own features), else the number of ``code``."""
        if condition is None:
            return self.alarms.get(code)
        if isinstance(condition, str):
            return self.alarms.get(condition)
        return condition

    def error(self, message: str, code: str, *, alarm: str | int | None = None, column: int | None = None,
              ) -> ProgramError:  # fmt: skip
        """A ProgramError with this dialect's alarm number for ``code`` or for the condition ``alarm``
        (:meth:`alarm`); file and line are filled in later. In a dialect whose manual is not the family's
        (:attr:`family_manual` empty), the family's section citations are left out of the message."""
        if not self.family_manual and "GSK 25i §" in message:
            message = drop_family_citations(message)
        return ProgramError(message, code=code, alarm=self.alarm(code, alarm), column=column)


#: A citation of the Fanuc family's manual (the GSK 25i programming manual) inside a message.
_CITATION = re.compile(r"GSK 25i §\d+(?:\.\d+)*")


def drop_family_citations(message: str) -> str:
    """``message`` without its "GSK 25i §n" citations (and the brackets or separators left empty), for a
    dialect whose own manual numbers its sections otherwise: "(GSK 25i §3.2.5)" goes, "(only jumps out
    of one are allowed, GSK 25i §3.7.5)" keeps its words."""
    out = re.sub(r"\s*\(" + _CITATION.pattern + r"\)", "", message)
    out = re.sub(r"[,;]\s*" + _CITATION.pattern + r"(?=\))", "", out)
    out = re.sub(_CITATION.pattern + r"(?:[:;]\s*|\s+)", "", out)
    return _CITATION.sub("", out)


#: The dialect a program is read in when none is named (``interpret``, ``cnc-gym``, the envs, ``bench``).
DEFAULT_DIALECT = "gsk25i"
#: Dialect names → module under cnc_gym.gcode.dialects, or None where not built yet.
DIALECT_MODULES: dict[str, str | None] = {
    DEFAULT_DIALECT: "cnc_gym.gcode.dialects.gsk25i",
    "fanuc": "cnc_gym.gcode.dialects.fanuc",
    "h4cm": "cnc_gym.gcode.dialects.h4cm",
    "syntec": "cnc_gym.gcode.dialects.syntec",
    "azmc1": "cnc_gym.gcode.dialects.azmc1",
}

_CACHE: dict[str, Dialect] = {}


def get_dialect(name: str | Dialect) -> Dialect:
    """The dialect called ``name`` (``gsk25i``, ``fanuc``, …), or ConfigError."""
    if isinstance(name, Dialect):
        return name
    key = str(name).lower()
    if key in _CACHE:
        return _CACHE[key]
    if key not in DIALECT_MODULES:
        raise ConfigError(f"unknown dialect {name!r}; dialects: {', '.join(DIALECT_MODULES)}")
    module = DIALECT_MODULES[key]
    if module is None:
        raise ConfigError(f"dialect {key!r} is not built (built: "
                          f"{', '.join(k for k, v in DIALECT_MODULES.items() if v)})")  # fmt: skip
    dialect = importlib.import_module(module).DIALECT
    _CACHE[key] = dialect
    return dialect


def calculator_input(dialect: Dialect) -> Dialect:
    """``dialect`` with calculator-type input: a number without a decimal point is in mm, inch or seconds
    (``X10`` is 10 mm), the setting of ``calculator_input_parameter`` (Fanuc 3401#0 DPI = 1); a dialect
    that reads numbers so already is returned as it is, one without the setting is a ConfigError."""
    if dialect.integer_is_unit:
        return dialect
    if not dialect.calculator_input_parameter:
        raise ConfigError(f"dialect {dialect.name} has no calculator-type input setting (its manual reads a "
                          "number without a decimal point in least input units, always)")  # fmt: skip
    key = f"{dialect.name}+calculator"
    if key not in _CACHE:
        _CACHE[key] = replace(dialect, integer_is_unit=True)
    return _CACHE[key]
