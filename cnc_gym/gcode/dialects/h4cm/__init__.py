"""``h4cm``: the HUST H4C-M mill controller (HUST H4C-M manual, 2006), a Fanuc-like controller whose
language differs where it counts: one G code per block (the last wins), U/V/W as incremental X/Y/Z,
numbers without a decimal point in least increments, string block labels, and G65 as HUST's one-operation
macro instruction set over integer variables. docs/h4cm.md lists every difference from the Fanuc family
with its reason; docs/h4cm_examples.md and docs/h4cm_alarms.md index the manual's worked examples and
errors against the tests.

The folder: ``codes.py`` (tables, addresses, error numbers), ``options.py`` (its MCM parameters and its
features' state), ``reader.py`` (64-character blocks, string labels, G65 statements, variables in words),
``variables.py`` (#1-#9999 integers), ``macro.py`` (G65 operations, M98/M99, the part counter),
``blocks.py`` (the last G wins, U/V/W, the arc-mode and compensation rules), ``modes.py`` (CNC and
master/slave interpolation, #93), ``motion.py`` (G04, the R rule, G28/G29/G30), ``coordinates.py``
(G10, G68/G69 mirror, G51 scaling), ``cycles.py`` (G81-G89, G34-G37), ``grooves.py`` (G22-G25).
"""

from __future__ import annotations

from dataclasses import replace

from cnc_gym.gcode.dialect import Dialect
from cnc_gym.gcode.dialects.h4cm import blocks, coordinates, cycles, grooves, macro, modes, motion
from cnc_gym.gcode.dialects.h4cm.codes import (
    ADDRESSES,
    ALARMS,
    G_CODES,
    M_CODES,
    M_GROUPS,
    MACHINE_MCODES,
    POWER_ON,
)
from cnc_gym.gcode.dialects.h4cm.options import H4cmOptions
from cnc_gym.gcode.dialects.h4cm.reader import HustReader, evaluate
from cnc_gym.gcode.dialects.h4cm.variables import HustVariables
from cnc_gym.gcode.lang import fanuc
from cnc_gym.gcode.lang.fanuc import checks, codes
from cnc_gym.gcode.lang.fanuc import cycles as family_cycles
from cnc_gym.gcode.settings import CompensationSettings, CycleParameters

#: The family's hooks with the H4C-M's normaliser and block rules, its R rule for arcs and the power-on G01
#: feed (#112). The end of the text ends a program without M02/M30 (the project's rule, docs/gcode.md;
#: the controller's ERROR 18 is not raised, docs/h4cm_alarms.md).
HOOKS = replace(
    fanuc.HOOKS,
    normalise=blocks.normalise,
    checks=(family_cycles.check_codes, checks.axis_owners, family_cycles.check_mode, blocks.check_block),
    arc=motion.arc,
    initial_feed=H4cmOptions().power_on_feed,
)
#: The family's language with the H4C-M's reader, integer variables and G65 runner (no system variables).
LANGUAGE = replace(fanuc.LANGUAGE, name="h4cm", reader=HustReader, evaluate=evaluate, variables=HustVariables,
                   system_variables=None, runner=macro.HustRunner)  # fmt: skip

DIALECT = Dialect(
    name="h4cm",
    title="HUST H4C-M mill",
    gcodes=G_CODES,
    mcodes=M_CODES,
    power_on=POWER_ON,
    execution_order=codes.EXECUTION_ORDER,
    addresses=ADDRESSES,
    words=codes.WORDS,
    actions={**fanuc.ACTIONS, **modes.ACTIONS, **motion.ACTIONS, **coordinates.ACTIONS, **cycles.ACTIONS,
             **macro.ACTIONS, "hust_groove": grooves.groove},
    cycles=cycles.CYCLES,
    language=LANGUAGE,
    hooks=HOOKS,
    alarms=ALARMS,
    # §2.3.5: a number without a decimal point counts least increments, 0.001 mm in the 4/3 format.
    integer_is_unit=False,
    least_increment_mm=0.001,
    least_increment_inch=0.0001,
    arc_radius_tolerance_mm=0.01,
    # §2.3.5: at most 7 digits: a sign, 7 digits and a point after the letter.
    max_word_length=10,
    m_groups=M_GROUPS,
    machine_mcodes=MACHINE_MCODES,
    other_axes="ABC",
    variables=((1, 9999),),
    system_variables=(),
    # #282 G83 clearance d 2.000 mm; drilling along Z (the cycles are "special use for mill", G17).
    cycle_params=CycleParameters(g83_clearance_mm=2.0),
    # §3.39: five levels (ERROR 24).
    max_subprogram_nesting=5,
    # §3.40: 40 tool groups; the length offset on Z; G43 H_ may come without Z; start-up straight to the
    # vector of the next block (the start-up block builds the offset up, "full comp. starting at B"); an
    # arc round every outer corner ("the tool will make a circular movement").
    compensation=CompensationSettings(tool_length_type="A", startup_type="A", offset_count=40,
                                      length_needs_axis=False, outer_corner_arcs=True),
    options=H4cmOptions(),
)
