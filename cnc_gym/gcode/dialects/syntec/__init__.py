"""``syntec``: the Syntec 8.20 mill controller (Syntec 8.20 mill programming manual, 2015), a member of the
Fanuc family with its own units, comments, modes, cycles and calls. docs/syntec.md lists every difference
from the family with its reason; docs/syntec_examples.md and docs/syntec_alarms.md index the manual's
worked examples and alarms against the tests.

The folder: ``codes.py`` (tables, addresses, alarms), ``options.py`` (its parameters and its features'
state), ``reader.py`` (``//`` comments, least-unit literals), ``blocks.py`` (words a code takes for itself,
block checks), ``modes.py`` (G04, G70/G71, default F, G05/G05.1 smoothing, G33, G96/G97, G06.2's feed),
``cycles.py`` (G73-G89), ``patterns.py`` (G134-G137.1), ``coordinates.py`` (G54-G59.9, G10, G30, G16, G68),
``measurement.py`` (G37, G37.1), ``calls.py`` (M98 P H L).
"""

from __future__ import annotations

from dataclasses import replace

from cnc_gym.gcode.dialect import Dialect
from cnc_gym.gcode.dialects.syntec import (
    blocks,
    calls,
    coordinates,
    cycles,
    measurement,
    modes,
    patterns,
)
from cnc_gym.gcode.dialects.syntec.codes import ADDRESSES, ALARMS, G_CODES, M_CODES, M_GROUPS, POWER_ON
from cnc_gym.gcode.dialects.syntec.options import SyntecOptions
from cnc_gym.gcode.dialects.syntec.reader import SyntecReader
from cnc_gym.gcode.lang import fanuc
from cnc_gym.gcode.lang.fanuc import checks, codes
from cnc_gym.gcode.lang.fanuc import cycles as family_cycles
from cnc_gym.gcode.lang.fanuc.least_units import evaluate
from cnc_gym.gcode.settings import CompensationSettings, CycleParameters

#: The family's block hooks with Syntec's word normaliser and checks, its default feed (§G01: "1000 mm/min
#: for G94 mode") and the G05 end-of-program rule.
HOOKS = replace(
    fanuc.HOOKS,
    normalise=blocks.normalise,
    checks=(family_cycles.check_codes, blocks.check_block, checks.axis_owners, family_cycles.check_mode),
    initial_feed=SyntecOptions().default_feed_per_minute,
    finish=(*fanuc.HOOKS.finish, modes.finish),
)
#: The family's language with Syntec's reader, least-unit evaluator and label calls.
LANGUAGE = replace(fanuc.LANGUAGE, name="syntec", reader=SyntecReader, evaluate=evaluate,
                   runner=calls.SyntecRunner)  # fmt: skip

DIALECT = Dialect(
    name="syntec",
    title="Syntec 8.20 mill",
    gcodes=G_CODES,
    mcodes=M_CODES,
    power_on=POWER_ON,
    execution_order=codes.EXECUTION_ORDER,
    addresses=ADDRESSES,
    words=codes.WORDS,
    actions={**fanuc.ACTIONS, **modes.ACTIONS, **coordinates.ACTIONS, **cycles.ACTIONS, **patterns.ACTIONS,
             **measurement.ACTIONS, **calls.ACTIONS},
    cycles=cycles.CYCLES,
    language=LANGUAGE,
    hooks=HOOKS,
    functions=codes.FUNCTIONS,
    alarms=ALARMS,
    # §G70/G71 and the decimal-point rule: a length without a decimal point is in least input units,
    # 0.001 mm (G71) or 0.0001 inch (G70) (reader.py).
    integer_is_unit=False,
    least_increment_mm=0.001,
    least_increment_inch=0.0001,
    # The manual's own G68 example needs a tolerance: its R8 half circles have chords 0.18 µm longer than
    # 16 mm. A 10 µm radius difference is allowed on I/J/K arcs.
    arc_radius_tolerance_mm=0.01,
    # G92 shifts every work system (the Fanuc 0M rule the manual claims; its own §G53 example sets G92
    # and then selects G54, which would be pointless if G54 dropped it; docs/syntec.md).
    g92_shifts_work_systems=True,
    # Pr4002 peck return d (G73, G83, peck tapping), Pr4020 shift direction 0 (+ first axis of the plane),
    # the drilling axis normal to the plane (G17 Z, G18 Y, G19 X).
    cycle_params=CycleParameters(g73_retract_mm=0.5, g83_clearance_mm=0.5, drilling_axis_follows_plane=True,
                                 shift_direction=0),
    m_groups=M_GROUPS,
    corner_words=frozenset(),
    # The macro language is the family's Macro B (the manual does not describe one; docs/syntec.md).
    keywords=frozenset({"IF", "GOTO", "WHILE", "DO", "END", "THEN"}),
    condition_operators=frozenset({"AND", "OR"}),
    system_variables=(
        (1000, 1135), (2001, 2906), (3000, 3012), (3901, 3902), (4001, 4130), (5001, 5105), (10001, 13400),
    ),
    # §G43/G44/G49: the length offset acts on Z ("Z axis end coordinates"), and G43 H_ may come without Z.
    compensation=CompensationSettings(tool_length_type="A", startup_type="A", offset_count=400,
                                      length_needs_axis=False),
    options=SyntecOptions(),
)
