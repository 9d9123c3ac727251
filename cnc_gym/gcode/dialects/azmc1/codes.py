"""The AZ-MC1's code tables, addresses, power-on state and order of execution (AMK AZ-MC1 programming
manual §3 "G functions", §4 "M functions", §2.4.2 "Assigned address letters", appendix §13.1).

The tables reuse the Fanuc family's table helpers and, where a code means the same, the family's actions
(plane, distance mode, G94/G95, spindle, program stop); every AZ-MC1 meaning is an action of this folder.
Codes the controller has and this interpreter does not carry out are rejected by name (``unbuilt``).
"""

from __future__ import annotations

from cnc_gym.gcode.codes import AddressRule, CodeSpec, gkey
from cnc_gym.gcode.lang.fanuc.codes import g, m, table, unbuilt
from cnc_gym.toolpath import Plane

#: ±214 000 mm (§2.7): the range of every length entry, after expressions and offsets.
TRAVEL_MM = 214_000.0

def refused(number: int, note: str) -> CodeSpec:
    """An M code the controller has and this interpreter does not carry out: rejected by name."""
    return m(number, "not_implemented", step="spindle", implemented=False, note=note)


G_CODES = table([
    # Motion (§3.1). G01 is the basic state; I/J/K are the arc centre (no R: R is a parameter).
    g(0, 1, "motion", 0, step="motion"),
    g(1, 1, "motion", 1, step="motion"),
    g(2, 1, "motion", 2, step="motion", words="IJK"),
    g(3, 1, "motion", 3, step="motion", words="IJK"),
    # One-shot codes.
    g(4, 0, "dwell", step="dwell", uses_axes=True),  # §3.1.4: seconds under the first axis's address
    g(9, 0, "feed_adaptation_end", step="modes"),  # §3.2: decelerate to the next block's feed at the end
    g(60, 0, "exact_stop_once", step="modes"),  # §3.8: feed to zero at the block end, in-position window
    g(63, 0, "override_lock", step="modes"),  # §3.14: override fixed at 100 % for this block
    g(74, 0, "homing", step="motion", uses_axes=True),  # §3.1.5: programmable homing, order indices
    g(92, 0, "datum_offset", step="setting", uses_axes=True),  # §3.1.6: additive datum point offset
    g(98, 0, "soft_limit", -1, step="setting", uses_axes=True),  # §3.1.7: negative software limit
    g(99, 0, "soft_limit", 1, step="setting", uses_axes=True),  # §3.1.8: positive software limit
    unbuilt(8, 0, "G08 (feed adaptation at the block start) is listed in the manual's overview only, "
                  "without a description"),
    # Plane (§3.4).
    g(17, 2, "plane", Plane.XY, step="plane"),
    g(18, 2, "plane", Plane.ZX, step="plane"),
    g(19, 2, "plane", Plane.YZ, step="plane"),
    # Distance mode (§3.7).
    g(90, 3, "distance", False, step="distance"),
    g(91, 3, "distance", True, step="distance"),
    # Mirroring about the program zero (§3.5): G20 off, G21 X, G22 Y, G23 both.
    g(20, 4, "mirror", (), step="mirror"),
    g(21, 4, "mirror", (0,), step="mirror"),
    g(22, 4, "mirror", (1,), step="mirror"),
    g(23, 4, "mirror", (0, 1), step="mirror"),
    # Feed per minute / per revolution (§3.3).
    g(94, 5, "feed_mode", "minute", step="feed_mode"),
    g(95, 5, "feed_mode", "revolution", step="feed_mode"),
    # Units (§3.6): distances and coordinates only, not F, tool offsets or zero offsets.
    g(70, 6, "units", True, step="units"),
    g(71, 6, "units", False, step="units"),
    # Tool radius offset, TRO (§3.9, §11.3).
    g(40, 7, "cutter_comp", 0, step="cutter_comp"),
    g(41, 7, "cutter_comp", 1, step="cutter_comp"),
    g(42, 7, "cutter_comp", -1, step="cutter_comp"),
    # Zero point offsets (§3.12): G53 none (basic state), G54..G59 the ZPO table's entries 02..07.
    g(53, 14, "wcs", None, step="wcs"),
    *[g(n, 14, "wcs", n - 52, step="wcs") for n in range(54, 60)],
    # TRO approach (§3.10): G138 direct, G139 with transition blocks (basic state).
    g(138, 18, "tro_approach", "A", step="modes"),
    g(139, 18, "tro_approach", "B", step="modes"),
    # Circle centre (§3.11): G161 absolute, G162 relative to the start (basic state).
    g(161, 19, "centre_mode", True, step="modes"),
    g(162, 19, "centre_mode", False, step="modes"),
    # Rounding of linear blocks (§3.13): G36 on, G37 off (basic state).
    g(36, 20, "block_rounding", True, step="modes"),
    g(37, 20, "block_rounding", False, step="modes"),
])

