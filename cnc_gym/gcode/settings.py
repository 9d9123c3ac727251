"""The controller's settings a dialect fixes (its machine parameters) and the options of one run.

Each record belongs to one feature and is read by it; the :class:`~cnc_gym.gcode.dialect.Dialect` carries
one of each (``cycle_params``, ``nurbs_params``, ``compensation``, ``macro_calls``), and ``interpret()``
takes the run's options (:class:`FlowOptions`, :class:`ToolMeasurement`, the skip signal). They live
below every feature module so that the dialect record and the features can both name them without an
import cycle. Parameter numbers are the GSK 25i's, beside each field.

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

from cnc_gym.errors import ConfigError
from cnc_gym.gcode.offsets import ToolOffsets

#: Default bound on executed blocks (a runaway WHILE/GOTO loop ends with a clear error).
DEFAULT_MAX_BLOCKS = 2_000_000
#: Default bound on the CPU seconds one interpretation may take (2 000 000 blocks of a macro loop take
#: 10-20 s; the bound catches what the block count does not: heavy blocks).
DEFAULT_MAX_SECONDS = 60.0
#: Default bound on the segments of one tool path (about 0.6 kB each while it is built: ~1.2 GB).
DEFAULT_MAX_SEGMENTS = 2_000_000


@dataclass(frozen=True)
class CycleParameters:
    """Machine parameters the cycles read (GSK number and standard setting beside each)."""

    #: P2010: G73 retract amount d, mm.
    g73_retract_mm: float = 0.5
    #: P2011: G83 clearance d (rapid re-approach stops d above the last depth), mm.
    g83_clearance_mm: float = 0.5
    #: P2000#0 FXY: False = the drilling axis is always Z; True = the axis normal to the selected plane.
    drilling_axis_follows_plane: bool = False
    #: P2000#5 RD2, #4 RD1 as 2·RD2 + RD1: G76/G87 shift 0 = +1st plane axis (G17 +X), 1 = -1st axis,
    #: 2 = +2nd axis (G17 +Y), 3 = -2nd axis.
    shift_direction: int = 0
    #: P2000#6 M5B: False = spindle stop (M05) is output before the oriented stop in G76/G87.
    no_m05_before_orient: bool = False
    #: P2141/P2142: largest spindle speed in rigid tapping, r/min (P2140, gear 1, is not printed; one gear).
    rigid_tap_max_rpm: float = 1000.0
    #: P1225/P1224: cutting-feed upper limit, mm/min (rigid tapping F above it is an alarm).
    max_cutting_feed: float = 4000.0
    #: The unnamed G124/G125 parameter: hole-to-hole moves as cutting feed (True) or rapid (False).
    pattern_moves_cutting: bool = False
    #: "022#6 SIJ" (§3.4.3; not in the Parameter volume): True = the G76/G87 shift is the incremental
    #: vector I (X), J (Y), modal in the cycle mode, moved at the feed F; Q then shifts nothing (it stays
    #: the modal peck depth of G73/G83). False = the shift is |Q| in the 2000#4/#5 direction, at rapid.
    shift_by_ij: bool = False
    #: G87 variant (§3.4.11): 2 = back boring (the manual's example X41), 1 = boring with a feed
    #: hold and manual retract at the bottom (like G88, without the shift). The manual names no selector
    #: but "canned cycle I / II"; its only parameter there, 009#7 FIX2, is not in the Parameter volume.
    g87_variant: int = 2
    #: A cycle whose R was never given drills from the initial level (R = the initial level; Haas: R is
    #: optional). False: the first drilling block must give R (``cycle-missing-data``).
    r_defaults_to_initial: bool = False
    #: L is the repeat count of a cycle block, as K (Haas, and the L of older Fanuc 0-M programs).
    l_repeats: bool = False

    def __post_init__(self) -> None:
        if self.shift_direction not in (0, 1, 2, 3):
            raise ConfigError(f"cycle parameter shift_direction {self.shift_direction!r}: must be 0..3 "
                              "(2000#5 RD2, #4 RD1 as 2·RD2 + RD1)")  # fmt: skip
        if self.g87_variant not in (1, 2):
            raise ConfigError(f"cycle parameter g87_variant {self.g87_variant!r}: must be 1 (manual retract) "
                              "or 2 (back boring)")  # fmt: skip


@dataclass(frozen=True)
class NurbsParameters:
    """GSK 25i NURBS parameters (the parameter manual; programming manual §3.2.5).

    Only ``max_blocks`` (P1407) changes what the interpreter does: a curve longer than that many blocks
    (control-point and knot-only blocks) is an error. The others are interpolator settings, kept here for
    the motion stage (the tool path carries the exact curve; acceleration limits along it are the
    interpolator's business, §3.2.5).
    """

    curve_degree: int = 3  # P1404 "curve frequency" 1..4 (the program's P sets the rank of each curve)
    point_density_per_mm: float | None = None  # P1405 standard density 5..1000 points/mm (value lost)
    max_blocks: int = 200  # P1407 max program blocks of one NURBS curve, 10..500
    decel_min_distance_mm: float = 1.0  # P1493: shorter control polygon legs are deceleration points
    decel_min_corner_deg: float = 10.0  # P1494: larger corners are deceleration points
    fold_line_corner_deg: float = 150.0  # P1495: least included angle of a smoothed fold-line junction


@dataclass(frozen=True)
class CompensationSettings:
    """A controller's tool compensation parameters (a :class:`~cnc_gym.gcode.dialect.Dialect` field).

    ``tool_length_type``: ``A`` (the offset always on Z) or ``B`` (on the axis normal to the plane of the
    G43/G44 block); GSK 2600#1 TLB, standard setting 1 = B. ``startup_type``: ``A`` or ``B`` start-up and
    cancel at outer corners (GSK "2602#2 TPH", not in the parameter volume; Fanuc's standard is A, and the
    manual's worked example describes A: "offset by the radius vertical to the next block", §3.5.2).
    ``d_is_diameter``: 2601#7 ODI (see offsets.py). ``offset_count``: H/D numbers 0..count.
    ``length_needs_axis``, ``outer_corner_arcs``, ``correct_interference``: see the fields.
    """

    tool_length_type: str = "B"
    startup_type: str = "A"
    #: G43/G44 need an axis word in their block (GSK alarm 27); False: ``G43 H_`` alone puts the offset in
    #: force and the next move of the tool axis carries it (Fanuc 0i, Haas).
    length_needs_axis: bool = True
    d_is_diameter: bool = False
    #: Outer corners between two compensated blocks get an arc of the offset radius about the programmed
    #: corner (as G39 makes one), instead of the type C intersection or extension points (HUST's corner type).
    outer_corner_arcs: bool = False
    #: Interference of a compensated block is corrected before it alarms (GSK/Fanuc: corner vectors are
    #: dropped, §3.5.3); False: any interference is an alarm at once (a DIN controller's contour violation).
    correct_interference: bool = True
    offset_count: int = 256
    geometry_limit_mm: float = 999.999
    wear_limit_mm: float = 99.999

    def new_offsets(self, initial: Mapping | ToolOffsets | None = None) -> ToolOffsets:
        """A fresh offset memory with these limits, filled from ``initial`` (as ToolOffsets.from_mapping)."""
        return ToolOffsets.from_mapping(
            initial,
            count=self.offset_count,
            geometry_limit_mm=self.geometry_limit_mm,
            wear_limit_mm=self.wear_limit_mm,
            d_is_diameter=self.d_is_diameter,
        )


@dataclass(frozen=True)
class MacroCalls:
    """Which codes call macros and subprograms (GSK parameters 6001#0, 6050-6059, 6071-6089).

    ``g_macro``: G code → program, called like G65 with arguments (6050-6059 → O9010-O9019).
    ``m_macro``: M code → program, called like G65 with arguments (6080-6089 → O9020-O9029).
    ``m_sub``: M code → program, called like M98 after the block's other commands (6071-6079 → O9001-O9009).
    ``t_sub``: with a program number (6001#0 TCS = 1: O9000), ``Tt`` is ``#149=t`` then ``M98 P9000``.
    Inside a program called by one of these codes, the codes are ordinary (§3.7.6).
    """

    g_macro: Mapping[int, int] = field(default_factory=dict)
    m_macro: Mapping[int, int] = field(default_factory=dict)
    m_sub: Mapping[int, int] = field(default_factory=dict)
    t_sub: int | None = None


@dataclass(frozen=True)
class ToolMeasurement:
    """The simulated measuring instrument and the G37 parameters.

    ``signal_at``: H number → work coordinate (mm) of the measured axis where the approach-end signal
    comes; numbers not listed signal at the commanded measurement position.
    ``feed_mm_min`` (P2651), ``decel_mm`` (r, P2652), ``band_mm`` (e, P2653): the machine tool
    builder's settings; ``G10 L50`` in the program overrides them.
    """

    signal_at: Mapping[int, float] = field(default_factory=dict)
    feed_mm_min: float = 1000.0
    decel_mm: float = 0.0
    band_mm: float = 0.0

    def __post_init__(self) -> None:
        for name in ("feed_mm_min", "decel_mm", "band_mm"):
            value = getattr(self, name)
            if not isinstance(value, int | float) or value != value or value < 0:
                raise ConfigError(f"ToolMeasurement.{name} must be a non-negative number, got {value!r}")
        if self.feed_mm_min <= 0:
            raise ConfigError("ToolMeasurement.feed_mm_min must be positive")
        for number, coordinate in dict(self.signal_at).items():
            if not isinstance(number, int) or not 1 <= number <= 256:
                raise ConfigError(f"ToolMeasurement.signal_at: H numbers are 1..256, got {number!r}")
            if not isinstance(coordinate, int | float) or coordinate != coordinate:
                raise ConfigError(f"ToolMeasurement.signal_at[{number}] must be a number, got {coordinate!r}")

    @classmethod
    def coerce(cls, value: ToolMeasurement | Mapping | None) -> ToolMeasurement:
        """``None`` (standard settings), a ToolMeasurement, or ``{"signal_at": {1: 198.0}, …}``."""
        if value is None:
            return cls()
        if isinstance(value, cls):
            return value
        if isinstance(value, Mapping):
            unknown = set(value) - {"signal_at", "feed_mm_min", "decel_mm", "band_mm"}
            if unknown:
                raise ConfigError(f"tool_measurement: unknown keys {sorted(unknown)}")
            return cls(**value)
        raise ConfigError(f"tool_measurement must be a ToolMeasurement or a mapping, "
                          f"got {type(value).__name__}")  # fmt: skip


def skip_signal_surfaces(value: Mapping | None, axes: str) -> dict[str, float]:
    """G31's simulated skip signal: ``{"X": 60.0}`` — the probe signals when the tool reaches X60
    (program coordinates, mm); the first surface a G31 move reaches stops it. None: no signal."""
    if value is None:
        return {}
    if not isinstance(value, Mapping):
        raise ConfigError(f"skip_signal must be a mapping of axis → coordinate, got {type(value).__name__}")
    surfaces = {}
    for letter, coordinate in value.items():
        if letter not in axes:
            raise ConfigError(f"skip_signal: {letter!r} is not an axis ({', '.join(axes)})")
        number = isinstance(coordinate, int | float) and not isinstance(coordinate, bool)
        if not number or coordinate != coordinate:
            raise ConfigError(f"skip_signal[{letter!r}] must be a number, got {coordinate!r}")
        surfaces[letter] = float(coordinate)
    return surfaces


@dataclass
class FlowOptions:
    """Options of one run (``interpret(..., max_blocks=, max_seconds=, max_segments=, program_dir=,
    macro_calls=, main_m99=)``).

    ``main_m99``: what M99 in the main program does. ``"end"`` (default): the program ends after one pass
    (a simulated episode is one part; docs/gcode.md). ``"restart"``: the controller's behaviour (§1.3.1), back
    to the start (or to ``Nn`` for ``M99 Pn``), so only a macro exit (a GOTO to M30) ends the run, else
    ``max_blocks`` does.
    ``follow_links``: a called program's file may lead out of the folder programs are looked up in (a
    symbolic link to elsewhere); off by default, when such a file is refused (:meth:`leaves_folder`).
    """

    max_blocks: int = DEFAULT_MAX_BLOCKS
    max_seconds: float = DEFAULT_MAX_SECONDS
    max_segments: int = DEFAULT_MAX_SEGMENTS
    program_dir: str | None = None
    macro_calls: MacroCalls | None = None
    main_m99: str = "end"
    follow_links: bool = False

    def program_folder(self, main_file: str) -> str | None:
        """The folder called programs are looked up in: ``program_dir``, else the main program's own folder
        (none when the main program is not a file)."""
        if self.program_dir is not None:
            return self.program_dir
        main = Path(main_file)
        return str(main.parent) if main.is_file() else None

    def leaves_folder(self, path: Path, main_file: str) -> str | None:
        """Why a called program's file ``path`` may not be read: it leads out of the lookup folder (a
        symbolic link, itself or on the way, to somewhere else), unless ``follow_links``. None when it may.
        The folder's own real path is the boundary, so a folder reached through a link is fine."""
        folder = self.program_folder(main_file)
        if self.follow_links or folder is None:
            return None
        root = os.path.realpath(folder)
        real = os.path.realpath(path)
        if os.path.commonpath([root, real]) == root:
            return None
        return (f"{path.name} leads out of the folder {folder} (to {real}); a called program is read only "
                "from inside its folder (follow_links=True, --follow-links, allows links out of it)")

    def program_files(self, main_file: str) -> dict[str, Path]:
        """Lower-case file name → path of every file in the folder called programs are looked up in
        (:meth:`program_folder`). The first of two names that differ only in case wins (sorted order)."""
        folder = self.program_folder(main_file)
        files: dict[str, Path] = {}
        if folder is not None and os.path.isdir(folder):
            for entry in sorted(os.listdir(folder)):
                path = Path(folder) / entry
                if path.is_file():
                    files.setdefault(entry.lower(), path)
        return files
