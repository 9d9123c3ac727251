"""The canonical output boundary: program coordinates → machine coordinates → :class:`ToolpathBuilder`.

Everything the interpreter emits passes through here. A program point (work coordinates, mm, after
G20 conversion and G16 polar conversion) becomes a machine point through the stages, in the manual's
order (§3.2.18: "the scaling is applied firstly and then the coordinates are rotated"):

    program ─▶ mirror G51.1 ─▶ scaling/mirror G51 ─▶ rotation G68 ─▶ + origin ─▶ machine
    origin = local (G52) + work origin + tool length vector (G43/G44, owned by compensation),
    work origin = G92 floating origin while one is set, else external (G10 L2 P0) + G54..G59 / G54.1 Pn.

:class:`TransformChain` holds the program-side stages (each a small :class:`AffineStage`) and composes
them into one affine map ``work = A·p + t``; with no stage active it is the identity and the interpreter
skips it altogether (the plain-G-code hot path does ``program + origin`` only). :class:`OffsetStack`
holds the translations. :class:`CanonicalMachine` keeps the current machine position and appends
segments.

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

from cnc_gym.errors import ProgramError
from cnc_gym.toolpath import PLANE_AXES, Plane, SegmentKind, SegmentMode, ToolpathBuilder

Vec = tuple[float, float, float]
Mat = tuple[Vec, Vec, Vec]
IDENTITY: Mat = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))
_PLANE_AXES = {int(p): axes for p, axes in PLANE_AXES.items()}
_ARC = SegmentKind.ARC
ZERO: Vec = (0.0, 0.0, 0.0)
TWO_PI = 2.0 * math.pi
#: No move may reach a machine coordinate beyond this, mm (1 000 km: far beyond any stroke, so only a
#: runaway chain of offsets or transforms meets it, e.g. G51 applied again and again in a loop, which
#: would otherwise double a coordinate to infinity).
MAX_COORDINATE_MM = 1e9


def mat_mul(a: Mat, b: Mat) -> Mat:
    """3×3 product a·b."""
    return tuple(tuple(sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3))
                 for i in range(3))  # type: ignore[return-value]  # fmt: skip


def mat_vec(a: Mat, v) -> Vec:
    return (a[0][0] * v[0] + a[0][1] * v[1] + a[0][2] * v[2],
            a[1][0] * v[0] + a[1][1] * v[1] + a[1][2] * v[2],
            a[2][0] * v[0] + a[2][1] * v[1] + a[2][2] * v[2])  # fmt: skip


def mat_inverse(a: Mat) -> Mat:
    """Inverse of a non-singular 3×3 matrix (cofactors; the stages never give a singular one)."""
    (a00, a01, a02), (a10, a11, a12), (a20, a21, a22) = a
    c00, c01, c02 = a11 * a22 - a12 * a21, a12 * a20 - a10 * a22, a10 * a21 - a11 * a20
    det = a00 * c00 + a01 * c01 + a02 * c02
    inv = 1.0 / det
    return ((c00 * inv, (a02 * a21 - a01 * a22) * inv, (a01 * a12 - a02 * a11) * inv),
            (c01 * inv, (a00 * a22 - a02 * a20) * inv, (a02 * a10 - a00 * a12) * inv),
            (c02 * inv, (a01 * a20 - a00 * a21) * inv, (a00 * a11 - a01 * a10) * inv))  # fmt: skip


@dataclass(frozen=True)
class AffineStage:
    """One program-side stage: ``p' = centre + linear·(p - centre)``.

    ``centre`` is the program point the stage was commanded about; the chain carries it through the
    stages before this one (the G68 centre "will also be scaled", §3.2.18).
    """

    name: str
    linear: Mat
    centre: Vec


def scaling_stage(name: str, centre: Vec, factors: Vec) -> AffineStage:
    """G51 (or G51.1 with factors ±1): per-axis factors about ``centre``; a negative factor mirrors."""
    fx, fy, fz = factors
    return AffineStage(name, ((fx, 0.0, 0.0), (0.0, fy, 0.0), (0.0, 0.0, fz)), centre)


def rotation_stage(plane: Plane, centre: Vec, angle_deg: float) -> AffineStage:
    """G68: rotation by ``angle_deg`` (CCW seen from the + end of the plane normal) about ``centre``."""
    u, v, _ = _PLANE_AXES[int(plane)]
    c, s = math.cos(math.radians(angle_deg)), math.sin(math.radians(angle_deg))
    rows = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
    rows[u][u], rows[u][v], rows[v][u], rows[v][v] = c, -s, s, c
    return AffineStage("G68", tuple(tuple(r) for r in rows), centre)  # type: ignore[arg-type]


#: Slots of the program-side stages, in the order they apply to a program point.
STAGE_ORDER = ("mirror", "scaling", "rotation")


class TransformChain:
    """The program-side stages (mirror G51.1, scaling G51, rotation G68) composed into ``A·p + t``.

    ``active`` is False when no stage is set: the map is then the identity and callers skip it.
    """

    def __init__(self) -> None:
        self.stages: dict[str, AffineStage | None] = dict.fromkeys(STAGE_ORDER)
        self.active = False
        self.linear: Mat = IDENTITY
        self.shift: Vec = ZERO
        self.inverse_linear: Mat = IDENTITY
        self.det_sign = 1.0

    def set(self, slot: str, stage: AffineStage | None) -> None:
        """Install (or, with None, remove) the stage of ``slot`` and recompose."""
        self.stages[slot] = stage
        self._compose()

    def _compose(self) -> None:
        linear, shift = IDENTITY, ZERO
        for slot in STAGE_ORDER:
            stage = self.stages[slot]
            if stage is None:
                continue
            # This stage's centre, carried through the stages before it.
            cm = mat_vec(linear, stage.centre)
            centre = (cm[0] + shift[0], cm[1] + shift[1], cm[2] + shift[2])
            # p'' = c + L (A p + t - c) = (L A) p + L (t - c) + c
            lt = mat_vec(stage.linear, (shift[0] - centre[0], shift[1] - centre[1], shift[2] - centre[2]))
            linear = mat_mul(stage.linear, linear)
            shift = (lt[0] + centre[0], lt[1] + centre[1], lt[2] + centre[2])
        self.active = any(stage is not None for stage in self.stages.values())
        self.linear, self.shift = linear, shift
        self.inverse_linear = mat_inverse(linear)
        (a00, a01, a02), (a10, a11, a12), (a20, a21, a22) = linear
        det = a00 * (a11 * a22 - a12 * a21) - a01 * (a10 * a22 - a12 * a20) + a02 * (a10 * a21 - a11 * a20)
        self.det_sign = 1.0 if det > 0 else -1.0

    def apply(self, p) -> Vec:
        """Program point → work point (before the origin translation)."""
        q = mat_vec(self.linear, p)
        t = self.shift
        return (q[0] + t[0], q[1] + t[1], q[2] + t[2])

    def invert(self, w) -> Vec:
        """Work point → program point."""
        t = self.shift
        return mat_vec(self.inverse_linear, (w[0] - t[0], w[1] - t[1], w[2] - t[2]))

    def plane_map(self, plane: Plane) -> tuple[float, float, float, float, float, bool] | None:
        """The in-plane 2×2 block (a, b, c, d) and the normal factor of the map for an arc in ``plane``,
        plus whether the in-plane block is a similarity (maps circles to circles); None when the map
        mixes the plane with its normal axis (a G68 of another plane; the interpreter forbids that)."""
        u, v, w = _PLANE_AXES[int(plane)]
        m = self.linear
        if abs(m[u][w]) > 1e-12 or abs(m[v][w]) > 1e-12 or abs(m[w][u]) > 1e-12 or abs(m[w][v]) > 1e-12:
            return None
        a, b, c, d = m[u][u], m[u][v], m[v][u], m[v][v]
        similar = abs(a * a + c * c - b * b - d * d) < 1e-12 and abs(a * b + c * d) < 1e-12
        return a, b, c, d, m[w][w], similar



class PolarState:
    """G16 polar input: the plane's first axis word is the radius, the second the angle (degrees, CCW
    from the first axis's + direction). GSK 25i programming manual §3.2.16 (polar coordinate command).

    * radius word in G90: the origin is the work zero; in G91: the origin is the current position;
    * angle word in G90: the angle itself; in G91: added to the last angle;
    * an omitted radius or angle keeps the last one (with the last origin), so ``G91 Y120`` steps round
      the same circle;
    * the plane's normal axis is an ordinary Cartesian word.
    """

    def __init__(self, program_position, plane: Plane) -> None:
        u, v, _ = _PLANE_AXES[int(plane)]
        # Start from the current point seen from the work zero.
        self.origin = (0.0, 0.0)
        self.radius = math.hypot(program_position[u], program_position[v])
        self.angle_deg = math.degrees(math.atan2(program_position[v], program_position[u]))

    def resolve(self, words, plane: Plane, scale: float, incremental: bool, position) -> tuple:
        """Program-unit words (x, y, z; None = absent) → program target in mm (None = not commanded), with
        ``plane``'s axes as (radius, angle), from the program ``position``."""
        u, v, w = _PLANE_AXES[int(plane)]
        s = scale
        p = position
        out: list[float | None] = [None, None, None]
        radius_word, angle_word = words[u], words[v]
        if radius_word is not None or angle_word is not None:
            if radius_word is not None:
                self.origin = (p[u], p[v]) if incremental else (0.0, 0.0)
                self.radius = radius_word * s
            if angle_word is not None:
                self.angle_deg = self.angle_deg + angle_word if incremental else angle_word
            a = math.radians(self.angle_deg)
            out[u] = self.origin[0] + self.radius * math.cos(a)
            out[v] = self.origin[1] + self.radius * math.sin(a)
        normal = words[w]
        if normal is not None:
            out[w] = p[w] + normal * s if incremental else normal * s
        return tuple(out)


