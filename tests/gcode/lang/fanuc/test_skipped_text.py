"""No silent truncation: text of a program file that the control does not run is named in a note on the
tool path (``Toolpath.notices``, printed by ``cnc-gym trace`` and ``run``): the leader before the tape start
'%', text after the end-of-tape '%', and ``O`` programs of the file that are never called."""

from __future__ import annotations

import pytest

from cnc_gym.gcode import interpret

BODY = "".join(f"G01 X{i}. F100.\n" for i in range(1, 301))


@pytest.mark.parametrize("dialect", ["gsk25i", "fanuc", "syntec"])
def test_a_program_after_an_o_boundary_that_is_never_called_is_named(dialect):
    # A block before O4001 and 300 blocks after it: the main program is the text before O4001, as on the
    # control; O4001 is a program of its own that runs only when called, and the note says so.
    text = "%\nG00 Z4.\nO4001 (PART)\n" + BODY + "M30\n%\n"
    tp = interpret(text, dialect=dialect)
    assert len(tp) == 1 and tp.end[0].tolist() == [0.0, 0.0, 4.0]
    assert tp.notices == ("<program>:3: note: program O4001 (lines 3-304, 302 blocks) in this file was never "
                          "called: the run ended with the main program (lines 2-2); call it with M98 P or "
                          "G65 P, or make it the first program of the file [uncalled-program]",)  # fmt: skip
    # Called, it runs and there is nothing to say.
    called = interpret("%\nG00 Z4.\nM98 P4001\nM30\nO4001\n" + BODY + "M99\n%\n", dialect=dialect)
    assert len(called) == 301 and called.notices == ()


def test_only_the_programs_that_never_ran_are_named():
    text = "O1\nM98 P2\nM30\nO2\nG00 X1.\nM99\nO3\nG00 X9.\nM99\n"
    tp = interpret(text, dialect="fanuc")
    assert tp.end.tolist() == [[1.0, 0.0, 0.0]]
    assert len(tp.notices) == 1 and tp.notices[0].startswith("<program>:7: note: program O0003 (lines 7-9")


def test_the_leader_before_the_tape_start_is_not_read_and_is_named():
    # A simulator's directive before '%': the control skips what comes before the first '%' of a file.
    text = '($Message("load the machine settings") )\n%\nO0025\nG00 X1.\nM30\n'
    tp = interpret(text, dialect="fanuc")
    assert tp.end.tolist() == [[1.0, 0.0, 0.0]]
    assert tp.notices == ("<program>:1: note: line 1 before the tape start '%' (line 2) is the leader "
                          "section, not read (the control skips what comes before the first '%' of a file) "
                          "[leader-skipped]",)  # fmt: skip
    # A '%' that ends the file is the end of the tape: the text before it is the program.
    assert interpret("G00 X1.\nM30\n%\n", dialect="fanuc").notices == ()


def test_text_after_the_end_of_tape_is_named_and_a_tape_mark_may_carry_an_end_of_block():
    tp = interpret("%;\nG00 X2.\n%\nG00 X9.\n\nG00 X8.\n", dialect="fanuc")
    assert tp.end.tolist() == [[2.0, 0.0, 0.0]]
    assert tp.notices == ("<program>:3: note: lines 4-6 after the end-of-tape '%' (line 3) are not read "
                          "[after-end-of-tape]",)  # fmt: skip
