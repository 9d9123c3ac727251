"""The ``fanuc`` code tables: a generic Fanuc 0i-M / Haas-class 3-axis mill, the Fanuc family's tables
(``lang/fanuc/codes.py``) with the differences docs/fanuc.md lists, each with its reason.

Alarm numbers are the Fanuc 0i-M program (P/S) alarms where the condition is the same.
"""

from __future__ import annotations

from cnc_gym.gcode.codes import AddressRule, gkey
from cnc_gym.gcode.lang.fanuc import codes as family
from cnc_gym.gcode.lang.fanuc.codes import BIG, g, m, table, unbuilt

G_CODES = table([
    *family.G_CODES,
    # The canned cycles also take L, the repeat count (Haas; cycles.py, CycleParameters.l_repeats).
    *[g(n, 9, "cycle", kind, step="motion", uses_axes=True, words=words + "L")
      for n, (kind, words) in family.CYCLE_CODES.items()],
    # G94/G95: feed per minute / per revolution (F × S), group 05.
    g(94, 5, "feed_mode", "minute", step="feed_mode"),
    g(95, 5, "feed_mode", "revolution", step="feed_mode"),
    # G47: Haas's text engraving (engraving.py), not Fanuc's position offset double increase. I is an
    # angle, J the text height, E the plunge feed; the text is the block's comment.
    g(47, 0, "engrave", step="motion", uses_axes=True, words="PIJRE",
      address_rules={"I": AddressRule(-360.0, 360.0, "plain"), "P": AddressRule(0.0, 126.0, "plain"),
                     "E": AddressRule(0.0, 1000000.0, "feed")}),
    unbuilt(5.1, 0, "AI contour control G05.1"),
    unbuilt(7.1, 0, "cylindrical interpolation G07.1"),
    unbuilt(33, 1, "thread cutting G33"),
    unbuilt(68.2, 16, "tilted working plane G68.2"),
])
POWER_ON = family.POWER_ON

M_CODES = table([
    *family.M_CODES,
    m(19, "spindle_orient", step="spindle"),  # oriented spindle stop, recorded
    # Haas's local subprogram call: the blocks from N<P> of the same program up to M99, L times.
    m(97, "local_subprogram_call", step="stop", words="PL"),
])

#: M codes that shop programs for such machines often carry but whose meaning the machine builder sets,
#: with what they usually do: run as machine functions (no motion; listed on the tool path), as the
#: control hands them to the machine.
MACHINE_MCODES = {
    gkey(n): what for n, what in {
        7: "mist coolant on", 10: "rotary axis brake on", 11: "rotary axis brake off",
        12: "rotary axis brake on (Haas)", 13: "spindle CW with coolant on (Haas: rotary axis brake off)",
        14: "spindle CCW with coolant on", 21: "optional user M code",
        31: "chip conveyor forward", 33: "chip conveyor stop", 34: "coolant spigot position",
        35: "coolant spigot position", 41: "low gear", 42: "high gear", 50: "pallet change",
        51: "optional user M code", 52: "optional user M code", 53: "optional user M code",
        59: "output relay", 69: "output relay", 75: "set the G35/G136 reference point",
        82: "tool unclamp", 83: "air blast on", 84: "air blast off", 86: "tool clamp",
        88: "through-spindle coolant on", 89: "through-spindle coolant off",
        109: "interactive user input",
    }.items()
}  # fmt: skip

#: Addresses (Fanuc 0i-M, increment system IS-B: 0.001 mm / 0.0001 inch).
ADDRESSES = {
    **{a: AddressRule(-BIG, BIG, "length") for a in "XYZIJKRQ"},
    "F": AddressRule(0.0, 1000000.0, "feed"),
    "P": AddressRule(-99999999.0, 99999999.0, "plain"),
    "L": AddressRule(0.0, 99999999.0, "integer", point_allowed=False),
    "N": AddressRule(0.0, 99999.0, "integer", point_allowed=False),
    # O up to 8 digits (the 8-digit program number of the 0i-F; 4-digit O numbers are the same programs).
    "O": AddressRule(0.0, 99999999.0, "integer", point_allowed=False),
    "S": AddressRule(0.0, 99999.0, "plain"),
    "T": AddressRule(0.0, 99999999.0, "integer", point_allowed=False),
    "M": AddressRule(0.0, 999.0, "integer", point_allowed=False),
    "G": AddressRule(0.0, 999.9, "plain", alarm=10),
    "H": AddressRule(0.0, 400.0, "integer", point_allowed=False, alarm=30),
    "D": AddressRule(0.0, 400.0, "integer", point_allowed=False, alarm=30),
    **{a: AddressRule(-BIG, BIG, "plain") for a in "ABCEUVW"},
    # Chamfer and corner rounding: ,C is the chamfer distance, ,R the corner radius.
    ",C": AddressRule(0.0, BIG, "length"),
    ",R": AddressRule(0.0, BIG, "length"),
}