POWER_ON = tuple(gkey(n) for n in (1, 17, 90, 20, 94, 71, 40, 53, 139, 162, 37))

M_CODES = table([
    m(0, "stop", "program_stop", step="stop"),  # §4.1.1: after the block's motion
    m(1, "stop", "optional_stop", step="stop"),
    m(2, "stop", "end", step="stop"),  # §2.2: M30 or M02 ends the program
    m(30, "stop", "end", step="stop"),
    m(29, "subroutine_end", step="stop"),  # §4.1.4
    m(3, "spindle", 1, step="spindle"),
    m(4, "spindle", -1, step="spindle"),
    m(5, "spindle", 0, step="spindle"),
    m(13, "spindle_2", 1, step="spindle"),
    m(14, "spindle_2", -1, step="spindle"),
    m(15, "spindle_2", 0, step="spindle"),
    m(6, "tool_change", step="tool_change"),  # the usual tool change (§4.5, the examples)
    m(19, "spindle_orient", step="spindle"),  # §4.1.7: to position 0
    m(25, "plc_read", False, step="setting"),  # §4.2: PLC transfer parameters → R1000+n, no sync
    m(112, "plc_read", True, step="setting"),  # §4.2: the same, the decoder waits for the PLC
    m(26, "axis_group_wait", step="modes"),  # §4.1.5
    *[refused(number, note) for number, note in (
        (17, "the Vconst speed limit of constant cutting speed (§4.1.7): no cutting-speed model"),
        (18, "constant cutting speed (§4.1.7): no cutting-speed model"),
        (20, "spindle 2's Vconst speed limit (§4.1.7): no cutting-speed model"),
        (21, "spindle 2's constant cutting speed (§4.1.7): no cutting-speed model"),
        (22, "spindle 2 positioning (§4.1.7): spindle 2 has no position axis here"),
        (27, "synchronous control of a slave axis to spindle 1 (§4.1.8): no synchronous axes here"),
        (28, "synchronous control of a slave axis to spindle 2 (§4.1.8): no synchronous axes here"),
        (96, "acceleration override (§4.1.6): the tool path carries no acceleration scale to the motion "
             "stage"),
    )],
])

#: M codes of one kind may not share a block.
M_GROUPS = {
    "stop": frozenset(gkey(n) for n in (0, 1, 2, 29, 30)),
    "spindle": frozenset(gkey(n) for n in (3, 4, 5, 19)),
    "spindle_2": frozenset(gkey(n) for n in (13, 14, 15)),
}

#: Assigned addresses (§2.4.2) and axes (§2.6). Lengths: ±214 000 mm at 0.1 µm (§2.7).
_LENGTH = AddressRule(-TRAVEL_MM, TRAVEL_MM, "length")
ADDRESSES = {
    **{letter: _LENGTH for letter in "XYZIJKABCUVWQ"},
    "F": AddressRule(0.0, 1e9, "plain"),
    "S": AddressRule(-1e9, 1e9, "plain"),
    "T": AddressRule(0, 99_999_999, "integer"),
    "D": AddressRule(0, 40, "integer"),  # D0..D40; D00 deselects (§11.1)
    "H": AddressRule(0, 99_999_999, "integer"),
    "G": AddressRule(0, 999, "integer"),
    "M": AddressRule(0, 999, "integer"),
    "N": AddressRule(0, 99_999_999, "integer"),
}

#: The order in which one block's items run (§2.3: the controller fixes it; the manual does not print
#: it). Parameter assignments have run before (the runner); then the modes, the technology words and the
#: pre-motion M functions, the settings, the motion, and last the stops (M00 "after execution of this
#: motion statement", §4.1.1).
EXECUTION_ORDER = (
    "units", "feed_mode", "distance", "plane", "mirror", "wcs", "modes", "feed", "spindle_speed", "tool",
    "tool_change", "spindle", "cutter_comp", "setting", "dwell", "motion", "stop",
)  # fmt: skip

#: Words with actions: F (feed), S (spindle speed), T (tool location, to the PLC), D (the tool offset
#: record: length and radius), H (auxiliary function, to the PLC).
WORDS = {
    "F": CodeSpec("F", -1, "feed", step="feed"),
    "S": CodeSpec("S", -1, "spindle_speed", step="spindle_speed"),
    "T": CodeSpec("T", -1, "tool", step="tool"),
    "D": CodeSpec("D", -1, "tool_offset", step="tool"),
    "H": CodeSpec("H", -1, "auxiliary", step="tool"),
}

#: Machine-specific M codes of the manual's examples (passed to the PLC, meaning set by the machine builder).
MACHINE_MCODES = {gkey(80): "a message to the PLC (the manual's tool-life example)"}
