"""The DIN 66025 family: the language of DIN-style controllers (AMK AZ-MC1 and its relatives), a family
of its own beside the Fanuc family (``lang/fanuc``).

Language components (:data:`LANGUAGE`):

=====================  ==================================================================================
``reader.py``          the lexer and block reader: nested ``( )`` comments, words ended by grammar, ``%n``
                       and ``%L<n>`` program units, ``R<n> = e`` assignments, ``$`` control blocks
``expressions.py``     the expression language: R/P parameters, ``[ ]``, ``+ - * / ** MOD``, comparisons,
                       functions in degrees, compiled to closures; truth is |x| ≥ 0.5
``parameters.py``      the variable model: global R parameters (a list, for speed)
``control.py``         ``$IF/$SWITCH/$FOR/$WHILE/$DO/$BREAK/$CONTINUE/$TIME`` compiled to jump tables
``runner.py``          the program-counter loop, ``LL``/``L`` calls, M29, nesting 10, the run's bounds
``hints.py``           what a Fanuc-style line that fails to read probably is, and how DIN writes it
=====================  ==================================================================================

A dialect takes :data:`LANGUAGE` as it is, or subclasses the reader (its data functions and procedures,
e.g. a tool table's ``TLOC[n]``) and the parameter store (the data those read).
"""

from __future__ import annotations

from cnc_gym.gcode.dialect import Language
from cnc_gym.gcode.lang.din.expressions import FUNCTIONS, evaluate
from cnc_gym.gcode.lang.din.hints import hint
from cnc_gym.gcode.lang.din.parameters import ParameterStore
from cnc_gym.gcode.lang.din.reader import DinProgram, DinReader
from cnc_gym.gcode.lang.din.runner import DinRunner

#: The DIN family's language components.
LANGUAGE = Language(
    name="din",
    reader=DinReader,
    evaluate=evaluate,
    variables=ParameterStore,
    system_variables=None,
    runner=DinRunner,
    hint=hint,
)

__all__ = ["FUNCTIONS", "LANGUAGE", "DinProgram", "DinReader", "DinRunner", "ParameterStore"]
