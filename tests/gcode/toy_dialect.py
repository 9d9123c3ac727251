"""A toy dialect, kept as a test fixture and as the worked example of docs/dialects.md: the GSK 25i with
Fanuc's chamfer word ``,C`` in place of its ``,L`` — built from tables alone, no core edit.

    from toy_dialect import TOY
    interpret("G01 X10 ,C2 F100\\nY10\\n", dialect=TOY)
"""

from __future__ import annotations

from dataclasses import replace

from cnc_gym.gcode.codes import AddressRule
from cnc_gym.gcode.dialects.gsk25i import DIALECT as GSK

_addresses = {letter: rule for letter, rule in GSK.addresses.items() if letter != ",L"}
_addresses[",C"] = AddressRule(0.0, 999999.9999, "length")  # the chamfer distance, mm or inch

TOY = replace(GSK, name="toy-chamfer-c", title="GSK 25i with ,C chamfers", addresses=_addresses,
              corner_words=frozenset({",C", ",R"}))  # fmt: skip
