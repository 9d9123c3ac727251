"""The HUST H4C-M code tables: the G and M codes of the HUST H4C-M mill controller (HUST H4C-M manual
§3.1 Table 3-1 and each code's section), addresses and alarm numbers (chapter 6, error messages).

The controller's G codes keep the Fanuc family's meaning where the manual gives it (G00-G03, G17-G19,
G20/G21, G31, G40-G44/G49, G54-G59, G80-G83, G85, G89, G90/G91) and have HUST meanings elsewhere:
G04 takes X seconds only, G08 clears machine coordinates, G10 is HUST's data-setting and system
command, G22-G25 are groove cycles, G28/G29/G30 select axes without an intermediate point, G34-G37 are
hole patterns, G51 scales about the G51 position, G65 is one macro instruction (the reader turns it
into a statement), G68/G69 are mirror toggles. Codes the manual does not define are unknown (ERROR 13,
"G-code not accepted by H4C-M"); G84, listed in the manual's contents without a section, is rejected by
name. docs/h4cm.md lists every difference with its reason.
"""

from __future__ import annotations

from cnc_gym.gcode.codes import AddressRule, gkey
from cnc_gym.gcode.lang.fanuc import codes as family
from cnc_gym.gcode.lang.fanuc.codes import g, m, table, unbuilt

#: The family's codes whose meaning is the same on the H4C-M.
_FAMILY = frozenset(gkey(n) for n in (0, 1, 2, 3, 17, 18, 19, 20, 21, 31, 40, 41, 42, 43, 44, 49, 54, 55, 56,
                                      57, 58, 59, 80, 90, 91))  # fmt: skip

#: Words of the groove cycles G22-G25 (§3.29-§3.32) and hole patterns G34-G37 (§3.33-§3.37). T and D of a
#: groove block are its type and tool radius (blocks.py takes them off the block's words).
GROOVE_WORDS = {22: "RIJ", 23: "RIJK", 24: "RIJ", 25: "RK"}
PATTERN_WORDS = {34: "IJK", 35: "IJK", 36: "IJPK", 37: "IJPK"}
#: Counts and angles read as plain numbers, not least increments: a cycle's K (``K3`` drills 3 times), a
#: pattern's J angle, P angle step or count, K count (``J45`` is 45°), G51's I/J/K factors (``I2`` is 2).
_PLAIN = AddressRule(-9999999.0, 9999999.0, "plain")
_COUNT = AddressRule(0.0, 9999.0, "integer", point_allowed=False)
CYCLE_RULES = {"K": _COUNT}
PATTERN_RULES = {34: {"J": _PLAIN, "K": _COUNT}, 35: {"J": _PLAIN, "K": _COUNT},
                 36: {"J": _PLAIN, "P": _PLAIN, "K": _COUNT}, 37: {"P": _COUNT, "K": _COUNT}}  # fmt: skip
SCALE_RULES = {letter: AddressRule(0.0, 9999999.0, "plain") for letter in "IJK"}
#: §3.19-§3.28: the cycle codes and their kinds (cycles.py); G84 has no definition.
CYCLE_CODES = {81: "drill", 82: "drill_dwell", 83: "peck_deep", 85: "bore", 86: "hust_bore_spindle_stop",
               89: "bore_dwell"}  # fmt: skip

G_CODES = table([
    *(spec for spec in family.G_CODES if gkey(float(spec.name[1:])) in _FAMILY),
    # §3.7 G04: dwell X in seconds (X without a point counts 0.001 s); no P form.
    g(4, 0, "hust_dwell", step="dwell", uses_axes=True),
    # §3.8 G08: clears the machine coordinates of the named axes (a homing operation).
    unbuilt(8, 0, "G08 clears the machine coordinates (a homing step of the operator's panel); the simulated "
                  "machine keeps its coordinate system", uses_axes=True),
    # §3.9 G10: HUST's data setting (work origin, tool offsets and wear) and system functions (P100-P2002).
    g(10, 0, "hust_g10", step="setting", uses_axes=True, words="PLIJKUVWR"),
    # §3.29-§3.32 grooves; §3.33-§3.37 hole patterns (one-shot; the value is the G number).
    *[g(n, 0, "hust_groove", n, step="motion", uses_axes=True, words=words)
      for n, words in GROOVE_WORDS.items()],
    *[g(n, 0, "hust_pattern", n, step="motion", uses_axes=True, words=words, address_rules=PATTERN_RULES[n])
      for n, words in PATTERN_WORDS.items()],
    # §3.19-§3.28 canned cycles (cycles.py): G86 retracts at feed; no G73, G74, G76, G87, G88.
    *[g(n, 9, "cycle", kind, step="motion", uses_axes=True, words="RQPK", address_rules=CYCLE_RULES)
      for n, kind in CYCLE_CODES.items()],
    # §3.11-§3.13 G28/G29/G30: the axis words only select axes; no intermediate point.
    g(28, 0, "hust_reference", 1, step="motion", uses_axes=True),
    g(29, 0, "hust_reference_back", step="motion", uses_axes=True),
    g(30, 0, "hust_reference", 2, step="motion", uses_axes=True),
    # §3.15 G50/G51 scaling: I J K are the X Y Z factors, about the position where G51 is given.
    g(50, 11, "hust_scaling_cancel", step="modes"),
    g(51, 11, "hust_scaling", step="setting", words="IJK", address_rules=SCALE_RULES),
    # §3.41 G65: one macro instruction (reader.py makes it a statement; macro.py runs it).
    g(65, 0, "hust_g65", step="stop", words="LPAB"),
    # §3.17 G68/G69: X and Y mirror toggles.
    g(68, 0, "hust_mirror", 0, step="setting"),
    g(69, 0, "hust_mirror", 1, step="setting"),
    # G84: in the manual's contents only ("3.26 G84 Thread Tapping Cycle"); no section defines it.
    unbuilt(84, 9, "G84 tapping is listed in the manual's contents but has no section, format or cycle-table "
                   "row on the H4C-M"),
    # G98/G99: a modal group (Table 3-1) the manual never defines. G98 stands before the cycles in their
    # format and the cycles always end at the initial level: G98 is that (and the power-on state); G99,
    # per revolution on HUST lathes, is refused by name.
    g(98, 10, "cycle_return", "initial", step="modes"),
    unbuilt(99, 10, "G99 (feed per revolution on HUST lathes) is listed as a modal code but not defined for "
                    "the mill"),
])  # fmt: skip

