"""Cutter compensation's stage: an output stage (:class:`~cnc_gym.gcode.canonical.Output`) in front of the
canonical machine.

:class:`OffsetStage` receives programmed moves in machine coordinates (after the work offsets), keeps the
look-ahead the corners need (the manual's three-block buffer: a corner is resolved with the next move in
the plane if it comes within the next two blocks, else the vector is perpendicular to the block, §3.5.3),
and emits compensated moves (the tool length vector is already in every target:
``OffsetStack.tool_length``). ``position`` reports the *programmed* position, so the interpreter's
incremental and arc arithmetic stays in programmed coordinates. The corner and interference rules are the
pure functions of ``geometry.py``; G45-G48 position offsets are applied to the block's move here.

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import partial

from cnc_gym.gcode.lang.fanuc.compensation.geometry import (
    SAME_POINT,
    SMOOTH,
    CompensationError,
    PlaneElement,
    Point,
    Vec,
    arc_sweep_between,
    block_interference,
    cancel_with_direction,
    circle_point,
    corner,
    correct_interference,
    distance,
)
from cnc_gym.toolpath import PLANE_AXES, Plane, SegmentMode

#: Blocks the stage reads past a block to find the next move in the plane (executing + 2 buffered).
LOOKAHEAD_BLOCKS = 2


@dataclass(slots=True)
class _Item:
    """A programmed move waiting in the look-ahead buffer, with its block's context."""

    rapid: bool  # emitted as a rapid (G00) rather than at ``feed``; False for arcs
    target: Vec  # programmed machine-coordinate end
    feed: float | None
    context: tuple  # (line, file_index, modes, tool, spindle_rpm)
    element: PlaneElement | None = None  # in-plane moves only
    d: float = 0.0
    lead: list[Point] = field(default_factory=list)
    start_b: Point | None = None
    role: str = "offset"

    @property
    def move(self) -> PlaneElement:
        """The element of a move in the plane (every item the corner logic sees has one)."""
        assert self.element is not None
        return self.element

    @property
    def is_arc(self) -> bool:
        return self.element is not None and self.element.is_arc


