"""``fanuc``: a generic Fanuc 0i-M / Haas-class 3-axis mill, the Fanuc family with the differences a shop
program written for such a machine needs (docs/fanuc.md lists each difference from the GSK 25i with its
reason).
"""

from __future__ import annotations

from dataclasses import replace

from cnc_gym.gcode.codes import gkey
from cnc_gym.gcode.dialect import Dialect
from cnc_gym.gcode.dialects.fanuc import blocks, engraving
from cnc_gym.gcode.dialects.fanuc.codes import ADDRESSES, ALARMS, G_CODES, M_CODES, MACHINE_MCODES, POWER_ON
from cnc_gym.gcode.lang import fanuc
from cnc_gym.gcode.lang.fanuc import abbreviations, checks, codes, cycles, least_units
from cnc_gym.gcode.settings import CompensationSettings, CycleParameters

#: Abbreviated words the dialect reads besides its functions' (lang/fanuc/abbreviations.py).
_STATEMENT_AND_OPERATOR_WORDS = frozenset({"WHILE", "GOTO", "END", "THEN", "AND", "XOR", "MOD"})

#: The family's block checks with the G00/G01-beside-G28 rule (blocks.py).
HOOKS = replace(fanuc.HOOKS, checks=(cycles.check_codes, blocks.motion_with_reference_return,
                                     checks.axis_owners, cycles.check_mode))  # fmt: skip

#: The family's language with the least-unit reading of numbers without a decimal point (DPI = 0): X1000
#: is 1 mm in G21 and 0.1 inch in G20 (lang/fanuc/least_units.py).
LANGUAGE = replace(fanuc.LANGUAGE, name="fanuc", reader=least_units.LeastUnitReader,
                   evaluate=least_units.evaluate)  # fmt: skip

DIALECT = Dialect(
    name="fanuc",
    title="Fanuc 0i-M / Haas-class mill",
    gcodes=G_CODES,
    mcodes=M_CODES,
    power_on=POWER_ON,
    execution_order=codes.EXECUTION_ORDER,
    addresses=ADDRESSES,
    words=codes.WORDS,
    actions={**fanuc.ACTIONS, **engraving.ACTIONS},
    cycles=dict(fanuc.CYCLES),
    language=LANGUAGE,
    hooks=HOOKS,
    axes="XYZ",
    other_axes="ABCUVW",
    functions=codes.FUNCTIONS,
    alarms=ALARMS,
    user_alarm_base=3000,  # #3000 = n (0..200): alarm 3000 + n
    # Parameter 3401#0 DPI = 0, the Fanuc standard: a number without a decimal point is in least input
    # increments of the unit in force (X1000 = 1 mm in G21, 0.1 inch in G20); IS-B: 0.001 mm, 0.0001 inch.
    integer_is_unit=False,
    calculator_input_parameter="parameter 3401#0 DPI",  # --calculator-input: DPI = 1
    least_increment_mm=0.001,
    least_increment_inch=0.0001,
    arc_radius_tolerance_mm=0.02,  # parameter 3410 (a typical setting)
    arc_tolerance_parameter="parameter 3410",
    # G92 shifts every work system G54-G59 by one vector until reset or reference return (Fanuc 0i).
    g92_shifts_work_systems=True,
    external_work_offset=True,  # G10 L2 P0, the EXT offset of the work offset screen
    # Parameters 5114, 5115; a cycle without R drills from the initial level and L is its repeat count
    # (Haas; the L of older Fanuc 0-M programs).
    cycle_params=CycleParameters(g73_retract_mm=0.5, g83_clearance_mm=0.5, r_defaults_to_initial=True,
                                 l_repeats=True),
    dwell_p_decimal_seconds=True,  # Haas: G04 P10. is 10 s, P10 10 ms; a cycle's P the same
    max_words_per_block=32,
    max_m_per_block=3,
    m_groups=codes.M_GROUPS,
    machine_mcodes=MACHINE_MCODES,
    accepts_machine_mcodes=True,  # the control hands an M code it does not know to the machine
    corner_words=frozenset({",C", ",R"}),
    max_bracket_depth=5,
    keywords=frozenset({"IF", "GOTO", "WHILE", "DO", "END", "THEN"}),
    # Fanuc's abbreviated macro words (WH[ is WHILE[, SQ[ is SQRT[ …), those whose word the dialect has.
    comment_codes=frozenset({gkey(47)}),  # G47's text is its block's comment (Haas)
    macro_abbreviations={a: w for a, w in abbreviations.FANUC_ABBREVIATIONS.items()
                         if w in codes.FUNCTIONS or w in _STATEMENT_AND_OPERATOR_WORDS},
    condition_operators=frozenset({"AND", "OR"}),  # IF[[#1 GT 0] AND [#2 LT 5]]GOTO10
    program_number_marks="O:",  # ":1234" is O1234 (ISO code)
    variables=((1, 33), (100, 199), (500, 999)),
    system_variables=(
        (1000, 1135), (2001, 2906), (3000, 3012), (3020, 3027), (3901, 3902), (4001, 4130), (5001, 5105),
        (5401, 6000), (10001, 13400),
    ),  # (#3020-#3027 and #5401-#6000: Haas's timers and tool life table, lang/fanuc/sysvars.py)
    # Tool length offset on Z whatever the plane (type A, parameter 5001#0 TLC = 0); G43 H_ alone puts it in
    # force for the next Z move.
    compensation=CompensationSettings(tool_length_type="A", startup_type="A", offset_count=400,
                                      length_needs_axis=False),
)
