"""GSK 25i (milling): the reference dialect, a member of the Fanuc family.

Sources are the GSK 25i programming manual (sections cited as "§n") and its parameter volume. This folder
holds what is the GSK's own: its code tables, addresses and alarm numbers (``codes.py``), its special
canned cycles (pockets and bosses, ``pockets.py``) and hole patterns (``patterns.py``); everything else is
the Fanuc family's (``cnc_gym/gcode/lang/fanuc``). docs/gsk25i.md describes the dialect.

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

from dataclasses import replace

from cnc_gym.gcode.codes import AddressRule
from cnc_gym.gcode.dialect import Dialect
from cnc_gym.gcode.dialects.gsk25i import patterns, pockets
from cnc_gym.gcode.dialects.gsk25i.codes import ADDRESSES, ALARMS, G_CODES, M_CODES, POWER_ON
from cnc_gym.gcode.lang import fanuc
from cnc_gym.gcode.lang.fanuc import checks, codes, cycles
from cnc_gym.gcode.settings import CycleParameters

#: GSK 25i parameter numbers of the parameters the features read (parameter volume).
PARAMETER_NUMBERS = {
    "reference_2": 1051, "reference_3": 1052, "reference_4": 1053,  # 2nd-4th reference positions
    "rotation_angle": 1860, "scale": 1861, "scale_axis": 1862,  # G68 angle, G51 magnifications
    "positioning_overrun": 1880,  # G60 overrun
    "measure_feed": 2651, "measure_decel": 2652, "measure_band": 2653,  # G37
}  # fmt: skip
#: Raw ranges checked when G10 L50 writes them.
PARAMETER_RANGES = {1051: 99999999, 1052: 99999999, 1053: 99999999, 1880: 9999999, 1860: 360000, 1861: 99999,
                    1862: 99999}  # fmt: skip

#: The family's block checks with the patterns' own (a G124/G125 takes its block's cycle code).
HOOKS = replace(fanuc.HOOKS,
                checks=(cycles.check_codes, patterns.check_block, checks.axis_owners, cycles.check_mode))

DIALECT = Dialect(
    name="gsk25i",
    title="GSK 25i milling",
    gcodes=G_CODES,
    mcodes=M_CODES,
    power_on=POWER_ON,
    execution_order=codes.EXECUTION_ORDER,
    addresses=ADDRESSES,
    words=codes.WORDS,
    actions={**fanuc.ACTIONS, **patterns.ACTIONS},
    cycles={**fanuc.CYCLES, **pockets.CYCLES},
    language=fanuc.LANGUAGE,
    hooks=HOOKS,
    axes="XYZ",
    other_axes="ABCUVW",
    parameter_input_r=AddressRule(-99999999.0, 99999999.0, "integer", point_allowed=False, alarm=8),
    parameter_numbers=PARAMETER_NUMBERS,
    parameter_ranges=PARAMETER_RANGES,
    functions=codes.FUNCTIONS,
    alarms=ALARMS,
    user_alarm_base=3000,  # #3000 = n: alarm 3000 + n (§3.7.3)
    integer_is_unit=True,  # 1800#0 DPI standard setting 1: X10 = 10 mm (§2.5; parameter manual §4.7)
    least_increment_mm=0.0001,  # §3.2.19
    least_increment_inch=0.0001,
    arc_radius_tolerance_mm=0.01,  # P1810
    arc_tolerance_parameter="P1810",
    family_manual="GSK 25i",  # the family's messages cite its sections
    external_work_offset=True,  # G10 L2 P0 (§3.2.10)
    cycle_params=CycleParameters(),  # P2010/P2011 = 0.5 mm, P2000 = 0, P2141/2142 = 1000 r/min
    max_words_per_block=32,  # alarm 12
    max_m_per_block=3,  # 1803#6 M3B standard 1
    m_groups=codes.M_GROUPS,
    corner_words=frozenset({",L", ",R"}),
    max_bracket_depth=5,  # §3.7.4
    keywords=frozenset({"IF", "GOTO", "WHILE", "DO", "END", "THEN"}),
    variables=((1, 33), (100, 199), (500, 999)),
    system_variables=(
        (1000, 1135), (2001, 2906), (3000, 3012), (3901, 3902), (4001, 4130), (5001, 5105), (10001, 13400),
    ),
)
