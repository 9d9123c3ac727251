"""The GSK 25i (milling) code tables: the Fanuc family's tables (``lang/fanuc/codes.py``) with the GSK's own
codes, addresses and alarms.

Sources: the GSK 25i programming manual and its parameter volume, section numbers beside each entry. Codes
the controller has but this simulator does not carry out are listed as ``unbuilt`` so they are rejected by
name (``not-implemented``), never ignored; codes missing from these tables are ``unknown-code`` (GSK alarm
10 "IMPROPER G-CODE").

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

from cnc_gym.gcode.codes import AddressRule
from cnc_gym.gcode.dialects.gsk25i.patterns import PATTERN_WORDS
from cnc_gym.gcode.dialects.gsk25i.pockets import KIND_CODES, POCKET_WORDS
from cnc_gym.gcode.lang.fanuc import codes as family
from cnc_gym.gcode.lang.fanuc.codes import BIG, NURBS_RULES, g, m, table, unbuilt

#: Number formats codes give their own words (CodeSpec.address_rules). The L of the pocket, boss and
#: face-milling cycles is a step-over length (``L2.5``), not the whole-number L of M98/G65/G10.
STEP_LENGTH = {"L": AddressRule(0.0, BIG, "length")}

G_CODES = table([
    *family.G_CODES,
    # G06.2 NURBS (§3.2.5; nurbs.py): modal in group 01; the block's axis words are control points.
    g(6.2, 1, "nurbs", step="motion", uses_axes=True, words="PKR", address_rules=NURBS_RULES),
    unbuilt(33, 1, "thread cutting G33"),
    # G09 (one-shot exact stop) is missing from GSK's table (§3.8); Fanuc-standard, kept.
    g(5, 0, "contour_control", step="modes", words="P"),  # G05 P10000 / P0: high-precision contour control
    unbuilt(7.1, 0, "cylindrical interpolation G07.1"),
    unbuilt(107, 0, "cylindrical interpolation G107"),
    unbuilt(53.1, 0, "tool axis direction control G53.1"),
    unbuilt(43.4, 8, "tool centre point control G43.4"),
    unbuilt(68.2, 16, "tilted working plane G68.2"),
    # Hole patterns G120-G125 and face milling G126/G127 (§3.6; patterns.py): the value is the G number.
    *[g(n, 0, "pattern", n, step="motion", uses_axes=True, words=PATTERN_WORDS[n],
        address_rules=STEP_LENGTH if "L" in PATTERN_WORDS[n] else None) for n in range(120, 128)],
    # Special cycles G110-G117, G130-G137 (§3.4.16-§3.4.23; pockets.py): canned cycles of their own kinds.
    *[g(code, 9, "cycle", kind, step="motion", uses_axes=True, words=POCKET_WORDS[code],
        address_rules=STEP_LENGTH if "L" in POCKET_WORDS[code] else None)
      for kind, code in KIND_CODES.items()],
])  # fmt: skip

POWER_ON = family.POWER_ON

M_CODES = table([
    *family.M_CODES,
    m(19, "not_implemented", step="spindle", implemented=False, note="spindle orientation M19"),
    m(96, "not_implemented", step="stop", implemented=False, note="macro interrupt M96"),
    m(97, "not_implemented", step="stop", implemented=False, note="macro interrupt M97"),
])

# --------------------------------------------------------------------------- addresses (Table 1-1, §2.5)
ADDRESSES = {
    **{a: AddressRule(-BIG, BIG, "length") for a in "XYZIJKRQ"},
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
    **{a: AddressRule(-BIG, BIG, "plain") for a in "ABCEUVW"},
    # Chamfer and corner rounding (§3.2.11): ,L is the chamfer distance, ,R the corner radius.
    ",L": AddressRule(0.0, BIG, "length"),
    ",R": AddressRule(0.0, BIG, "length"),
}


# --------------------------------------------------------------------------- alarms (the manual's alarm list)
#: Error code, or condition ``"<code>/<what>"`` where the list numbers one case of a code apart → alarm.
ALARMS = {
    "too-many-digits": 3,
    "missing-value": 5,
    "missing-address": 4,
    "bad-sign": 6,
    "decimal-point-not-allowed": 7,
    "bad-number": 8,
    "bad-number/decimal-point": 7,  # ILLEGAL USE OF DECIMAL POINT (a second point, a point alone)
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
    # Coordinates and transforms (docs/gsk25i_alarms.md M14-M20).
    "forbidden-in-scaling": 109,
    "bad-scale-factor": 110,
    "reference-check-failed": 46,
    "bad-reference": 46,
    "bad-reference/no-intermediate": 46,  # G29 before any G28/G30
    # Stored stroke limit 1 (GSK 25i operation manual §2.5.4): "OVER TRAVEL:+n" / "OVER TRAVEL:-n".
    "travel-limit/+": 500,
    "travel-limit/-": 501,
    "division-by-zero": 208,
    "bad-expression": 206,
    "missing-operand": 207,
    "bracket-nesting": 209,
    "bad-variable": 107,
    "overflow": 102,
    "variable-not-allowed": 205,
    "too-many-m-codes": 201,
    # Tool compensation (§3.5; compensation.py, offsets.py).
    "length-no-axis": 27,
    "bad-offset-number": 30,
    "bad-offset-value": 32,  # ILLEGAL OFFSET VALUE IN G10
    "bad-offset-value/variable": 29,  # ILLEGAL OFFSET VALUE (#2001… written)
    "g31-in-cutter-compensation": 36,
    "comp-no-intersection": 33,
    "comp-arc-startup": 34,
    "comp-plane-change": 37,
    "comp-arc-centre": 38,
    "comp-interference": 41,
    # Canned cycles (docs/gsk25i_alarms.md; the special-cycle checks pass their own 210-228 numbers).
    "cycle-group01": 61,
    "cycle-conflict": 61,
    "cycle-missing-data": 61,
    "cycle-levels": 61,
    "cycle-argument": 61,
    "bad-cycle": 61,
    "rigid-tap": 61,
    "rigid-tap/spindle-speed": 200,  # S above the gear's rigid-tapping maximum
    "cycle-too-long": 61,
    "cycle-argument/special-in-drilling": 214,  # CANNED CYCLE PUNCHING G73-G89 DEFINED
    "cycle-argument/special-plane": 227,  # a special cycle outside G17
    "cycle-not-allowed/other": 61,  # G10, or a plane change moving the drilling axis, in cycle mode
    "cycle-missing-q": 45,
    "cycle-not-allowed": 44,
    # G37 tool length measurement (alarm 80 "illegal G37 measurement").
    "g37-signal": 80,
    "g37-h-in-block": 80,
    "g37-no-h": 80,
    # Macros and subprograms (docs/gsk25i_alarms.md S1-S15).
    "bad-call": 17,  # illegal macro program number / beyond the maximum repeat count
    "program-not-found": 59,
    "sequence-not-found": 60,
    "duplicate-program": 73,
    "missing-program-number": 76,  # ADDRESS P NOT DEFINED
    "nesting": 77,  # SUBPROGRAM NESTING ERROR (subprograms and macro calls)
    "do-end": 96,  # NO CORRESPONDING OF DO-END
    "do-end/loop-number": 97,  # ILLEGAL CYCLE NUMBER (DOm, ENDm with m not 1..3)
    "read-only-variable": 107,
    "bad-macro-command": 205,
}
