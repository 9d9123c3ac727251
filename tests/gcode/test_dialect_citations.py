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
