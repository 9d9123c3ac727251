"""Messages cite the dialect's own manual and parameters, never another controller's: the arc radius
check names the parameter that holds its tolerance where the dialect's manual names one (GSK 25i P1810,
Fanuc parameter 3410) and none elsewhere; the Fanuc family's rules cite GSK 25i sections only in the
GSK 25i dialect."""

from __future__ import annotations

import pytest
from gcode_helpers import program_error

#: Start (0, 0), centre (6, 0): start radius 6, end (10, 0) radius 4, far beyond every tolerance.
MISMATCH = "G01 X0. Y0. F100.\nG02 X10. Y0. I6. J0.\n"


@pytest.mark.parametrize(("dialect", "parameter"), [("gsk25i", "(P1810)"), ("fanuc", "(parameter 3410)"),
                                                     ("syntec", None), ("h4cm", None), ("azmc1", None)])
def test_arc_radius_mismatch_cites_the_dialects_own_parameter(dialect, parameter):
    err = program_error(MISMATCH, dialect=dialect)
    assert err.code == "arc-radius-mismatch"
    if parameter is None:
        assert "P1810" not in err.message and "parameter" not in err.message, err.message
    else:
        assert err.message.endswith(parameter) and ("P1810" in err.message) == (dialect == "gsk25i")


@pytest.mark.parametrize("dialect", ["gsk25i", "fanuc", "h4cm"])
def test_the_units_switch_cites_the_gsk_manual_only_in_the_gsk_dialect(dialect):
    err = program_error("G21\nG01 X1. F100.\nG20\n", dialect=dialect)
    assert err.code == "units-switch" and err.line == 3
    assert ("GSK 25i §3.2.19" in err.message) == (dialect == "gsk25i"), err.message


#: Errors of the family's language parts whose messages cite a GSK 25i section: DO loops nested too
#: deep, END without DO, a jump into a DO range (§3.7.5).
FAMILY_RULES = [
    pytest.param("WHILE[1 LT 2] DO1\nWHILE[1 LT 2] DO2\nWHILE[1 LT 2] DO3\nWHILE[1 LT 2] DO1\n"
                 "END1\nEND3\nEND2\nEND1\nM30\n", "§3.7.5", id="do-nesting"),
    pytest.param("G01 X1. F100.\nEND1\nM30\n", "§3.7.5", id="end-without-do"),
    pytest.param("GOTO5\nWHILE[#1 LT 2] DO1\nN5 #1=#1+1\nEND1\nM30\n", "§3.7.5", id="goto-into-do"),
]


@pytest.mark.parametrize(("text", "section"), FAMILY_RULES)
@pytest.mark.parametrize("dialect", ["gsk25i", "fanuc", "syntec"])
def test_family_rules_cite_gsk_sections_only_in_the_gsk_dialect(text, section, dialect):
    err = program_error(text, dialect=dialect)
    assert (f"GSK 25i {section}" in err.message) == (dialect == "gsk25i"), err.message
    if dialect != "gsk25i":
        assert "§" not in err.message and "()" not in err.message and " ," not in err.message, err.message


def test_dropping_a_citation_keeps_the_rest_of_the_message():
    from cnc_gym.gcode.dialect import drop_family_citations as drop

    assert drop("no M codes in NURBS mode (GSK 25i §3.2.5)") == "no M codes in NURBS mode"
    assert drop("a jump into a DO range (only jumps out are allowed, GSK 25i §3.7.5)") == (
        "a jump into a DO range (only jumps out are allowed)")
    assert drop("a G06.2 block (GSK 25i §3.2.5: only X Y Z)") == "a G06.2 block (only X Y Z)"
    assert drop("start (GSK 25i §3.2.5; in G91 write G06.2 X0)") == "start (in G91 write G06.2 X0)"
