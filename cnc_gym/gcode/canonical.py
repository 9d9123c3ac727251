"""The canonical output boundary: program coordinates → machine coordinates → :class:`ToolpathBuilder`.

Everything the interpreter emits passes through here. :class:`OffsetStack` holds the chain that turns a
program coordinate into a machine coordinate (GSK 25i, seed notes §3.9-§3.12):

    machine = program + local (G52) + work origin,
    work origin = G92 floating origin while one is set, else external offset (G10 L2 P0) + G54..G59 offset.

:class:`CanonicalMachine` keeps the current machine position and appends segments. Later transforms
(G51 scaling, G68 rotation, cutter compensation, tool length offset) plug in between the interpreter's
program-coordinate targets and :meth:`CanonicalMachine.straight_feed` & co.
"""

from __future__ import annotations

import math

from cnc_gym.toolpath import PLANE_AXES, Plane, SegmentKind, SegmentMode, ToolpathBuilder

Vec = tuple[float, float, float]
_PLANE_AXES = {int(p): axes for p, axes in PLANE_AXES.items()}
_ARC = SegmentKind.ARC
ZERO: Vec = (0.0, 0.0, 0.0)


class OffsetStack:
    """Work offsets of one program run, all in mm (stored physically; G20/G21 do not rescale them)."""

    def __init__(self, n_wcs: int = 6) -> None:
        self.external: list[float] = [0.0, 0.0, 0.0]  # G10 L2 P0
        self.wcs: list[list[float]] = [[0.0, 0.0, 0.0] for _ in range(n_wcs)]  # G54..G59 (index 0..5)
        self.active_wcs = 0
        self.local: list[float] = [0.0, 0.0, 0.0]  # G52
        self.floating: list[float] | None = None  # G92 origin in machine coordinates, or None
        self.origin: Vec = ZERO
        self.update()

    def work_origin(self) -> list[float]:
        if self.floating is not None:
            return list(self.floating)
        w = self.wcs[self.active_wcs]
        return [self.external[a] + w[a] for a in range(3)]

    def update(self) -> None:
        """Recompute the program→machine translation after any change."""
        work = self.work_origin()
        self.origin = (work[0] + self.local[0], work[1] + self.local[1], work[2] + self.local[2])

    def select_wcs(self, index: int) -> None:
        """G54..G59. GSK: selecting any work coordinate system drops a G92 floating system (L1707-L1712)."""
        self.active_wcs = index
        self.floating = None
        self.update()

    def set_floating(self, axis: int, machine_pos: float, program_value: float) -> None:
        """G92 on one axis: the current machine position gets ``program_value``; clears that axis's G52."""
        if self.floating is None:
            self.floating = self.work_origin()
        self.floating[axis] = machine_pos - program_value
        self.local[axis] = 0.0

    def to_machine(self, program: Vec) -> Vec:
        o = self.origin
        return (program[0] + o[0], program[1] + o[1], program[2] + o[2])

    def to_program(self, machine: Vec) -> Vec:
        o = self.origin
        return (machine[0] - o[0], machine[1] - o[1], machine[2] - o[2])


class FastToolpathBuilder(ToolpathBuilder):
    """ToolpathBuilder with a scalar-math ``arc``: the same rows, nearly half the cost per arc.

    The base class computes radius and start angle with numpy scalar functions (several µs per call on
    the interpreter's hot path). This override computes the same two values with :mod:`math`; the test
    ``tests/gcode/test_canonical.py`` checks row for row that both give the same Toolpath.
    """

    def arc(self, start, end, center, plane: Plane, sweep: float, feed: float, **kw) -> None:
        u, v, w = _PLANE_AXES[plane]
        c = list(center)
        c[w] = start[w]
        du = start[u] - c[u]
        dv = start[v] - c[v]
        self._append(_ARC, tuple(start), tuple(end), feed=feed, center=tuple(c), plane=plane,
                     radius=math.hypot(du, dv), start_angle=math.atan2(dv, du), sweep=sweep,
                     **kw)  # fmt: skip


class CanonicalMachine:
    """Current machine position plus the per-segment context; appends segments to a builder."""

    def __init__(self, builder: ToolpathBuilder, start: Vec = ZERO) -> None:
        self.builder = builder
        self.position: Vec = tuple(float(c) for c in start)  # type: ignore[assignment]
        self.line = 0
        self.file_index = 0
        self.modes = SegmentMode.NONE
        self.tool = 0
        self.spindle_rpm = 0.0

    def _context(self) -> dict:
        return {"line": self.line, "file_index": self.file_index, "modes": self.modes, "tool": self.tool,
                "spindle_rpm": self.spindle_rpm}  # fmt: skip

    def straight_traverse(self, target: Vec) -> None:
        """Rapid to a machine-coordinate target (no segment for a zero-length move)."""
        if target != self.position:
            self.builder.rapid(self.position, target, line=self.line, file_index=self.file_index,
                               modes=self.modes, tool=self.tool, spindle_rpm=self.spindle_rpm)  # fmt: skip
            self.position = target

    def straight_feed(self, target: Vec, feed: float) -> None:
        """Feed move to a machine-coordinate target at ``feed`` mm/min."""
        if target != self.position:
            self.builder.line(self.position, target, feed, line=self.line, file_index=self.file_index,
                              modes=self.modes, tool=self.tool, spindle_rpm=self.spindle_rpm)  # fmt: skip
            self.position = target

    def arc_feed(self, end: Vec, center: Vec, plane: Plane, sweep: float, feed: float) -> None:
        """Arc or helix (signed sweep in rad, + = CCW about the plane normal) to ``end``."""
        self.builder.arc(self.position, end, center, plane, sweep, feed, line=self.line,
                         file_index=self.file_index, modes=self.modes, tool=self.tool,
                         spindle_rpm=self.spindle_rpm)  # fmt: skip
        self.position = end

    def dwell(self, seconds: float, modes: SegmentMode = SegmentMode.NONE) -> None:
        context = self._context()
        context["modes"] = self.modes | modes
        self.builder.dwell(self.position, seconds, **context)
