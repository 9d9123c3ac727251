"""``azmc1``: the AMK AZ-MC1 (AMK "CNC ISO programming", 1998), a DIN 66025 controller on the DIN language
family (``lang/din``): R parameters, ``$`` control blocks, ``LL``/``L`` calls. docs/azmc1.md lists what it
does and why; docs/azmc1_examples.md and docs/azmc1_alarms.md index the manual's worked examples and error
conditions against the tests.

The folder: ``codes.py`` (tables, addresses, order of execution), ``options.py`` (its machine data and its
features' state), ``modes.py`` (dwell, units, feed, G09/G60/G63/G36, G161/G162, mirroring, M29, the PLC),
``coordinates.py`` (G53-G59, G92, G98/G99 software limits, G74 homing), ``tools.py`` (the D record, TRO
rules, arcs, the tool table and its reader functions).
"""

from __future__ import annotations

from dataclasses import replace

from cnc_gym.gcode.dialect import BlockHooks, Dialect
from cnc_gym.gcode.dialects.azmc1 import coordinates, modes, tools
from cnc_gym.gcode.dialects.azmc1.codes import (
    ADDRESSES,
    EXECUTION_ORDER,
    G_CODES,
    M_CODES,
    M_GROUPS,
    MACHINE_MCODES,
    POWER_ON,
    WORDS,
)
from cnc_gym.gcode.dialects.azmc1.options import AzOptions
from cnc_gym.gcode.lang import din, fanuc
from cnc_gym.gcode.lang.fanuc import checks, compensation
from cnc_gym.gcode.settings import CompensationSettings

#: The family's axis-owner rule and the G74 spindle rule; the I/J/K arc; no feed at power-on; at the end the
#: compensation look-ahead is emitted and the software limits checked.
HOOKS = BlockHooks(
    checks=(checks.axis_owners, modes.check_spindle_with_homing),
    arc=tools.arc,
    initial_feed=None,
    finish=(compensation.finish, coordinates.check_soft_limits),
)
#: The DIN language with the AZ-MC1's tool-table functions.
LANGUAGE = replace(din.LANGUAGE, name="azmc1", reader=tools.AzReader, variables=tools.AzParameters)

DIALECT = Dialect(
    name="azmc1",
    title="AMK AZ-MC1",
    gcodes=G_CODES,
    mcodes=M_CODES,
    power_on=POWER_ON,
    execution_order=EXECUTION_ORDER,
    addresses=ADDRESSES,
    words=WORDS,
    actions={**fanuc.ACTIONS, **modes.ACTIONS, **coordinates.ACTIONS, **tools.ACTIONS},
    cycles={},
    language=LANGUAGE,
    hooks=HOOKS,
    power_on_actions=frozenset({"motion", "plane", "distance", "units", "wcs", "mirror", "block_rounding",
                                "centre_mode", "tro_approach"}),
    rotary_word_actions=frozenset(),
    axes="XYZ",
    other_axes="ABCUVWQ",
    functions=din.FUNCTIONS,
    alarms={},
    integer_is_unit=True,
    # 0.1 µm (§2.7: "4 places after the comma" in mm); in inch the same resolution, about 4 µin.
    least_increment_mm=0.0001,
    least_increment_inch=0.00001,
    # "There is an error message if the circle center point is wrongly defined" (§3.1.3); the tolerance is
    # not given: the family's 10 µm.
    arc_radius_tolerance_mm=0.01,
    max_word_length=64,
    max_m_per_block=3,
    m_groups=M_GROUPS,
    machine_mcodes=MACHINE_MCODES,
    keywords=frozenset(),
    # The D record: the length along the plane's tool axis (type B), carried by that axis's next move
    # (no axis word needed); D0..D40; start-up by G139 (transition blocks, type B) unless G138; a contour
    # violation is an error, not corrected (§11.3.5).
    compensation=CompensationSettings(tool_length_type="B", startup_type="B", length_needs_axis=False,
                                      offset_count=40, correct_interference=False),
    max_subprogram_nesting=10,
    options=AzOptions(),
)

__all__ = ["DIALECT", "AzOptions"]
