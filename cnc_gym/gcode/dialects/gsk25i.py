"""GSK 25i (milling) as data: the reference dialect.

Sources are the programming spec ``shared/notes/seed000_programming.md`` (§1 lexical, §2 G-code table,
§3 motion, §6 macros, §9 errors, Appendix B alarms) and the manual itself (``Lnnnn`` = line of
``shared/seeds/000_*.txt``). Codes the controller has but this interpreter does not carry out yet are
listed with ``implemented=False`` so they are rejected by name (``not-implemented``), never ignored; codes
missing from these tables are ``unknown-code`` (GSK alarm 10 "IMPROPER G-CODE").
"""

from __future__ import annotations

import math

from cnc_gym.gcode.cycles import CYCLE_WORDS, PATTERN_WORDS, CycleParameters
from cnc_gym.gcode.dialect import AddressRule, CodeSpec, Dialect, gkey
from cnc_gym.toolpath import Plane

# --------------------------------------------------------------------------- G codes
_LATER = "a later issue"
#: Addresses of a G65/G66 block besides G, N, O: P, L and the arguments (calls.py handles the block; these let
#: a G65 that came from a variable reach its action, which names the problem).
_ARGUMENTS = "ABCDEFHIJKLMPQRSTUVWXYZ"
_AXES = "XYZ"
_BIG = 999999.9999
#: Number formats codes give their own words (CodeSpec.address_rules). The L of the pocket, boss and
#: face-milling cycles is a step-over length (``L2.5``), not the whole-number L of M98/G65/G10.
_STEP_LENGTH = {"L": AddressRule(0.0, _BIG, "length")}
#: G06.2: K is a knot and R a weight, plain numbers (``K0.008286`` keeps its digits; G20 does not convert).
_NURBS_RULES = {"K": AddressRule(-_BIG, _BIG, "plain"), "R": AddressRule(-_BIG, _BIG, "plain")}


def _g(
    number: float,
    group: int,
    action: str,
    value: object = None,
    *,
    step: str = "record",
    uses_axes: bool = False,
    words: str = "",
    implemented: bool = True,
    note: str = "",
    address_rules: dict | None = None,
) -> CodeSpec:
    whole, tenth = divmod(gkey(number), 10)
    name = f"G{whole:02d}" + (f".{tenth}" if tenth else "")
    return CodeSpec(name, group, action, value, step, uses_axes, words, implemented, note, address_rules)


def _todo(number: float, group: int, what: str, *, uses_axes: bool = False) -> CodeSpec:
    return _g(number, group, "not_implemented", step="motion", uses_axes=uses_axes, implemented=False,
              note=f"{what} ({_LATER})")  # fmt: skip


