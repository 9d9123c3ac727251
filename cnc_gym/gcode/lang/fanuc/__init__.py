"""The Fanuc family: the language and features shared by Fanuc-style controllers (Fanuc 0i/16i, Haas,
GSK 25i, Syntec, HUST …), the default components of their dialects.

Language components (:data:`LANGUAGE`): the lexer (``reader.py``), the Macro B expression language
(``expressions.py``) and variable model (``variables.py``, ``sysvars.py``), control flow (``flow.py``,
``units.py``) and the call convention (``calls.py``).

Features, each a module of actions (``action(core, spec, values)``) that sees the core only through the
seam (:class:`~cnc_gym.gcode.dialect.Seam`):

=====================  ==================================================================================
``modal.py``           plane, distance mode, units, path modes, F S T, spindle, coolant, stops, G04 dwell
``motion.py``          G00-G03 and the modal motion, rotary axes, G53
``arcs.py``            the arc rule (I/J/K, R, full circles, helices)
``coordinates.py``     G54-G59, G54.1, G52, G92, G10 data input
``transforms.py``      G68/G69 rotation, G51/G50 scaling, G51.1/G50.1 mirror, G16/G15 polar input
``reference.py``       G27-G30 reference positions, G60 single-direction positioning
``probing.py``         G31 skip
``measurement.py``     G37 tool length measurement
``corners.py``         chamfer and corner rounding ``,L``/``,C``/``,R``
``compensation.py``    G40-G42 cutter compensation C, G43/G44/G49 tool length, G45-G48, G39
``cycles.py``          canned cycles G73-G89 (the cycle library :data:`CYCLES`), G98/G99, M29
``nurbs.py``           G05 P10000 contour control, G06.2 NURBS
``parameters.py``      G10 L50 parameter input and the parameters the features read
``checks.py``          block checks
=====================  ==================================================================================

A dialect builds its registry from :data:`ACTIONS` (adding or replacing entries), its cycle library from
:data:`CYCLES`, and its hooks from :data:`HOOKS`.
"""

from __future__ import annotations

from cnc_gym.gcode.dialect import BlockHooks, Language
from cnc_gym.gcode.lang.fanuc import (
    arcs,
    calls,
    checks,
    compensation,
    coordinates,
    corners,
    cycles,
    measurement,
    modal,
    motion,
    nurbs,
    parameters,
    probing,
    reference,
    transforms,
)
from cnc_gym.gcode.lang.fanuc.expressions import evaluate
from cnc_gym.gcode.lang.fanuc.flow import FlowRunner
from cnc_gym.gcode.lang.fanuc.hints import hint
from cnc_gym.gcode.lang.fanuc.reader import Reader
from cnc_gym.gcode.lang.fanuc.sysvars import SystemVariables
from cnc_gym.gcode.lang.fanuc.variables import VariableStore

#: The Fanuc family's action registry: action name → callable(core, spec, values).
ACTIONS = {
    **modal.ACTIONS,
    **motion.ACTIONS,
    **coordinates.ACTIONS,
    **transforms.ACTIONS,
    **reference.ACTIONS,
    **probing.ACTIONS,
    **measurement.ACTIONS,
    **compensation.ACTIONS,
    **cycles.ACTIONS,
    **nurbs.ACTIONS,
    **parameters.ACTIONS,
    **calls.ACTIONS,
}
#: The Fanuc family's cycle library: kind → CycleKind.
CYCLES = dict(cycles.CYCLES)
#: The Fanuc family's block hooks: two codes of one group are an error (the core), the cycle rules and the
#: axis-owner rule, the I/J/K-or-R arc, no feed at power-on; at the end a pending chamfer, an incomplete
#: NURBS curve and the compensation look-ahead are settled.
HOOKS = BlockHooks(
    checks=(cycles.check_codes, checks.axis_owners, cycles.check_mode),
    arc=arcs.arc,
    initial_feed=None,
    finish=(corners.finish, nurbs.finish, compensation.finish),
)
#: The Fanuc family's language components.
LANGUAGE = Language(
    name="fanuc",
    reader=Reader,
    evaluate=evaluate,
    variables=VariableStore,
    system_variables=SystemVariables,
    runner=FlowRunner,
    hint=hint,
)

__all__ = ["ACTIONS", "CYCLES", "HOOKS", "LANGUAGE"]
