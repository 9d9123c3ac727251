"""Controller dialects as data.

A :class:`Dialect` is a frozen table of everything that differs between controllers: which G and M codes
exist, their modal groups and power-on defaults, which ones this interpreter implements, the order in
which the items of one block execute, number formats (decimal-point rules, least input increment,
per-address ranges), expression functions, and the mapping from our stable error codes to the
controller's own alarm numbers. The interpreter core (:mod:`cnc_gym.gcode.interpreter`) reads only these
tables; adding a controller means adding a module under ``cnc_gym/gcode/dialects/`` and registering it
in :data:`DIALECT_MODULES`, never touching the core loop.

G codes are keyed by ``round(number * 10)`` so decimal codes fit: G01 → 10, G54.1 → 541, G06.2 → 62.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace

from cnc_gym.errors import ConfigError, ProgramError
from cnc_gym.gcode.cycles import CycleParameters
from cnc_gym.gcode.nurbs import NurbsParameters
from cnc_gym.gcode.offsets import CompensationSettings


def gkey(number: float) -> int:
    """Table key of a G/M code number: tenths, so G54.1 and G06.2 are exact integers."""
    return round(number * 10)


def code_name(letter: str, key: int) -> str:
    """``G01``, ``G54.1``, ``M30`` from a table key."""
    whole, tenth = divmod(key, 10)
    return f"{letter}{whole:02d}" + (f".{tenth}" if tenth else "")


@dataclass(frozen=True)
class CodeSpec:
    """One G or M code of a dialect.

    ``action`` names the core operation that carries it out (``motion``, ``plane``, ``units``, ``dwell``,
    ``g10``, ``record`` …) and ``value`` is that operation's argument (e.g. the plane, the motion kind).
    ``step`` places it in the dialect's order of execution. ``group`` is the modal group (0 = one-shot).
    ``uses_axes`` marks one-shot codes whose block's axis words belong to them rather than to the modal
    motion (G04 X, G10, G52, G92). ``words`` are the extra addresses the code gives a meaning to.
    ``implemented`` False: the code exists on the controller but this interpreter rejects it by name.
    ``address_rules``: number formats this code gives its own words, in place of the dialect's address
    rules (the L of a pocket cycle is a step-over length, ``L2.5``, where M98's L is a count). The reader
    applies them to blocks that name the code; G06.2's modal blocks re-read theirs (nurbs.py).
    """

    name: str
    group: int
    action: str
    value: object = None
    step: str = "record"
    uses_axes: bool = False
    words: str = ""
    implemented: bool = True
    note: str = ""
    address_rules: Mapping[str, AddressRule] | None = None


@dataclass(frozen=True)
class AddressRule:
    """Number format of one address: range, whether a decimal point is allowed, unit class.

    ``unit``: ``length`` (mm or inch by G20/G21; truncated to the least input increment), ``feed``
    (mm/min or inch/min), ``integer`` (a whole number: N, O, T, M, S, L, H, D), ``plain`` (a bare real).
    """

    low: float
    high: float
    unit: str = "plain"
    point_allowed: bool = True
    alarm: int | None = None  # alarm raised when the value is out of range


@dataclass(frozen=True)
class MacroCalls:
    """Which codes call macros and subprograms (GSK parameters 6001#0, 6050-6059, 6071-6089).

    ``g_macro``: G code → program, called like G65 with arguments (6050-6059 → O9010-O9019).
    ``m_macro``: M code → program, called like G65 with arguments (6080-6089 → O9020-O9029).
    ``m_sub``: M code → program, called like M98 after the block's other commands (6071-6079 → O9001-O9009).
    ``t_sub``: with a program number (6001#0 TCS = 1: O9000), ``Tt`` is ``#149=t`` then ``M98 P9000``.
    Inside a program called by one of these codes, the codes are ordinary (L6265, L6331).
    """

    g_macro: Mapping[int, int] = field(default_factory=dict)
    m_macro: Mapping[int, int] = field(default_factory=dict)
    m_sub: Mapping[int, int] = field(default_factory=dict)
    t_sub: int | None = None


@dataclass(frozen=True)
class Dialect:
    """Everything controller-specific the interpreter core needs. See the module docstring."""

    name: str
    title: str
    gcodes: Mapping[int, CodeSpec]
    mcodes: Mapping[int, CodeSpec]
    #: Keys of the G codes active at power-on (one per modal group).
    power_on: tuple[int, ...]
    #: Order of execution of the items in one block: step names (see interpreter.STEP_DOC).
    execution_order: tuple[str, ...]
    addresses: Mapping[str, AddressRule]
    #: Step that runs each non-G/M word ("F" → "feed"); axis words always go to the motion/setting step.
    word_steps: Mapping[str, str]
    #: Linear axes of the machine, in order; the toolpath is XYZ.
    axes: str = "XYZ"
    #: Other axis letters the controller knows: A/B/C are rotary axes where the machine preset has them
    #: (``rotary_axes``), the rest are rejected by name (``unsupported-axis``).
    other_axes: str = "ABCUVW"
    #: Expression functions: name → (number of arguments, function on floats).
    functions: Mapping[str, tuple[int, Callable[..., float]]] = field(default_factory=dict)
    #: Stable error code → controller alarm number (the ``alarm=`` of ProgramError).
    alarms: Mapping[str, int] = field(default_factory=dict)
    #: A number without a decimal point is in mm/inch/s (True, GSK 1800#0 DPI = 1) or in least increments.
    integer_is_unit: bool = True
    #: Least input increment in mm (G21) and inch (G20); literals are truncated to it, variables rounded.
    least_increment_mm: float = 0.0001
    least_increment_inch: float = 0.0001
    #: Largest start/end radius difference of an I/J/K arc, mm (GSK P1810); 0 disables the check.
    arc_radius_tolerance_mm: float = 0.01
    max_words_per_block: int = 32
    #: Longest literal word, address letter included (GSK alarm 13 "A UNIT CHARACTER STRING EXCEEDS 16");
    #: words holding an expression are not limited.
    max_word_length: int = 16
    max_m_per_block: int = 3
    #: M-code groups (codes of one group may not share a block): group name → M keys.
    m_groups: Mapping[str, frozenset[int]] = field(default_factory=dict)
    #: Bracket nesting limit in expressions (GSK: 5, functions' brackets included).
    max_bracket_depth: int = 5
    #: Macro statement keywords (IF, THEN, GOTO, WHILE, DO, END) the reader recognises (reader.py, calls.py).
    keywords: frozenset[str] = frozenset()
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
    #: DO-END nesting per program level (L5792).
    max_loop_nesting: int = 3
    #: Tool compensation parameters: tool length type A/B, start-up type A/B, D radius/diameter (offsets.py).
    compensation: CompensationSettings = field(default_factory=CompensationSettings)
    #: NURBS parameters (P1404, P1405, P1407, P1493-P1495; nurbs.py).
    nurbs_params: NurbsParameters = field(default_factory=NurbsParameters)
    #: G60 modal in group 01 (GSK 1870#0 MDL = 1) instead of one-shot (0, the standard setting).
    g60_modal: bool = False
    #: The R of a parameter-input block (G10 L50 … G11): a raw integer with its own range (GSK: 8 digits,
    #: a bit parameter's eight binary digits, L1503), wider than the R address's. None: the R address rule.
    parameter_input_r: AddressRule | None = None
    #: Whether a dialect that is listed but not built yet (raises on use).
    implemented: bool = True

    def __post_init__(self) -> None:
        # 1870#0 MDL = 1: G60 is a modal code of group 01 (ended by G00-G03), not a one-shot code.
        key = gkey(60)
        spec = self.gcodes.get(key)
        if self.g60_modal and spec is not None and spec.group != 1:
            object.__setattr__(self, "gcodes", {**self.gcodes, key: replace(spec, group=1)})

    def alarm(self, code: str) -> int | None:
        return self.alarms.get(code)

    def error(self, message: str, code: str, *, alarm: int | None = None, column: int | None = None,
              ) -> ProgramError:  # fmt: skip
        """A ProgramError with this dialect's alarm number for ``code`` (file/line filled in later)."""
        return ProgramError(message, code=code, alarm=alarm if alarm is not None else self.alarms.get(code),
                            column=column)  # fmt: skip


#: Dialect names (DESIGN.md) → module under cnc_gym.gcode.dialects, or None where not built yet.
DIALECT_MODULES: dict[str, str | None] = {
    "gsk25i": "cnc_gym.gcode.dialects.gsk25i",
    "h4cm": None,
    "syntec": None,
    "azmc1": None,
}

_CACHE: dict[str, Dialect] = {}


def get_dialect(name: str | Dialect) -> Dialect:
    """The dialect called ``name`` (``gsk25i``, ``h4cm``, ``syntec``, ``azmc1``), or ConfigError."""
    if isinstance(name, Dialect):
        return name
    key = str(name).lower()
    if key in _CACHE:
        return _CACHE[key]
    if key not in DIALECT_MODULES:
        raise ConfigError(f"unknown dialect {name!r}; dialects: {', '.join(DIALECT_MODULES)}")
    module = DIALECT_MODULES[key]
    if module is None:
        raise ConfigError(f"dialect {key!r} is not implemented yet (implemented: "
                          f"{', '.join(k for k, v in DIALECT_MODULES.items() if v)})")  # fmt: skip
    dialect = importlib.import_module(module).DIALECT
    _CACHE[key] = dialect
    return dialect