_G_LIST = [
    # Group 01: motion (L915-L1101). Modal; the axis words of the block belong to it.
    _g(0, 1, "motion", 0, step="motion"),
    _g(1, 1, "motion", 1, step="motion"),
    _g(2, 1, "motion", 2, step="motion", words="IJKR"),
    _g(3, 1, "motion", 3, step="motion", words="IJKR"),
    # G06.2 NURBS (L1201-L1303; nurbs.py): modal in group 01; the block's axis words are control points.
    _g(6.2, 1, "nurbs", step="motion", uses_axes=True, words="PKR", address_rules=_NURBS_RULES),
    _todo(33, 1, "thread cutting G33"),
    # Group 00: one-shot.
    _g(4, 0, "dwell", step="dwell", uses_axes=True, words="P"),
    # G09 (one-shot exact stop) is missing from GSK's table (notes §3.5); Fanuc-standard, kept.
    _g(9, 0, "g09", step="modes"),  # after G61-G64 of the same block
    _g(5, 0, "g05", step="modes", words="P"),  # G05 P10000 / P0: high-precision contour control (nurbs.py)
    _todo(7.1, 0, "cylindrical interpolation G07.1"),
    _todo(107, 0, "cylindrical interpolation G107"),
    _g(10, 0, "g10", step="setting", uses_axes=True, words="LPR"),
    _g(11, 0, "record", step="setting", note="G10 L50 parameter-input mode off (the power-on state)"),
    _g(27, 0, "g27", step="motion", uses_axes=True),
    _g(28, 0, "g28", step="motion", uses_axes=True),
    _g(29, 0, "g29", step="motion", uses_axes=True),
    _g(30, 0, "g30", step="motion", uses_axes=True, words="P"),
    _g(31, 0, "g31", step="motion", uses_axes=True),
    _g(37, 0, "g37", step="motion", uses_axes=True),  # automatic tool length measurement (measurement.py)
    # G39 corner arc in cutter compensation (L4646-L4666; compensation.py).
    _g(39, 0, "corner_arc", step="cutter_comp", words="IJK"),
    _g(45, 0, "position_offset", 1, step="cutter_comp"),
    _g(46, 0, "position_offset", -1, step="cutter_comp"),
    _g(47, 0, "position_offset", 2, step="cutter_comp"),
    _g(48, 0, "position_offset", -2, step="cutter_comp"),
    _g(52, 0, "g52", step="setting", uses_axes=True),
    _g(53, 0, "g53", step="motion"),
    _todo(53.1, 0, "tool axis direction control G53.1"),
    _g(60, 0, "g60", step="motion", uses_axes=True),
    _g(65, 0, "macro_call", step="stop", words=_ARGUMENTS, note="one-shot macro call (calls.py)"),
    _g(92, 0, "g92", step="setting", uses_axes=True),
    # Hole patterns G120-G125 and face milling G126/G127 (L4863-L5077; cycles.py).
    *[_g(n, 0, "pattern", n, step="motion", uses_axes=True, words=PATTERN_WORDS[n],
         address_rules=_STEP_LENGTH if "L" in PATTERN_WORDS[n] else None) for n in range(120, 128)],
    # Group 02: plane (L1755-L1773).
    _g(17, 2, "plane", Plane.XY, step="plane"),
    _g(18, 2, "plane", Plane.ZX, step="plane"),
    _g(19, 2, "plane", Plane.YZ, step="plane"),
    # Group 03: distance mode (L614-L641).
    _g(90, 3, "distance", False, step="distance"),
    _g(91, 3, "distance", True, step="distance"),
    # Group 04: stored stroke check 2 (OP-VOL L7164-L7250). G23 (off) is the standard power-on state.
    _todo(22, 4, "stored stroke check G22"),
    _g(23, 4, "record", step="modes"),
    # Group 05: feed mode (L6799-L6847).
    _g(94, 5, "record", step="feed_mode"),
    _todo(95, 5, "feed per revolution G95"),
    # Group 06: units (L2100-L2129).
    _g(20, 6, "units", True, step="units"),
    _g(21, 6, "units", False, step="units"),
    # Group 07: cutter radius compensation C (L3921-L4646; compensation.py).
    _g(40, 7, "cutter_comp", 0, step="cutter_comp", words="IJK"),  # I/J/K: the cancel direction (L4420)
    _g(41, 7, "cutter_comp", 1, step="cutter_comp"),
    _g(42, 7, "cutter_comp", -1, step="cutter_comp"),
    # Group 08: tool length offset (L3845-L3919).
    _g(43, 8, "length_comp", 1, step="length_comp"),
    _g(44, 8, "length_comp", -1, step="length_comp"),
    _todo(43.4, 8, "tool centre point control G43.4"),
    _g(49, 8, "length_comp", 0, step="length_comp"),
    # Group 09: canned cycles (L2338-L3830). G80 = no cycle.
    # The axis words of a cycle block are the hole position and bottom (cycles.py).
    *[_g(n, 9, "cycle", n, step="motion", uses_axes=True, words=CYCLE_WORDS[n],
         address_rules=_STEP_LENGTH if "L" in CYCLE_WORDS[n] else None) for n in sorted(CYCLE_WORDS)],
    _g(80, 9, "cycle_cancel", step="motion"),
    # Group 10: canned-cycle return level; recorded for the cycles to come.
    _g(98, 10, "record", step="modes"),
    _g(99, 10, "record", step="modes"),
    # Group 11: scaling (L1866-L2016).
    _g(50, 11, "g50", step="modes"),
    _g(51, 11, "g51", step="setting", uses_axes=True, words="PIJK"),
    # Group 12: modal macro call.
    _g(66, 12, "macro_call", step="stop", words=_ARGUMENTS, note="modal macro call (calls.py)"),
    _g(67, 12, "modal_call_cancel", step="modes"),
    # Group 13: constant surface speed.
    _todo(96, 13, "constant surface speed G96"),
    _g(97, 13, "record", step="modes"),
    # Group 14: work coordinate systems (L1519-L1595).
    *[_g(n, 14, "wcs", n - 53, step="wcs") for n in range(54, 60)],
    _g(54.1, 14, "g54_1", step="wcs", words="P"),
    # Group 15: path mode (L6417-L6470): flags on the segments for the controller.
    _g(61, 15, "path_mode", "exact_stop", step="path_mode"),
    _g(62, 15, "path_mode", "auto_corner", step="path_mode"),
    _g(63, 15, "path_mode", "tapping", step="path_mode"),
    _g(64, 15, "path_mode", "cutting", step="path_mode"),
    # Group 16: rotation (L2018-L2098).
    _g(68, 16, "g68", step="setting", uses_axes=True, words="R"),
    _todo(68.2, 16, "tilted working plane G68.2"),
    _g(69, 16, "g69", step="modes"),
    # Group 17: polar coordinates (L1775-L1865).
    _g(15, 17, "g15", step="modes"),
    _g(16, 17, "g16", step="modes"),
    # Group 22: programmable mirror (listed in #4022 only).
    _g(50.1, 22, "g50_1", step="setting", uses_axes=True),
    _g(51.1, 22, "g51_1", step="setting", uses_axes=True),
]
GCODES = {gkey(float(s.name[1:])): s for s in _G_LIST}