#: Our error codes (or conditions ``"<code>/<what>"``, lang/fanuc) → Fanuc 0i-M alarms (PS numbers; OT for
#: the stroke limit) where the condition is the same. A code or condition missing here carries no number:
#: the GSK 25i's numbers for conditions Fanuc numbers otherwise or not at all are never shown.
ALARMS = {
    "word-too-long": 3,  # TOO MANY DIGITS
    "missing-address": 4,  # ADDRESS NOT FOUND
    "missing-value": 5,  # NO DATA AFTER ADDRESS
    "bad-sign": 6,  # ILLEGAL USE OF NEGATIVE SIGN
    "decimal-point-not-allowed": 7,  # ILLEGAL USE OF DECIMAL POINT
    "bad-number": 7,
    "bad-number/decimal-point": 7,
    "bad-character": 9,  # ILLEGAL ADDRESS INPUT
    "unknown-code": 10,  # IMPROPER G-CODE
    "not-implemented": 10,
    "missing-feed": 11,  # NO FEEDRATE COMMANDED
    "zero-feed": 11,
    "arc-radius-mismatch": 20,  # OVER TOLERANCE OF RADIUS
    "arc-bad-offset": 21,  # ILLEGAL PLANE AXIS COMMANDED
    "length-no-axis": 27,  # NO AXES COMMANDED IN G43/G44
    "bad-offset-value": 32,  # ILLEGAL OFFSET VALUE IN G10 (G10 or a system variable written)
    "bad-offset-value/variable": 32,
    "bad-offset-number": 30,  # ILLEGAL OFFSET NUMBER
    "comp-no-intersection": 33,  # NO SOLUTION AT CRC
    "comp-arc-startup": 34,  # NO CIRC ALLOWED IN ST-UP/EXT BLK
    "comp-plane-change": 37,  # CAN NOT CHANGE PLANE IN CRC
    "comp-interference": 41,  # INTERFERENCE IN CRC
    "g31-in-cutter-compensation": 36,  # CAN NOT COMMANDED G31
    "cycle-not-allowed": 44,  # G27-G30 NOT ALLOWED IN FIXED CYC
    "cycle-missing-q": 45,  # ADDRESS Q NOT FOUND (G73/G83)
    "bad-reference": 46,  # ILLEGAL REFERENCE RETURN COMMAND (G30 P other than 2-4)
    "program-not-found": 59,  # PROGRAM NUMBER NOT FOUND
    "sequence-not-found": 60,  # SEQUENCE NUMBER NOT FOUND
    "missing-program-number": 76,  # ADDRESS P NOT DEFINED
    "reference-check-failed": 92,  # ZERO RETURN CHECK (G27) ERROR
    "nesting": 77,  # SUB PROGRAM NESTING ERROR
    "overflow": 111,  # CALCULATED DATA OVERFLOW
    "division-by-zero": 112,  # DIVIDED BY ZERO
    "bad-expression": 114,  # FORMAT ERROR IN MACRO
    "missing-operand": 114,
    "bad-variable": 115,  # ILLEGAL VARIABLE NUMBER
    "read-only-variable": 116,  # WRITE PROTECTED VARIABLE
    "bracket-nesting": 118,  # PARENTHESIS NESTING ERROR
    "math-domain": 119,  # ILLEGAL ARGUMENT
    "bad-macro-command": 125,  # FORMAT ERROR IN MACRO
    "do-end": 126,  # ILLEGAL LOOP NUMBER
    "do-end/loop-number": 126,
    "rigid-tap/spindle-speed": 200,  # ILLEGAL S CODE COMMAND (rigid tapping S out of range)
    "travel-limit/+": 500,  # OT500 + OVERTRAVEL (SOFT 1)
    "travel-limit/-": 501,  # OT501 - OVERTRAVEL (SOFT 1)
}
