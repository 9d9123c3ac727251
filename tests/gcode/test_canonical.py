"""The canonical output boundary: the fast arc rows equal the toolpath package's own, offsets compose."""

from __future__ import annotations

import math
import random

import numpy as np
import pytest

from cnc_gym.gcode.canonical import FastToolpathBuilder, OffsetStack
from cnc_gym.toolpath import Plane, ToolpathBuilder


def test_fast_builder_gives_the_same_toolpath_as_the_reference_builder():
    # The interpreter appends arcs through FastToolpathBuilder (math instead of numpy scalars); every
    # field of the built Toolpath must match ToolpathBuilder's, for arcs in all planes, both directions,
    # helices and full circles, plus lines, rapids and dwells.
    rng = random.Random(7)
    fast, ref = FastToolpathBuilder(), ToolpathBuilder()
    for i in range(300):
        start = tuple(rng.uniform(-500, 500) for _ in range(3))
        end = tuple(rng.uniform(-500, 500) for _ in range(3))
        center = tuple(rng.uniform(-500, 500) for _ in range(3))
        plane = Plane(i % 3)
        sweep = rng.choice([-2 * math.pi, 2 * math.pi, rng.uniform(-6, 6)])
        kw = {"line": i + 1, "modes": i % 4, "tool": i % 5, "spindle_rpm": float(i)}
        for builder in (fast, ref):
            builder.arc(start, end, center, plane, sweep, 100.0 + i, **kw)
            builder.line(end, start, 50.0, **kw)
            builder.rapid(start, end, **kw)
            builder.dwell(end, 0.5, **kw)
    a, b = fast.build(), ref.build()
    for name in ("kind", "start", "end", "center", "plane", "radius", "start_angle", "sweep", "feed",
                 "dwell_s", "line", "file_index", "modes", "tool", "spindle_rpm", "length", "s_start"):
        np.testing.assert_allclose(getattr(a, name), getattr(b, name), rtol=1e-13, atol=1e-9, err_msg=name)


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
