"""The input unit at power-on (a controller parameter): ``interpret(units=)``, a machine preset's
``power_on_units``, the dialect's power-on code, and a program's own G20/G21.

Precedence: the argument over the preset over the dialect's power-on code; a G20/G21 in the program rules
over all three from its block on.
"""

from __future__ import annotations

import pytest

from cnc_gym.errors import ConfigError
from cnc_gym.gcode import interpret
from cnc_gym.machine import machine_from_dict
from tests.gcode.dialects.fanuc.test_fanuc import HAAS_INCH

INCH = machine_from_dict({"power_on_units": "inch"}, source="inch.yaml")
METRIC = machine_from_dict({"power_on_units": "mm"}, source="metric.yaml")
UNSET = machine_from_dict({}, source="plain.yaml")


def first_x(text: str, **options) -> float:
    """X (mm, machine) at the end of the first move."""
    return float(interpret(text, **options).end[0][0])


@pytest.mark.parametrize("dialect", ["gsk25i", "fanuc", "syntec"])
@pytest.mark.parametrize(
    ("options", "expected"),
    [
        ({}, 1.0),  # the dialect's power-on code: G21 (Syntec: G71)
        ({"machine": UNSET}, 1.0),  # a preset without the key changes nothing
        ({"machine": INCH}, 25.4),  # the preset's parameter
        ({"machine": METRIC}, 1.0),
        ({"units": "inch"}, 25.4),  # the argument
        ({"units": "inch", "machine": METRIC}, 25.4),  # the argument over the preset
        ({"units": "mm", "machine": INCH}, 1.0),
    ],
)
def test_precedence_argument_preset_dialect(dialect, options, expected):
    assert first_x("G00 X1.\n", dialect=dialect, **options) == pytest.approx(expected)


@pytest.mark.parametrize("dialect", ["gsk25i", "fanuc"])
def test_the_programs_own_g20_g21_rules(dialect):
    assert first_x("G21 G00 X1.\n", dialect=dialect, units="inch", machine=INCH) == pytest.approx(1.0)
    assert first_x("G20 G00 X1.\n", dialect=dialect, units="mm", machine=METRIC) == pytest.approx(25.4)


def test_syntec_uses_its_own_unit_codes():
    assert first_x("G71 G00 X1.\n", dialect="syntec", machine=INCH) == pytest.approx(1.0)
    assert first_x("G70 G00 X1.\n", dialect="syntec", units="mm") == pytest.approx(25.4)


def test_an_inch_shop_program_without_g20_on_an_inch_preset():
    # The Haas-style program of test_fanuc, run on a preset whose power-on unit is inch: no argument needed.
    tp = interpret(HAAS_INCH, dialect="fanuc", machine=INCH, tool_offsets={"H": {1: 101.6}})
    by_argument = interpret(HAAS_INCH, dialect="fanuc", units="inch", tool_offsets={"H": {1: 101.6}})
    assert tp.to_records() == by_argument.to_records()
    rapid, approach, plunge = tp.to_records()[:3]
    assert rapid["end"] == pytest.approx([25.4, 25.4, 0.0])  # X1. Y1.
    assert approach["end"] == pytest.approx([25.4, 25.4, 25.4 + 101.6])  # G43 H01 Z1.
    assert plunge["feed"] == pytest.approx(254.0)  # F10. in/min
    # The same text on the metric preset is another part (X1. = 1 mm).
    assert first_x(HAAS_INCH, dialect="fanuc", machine=METRIC) == pytest.approx(1.0)


def test_the_feed_of_an_inch_power_on_is_in_inch_per_minute():
    (line,) = interpret("G01 X1. F10.\n", dialect="gsk25i", machine=INCH).to_records()
    assert line["end"] == pytest.approx([25.4, 0.0, 0.0]) and line["feed"] == pytest.approx(254.0)
    assert "inch_program" in line["modes"]


@pytest.mark.parametrize("bad", ["cm", "INCH", "", 25.4])
def test_a_bad_preset_value_is_one_line_naming_the_key(bad):
    with pytest.raises(ConfigError, match=r"inch\.yaml.*power_on_units.*must be one of null, mm, inch"):
        machine_from_dict({"power_on_units": bad}, source="inch.yaml")


def test_a_bad_argument_is_a_config_error():
    with pytest.raises(ConfigError, match="units must be 'mm' or 'inch'"):
        interpret("G00 X1\n", units="inches", machine=INCH)