# Power-on modal state (Appendix A; 1801 standard setting 1000 0000): G00 G17 G90 G23 G94 G21 G40 G49 G80
# G98 G50 G67 G97 G54 G64 G69 G15.
POWER_ON = tuple(gkey(n) for n in (0, 17, 90, 23, 94, 21, 40, 49, 80, 98, 50, 67, 97, 54, 64, 69, 15, 50.1))

# --------------------------------------------------------------------------- M codes (§8.1)
def _m(number: int, action: str, value: object = None, *, step: str, implemented: bool = True,
       words: str = "", note: str = "") -> CodeSpec:  # fmt: skip
    return CodeSpec(f"M{number:02d}", 0, action, value, step, False, words, implemented, note)


_M_LIST = [
    _m(0, "stop", "program_stop", step="stop"),
    _m(1, "stop", "optional_stop", step="stop"),
    _m(2, "stop", "end", step="stop"),
    _m(30, "stop", "end", step="stop"),
    _m(3, "spindle", 1, step="spindle"),
    _m(4, "spindle", -1, step="spindle"),
    _m(5, "spindle", 0, step="spindle"),
    _m(6, "tool_change", step="tool_change"),
    _m(8, "coolant", True, step="coolant"),
    _m(9, "coolant", False, step="coolant"),
    _m(19, "not_implemented", step="spindle", implemented=False, note="spindle orientation M19"),
    _m(29, "rigid_tap", step="spindle"),
    _m(96, "not_implemented", step="stop", implemented=False, note="macro interrupt M96"),
    _m(97, "not_implemented", step="stop", implemented=False, note="macro interrupt M97"),
    _m(98, "subprogram_call", step="stop", words="PL"),
    _m(99, "subprogram_return", step="stop", words="P"),
]
MCODES = {gkey(int(s.name[1:])): s for s in _M_LIST}
M_GROUPS = {
    "stop": frozenset(gkey(n) for n in (0, 1, 2, 30, 98, 99)),
    "spindle": frozenset(gkey(n) for n in (3, 4, 5, 19, 29)),
    "coolant": frozenset(gkey(n) for n in (8, 9)),
}

# --------------------------------------------------------------------------- order of execution
# NIST RS274NGC Table 8, adapted (docs/gcode.md): G20/G21 first so every value of the block is read in
# the block's unit system (GSK wants G20/G21 alone at the program start anyway, L2110).
EXECUTION_ORDER = (
    "units", "feed_mode", "feed", "spindle_speed", "tool", "tool_change", "spindle", "coolant", "dwell",
    "plane", "cutter_comp", "length_comp", "wcs", "path_mode", "distance", "modes", "setting", "motion",
    "stop",
)  # fmt: skip

