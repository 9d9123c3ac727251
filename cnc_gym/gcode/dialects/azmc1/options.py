"""The AZ-MC1's own parameters (:class:`AzOptions`, in ``Dialect.options``) and its features' run state
(:class:`AzData`, in ``State.dialect_data``).

The manual leaves the machine data to the machine builder: the zero offset table, the tool table, the PLC's
transfer parameters. They are parameters here, with neutral defaults; a variant dialect sets them::

    from dataclasses import replace
    az = replace(get_dialect("azmc1"), options=AzOptions(zero_offsets={2: (100.0, 50.0, 0.0)}))
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from cnc_gym.errors import ConfigError

if TYPE_CHECKING:
    from cnc_gym.gcode.dialect import Seam

Vec = tuple[float, float, float]
INF = math.inf


@dataclass(frozen=True)
class ToolRecord:
    """One entry of the tool table (AMK AZ-MC1 programming manual §12 "Tool management"), by D number:
    maximum life, warning limit, residual life (minutes), magazine location, and the D number of the
    sister tool (0: none)."""

    life: float = 0.0
    warn: float = 0.0
    residual: float = 0.0
    location: float = 0.0
    alternative: float = 0.0


@dataclass(frozen=True)
class AzOptions:
    """The AZ-MC1's machine data (module docstring).

    ``zero_offsets``: ZPO table entry (2..7, selected by G54..G59) → (x, y, z) in mm; entries not given are
    zero; entry 1 is G53, no offset. ``tools``: D number (1..40) → :class:`ToolRecord`; a D number not
    given reads life 0, location = its own number, no sister tool. ``plc_transfer``: the PLC's transfer
    parameters (n → value) that ``M25``/``M112 S<n>`` copy into R1000+n; not given: 0.
    """

    zero_offsets: Mapping[int, Vec] = field(default_factory=dict)
    tools: Mapping[int, ToolRecord] = field(default_factory=dict)
    plc_transfer: Mapping[int, float] = field(default_factory=dict)

    def __post_init__(self) -> None:
        for entry, offset in self.zero_offsets.items():
            if entry not in range(2, 8):
                raise ConfigError(f"azmc1 zero_offsets: entry {entry!r} is not 2..7 (G54..G59)")
            if len(offset) != 3 or not all(isinstance(c, int | float) and math.isfinite(c) for c in offset):
                raise ConfigError(f"azmc1 zero_offsets[{entry}]: expected (x, y, z) in mm, got {offset!r}")
        for number in self.tools:
            if number not in range(1, 41):
                raise ConfigError(f"azmc1 tools: D number {number!r} is not 1..40")


@dataclass(eq=False)
class AzData:
    """The AZ-MC1 features' state of one run (``State.dialect_data``)."""

    #: G161 in force: I/J/K are the absolute centre (False: G162, relative to the start).
    centre_absolute: bool = False
    #: G138 (``"A"``: direct) or G139 (``"B"``: with transition blocks) TRO approach.
    approach: str = "B"
    #: Software limit switches (G98 −, G99 +), machine coordinates mm, per axis.
    low: list[float] = field(default_factory=lambda: [-INF, -INF, -INF])
    high: list[float] = field(default_factory=lambda: [INF, INF, INF])
    #: Limits in force from a segment index on: (first segment, low, high, source line).
    limit_epochs: list[tuple[int, tuple, tuple, int]] = field(default_factory=list)
    #: Spindle 2 (M13/M14/M15): +1 CW, -1 CCW, 0 stopped.
    spindle2: int = 0
    #: The last H word sent to the PLC (kept until the next H, §4.3), None before the first.
    h_word: int | None = None
    #: A TRO selection (``"selection"``) or withdrawal (``"withdrawal"``) whose first travel in the plane
    #: is still to come: it may not be a circle, whatever the radius (§11.3.1, §11.3.4); None: none.
    tro_transition: str | None = None


def data(core: Seam) -> AzData:
    """The run's :class:`AzData`, created on first use. The software limits start at the machine preset's
    travel ("preset from the axis machine data record at run-up", §3.1.7), unbounded without a preset."""
    st = core.state
    if st.dialect_data is None:
        st.dialect_data = AzData()
        if st.machine is not None:
            st.dialect_data.low = [float(v) for v in st.machine.axis_array("min_position_mm")]
            st.dialect_data.high = [float(v) for v in st.machine.axis_array("max_position_mm")]
    return st.dialect_data


def options(core: Seam) -> AzOptions:
    opts = core.dialect.options
    return opts if isinstance(opts, AzOptions) else AzOptions()