class OffsetStage:
    """The compensation stage: an :class:`~cnc_gym.gcode.canonical.Output` in front of the canonical
    machine (see the module docstring).

    The interpreter installs it in place of its canonical machine the first time a program uses G41/G42,
    G43/G44 or G45-G48, and drives it through :meth:`set_cutter`, :meth:`set_position_offset`,
    :meth:`corner_arc`, :meth:`begin_block`, :meth:`suspend` and :meth:`flush`. Every member of the
    output protocol is implemented here explicitly; nothing is forwarded to the machine by name.
    """

    def __init__(self, machine, *, startup_type: str = "A", alarms=None, outer_corner_arcs: bool = False,
                 correct_interference: bool = True) -> None:  # fmt: skip
        self.machine = machine
        self.alarms = alarms or {}
        self.startup_type = startup_type
        self.outer_corner_arcs = outer_corner_arcs  # CompensationSettings.outer_corner_arcs
        self.correct_interference = correct_interference  # CompensationSettings.correct_interference
        self._position: Vec = machine.position  # programmed (uncompensated) position
        self.file_index = machine.file_index
        self.modes = machine.modes
        self.tool = machine.tool
        self.spindle_rpm = machine.spindle_rpm
        self.line = machine.line
        # Cutter compensation state.
        self.d = 0.0  # signed offset of the blocks to come (left +)
        self.plane = Plane.XY
        self.active = False  # a vector is (or is about to be) applied
        self.pending: _Item | None = None  # the last in-plane block, waiting for its end corner
        # What comes after the pending block without moving in the plane (moves of the normal axis, dwells),
        # to be emitted once the pending block's end corner is known.
        self.deferred: list[Callable[[], None]] = []
        self.blocks_since = 0
        self.cancel_requested = False
        self.cancel_direction: Point | None = None
        self.corner_arc_pending = False
        self.corner_arc_direction: Point | None = None
        self.corner_arc_feed: float | None = None
        # The tool length vector lives in OffsetStack.tool_length (it is in every target already).
        # ``length_pending``: the change of that vector an incremental move of
        # the offset axis in the block that changes it must carry (``G43 G91 Z0 H_`` moves by H, §3.5.1).
        self.length_pending: Vec | None = None
        self.suspended = False  # this block's moves pass through uncompensated (G53, G27-G30, G60)
        self._position_offset: tuple[int, float, frozenset[int], bool] | None = None
        # The rotary axes' target of the next straight move (Output.rotary_next, set by the interpreter for
        # a block with rotary words; no rotary word is allowed in cutter compensation).
        self._rotary_next: tuple[float, ...] | None = None

    # ------------------------------------------------------------------ context
    @property
    def position(self) -> Vec:
        """The programmed position (machine coordinates without the cutter compensation vector)."""
        pending = self.length_pending
        if pending is None:
            return self._position
        p = self._position
        return (p[0] + pending[0], p[1] + pending[1], p[2] + pending[2])

    @property
    def rotary(self) -> tuple[float, ...]:
        """The rotary axes' machine position (the stage never moves them itself)."""
        return self.machine.rotary

    @property
    def rotary_next(self) -> tuple[float, ...] | None:
        return self._rotary_next

    @rotary_next.setter
    def rotary_next(self, target: tuple[float, ...] | None) -> None:
        self._rotary_next = target

    def _guard(self, fn, *args):
        """Run ``fn``; a compensation error gets the dialect's alarm number."""
        try:
            return fn(*args)
        except CompensationError as err:
            if err.alarm is None:
                err.alarm = self.alarms.get(err.code)
            raise

    def begin_block(self) -> None:
        """The interpreter starts a block (after setting ``line``): the look-ahead counts blocks here."""
        self._guard(self._new_block)

    def _new_block(self) -> None:
        self.length_pending = None
        self.suspended = False
        self._position_offset = None
        if self.cancel_requested and self.pending is not None:
            # G40 in a block without a move in the plane: the vector stays perpendicular to the last
            # block and is cancelled on the next move (§3.5.3).
            self._resolve(None)
            self.active = False
        elif self.pending is not None:
            self.blocks_since += 1
            if self.blocks_since > LOOKAHEAD_BLOCKS:
                # The two blocks after the pending one have no move in the plane: the next block cannot
                # be seen, so its end vector is perpendicular to it (the overcut of §3.5.3).
                self._resolve(None)
        if self.cancel_requested and self.pending is None:
            self.cancel_requested = False
            self.active = False

    def _context(self) -> tuple:
        return (self.line, self.file_index, self.modes, self.tool, self.spindle_rpm)

    # ------------------------------------------------------------------ controls
    def set_cutter(self, d: float, plane: Plane, *, cancel_direction: Point | None = None) -> None:
        """G41/G42 (``d`` signed, left +) or G40 (``d`` 0, optional I/J direction). The change applies to
        the blocks to come; a cancel happens on the next move in the plane (or at the next block)."""
        if d == 0.0:
            if self.active:
                self.cancel_requested = True
                self.cancel_direction = cancel_direction
            self.d = 0.0
            return
        self.cancel_requested = False
        self.d = d
        self.plane = plane

    def set_position_offset(
        self, factor: int, amount: float, axes: frozenset[int], incremental: bool
    ) -> None:
        """G45 (+1), G46 (-1), G47 (+2), G48 (-2) for the move of this block on ``axes``."""
        self._position_offset = (factor, amount, axes, incremental)

    def corner_arc(self, direction: Point | None, feed: float | None) -> None:
        """G39 [I J]: a corner arc of radius |d| at the end of the pending block (§3.5.4)."""
        self.corner_arc_pending = True
        self.corner_arc_direction = direction
        self.corner_arc_feed = feed

    def flush(self) -> None:
        """End of program (or a move that must see the true position): resolve and emit everything."""
        self._guard(self._flush)

    def _flush(self) -> None:
        if self.pending is not None:
            self._resolve(None)
        self._emit_deferred()
        self.cancel_requested = False
        if self.d == 0.0:
            self.active = False

    # ------------------------------------------------------------------ the output protocol (Output)
    def straight_traverse(self, target: Vec) -> None:
        self._guard(self._straight, True, target, None)

    def straight_feed(self, target: Vec, feed: float) -> None:
        self._guard(self._straight, False, target, feed)

    def arc_feed(self, end: Vec, center: Vec, plane: Plane, sweep: float, feed: float) -> None:
        self._guard(self._arc_feed, end, center, plane, sweep, feed)

    def dwell(self, seconds: float, modes: SegmentMode = SegmentMode.NONE) -> None:
        self._guard(self._dwell, seconds, modes)

    def nurbs_feed(self, curve, feed: float) -> None:
        """A NURBS segment (never compensated: G06.2 is refused in G41/G42, §3.2.5): what is buffered is
        emitted first, and the programmed position follows the machine's."""
        self._pass_through(self.machine.nurbs_feed, curve, feed)

    def _pass_through(self, operation: Callable[..., None], *args) -> None:
        self.flush()
        self._set_machine_context(self._context())
        operation(*args)
        self._position = self.machine.position
        self.active = False

    def _straight(self, rapid: bool, target: Vec, feed: float | None) -> None:
        target = self._adjust(target)
        if self._rotary_next is not None:
            # A move of the rotary axes too: it goes to the machine as it is, after what is buffered.
            self.flush()
            self.machine.rotary_next, self._rotary_next = self._rotary_next, None
            self._set_machine_context(self._context())
            self._emit_straight(rapid, target, feed)
            self._position = target
            return
        self._move(rapid, target, feed)

    def _arc_feed(self, end: Vec, center: Vec, plane: Plane, sweep: float, feed: float) -> None:
        if self._position_offset is not None:
            end, center = self._adjust_arc(end, center, plane, sweep)
        u, v, _w = PLANE_AXES[plane]
        start = self._position
        if (self.active or self.d != 0.0) and plane != self.plane:
            raise CompensationError(
                f"arc in the {Plane(plane).name} plane while cutter compensation works in "
                f"the {Plane(self.plane).name} plane",
                "comp-plane-change",
            )
        if self.suspended or (not self.active and self.d == 0.0):
            self._set_machine_context(self._context())
            self.machine.arc_feed(end, center, plane, sweep, feed)
            self._position = end
            return
        element = PlaneElement((start[u], start[v]), (end[u], end[v]), (center[u], center[v]), sweep)
        item = _Item(False, end, feed, self._context(), element, self.d)
        self._plane_move(item)

    def _dwell(self, seconds: float, modes: SegmentMode = SegmentMode.NONE) -> None:
        emit = partial(self._emit_dwell, seconds, modes, self._context())
        if self.pending is not None:
            self.deferred.append(emit)
        else:
            emit()

    def suspend(self) -> None:
        """G53, G27-G30, G60 come next: everything buffered is emitted first (the last block ending with its
        vector perpendicular to it) and this block's moves go through uncompensated; the next move in the
        plane is a new start-up. A simplification of the manual's temporary cancel (§3.2.12, §3.5.3):
        the vector is gone at the intermediate point and comes back with the next block's start-up."""
        self.flush()
        self.suspended = True
        self.active = False

    # ------------------------------------------------------------------ internals
    def _adjust(self, target: Vec) -> Vec:
        """G45-G48 on a straight move: each commanded axis's travel grows/shrinks by factor x D (§3.5.7)."""
        request = self._position_offset
        if request is None:
            return target
        self._position_offset = None
        factor, amount, axes, incremental = request
        pos = self._position
        out = list(target)
        for a in axes:
            delta = target[a] - pos[a]
            if delta != 0.0:
                delta += math.copysign(1.0, delta) * factor * amount
            elif incremental:
                delta = factor * amount  # a zero move in G91 moves by the offset (§3.5.7, N9/N11)
            out[a] = pos[a] + delta
        return (out[0], out[1], out[2])

    def _adjust_arc(self, end: Vec, center: Vec, plane: Plane, sweep: float) -> tuple[Vec, Vec]:
        """G45-G48 on a quarter or three-quarter I/J/K circle: the radius changes by factor x D (§3.5.7)."""
        assert self._position_offset is not None  # the caller checked it
        factor, amount, _axes, _incremental = self._position_offset
        self._position_offset = None
        u, v, _w = PLANE_AXES[plane]
        pos = self._position
        du, dv = end[u] - pos[u], end[v] - pos[v]
        iu, iv = center[u] - pos[u], center[v] - pos[v]
        radius = math.hypot(iu, iv)
        quarter = (
            abs(abs(du) - radius) < 1e-6 and abs(abs(dv) - radius) < 1e-6 and min(abs(iu), abs(iv)) < 1e-6
        )
        if not quarter or abs(abs(sweep) - math.pi) < 1e-6:
            raise CompensationError(
                "G45-G48 on an arc: only quarter and three-quarter circles with the "
                "centre on an axis direction can be offset (GSK 25i §3.5.7)",
                "position-offset-arc",
            )
        change = factor * amount
        new_end, new_center = list(end), list(center)
        new_end[u] = pos[u] + du + math.copysign(1.0, du) * change
        new_end[v] = pos[v] + dv + math.copysign(1.0, dv) * change
        new_center[u] = pos[u] + (iu + math.copysign(1.0, iu) * change if abs(iu) > 1e-6 else 0.0)
        new_center[v] = pos[v] + (iv + math.copysign(1.0, iv) * change if abs(iv) > 1e-6 else 0.0)
        if radius + change <= 0.0:
            raise CompensationError(
                "G45-G48: the offset makes the arc radius zero or negative", "position-offset-arc"
            )
        return (new_end[0], new_end[1], new_end[2]), (new_center[0], new_center[1], new_center[2])

    def _set_machine_context(self, context: tuple) -> None:
        m = self.machine
        m.line, m.file_index, m.modes, m.tool, m.spindle_rpm = context

    def _move(self, rapid: bool, target: Vec, feed: float | None) -> None:
        u, v, _w = PLANE_AXES[self.plane]
        start = self._position
        in_plane = abs(target[u] - start[u]) > SAME_POINT or abs(target[v] - start[v]) > SAME_POINT
        passthrough = not self.active and (self.d == 0.0 or not in_plane) and self.pending is None
        if self.suspended or (passthrough and not self.deferred):
            # Cancel mode (or G41/G42 waiting for its start-up block): straight through.
            self._set_machine_context(self._context())
            self._emit_straight(rapid, target, feed)
            self._position = target
            return
        item = _Item(rapid, target, feed, self._context())
        if in_plane:
            item.element = PlaneElement((start[u], start[v]), (target[u], target[v]))
            item.d = self.d
            self._plane_move(item)
        elif self.pending is None:
            # Offset mode with nothing waiting (after a look-ahead-starved block): the tool keeps its
            # compensated position in the plane.
            pos = self.machine.position
            self._set_machine_context(item.context)
            self._emit_straight(rapid, self._with_plane(target, (pos[u], pos[v])), feed)
            self._position = target
        else:
            self.deferred.append(partial(self._emit_held, item))
            self._position = target

    def _emit_straight(self, rapid: bool, target: Vec, feed: float | None) -> None:
        if rapid:
            self.machine.straight_traverse(target)
        else:
            self.machine.straight_feed(target, feed)

    def _plane_move(self, item: _Item) -> None:
        element = item.move
        line = self.line
        if not self.active:
            if item.is_arc:
                raise CompensationError(
                    "cutter compensation start-up in an arc block: the start-up block must be G00 or G01",
                    "comp-arc-startup",
                    line,
                )
            item.role = "startup"
            item.start_b = element.start
            self.active = True
            self.pending = item
            self.blocks_since = 0
            self._position = item.target
            return
        if self.cancel_requested or item.d == 0.0:
            if item.is_arc:
                raise CompensationError(
                    "cutter compensation cancel in an arc block: the cancel block must be G00 or G01",
                    "comp-arc-startup",
                    line,
                )
            item.role = "cancel"
            self._resolve(item)
            self._emit_deferred()
            # The cancel line: from the last compensated point straight to the programmed end.
            self._set_machine_context(item.context)
            for q in item.lead:
                self._emit_plane_point(q, item)
            self._emit_straight(item.rapid, item.target, item.feed)
            self.active = False
            self.cancel_requested = False
            self._position = item.target
            return
        if self.pending is None:
            # The previous block was resolved without seeing this one (look-ahead starved, §3.5.3): the tool
            # sits on the old vector and runs straight to this block's end vector (an arc: to its start).
            item.start_b = element.offset_point(False, item.d)
        else:
            self._resolve(item)
        self.pending = item
        self.blocks_since = 0
        self._position = item.target

    def _resolve(self, nxt: _Item | None) -> None:
        """Compute the corner at the end of the pending block with the next move ``nxt`` and emit it."""
        a = self.pending
        if a is None:
            return
        line = a.context[0]
        if self.corner_arc_pending:
            if nxt is not None and nxt.role != "cancel":
                self._corner_arc_resolve(a, nxt)
                return
            self.corner_arc_pending = False  # G39 before a cancel or the end: no corner to round
        b_el = nxt.move if nxt is not None else None
        role = "cancel"
        try:
            if nxt is not None and nxt.role == "cancel" and self.cancel_direction is not None:
                virtual = PlaneElement(
                    a.move.end,
                    (
                        a.move.end[0] + self.cancel_direction[0],
                        a.move.end[1] + self.cancel_direction[1],
                    ),
                )
                c = cancel_with_direction(a.move, virtual, a.d)
            else:
                role = (
                    "startup"
                    if a.role == "startup"
                    else ("cancel" if nxt is not None and nxt.role == "cancel" else "offset")
                )
                d_b = None if nxt is None or nxt.role == "cancel" else nxt.d
                c = corner(a.move, b_el, a.d, d_b, role=role, startup_type=self.startup_type)
        except CompensationError as err:
            err.line = err.line or line
            raise
        if self.outer_corner_arcs and role == "offset" and nxt is not None and c.is_outer:
            # An arc round the outer corner, as G39 would make one (CompensationSettings.outer_corner_arcs).
            self.corner_arc_direction = self.corner_arc_feed = None
            self._corner_arc_resolve(a, nxt)
            return
        try:
            rest = self._emit_block(a, [c.end_a, *c.lead_b])
        except CompensationError as err:
            err.line = err.line or line
            raise
        if nxt is not None:
            nxt.lead = rest
            nxt.start_b = c.start_b
        self.pending = None
        self._emit_deferred()

    def _corner_arc_resolve(self, a: _Item, nxt: _Item) -> None:
        """G39: a ends with the vector perpendicular to its end; an arc of radius |d| about the corner
        takes the tool to the vector perpendicular to the next block's start (or to the I/J direction)."""
        self.corner_arc_pending = False
        p = a.move.end
        end_a = a.move.offset_point(True, a.d)
        if self.corner_arc_direction is not None:
            virtual = PlaneElement(
                p, (p[0] + self.corner_arc_direction[0], p[1] + self.corner_arc_direction[1])
            )
            target = virtual.offset_point(False, a.d)
        else:
            target = nxt.move.offset_point(False, nxt.d)
        self._emit_block(a, [end_a])
        sweep = arc_sweep_between(p, end_a, target, 0.0)
        if abs(sweep) > SMOOTH:
            # The short way round the corner point: at an outer corner, the way the path turns.
            self._set_machine_context(a.context)
            u, v, w = PLANE_AXES[self.plane]
            pos = self.machine.position
            end3 = [0.0, 0.0, 0.0]
            end3[u], end3[v], end3[w] = target[0], target[1], pos[w]
            center3 = [0.0, 0.0, 0.0]
            center3[u], center3[v], center3[w] = p[0], p[1], pos[w]
            feed = self.corner_arc_feed or a.feed or nxt.feed
            if not feed:
                raise CompensationError("G39 needs a feed: no F programmed yet", "missing-feed", a.context[0])
            self.machine.arc_feed(tuple(end3), tuple(center3), self.plane, sweep, feed)
        nxt.lead = []
        nxt.start_b = target
        self.pending = None
        self._emit_deferred()

    def _with_plane(self, target: Vec, point: Point) -> Vec:
        """Machine target: programmed ``target`` with its plane coordinates replaced by ``point``."""
        out = list(target)
        u, v, _w = PLANE_AXES[self.plane]
        out[u], out[v] = point
        return (out[0], out[1], out[2])

    def _emit_plane_point(self, point: Point, item: _Item) -> None:
        """A straight connecting move in the plane (the normal axis stays) with the item's feed/rapid."""
        u, v, _w = PLANE_AXES[self.plane]
        target = list(self.machine.position)
        target[u], target[v] = point
        self._emit_straight(item.rapid, (target[0], target[1], target[2]), item.feed)

    def _emit_block(self, item: _Item, end_vectors: list[Point]) -> list[Point]:
        """Emit a resolved in-plane block: its lead moves, then its element to the first of
        ``end_vectors`` (the tool-centre points at its end corner; the rest are the next block's lead).

        The interference check and its correction (:func:`correct_interference`) run first and may drop
        vectors at both corners (an arc then runs as a straight line); returns the end corner's vectors
        that are left for the next block's lead. An arc whose start vector is not on its offset circle
        (D changed in this block: the start vector keeps the old offset, §3.5.3) steps radially onto it."""
        self._set_machine_context(item.context)
        element = item.move
        line = item.context[0]
        u, v, _w = PLANE_AXES[self.plane]
        pos = self.machine.position
        starts = [(pos[u], pos[v]), *item.lead]
        if item.is_arc and item.start_b is not None and distance(starts[-1], item.start_b) > 1e-7:
            starts.append(item.start_b)
        as_line = False
        if item.role != "startup":
            if self.correct_interference:
                starts, end_vectors, as_line = correct_interference(element, item.d, starts, end_vectors,
                                                                    line)  # fmt: skip
            else:
                reason = block_interference(element, item.d, starts[-1], end_vectors[0], False, line)
                if reason is not None:
                    raise CompensationError(f"contour violation: {reason}", "comp-interference", line)
        for q in starts[1:]:
            self._emit_plane_point(q, item)
        end = end_vectors[0]
        target = self._with_plane(item.target, end)
        if item.is_arc and not as_line:
            start = circle_point(element, item.d, starts[-1])
            if distance(starts[-1], start) > 1e-7:
                self._emit_plane_point(start, item)
            sweep = arc_sweep_between(element.arc_center, start, end, element.sweep)
            center = list(target)
            center[u], center[v] = element.arc_center
            self.machine.arc_feed(target, (center[0], center[1], center[2]), self.plane, sweep, item.feed)
        else:
            self._emit_straight(item.rapid, target, item.feed)
        return end_vectors[1:]

    def _emit_deferred(self) -> None:
        emits, self.deferred = self.deferred, []
        for emit in emits:
            emit()

    def _emit_held(self, item: _Item) -> None:
        """A move without plane motion that waited behind the pending block: it keeps the plane position
        the tool has now (the pending block's end vector)."""
        u, v, _w = PLANE_AXES[self.plane]
        pos = self.machine.position
        self._set_machine_context(item.context)
        self._emit_straight(item.rapid, self._with_plane(item.target, (pos[u], pos[v])), item.feed)

    def _emit_dwell(self, seconds: float, modes: SegmentMode, context: tuple) -> None:
        self._set_machine_context(context)
        self.machine.dwell(seconds, modes)