class MapError(ValueError):
    """An arc the transform chain cannot map (``code``: the stable error code)."""

    def __init__(self, message: str, code: str) -> None:
        super().__init__(message)
        self.code = code


def map_arc(chain: TransformChain, plane: Plane, sweep: float, start_m: Vec,
            mapped) -> tuple[Vec, Vec, float]:  # fmt: skip
    """An arc given in program coordinates → (end, centre, sweep) in machine coordinates.

    ``start_m``: the machine start point; ``mapped()`` gives the machine images of the program end and
    centre (the centre's normal coordinate set to the start's). The chain is affine and keeps the arc's
    plane (G68 rotates only in the selected plane, and a plane change in G68 mode is an error). With equal
    in-plane factors the image of the circle is a circle: the sweep keeps its size and flips its sign
    under a mirror (G02 ↔ G03). With unequal factors the controller traces no ellipse (GSK 25i programming
    manual §3.2.17, note 5; the figures are lost): we keep the mapped centre and the mapped start, so the
    radius is the mapped start's distance from the mapped centre, and move the mapped end radially onto
    that circle; a full circle stays a full circle. Raises :class:`MapError`.
    """
    u, v, w = _PLANE_AXES[int(plane)]
    shape = chain.plane_map(plane)
    if shape is None:
        raise MapError(f"an arc in the {plane.name} plane while G68 rotates another plane",
                       "plane-change-in-rotation")  # fmt: skip
    a, b, c, d, _, similar = shape
    mirror = a * d - b * c < 0
    end_image, centre_image = mapped()
    end_m = list(end_image)
    centre_m = list(centre_image)
    centre_m[w] = start_m[w]
    centre = (centre_m[0], centre_m[1], centre_m[2])
    if similar:
        return (end_m[0], end_m[1], end_m[2]), centre, -sweep if mirror else sweep
    radius = math.hypot(start_m[u] - centre_m[u], start_m[v] - centre_m[v])
    full = abs(abs(sweep) - TWO_PI) < 1e-12
    ccw = (sweep > 0) != mirror
    if full:
        end_m[u], end_m[v] = start_m[u], start_m[v]
        return (end_m[0], end_m[1], end_m[2]), centre, TWO_PI if ccw else -TWO_PI
    r_end = math.hypot(end_m[u] - centre_m[u], end_m[v] - centre_m[v])
    if radius < 1e-9 or r_end < 1e-9:
        raise MapError("the scaled arc has radius 0", "arc-impossible")
    k = radius / r_end
    end_m[u] = centre_m[u] + (end_m[u] - centre_m[u]) * k
    end_m[v] = centre_m[v] + (end_m[v] - centre_m[v]) * k
    a0 = math.atan2(start_m[v] - centre_m[v], start_m[u] - centre_m[u])
    a1 = math.atan2(end_m[v] - centre_m[v], end_m[u] - centre_m[u])
    turned = (a1 - a0) % TWO_PI if ccw else -((a0 - a1) % TWO_PI)
    return (end_m[0], end_m[1], end_m[2]), centre, turned


