"""The Syntec 8.20 (mill) code tables: the Fanuc family's tables (``lang/fanuc/codes.py``) with Syntec's own
codes, addresses and alarms (Syntec 8.20 mill programming manual §1.1 "G code list" and each code's
section; docs/syntec.md lists every difference from the family with its reason).

Codes the family has and the Syntec code list does not (G11, G20/G21, G22/G23, G27, G39, G45-G48, G54.1,
G60, M29) are left out: a program using them gets ``unknown-code``, as on the controller. Syntec names
no alarm numbers but the MAR-330..336 of automatic tool length measurement; every other error carries
none.
"""

from __future__ import annotations

from cnc_gym.gcode.codes import AddressRule, gkey
from cnc_gym.gcode.lang.fanuc import codes as family
from cnc_gym.gcode.lang.fanuc.codes import BIG, NURBS_RULES, g, m, table

#: The family's codes Syntec 8.20 does not have (its §1.1 code list and sections name none of them).
NOT_SYNTEC = frozenset(gkey(n) for n in (11, 20, 21, 22, 23, 27, 39, 45, 46, 47, 48, 54.1, 60))

#: ``State.motion`` of G33 thread cutting (a group-01 mode besides G00-G03).
THREAD = 33

#: Words of the hole-pattern codes (§G134-§G137.1).
PATTERN_WORDS = {134: "IJK", 135: "IJK", 136: "IJPK", 137.1: "IPJK"}

#: G37's D is a length (the probe over-travel), not an offset number.
PROBE_RULES = {"D": AddressRule(0.0, BIG, "length")}

G_CODES = table([
    *(spec for spec in family.G_CODES if gkey(float(spec.name[1:])) not in NOT_SYNTEC),
    # §G04: X seconds (or ms without a point), P ms; Syntec's rules in modes.py.
    g(4, 0, "dwell", step="dwell", uses_axes=True, words="P"),
    # §G05 high-speed, high-precision interpolation (P10000, P1-P5 / P0) and §G05.1 path smoothing.
    g(5, 0, "contour_control", step="modes", words="P"),
    g(5.1, 0, "smoothing", step="modes", words="QE"),
    # §G06.2 NURBS (only inside G05): modal in group 01; the block's axis words are control points.
    g(6.2, 1, "nurbs", step="motion", uses_axes=True, words="PKR", address_rules=NURBS_RULES),
    # §G33 thread cutting: F is the lead.
    g(33, 1, "motion", THREAD, step="motion"),
    # §G37 / §G37.1 automatic tool length measurement (measurement.py). D and F of the block are the
    # probe over-travel and the measuring feed (blocks.py takes them off the block's words).
    g(37, 0, "tool_length_measure", step="motion", uses_axes=True, words="RP", address_rules=PROBE_RULES),
    g(37.1, 0, "tool_length_measure_2", step="motion", uses_axes=True, words="RPQ"),
    # §G54…G59.9: fifteen work coordinate systems.
    *[g(59 + n / 10, 14, "wcs", 6 + n, step="wcs") for n in range(1, 10)],
    # §G64 / §G09/G61: G62 is a cutting mode without deceleration (not Fanuc's automatic corner override).
    g(62, 15, "path_mode", "no_decel", step="path_mode"),
    # §G70/G71: inch and metric input.
    g(70, 6, "units", True, step="units"),
    g(71, 6, "units", False, step="units"),
    # §G94/G95 feed per minute / per revolution; §G96/G97 constant surface speed (before S is read).
    g(94, 5, "feed_mode", "minute", step="feed_mode"),
    g(95, 5, "feed_mode", "revolution", step="feed_mode"),
    g(96, 13, "surface_speed", True, step="feed_mode"),
    g(97, 13, "surface_speed", False, step="feed_mode"),
    # §G134-§G137.1 hole patterns (patterns.py): the value is the G number.
    *[g(n, 0, "hole_pattern", n, step="motion", uses_axes=True, words=words)
      for n, words in PATTERN_WORDS.items()],
])  # fmt: skip

#: Power-on codes: the family's with G71 for G21 (§G70/G71: metric is the usual setting) and no G23.
POWER_ON = tuple(gkey(n) for n in (0, 17, 90, 94, 71, 40, 49, 80, 98, 50, 67, 97, 54, 64, 69, 15, 50.1))

M_CODES = table([
    *(spec for spec in family.M_CODES if spec.name != "M29"),
    m(19, "spindle_orient", step="spindle"),  # §M code description: spindle orientation
])
#: M-code groups (codes of one group may not share a block).
M_GROUPS = family.M_GROUPS

#: Addresses. Lengths (X Y Z I J K R Q E) without a decimal point are counts of the least input unit
#: (reader.py); F is never scaled; P is a dwell, a program number, a count or an angle by code.
ADDRESSES = {
    **{a: AddressRule(-BIG, BIG, "length") for a in "XYZIJKRQE"},
    "F": AddressRule(0.0, 1000000.0, "feed"),
    "P": AddressRule(-99999999.0, 99999999.0, "plain"),
    "L": AddressRule(0.0, 9999.0, "integer", point_allowed=False),
    "N": AddressRule(0.0, 99999.0, "integer", point_allowed=False),
    "O": AddressRule(0.0, 9999.0, "integer", point_allowed=False),
    "S": AddressRule(0.0, 99999.0, "plain"),
    "T": AddressRule(0.0, 9999.0, "integer", point_allowed=False),
    "M": AddressRule(0.0, 999.0, "integer", point_allowed=False),
    "G": AddressRule(0.0, 999.9, "plain"),
    "H": AddressRule(0.0, 99999.0, "integer", point_allowed=False),  # also M98's label (blocks.py)
    "D": AddressRule(0.0, 400.0, "integer", point_allowed=False),
    **{a: AddressRule(-BIG, BIG, "plain") for a in "ABCUVW"},
}

#: Our error codes → Syntec alarm numbers: only the MAR alarms of §G37 and §G37.1 have numbers.
ALARMS = {
    "g37-no-z": 330,  # MAR-330 Z min. coordinate set error alarm!
    "g37-start-point": 333,  # MAR-333 Z start point error alarm!
    "g37-no-h": 334,  # MAR-334 Without issue H code before G code tool length measurement
    "g37-early-signal": 335,  # MAR-335 measure position setting error, measure signal has being triggered
    "g37-no-signal": 336,  # MAR-336 measure signal hasn't being triggered
}
