"""Dialects are data: a variant is built from tables alone, and the core follows them.

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import dataclasses

import pytest
from gcode_helpers import moves

from cnc_gym.gcode import DIALECT_MODULES, get_dialect, interpret
from cnc_gym.gcode.dialect import CodeSpec, gkey

GSK = get_dialect("gsk25i")


def test_registry_names_the_seed_dialects_and_fanuc():
    assert set(DIALECT_MODULES) == {"gsk25i", "fanuc", "h4cm", "syntec", "azmc1"}
    assert get_dialect(GSK) is GSK


def test_gsk_tables_are_consistent():
    # One power-on code per modal group, every power-on code implemented, every step known.
    groups = [GSK.gcodes[k].group for k in GSK.power_on]
    assert len(groups) == len(set(groups))
    assert all(GSK.gcodes[k].implemented for k in GSK.power_on)
    steps = set(GSK.execution_order)
    assert all(s.step in steps for s in (*GSK.gcodes.values(), *GSK.mcodes.values()))
    assert GSK.execution_order.index("feed") < GSK.execution_order.index("motion")
    assert GSK.execution_order[-1] == "stop"


def test_power_on_defaults_are_table_data():
    # GSK 1801#0 = 1 makes G01 the power-on motion; 1801#1 = 1 makes G18 the power-on plane. A dialect (or a
    # machine variant) changes the table; the core is untouched.
    power_on = (*(k for k in GSK.power_on if GSK.gcodes[k].group not in (1, 2)), gkey(1), gkey(18))
    variant = dataclasses.replace(GSK, name="gsk25i-g01-g18", power_on=power_on)
    out = moves("F100\nX10\nG02 X0 Z10 I-10\n", dialect=variant)
    assert out[0]["kind"] == "line"  # an axis-only block with the power-on motion G01
    # ZX plane (u = Z, v = X, normal +Y): turning from +X to +Z is clockwise about +Y, so G02 does it in
    # a quarter turn.
    assert out[1]["plane"] == "ZX" and out[1]["sweep_deg"] == -90.0


def test_order_of_execution_is_table_data():
    # "G54 G92 X0" with G92 floating at machine X = 7. GSK order: G54 (wcs) then G92 (setting): the new
    # floating system survives, so X1 → machine 8. With setting before wcs, G54 would drop it again:
    # X1 → G54 origin 0 + 1 = 1.
    text = "G00 X7\nG54 G92 X0\nG00 X1\n"
    assert moves(text)[-1]["end"][0] == 8.0
    order = list(GSK.execution_order)
    order.remove("setting")
    order.insert(order.index("wcs"), "setting")
    variant = dataclasses.replace(GSK, name="setting-first", execution_order=tuple(order))
    assert moves(text, dialect=variant)[-1]["end"][0] == 1.0


def test_a_code_is_added_by_a_table_entry():
    # G09 does not exist on the GSK 25i (§3.8). A dialect that has it as "exact stop, one shot
    # dwell-less" can map it onto an existing action — here G04's — with one table entry.
    gcodes = dict(GSK.gcodes)
    gcodes[gkey(9)] = CodeSpec("G09", 0, "dwell", step="dwell", uses_axes=True, words="P")
    variant = dataclasses.replace(GSK, name="with-g09", gcodes=gcodes)
    assert interpret("G09\n", dialect=variant).to_records()[0]["modes"] == ["exact_stop"]


def test_a_dialect_naming_an_unknown_action_is_refused():
    gcodes = dict(GSK.gcodes)
    gcodes[gkey(9)] = CodeSpec("G09", 0, "teleport", step="motion")
    with pytest.raises(ValueError, match="teleport"):
        interpret("G00 X1\n", dialect=dataclasses.replace(GSK, gcodes=gcodes))


def test_arc_tolerance_is_dialect_data():
    # P1810 = 0 switches the radius check off (GSK 25i parameter manual): the 0.02 mismatch is then accepted.
    lax = dataclasses.replace(GSK, arc_radius_tolerance_mm=0.0)
    arc = moves("G00 X10\nG03 X0 Y10.02 I-10 F100\n", dialect=lax)[-1]
    assert arc["radius"] == 10.0 and arc["end"] == [0.0, 10.0, 0.0]