class Output(Protocol):
    """The output stage the interpreter moves (``State.out``): :class:`CanonicalMachine`, or a stage in front
    of it that implements the same protocol (cutter compensation's ``OffsetStage``). The position is the
    one moves are programmed from; the context attributes (line … spindle) go with the next segments;
    ``rotary_next`` is the rotary axes' target of the next straight move."""

    @property
    def position(self) -> Vec: ...

    @property
    def rotary(self) -> tuple[float, ...]: ...

    rotary_next: tuple[float, ...] | None
    line: int
    file_index: int
    modes: SegmentMode
    tool: int
    spindle_rpm: float

    def straight_traverse(self, target: Vec) -> None: ...

    def straight_feed(self, target: Vec, feed: float) -> None: ...

    def arc_feed(self, end: Vec, center: Vec, plane: Plane, sweep: float, feed: float) -> None: ...

    def nurbs_feed(self, curve, feed: float) -> None: ...

    def dwell(self, seconds: float, modes: SegmentMode = SegmentMode.NONE) -> None: ...


class OffsetStack:
    """Work offsets of one program run, all in mm (stored physically; G20/G21 do not rescale them).

    ``tool_length`` is the tool length offset vector (G43/G44; owned by the compensation module): it is
    added to the origin by :meth:`update`, after the program-side transforms (§3.2.18).
    """

    def __init__(self, n_wcs: int = 6, n_extra_wcs: int = 48) -> None:
        self.external: list[float] = [0.0, 0.0, 0.0]  # G10 L2 P0
        # G54..G59 (index 0..5), then G54.1 P1..P48 (index 6..53).
        self.wcs: list[list[float]] = [[0.0, 0.0, 0.0] for _ in range(n_wcs + n_extra_wcs)]
        self.n_standard_wcs = n_wcs
        #: Index of the work system in force; None: none (machine coordinates, a DIN controller's G53).
        self.active_wcs: int | None = 0
        self.local: list[float] = [0.0, 0.0, 0.0]  # G52
        self.floating: list[float] | None = None  # G92 origin in machine coordinates, or None
        #: G92 shifts every work system by one vector (Fanuc 0i) instead of replacing them until the next
        #: G54-G59 (GSK 25i §3.2.13); set from the dialect (``Dialect.g92_shifts_work_systems``).
        self.g92_shifts_all = False
        self.shift: list[float] = [0.0, 0.0, 0.0]  # the G92 shift of every work system (g92_shifts_all)
        self.tool_length: list[float] = [0.0, 0.0, 0.0]  # G43/G44 vector (compensation module)
        self.origin: Vec = ZERO
        self.update()

    @property
    def extra_wcs_number(self) -> int:
        """The G54.1 P number in force (#4130), 0 while G54..G59 is selected."""
        if self.active_wcs is None:
            return 0
        extra = self.active_wcs - self.n_standard_wcs + 1
        return extra if extra > 0 else 0

    def work_origin(self) -> list[float]:
        if self.floating is not None and not self.g92_shifts_all:
            return list(self.floating)
        if self.active_wcs is None:
            base = list(self.external)
        else:
            w = self.wcs[self.active_wcs]
            base = [self.external[a] + w[a] for a in range(3)]
        if self.g92_shifts_all:
            base = [base[a] + self.shift[a] for a in range(3)]
        return base

    def update(self) -> None:
        """Recompute the program→machine translation after any change."""
        work = self.work_origin()
        local, length = self.local, self.tool_length
        self.origin = (work[0] + local[0] + length[0], work[1] + local[1] + length[1],
                       work[2] + local[2] + length[2])  # fmt: skip

    def select_wcs(self, index: int | None) -> None:
        """G54..G59 (0..5), G54.1 P1..P48 (6..53); None: no work coordinate system, the work origin is the
        machine zero (plus the external offset): a DIN controller's G53 "no zero offset". GSK: selecting
        any work coordinate system drops a G92 floating system (§3.2.13); with ``g92_shifts_all`` (Fanuc
        0i) the G92 shift stays and applies to the new system too. An index outside the stack is a
        ValueError (a negative one would silently pick a slot from the end)."""
        if index is not None and not 0 <= index < len(self.wcs):
            raise ValueError(f"work coordinate system index {index} is not 0..{len(self.wcs) - 1}")
        self.active_wcs = index
        if not self.g92_shifts_all:
            self.floating = None
        self.update()

    def set_floating(self, axis: int, machine_pos: float, program_value: float) -> None:
        """G92 on one axis: the current machine position gets ``program_value``; clears that axis's G52.
        With ``g92_shifts_all`` the difference becomes the shift of every work system (Fanuc 0i)."""
        if self.g92_shifts_all:
            self.floating = self.floating or [0.0, 0.0, 0.0]  # (marks "a G92 is in force")
            unshifted = self.work_origin()[axis] - self.shift[axis]
            self.shift[axis] = machine_pos - program_value - self.tool_length[axis] - unshifted
            self.local[axis] = 0.0
            return
        if self.floating is None:
            self.floating = self.work_origin()
        # The tool length vector stays in the origin, so the position reads ``program_value`` right after.
        self.floating[axis] = machine_pos - program_value - self.tool_length[axis]
        self.local[axis] = 0.0

    def to_machine(self, program: Vec) -> Vec:
        o = self.origin
        return (program[0] + o[0], program[1] + o[1], program[2] + o[2])

    def to_program(self, machine: Vec) -> Vec:
        o = self.origin
        return (machine[0] - o[0], machine[1] - o[1], machine[2] - o[2])


