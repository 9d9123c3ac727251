"""The canonical output boundary: offsets compose."""

from __future__ import annotations

import pytest

from cnc_gym.gcode.canonical import OffsetStack


def test_offset_stack_composition():
    stack = OffsetStack()
    stack.external[:] = [1.0, 2.0, 3.0]
    stack.wcs[1][:] = [10.0, 20.0, 30.0]
    stack.select_wcs(1)
    stack.local[:] = [0.5, 0.0, -0.5]
    stack.update()
    # machine = program + local + external + G55
    assert stack.to_machine((0.0, 0.0, 0.0)) == (11.5, 22.0, 32.5)
    assert stack.to_program(stack.to_machine((1.0, 2.0, 3.0))) == pytest.approx((1.0, 2.0, 3.0))
    # G92 X0 at machine X = 100: the floating origin replaces external + G55 on every axis; X's G52 goes.
    stack.set_floating(0, 100.0, 0.0)
    stack.update()
    assert stack.to_machine((0.0, 0.0, 0.0)) == (100.0, 22.0, 32.5)
    stack.select_wcs(0)  # G54 drops the floating system
    assert stack.to_machine((0.0, 0.0, 0.0)) == (1.0, 2.0, 2.5)


def test_select_wcs_none_is_no_work_offset_and_a_bad_index_is_refused():
    # A DIN controller's G53 selects no work offset at all: not a sentinel index into the stack.
    stack = OffsetStack()
    stack.wcs[0] = [10.0, 20.0, 30.0]
    stack.wcs[-1] = [7.0, 7.0, 7.0]  # G54.1 P48: a negative index would silently pick it
    stack.select_wcs(0)
    assert stack.origin == (10.0, 20.0, 30.0)
    stack.select_wcs(None)
    assert stack.origin == (0.0, 0.0, 0.0) and stack.extra_wcs_number == 0
    with pytest.raises(ValueError, match="index -1"):
        stack.select_wcs(-1)
    with pytest.raises(ValueError):
        stack.select_wcs(len(stack.wcs))
