"""Names and constants that the interpreter and the commands share with the machine records: the default
machine preset's name, the power-on input units and the inch.

They live here rather than in :mod:`cnc_gym.machine` (which re-exports them) so that the interpreter and
``cnc-gym trace`` without a preset do not load the machine records and their config schema (dataclasses
built at import: a tenth of the command's start-up).
"""

from __future__ import annotations

#: The machine preset used where none is named (``cnc-gym run``, the envs, ``bench``, ``load_machine()``).
DEFAULT_MACHINE = "vmc-small"
#: The input units a controller can be in at power-on (a preset's ``power_on_units``,
#: ``interpret(units=)``, ``--units``): G21 millimetres or G20 inches.
INPUT_UNITS = ("mm", "inch")
#: Millimetres in an inch (the interpreter's G20 scale, a setup in inch, the rotary feed rule in G20).
INCH_MM = 25.4