class CanonicalMachine:
    """Current machine position plus the per-segment context; appends segments to a builder."""

    def __init__(self, builder: ToolpathBuilder, start: Vec = ZERO, rotary: tuple[float, ...] = (),
                 error=None) -> None:  # fmt: skip
        self.builder = builder
        # ``error(message, code)`` makes the ProgramError of a move beyond MAX_COORDINATE_MM (the dialect's,
        # with its alarm number).
        self.error = error or (lambda message, code: ProgramError(message, code=code))
        self.position: Vec = tuple(float(c) for c in start)  # type: ignore[assignment]
        # Rotary axes (machine degrees); ``rotary_next`` is the target the next rapid/feed move takes them
        # to (set by the interpreter for a block with rotary words, consumed by that move).
        self.rotary: tuple[float, ...] = tuple(rotary)
        self.rotary_next: tuple[float, ...] | None = None
        self.line = 0
        self.file_index = 0
        self.modes = SegmentMode.NONE
        self.tool = 0
        self.spindle_rpm = 0.0

    def _context(self) -> dict:
        return {"line": self.line, "file_index": self.file_index, "modes": self.modes, "tool": self.tool,
                "spindle_rpm": self.spindle_rpm}  # fmt: skip

    def _check(self, point) -> None:
        limit = MAX_COORDINATE_MM
        if not (-limit <= point[0] <= limit and -limit <= point[1] <= limit and -limit <= point[2] <= limit):
            where = ", ".join(f"{'XYZ'[a]}{point[a]:.6g}" for a in range(3))
            raise self.error(f"a move to ({where}) (machine) is beyond ±{limit:.0e} mm: a runaway offset or "
                             "transform", "value-out-of-range")  # fmt: skip

    def straight_traverse(self, target: Vec) -> None:
        """Rapid to a machine-coordinate target (no segment for a zero-length move)."""
        self._check(target)
        if self.rotary_next is not None:
            return self._rotary_move(target, None)
        if target != self.position:
            self.builder.rapid(self.position, target, self.line, self.file_index, self.modes, self.tool,
                               self.spindle_rpm)  # fmt: skip
            self.position = target

    def straight_feed(self, target: Vec, feed: float) -> None:
        """Feed move to a machine-coordinate target at ``feed`` mm/min."""
        self._check(target)
        if self.rotary_next is not None:
            return self._rotary_move(target, feed)
        if target != self.position:
            self.builder.line(self.position, target, feed, self.line, self.file_index, self.modes, self.tool,
                              self.spindle_rpm)  # fmt: skip
            self.position = target

    def _rotary_move(self, target: Vec, feed: float | None) -> None:
        """A rapid (``feed`` None) or feed move that also takes the rotary axes to ``rotary_next``."""
        rotary: tuple[float, ...] = self.rotary_next or ()
        self.rotary_next = None
        if target == self.position and rotary == self.rotary:
            return
        context = self._context()
        if feed is None:
            self.builder.rapid(self.position, target, **context)
        else:
            self.builder.line(self.position, target, feed, **context)
        if rotary != self.rotary:
            self.builder.move_rotary(self.rotary, rotary)
            self.rotary = rotary
        self.position = target

    def arc_feed(self, end: Vec, center: Vec, plane: Plane, sweep: float, feed: float) -> None:
        """Arc or helix (signed sweep in rad, + = CCW about the plane normal) to ``end``."""
        self._check(end)
        self._check(center)
        self.builder.arc(self.position, end, center, plane, sweep, feed, self.line, self.file_index,
                         self.modes, self.tool, self.spindle_rpm)  # fmt: skip
        self.position = end

    def nurbs_feed(self, curve, feed: float) -> None:
        """An exact NURBS segment (``NurbsCurve`` in machine coordinates, from the current position) at
        ``feed`` mm/min; the position becomes its last control point."""
        self._check(curve.control_points.min(axis=0))  # the curve lies in its control points' hull
        self._check(curve.control_points.max(axis=0))
        self.builder.nurbs(curve, feed, line=self.line, file_index=self.file_index, modes=self.modes,
                           tool=self.tool, spindle_rpm=self.spindle_rpm)  # fmt: skip
        end = curve.control_points[-1]
        self.position = (float(end[0]), float(end[1]), float(end[2]))

    def dwell(self, seconds: float, modes: SegmentMode = SegmentMode.NONE) -> None:
        context = self._context()
        context["modes"] = self.modes | modes
        self.builder.dwell(self.position, seconds, **context)
