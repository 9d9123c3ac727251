"""Tool compensation: cutter radius compensation C (G40/G41/G42, G39), tool length and position offsets.

Three parts:

* ``geometry.py``: the plane geometry, pure functions (offset curves, the corner rules of type C, the
  interference check and its correction, a whole compensated sequence);
* ``stage.py``: :class:`~cnc_gym.gcode.lang.fanuc.compensation.stage.OffsetStage`, an output stage
  (:class:`~cnc_gym.gcode.canonical.Output`) in front of the canonical machine with the look-ahead the
  corners need;
* ``actions.py``: the interpreter's actions and hooks (the codes and the D/H words), which this package
  exports.

Sections (§n) are those of the GSK 25i programming manual.
"""

from cnc_gym.gcode.lang.fanuc.compensation.actions import (
    ACTIONS,
    before_block,
    before_machine_move,
    cancel_length_at_intermediate,
    check_plane,
    corner_arc,
    cutter,
    finish,
    install,
    length,
    offset_words,
    position_offset,
    restore_length,
    signed_offset,
    words,
)

__all__ = ["ACTIONS", "before_block", "before_machine_move", "cancel_length_at_intermediate", "check_plane",
           "corner_arc", "cutter", "finish", "install", "length", "offset_words", "position_offset",
           "restore_length", "signed_offset", "words"]  # fmt: skip
