"""The interpreter's state, declared in one place.

:class:`State` is the slotted record of one run: the modal state the blocks change, the coordinate
systems and transforms, and one sub-record per feature (canned cycles, tool compensation, NURBS, the
pending chamfer/corner, controller parameters written by the program). Every field is declared here,
with its meaning; features read and write their own sub-record and the modal fields through the seam
(:class:`~cnc_gym.gcode.dialect.Seam`), which hands them ``core.state``. Behaviour lives with the
features; this module holds data only, so that every module can name it without an import cycle.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Protocol

from cnc_gym.gcode.canonical import ZERO, OffsetStack, TransformChain
from cnc_gym.toolpath import Plane, SegmentMode

if TYPE_CHECKING:
    from cnc_gym.gcode.canonical import Output, PolarState
    from cnc_gym.gcode.codes import CodeSpec
    from cnc_gym.gcode.offsets import ToolOffsets
    from cnc_gym.gcode.program import Block, Program
    from cnc_gym.gcode.settings import CompensationSettings, ToolMeasurement
    from cnc_gym.machine import MachineConfig
    from cnc_gym.toolpath import ToolpathBuilder

Vec = tuple[float, float, float]


class Variables(Protocol):
    """The language's variable model, as the core uses it (read/write by number; null is None)."""

    system: Any

    def read(self, number: float | None) -> float | None: ...

    def write(self, number: float | None, value: float | None) -> None: ...


@dataclass(eq=False)
class CycleState:
    """Modal canned-cycle data of one run (group 09). ``spec`` None = G80 (no cycle).

    ``spec`` is the modal cycle code (its name for messages, its words for the block check) and ``kind``
    its entry in the dialect's cycle library (:class:`~cnc_gym.gcode.dialect.CycleKind`).
    """

    spec: CodeSpec | None = None
    kind: Any = None
    #: Initial level: the program coordinate of the drilling axis when the cycle mode was entered.
    initial: float = 0.0
    #: R level (program mm, absolute: a G91 R is taken from the initial level when programmed) and the
    #: bottom Z: absolute, or (``z_from_r``, programmed in G91) the distance from the R level.
    z: float | None = None
    r: float | None = None
    z_from_r: bool = False
    q: float | None = None  # peck depth / shift, mm (|Q|)
    dwell_s: float = 0.0  # P, seconds
    words: dict = field(default_factory=dict)  # special-cycle data (I J L W V U D E), mm / plain
    #: G76/G87 I/J shift (SIJ), program mm; modal in the cycle mode, None = not programmed.
    shift_i: float | None = None
    shift_j: float | None = None
    rigid: bool = False  # M29 rigid tapping active
    rigid_pending: bool = False  # M29 given, the tapping cycle not yet
    #: The cycle code a G124/G125 block names (its own drilling mode), for this block only.
    block_spec: CodeSpec | None = None
    #: Oriented spindle stops (M19 inside G76/G87) so far.
    orients: int = 0

    def cancel(self) -> None:
        """G80 or a group-01 code: cycle off, Z, R and all hole data cleared (F is kept)."""
        self.spec = None
        self.kind = None
        self.z = self.r = self.q = None
        self.shift_i = self.shift_j = None
        self.z_from_r = False
        self.dwell_s = 0.0
        self.words = {}
        self.rigid = self.rigid_pending = False


@dataclass(eq=False)
class CurveInProgress:
    """One G06.2 curve being read: control points in program coordinates (mm), weights, knots."""

    rank: int
    feed: float
    line: int
    file_index: int
    axes: frozenset[int] | None = None  # the axes named in the first control-point block
    points: list[list[float]] = field(default_factory=list)
    weights: list[float] = field(default_factory=list)
    knots: list[float] = field(default_factory=list)
    knot_only: int = 0  # knot-only blocks read so far


@dataclass(eq=False)
class NurbsState:
    """High-precision contour control (G05 P10000) and the curve being read (None between curves)."""

    hpcc: bool = False
    curve: CurveInProgress | None = None
    curves: int = 0  # curves emitted


@dataclass(eq=False)
class CompensationState:
    """Tool compensation of one run: the offset memory, the selected D and H numbers, the G40/G41/G42
    and G43/G44/G49 modes, and the output stage that compensates moves once a program needs it.

    ``stage`` is the cutter-compensation stage (``lang/fanuc/compensation/stage.OffsetStage``) installed in
    place of ``State.out`` the first time a program needs it (plain programs keep the direct path).
    ``length_restore``: G28/G30 cancel the tool length vector at the intermediate point; the cancelled
    part per axis, restored by the next block that commands that axis, or None.
    """

    settings: CompensationSettings
    offsets: ToolOffsets
    d_number: int = 0
    h_number: int = 0
    side: int = 0  # +1 G41, -1 G42, 0 G40
    plane: Plane = Plane.XY  # plane of the G41/G42 in force
    length_sign: int = 0  # +1 G43, -1 G44, 0 G49
    length_axis: int = 2
    stage: Any = None
    length_restore: list[float] | None = None


@dataclass(eq=False)
class Parameters:
    """Controller parameters written by the program (G10 L50 … G11): ``(number, axis) → raw value``.

    Values are integers in the parameter's unit (R takes no decimal point). The features that read one
    look its number up in the dialect's parameter map (``lang/fanuc/parameters.py``).
    """

    raw: dict[tuple[int, int], int] = field(default_factory=dict)


