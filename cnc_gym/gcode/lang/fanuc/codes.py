"""Code-table parts shared by the Fanuc family's dialects: the table helpers, the G and M codes whose
meaning is the same on every Fanuc-style mill (G00-G03, G17-G19, G40-G49, G54-G59, the canned cycles …),
the addresses, the Macro B functions and the order of execution.

A dialect's ``codes.py`` starts from these and adds, replaces or removes entries; each entry names the
action that carries it out (``lang/fanuc/__init__.py``'s registry) and, for a canned cycle, the cycle kind
(``cycles.py``). Sources: GSK 25i programming manual (the reference dialect), checked against the Fanuc
0i-M conventions where a dialect differs (docs/dialects.md).

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import math

from cnc_gym.gcode.codes import AddressRule, CodeSpec, gkey
from cnc_gym.toolpath import Plane

#: Addresses of a G65/G66 block besides G, N, O: P, L and the arguments (calls.py handles the block; these
#: let a G65 that came from a variable reach its action, which names the problem).
ARGUMENTS = "ABCDEFHIJKLMPQRSTUVWXYZ"
BIG = 999999.9999
#: G06.2: K is a knot and R a weight, plain numbers (``K0.008286`` keeps its digits; G20 does not convert).
NURBS_RULES = {"K": AddressRule(-BIG, BIG, "plain"), "R": AddressRule(-BIG, BIG, "plain")}


def g(number: float, group: int, action: str, value: object = None, *, step: str = "record",
      uses_axes: bool = False, words: str = "", implemented: bool = True, note: str = "",
      address_rules: dict | None = None) -> CodeSpec:  # fmt: skip
    """A G code of a table: ``g(1, 1, "motion", 1, step="motion")``."""
    whole, tenth = divmod(gkey(number), 10)
    name = f"G{whole:02d}" + (f".{tenth}" if tenth else "")
    return CodeSpec(name, group, action, value, step, uses_axes, words, implemented, note, address_rules)


def unbuilt(number: float, group: int, what: str, *, uses_axes: bool = False) -> CodeSpec:
    """A G code the controller has and this interpreter does not carry out: rejected by name."""
    return g(number, group, "not_implemented", step="motion", uses_axes=uses_axes, implemented=False,
             note=what)  # fmt: skip


def m(number: int, action: str, value: object = None, *, step: str, implemented: bool = True,
      words: str = "", note: str = "") -> CodeSpec:  # fmt: skip
    """An M code of a table."""
    return CodeSpec(f"M{number:02d}", 0, action, value, step, False, words, implemented, note)


def table(specs: list[CodeSpec]) -> dict[int, CodeSpec]:
    """Code key → spec (a later entry for the same code replaces an earlier one)."""
    return {gkey(float(s.name[1:])): s for s in specs}


#: Canned-cycle codes → (kind in the cycle library, words). I/J of G76/G87 are the SIJ shift (cycles.py).
CYCLE_CODES = {
    73: ("peck_high_speed", "RQPK"), 74: ("tap_left", "RQPK"), 76: ("fine_bore", "RQPKIJ"),
    81: ("drill", "RQPK"), 82: ("drill_dwell", "RQPK"), 83: ("peck_deep", "RQPK"), 84: ("tap", "RQPK"),
    85: ("bore", "RQPK"), 86: ("bore_spindle_stop", "RQPK"), 87: ("back_bore", "RQPKIJ"),
    88: ("bore_manual", "RQPK"), 89: ("bore_dwell", "RQPK"),
}  # fmt: skip

#: The G codes every Fanuc-family mill dialect starts from (GSK 25i section numbers beside each group).
G_CODES = [
    # Group 01: motion (§3.2.1-§3.2.3). Modal; the axis words of the block belong to it.
    g(0, 1, "motion", 0, step="motion"),
    g(1, 1, "motion", 1, step="motion"),
    g(2, 1, "motion", 2, step="motion", words="IJKR"),
    g(3, 1, "motion", 3, step="motion", words="IJKR"),
    # Group 00: one-shot.
    g(4, 0, "dwell", step="dwell", uses_axes=True, words="P"),
    g(9, 0, "exact_stop_once", step="modes"),  # after G61-G64 of the same block
    g(10, 0, "data_input", step="setting", uses_axes=True, words="LPR"),
    g(11, 0, "parameter_input_end", step="setting", note="G10 L50 parameter input off (the power-on state)"),
    g(27, 0, "reference_check", step="motion", uses_axes=True),
    g(28, 0, "reference_return", step="motion", uses_axes=True),
    g(29, 0, "reference_return_from", step="motion", uses_axes=True),
    g(30, 0, "reference_return_n", step="motion", uses_axes=True, words="P"),
    g(31, 0, "skip", step="motion", uses_axes=True),
    g(37, 0, "tool_length_measure", step="motion", uses_axes=True),  # measurement.py
    g(39, 0, "corner_arc", step="cutter_comp", words="IJK"),  # corner arc in cutter compensation
    g(45, 0, "position_offset", 1, step="cutter_comp"),
    g(46, 0, "position_offset", -1, step="cutter_comp"),
    g(47, 0, "position_offset", 2, step="cutter_comp"),
    g(48, 0, "position_offset", -2, step="cutter_comp"),
    g(52, 0, "local_origin", step="setting", uses_axes=True),
    g(53, 0, "machine_move", step="motion"),
    g(60, 0, "single_direction", step="motion", uses_axes=True),
    g(65, 0, "macro_call", step="stop", words=ARGUMENTS, note="one-shot macro call (calls.py)"),
    g(92, 0, "floating_origin", step="setting", uses_axes=True),
    # Group 02: plane (§3.2.15).
    g(17, 2, "plane", Plane.XY, step="plane"),
    g(18, 2, "plane", Plane.ZX, step="plane"),
    g(19, 2, "plane", Plane.YZ, step="plane"),
    # Group 03: distance mode.
    g(90, 3, "distance", False, step="distance"),
    g(91, 3, "distance", True, step="distance"),
    # Group 04: stored stroke check 2; G23 (off) is the standard power-on state.
    unbuilt(22, 4, "stored stroke check G22"),
    g(23, 4, "record", step="modes"),
    # Group 05: feed mode.
    g(94, 5, "record", step="feed_mode"),
    unbuilt(95, 5, "feed per revolution G95"),
    # Group 06: units (§3.2.19).
    g(20, 6, "units", True, step="units"),
    g(21, 6, "units", False, step="units"),
    # Group 07: cutter radius compensation C (§3.5.2; compensation.py).
    g(40, 7, "cutter_comp", 0, step="cutter_comp", words="IJK"),  # I/J/K: the cancel direction
    g(41, 7, "cutter_comp", 1, step="cutter_comp"),
    g(42, 7, "cutter_comp", -1, step="cutter_comp"),
    # Group 08: tool length offset (§3.5.1).
    g(43, 8, "length_comp", 1, step="length_comp"),
    g(44, 8, "length_comp", -1, step="length_comp"),
    g(49, 8, "length_comp", 0, step="length_comp"),
    # Group 09: canned cycles (§3.4; cycles.py). G80 = no cycle. The axis words of a cycle block are the
    # hole position and bottom; the value is the cycle kind.
    *[g(n, 9, "cycle", kind, step="motion", uses_axes=True, words=words)
      for n, (kind, words) in CYCLE_CODES.items()],
    g(80, 9, "cycle_cancel", step="motion"),
    # Group 10: canned-cycle return level (G98 initial level, G99 R level).
    g(98, 10, "cycle_return", "initial", step="modes"),
    g(99, 10, "cycle_return", "r", step="modes"),
    # Group 11: scaling (§3.2.17).
    g(50, 11, "scaling_cancel", step="modes"),
    g(51, 11, "scaling", step="setting", uses_axes=True, words="PIJK"),
    # Group 12: modal macro call.
    g(66, 12, "macro_call", step="stop", words=ARGUMENTS, note="modal macro call (calls.py)"),
    g(67, 12, "modal_call_cancel", step="modes"),
    # Group 13: constant surface speed.
    unbuilt(96, 13, "constant surface speed G96"),
    g(97, 13, "record", step="modes"),
    # Group 14: work coordinate systems (§3.2.10, §3.2.20). G54.1's value: the codes whose P would collide
    # with its P.
    *[g(n, 14, "wcs", n - 53, step="wcs") for n in range(54, 60)],
    g(54.1, 14, "wcs_extra", frozenset(gkey(n) for n in (4, 10, 65, 30)), step="wcs", words="P"),
    # Group 15: path mode: flags on the segments for the controller.
    g(61, 15, "path_mode", "exact_stop", step="path_mode"),
    g(62, 15, "path_mode", "auto_corner", step="path_mode"),
    g(63, 15, "path_mode", "tapping", step="path_mode"),
    g(64, 15, "path_mode", "cutting", step="path_mode"),
    # Group 16: rotation (§3.2.18).
    g(68, 16, "rotation", step="setting", uses_axes=True, words="R"),
    g(69, 16, "rotation_cancel", step="modes"),
    # Group 17: polar coordinates (§3.2.16).
    g(15, 17, "polar_cancel", step="modes"),
    g(16, 17, "polar", step="modes"),
    # Group 22: programmable mirror.
    g(50.1, 22, "mirror_cancel", step="setting", uses_axes=True),
    g(51.1, 22, "mirror", step="setting", uses_axes=True),
]

#: Power-on codes of the family (Fanuc's standard: G00 G17 G90 G23 G94 G21 G40 G49 G80 G98 G50 G67 G97 G54
#: G64 G69 G15 G50.1).
POWER_ON = tuple(gkey(n) for n in (0, 17, 90, 23, 94, 21, 40, 49, 80, 98, 50, 67, 97, 54, 64, 69, 15, 50.1))

M_CODES = [
    m(0, "stop", "program_stop", step="stop"),
    m(1, "stop", "optional_stop", step="stop"),
    m(2, "stop", "end", step="stop"),
    m(30, "stop", "end", step="stop"),
    m(3, "spindle", 1, step="spindle"),
    m(4, "spindle", -1, step="spindle"),
    m(5, "spindle", 0, step="spindle"),
    m(6, "tool_change", step="tool_change"),
    m(8, "coolant", True, step="coolant"),
    m(9, "coolant", False, step="coolant"),
    m(29, "rigid_tap", step="spindle"),
    m(98, "subprogram_call", step="stop", words="PL"),
    m(99, "subprogram_return", step="stop", words="P"),
]
#: M-code groups (codes of one group may not share a block).
M_GROUPS = {
    "stop": frozenset(gkey(n) for n in (0, 1, 2, 30, 98, 99)),
    "spindle": frozenset(gkey(n) for n in (3, 4, 5, 19, 29)),
    "coolant": frozenset(gkey(n) for n in (8, 9)),
}

#: NIST RS274NGC Table 8, adapted (docs/gcode.md "Order of execution"): G20/G21 first so every value of the
#: block is read in the block's unit system.
EXECUTION_ORDER = (
    "units", "feed_mode", "feed", "spindle_speed", "tool", "tool_change", "spindle", "coolant", "dwell",
    "plane", "cutter_comp", "length_comp", "wcs", "path_mode", "distance", "modes", "setting", "motion",
    "stop",
)  # fmt: skip

#: Words with actions: F, S, T; D and H select offset numbers before anything of the block uses them.
WORDS = {
    "F": CodeSpec("F", -1, "feed", step="feed"),
    "S": CodeSpec("S", -1, "spindle_speed", step="spindle_speed"),
    "T": CodeSpec("T", -1, "tool", step="tool"),
    "D": CodeSpec("D", -1, "offset_words", step="tool"),
    "H": CodeSpec("H", -1, "offset_words", step="tool"),
}


# --------------------------------------------------------------------------- Macro B functions
def _deg_trig(fn):
    return lambda x: fn(math.radians(x))


def _tan(x: float) -> float:
    # GSK computes TAN as SIN/COS (§3.7.4); a zero cosine is a division by zero.
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
    # ASIN/ACOS/LN/EXP/POW are Fanuc Macro B functions the GSK list (§3.7.4) does not print;
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