# --------------------------------------------------------------------------- addresses (Table 1-1, §1.7)
ADDRESSES = {
    **{a: AddressRule(-_BIG, _BIG, "length") for a in "XYZIJKRQ"},
    "F": AddressRule(0.0, 1000000.0, "feed"),
    "P": AddressRule(-99999999.0, 99999999.0, "plain"),  # sign checked by the code using P (G04: alarm 18)
    "L": AddressRule(0.0, 9999.0, "integer", point_allowed=False),
    "N": AddressRule(0.0, 999999.0, "integer", point_allowed=False, alarm=16),
    "O": AddressRule(0.0, 9999.0, "integer", point_allowed=False, alarm=74),
    "S": AddressRule(0.0, 50000.0, "plain", alarm=200),
    "T": AddressRule(0.0, 999.0, "integer", point_allowed=False, alarm=202),
    "M": AddressRule(0.0, 999.0, "integer", point_allowed=False, alarm=201),
    "G": AddressRule(0.0, 999.9, "plain", alarm=10),
    "H": AddressRule(0.0, 256.0, "integer", point_allowed=False, alarm=30),
    "D": AddressRule(0.0, 256.0, "integer", point_allowed=False, alarm=30),
    **{a: AddressRule(-_BIG, _BIG, "plain") for a in "ABCEUVW"},
    # Chamfer and corner rounding (L1597-L1646): ,L is the chamfer distance, ,R the corner radius.
    ",L": AddressRule(0.0, _BIG, "length"),
    ",R": AddressRule(0.0, _BIG, "length"),
}
WORD_STEPS = {"F": "feed", "S": "spindle_speed", "T": "tool"}


# --------------------------------------------------------------------------- expression functions (§6.4)
def _deg_trig(fn):
    return lambda x: fn(math.radians(x))


def _tan(x: float) -> float:
    # GSK computes TAN as SIN/COS (L5532); a zero cosine is a division by zero.
    c = math.cos(math.radians(x))
    if abs(c) < 1e-15:
        raise ZeroDivisionError
    return math.sin(math.radians(x)) / c


def _atan2_deg(y: float, x: float) -> float:
    # Two-argument ATAN[y]/[x]: Fanuc Macro B convention, result in 0..360 degrees.
    return math.degrees(math.atan2(y, x)) % 360.0


def _round_half_away(x: float) -> float:
    return float(math.floor(abs(x) + 0.5)) * (1.0 if x >= 0 else -1.0)


def _fup(x: float) -> float:
    # FUP: raise to the next integer away from zero (FUP[1.2] = 2, FUP[-1.2] = -2).
    return float(math.ceil(abs(x))) * (1.0 if x >= 0 else -1.0)


def _bcd(x: float) -> float:
    n = int(x)
    if n < 0:
        raise ValueError
    return float(int(str(n), 16))


def _bin_from_bcd(x: float) -> float:
    n = int(x)
    if n < 0:
        raise ValueError
    digits = f"{n:x}"
    if any(c not in "0123456789" for c in digits):
        raise ValueError
    return float(int(digits))


FUNCTIONS = {
    "SIN": (1, _deg_trig(math.sin)),
    "COS": (1, _deg_trig(math.cos)),
    "TAN": (1, _tan),
    "ATAN": (1, lambda x: math.degrees(math.atan(x))),
    "ATAN2": (2, _atan2_deg),  # the parser maps ATAN[a]/[b] here
    # ASIN/ACOS/LN/EXP/POW are Fanuc Macro B functions the GSK list (L5527-L5545) does not print;
    # accepted as an extension (docs/gcode.md).
    "ASIN": (1, lambda x: math.degrees(math.asin(x))),
    "ACOS": (1, lambda x: math.degrees(math.acos(x))),
    "SQRT": (1, math.sqrt),
    "ABS": (1, abs),
    "BIN": (1, _bin_from_bcd),
    "BCD": (1, _bcd),
    "ROUND": (1, _round_half_away),
    "FIX": (1, lambda x: float(math.trunc(x))),
    "FUP": (1, _fup),
    "LN": (1, math.log),
    "EXP": (1, math.exp),
    "POW": (2, math.pow),
}