class PendingBlock(Protocol):
    """A feature waiting for the next block (a chamfer/corner block, the mark a coordinate change leaves):
    ``State.pending``. The core calls :meth:`before_block` before each block while one is set."""

    armed: bool

    def before_block(self, core: Any) -> None: ...


@dataclass(slots=True, eq=False)
class State:
    """Everything one run of the interpreter holds (module docstring). Lengths in mm, feeds in mm/min."""

    # ------------------------------------------------------------------ the run
    program: Program
    file: str  # the file of the running program (subprograms from other files change it)
    machine: MachineConfig | None  # reference positions (G27-G30), travel
    tool_measurement: ToolMeasurement  # G37's simulated instrument
    skip_signal: dict[str, float]  # G31's simulated probe: axis letter → program coordinate
    skip_mask: int  # bit n set: block-skip switch n is on
    builder: ToolpathBuilder
    out: Output  # the output stage: the canonical machine, or compensation's stage in front of it
    variables: Variables
    comp: CompensationState
    # ------------------------------------------------------------------ modal state
    #: The raw modal table: group → code key (for #4001-#4022); the fields below are what actions read.
    modal: dict[int, int] = field(default_factory=dict)
    motion: int = 0  # the modal motion's value (0 rapid, 1 line, 2/3 arcs, or a dialect's own mode)
    motion_key: int = 0  # key of the modal group-01 code
    plane: Plane = Plane.XY
    incremental: bool = False
    inch: bool = False
    scale: float = 1.0  # program length unit → mm
    increment: float = 0.0001  # least input increment of the unit in force
    feed: float | None = None  # mm/min; None = no F programmed yet
    spindle_speed: float = 0.0
    spindle_direction: int = 0
    coolant: bool = False
    tool: int = 0
    tool_changes: int = 0
    spindle_orients: int = 0  # M19 blocks
    feed_per_rev: bool = False  # G95: F is mm/rev (the feed in mm/min is F × S)
    feed_programmed: float | None = None  # the F word in its own unit (mm/rev in G95)
    path_mode: SegmentMode = SegmentMode.NONE
    #: #3004 (run control): (flags added, flags removed) on every segment from now on, or None.
    sys_modes: tuple[SegmentMode, SegmentMode] | None = None
    restore_modes: bool = False  # G09 in this block: the modes go back after it
    ended: bool = False
    stops: list[tuple[int, str]] = field(default_factory=list)  # (line, "program_stop" | "end" | …)
    # ------------------------------------------------------------------ axes and coordinates
    rotary_axes: str = ""  # rotary axes (A/B/C) of the machine, in order
    rotary_origin: list[float] = field(default_factory=list)  # program 0 in machine degrees (G92)
    offsets: OffsetStack = field(default_factory=OffsetStack)
    #: Program-side transforms (G51.1, G51, G68) and G16 polar input. While ``transformed`` is False no
    #: transform is active: targets are ``program + origin`` (the hot path). While True, ``program`` holds
    #: the program position explicitly and every target goes through the chain.
    chain: TransformChain = field(default_factory=TransformChain)
    polar: PolarState | None = None
    transformed: bool = False
    program_point: Vec = ZERO
    rotation_deg: float = 0.0  # G68 angle in force (for G91 R)
    mirror_axes: dict[int, float] = field(default_factory=dict)  # G51.1: axis → mirror coordinate (mm)
    after_g69: bool = False  # the first move after G69 must be absolute
    extra_wcs: int = 0  # G54.1 P number in force (0 = none; #4130)
    g28_intermediate: list[float | None] = field(default_factory=lambda: [None, None, None])  # work mm
    skip_position: Vec | None = None  # G31 end (#5061-#5063), work coordinates, mm
    parameters: Parameters = field(default_factory=Parameters)
    # ------------------------------------------------------------------ features
    cycle: CycleState = field(default_factory=CycleState)
    nurbs: NurbsState = field(default_factory=NurbsState)
    #: The dialect's own features' state: a record its folder declares (next to ``Dialect.options``),
    #: created by those features on first use; None until then. The core and the families never read it.
    dialect_data: Any = None
    #: A feature waiting for the next block (chamfer/corner, coordinate-change mark), or None.
    pending: PendingBlock | None = None
    #: While a chamfer/corner block is captured: the moves it would make, as geometry (not emitted).
    capture: list | None = None
    #: Blocks in a special mode go here first (True: handled): G10 L50 parameter input, G06.2 NURBS.
    block_hook: Any = None
    #: Per-block hooks of active features (tool compensation's look-ahead): ``hook(core, values)`` after
    #: the block's words are evaluated, before it executes.
    block_listeners: list[Any] = field(default_factory=list)
    #: Features that need every block on the general path (canned-cycle mode, M29 pending).
    general_path: set[str] = field(default_factory=set)
    #: What an axis-only block executes while a modal feature owns it (the canned cycle in force), None:
    #: the modal motion.
    modal_item: CodeSpec | None = None
    # ------------------------------------------------------------------ the block being executed
    block: Block | None = None
    block_words: Sequence = ()
    g53: bool = False  # G53 in this block: it makes the block's move
    #: Control flow requested by the block (M98/M99): ``("call", number, count)``, ``("return", n)``.
    flow_request: tuple | None = None
    #: The language's runner (program counter, calls): read by system variables (#4114, #4115, #3000).
    flow: Any = None