#: Power-on codes (§3.1 Table 3-1 '#' marks, §3.6 G17, §3.10 G21, §3.18 G90): G01, not G00.
POWER_ON = tuple(gkey(n) for n in (1, 17, 90, 21, 40, 49, 80, 98, 50, 54))

M_CODES = table([
    *(spec for spec in family.M_CODES if spec.name in ("M00", "M01", "M02", "M30", "M03", "M04", "M05", "M08",
                                                       "M09")),
    m(7, "coolant", True, step="coolant"),  # §3.38 lists M07 as coolant on, the appendix M08
    m(98, "subprogram_call", step="stop", words="PL"),
    m(99, "subprogram_return", step="stop"),  # no M99 P on the H4C-M (§3.39)
])  # fmt: skip
M_GROUPS = {**family.M_GROUPS, "coolant": frozenset(gkey(n) for n in (7, 8, 9))}
#: PLC-defined M codes of the manual's appendix, refused by name (the PLC program decides what they do).
MACHINE_MCODES = {gkey(10): "chuck clamp (PLC)", gkey(11): "chuck unclamp (PLC)"}

#: Seven digits at most (§2.3.5 "numeric input: at most 7 digits"); lengths in the 4/3 format. U/V/W are
#: incremental X/Y/Z (blocks.py); A/B are G65 operands (reader.py), never axes.
BIG = 9999.999
ADDRESSES = {
    **{a: AddressRule(-BIG, BIG, "length") for a in "XYZIJKRQUVW"},
    "F": AddressRule(0.0, 8000.0, "feed"),
    "P": AddressRule(-9999999.0, 9999999.0, "plain"),
    "L": AddressRule(0.0, 9999999.0, "integer", point_allowed=False),
    "N": AddressRule(0.0, 9999999.0, "integer", point_allowed=False),
    "O": AddressRule(0.0, 999.0, "integer", point_allowed=False),
    "S": AddressRule(0.0, 999999.0, "integer", point_allowed=False),
    "T": AddressRule(0.0, 99.0, "integer", point_allowed=False),
    "M": AddressRule(0.0, 999.0, "integer", point_allowed=False),
    "G": AddressRule(0.0, 99.0, "integer", point_allowed=False),
    "H": AddressRule(0.0, 40.0, "integer", point_allowed=False),
    "D": AddressRule(0.0, BIG, "plain"),  # a group number (G41/G42) or a tool radius (G24/G25)
    "K": AddressRule(-BIG, BIG, "length"),
    **{a: AddressRule(-9999999.0, 9999999.0, "plain") for a in "ABC"},
}

#: Our error codes → H4C-M error numbers (chapter 6 "Error messages").
ALARMS = {
    "part-count-limit": 3,  # ERROR 03 counter limit
    "block-too-long": 8,  # ERROR 8 more than 64 characters in one block
    "unknown-code": 13,  # ERROR 13 G-code not accepted by H4C-M
    "not-implemented": 13,
    "travel-limit/+": 20,  # ERROR 20 software over-travel (#171-#174)
    "travel-limit/-": 20,  # (#177-#180)
    "nesting": 24,  # ERROR 24 M98 nesting
    "arc-impossible": 25,  # ERROR 25 wrong circle format or data error
    "arc-radius-mismatch": 25,
    "arc-missing-center": 25,
    "arc-bad-offset": 25,
    "arc-r-sweep": 25,
    "arc-mode": 25,
}