# --------------------------------------------------------------------------- alarms (Appendix B)
ALARMS = {
    "too-many-digits": 3,
    "missing-value": 5,
    "missing-address": 4,
    "bad-sign": 6,
    "decimal-point-not-allowed": 7,
    "bad-number": 8,
    "value-out-of-range": 8,
    "bad-character": 9,
    "unknown-code": 10,
    "not-implemented": 10,
    "missing-feed": 11,
    "too-many-words": 12,
    "word-too-long": 13,
    "unsupported-axis": 15,
    "bad-dwell": 18,
    "arc-radius-mismatch": 20,
    "arc-bad-offset": 21,
    "arc-impossible": 22,
    "arc-missing-center": 22,
    "zero-feed": 25,
    "bad-g10": 31,
    # Coordinates and transforms (notes §9.2 M14-M20, Appendix B).
    "forbidden-in-scaling": 109,
    "bad-scale-factor": 110,
    "reference-check-failed": 46,
    "bad-reference": 46,
    "division-by-zero": 208,
    "bad-expression": 206,
    "missing-operand": 207,
    "bracket-nesting": 209,
    "bad-variable": 107,
    "overflow": 102,
    "variable-not-allowed": 205,
    "too-many-m-codes": 201,
    # Tool compensation (notes §5, §9.5; compensation.py, offsets.py).
    "length-no-axis": 27,
    "bad-offset-number": 30,
    "bad-offset-value": 32,
    "comp-no-intersection": 33,
    "comp-arc-startup": 34,
    "comp-plane-change": 37,
    "comp-arc-centre": 38,
    "comp-interference": 41,
    # Canned cycles (notes §9.4; the special-cycle checks pass their own 210-228 numbers).
    "cycle-group01": 61,
    "cycle-conflict": 61,
    "cycle-missing-data": 61,
    "cycle-levels": 61,
    "cycle-argument": 61,
    "bad-cycle": 61,
    "rigid-tap": 61,
    "cycle-missing-q": 45,
    "cycle-not-allowed": 44,
    # Macros and subprograms (notes §9.6, Appendix B).
    "bad-call": 17,  # illegal macro program number / beyond the maximum repeat count
    "program-not-found": 59,
    "sequence-not-found": 60,
    "duplicate-program": 73,
    "missing-program-number": 76,  # ADDRESS P NOT DEFINED
    "nesting": 77,  # SUBPROGRAM NESTING ERROR (subprograms and macro calls)
    "do-end": 96,  # NO CORRESPONDING OF DO-END
    "read-only-variable": 107,
    "bad-macro-command": 205,
}

DIALECT = Dialect(
    name="gsk25i",
    title="GSK 25i milling",
    gcodes=GCODES,
    mcodes=MCODES,
    power_on=POWER_ON,
    execution_order=EXECUTION_ORDER,
    addresses=ADDRESSES,
    word_steps=WORD_STEPS,
    axes=_AXES,
    other_axes="ABCUVW",
    parameter_input_r=AddressRule(-99999999.0, 99999999.0, "integer", point_allowed=False, alarm=8),
    functions=FUNCTIONS,
    alarms=ALARMS,
    integer_is_unit=True,  # 1800#0 DPI standard setting 1: X10 = 10 mm (L684, PARAM-VOL)
    least_increment_mm=0.0001,  # L2101-L2104
    least_increment_inch=0.0001,
    arc_radius_tolerance_mm=0.01,  # P1810
    cycle_params=CycleParameters(),  # P2010/P2011 = 0.5 mm, P2000 = 0, P2141/2142 = 1000 r/min
    max_words_per_block=32,  # alarm 12
    max_m_per_block=3,  # 1803#6 M3B standard 1
    m_groups=M_GROUPS,
    corner_words=frozenset({",L", ",R"}),
    max_bracket_depth=5,  # L5593
    keywords=frozenset({"IF", "GOTO", "WHILE", "DO", "END", "THEN"}),
    variables=((1, 33), (100, 199), (500, 999)),
    system_variables=(
        (1000, 1135), (2001, 2906), (3000, 3012), (3901, 3902), (4001, 4130), (5001, 5105), (10001, 13400),
    ),
)
