"""The H4C-M's own parameters (:class:`H4cmOptions`, in ``Dialect.options``) and its features' state
(:class:`H4cmData`, in ``State.dialect_data``).

The parameters are MCM numbers of the chapter-4 table (HUST H4C-M manual §4.1, the formal parameter
list; chapter 3 cites an older 3-axis numbering, kept in docs/h4cm.md as aliases). Only the ones that
change what the interpreter does are here; those that shape the motion profile live in the machine preset
``configs/machines/h4cm.yaml``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from cnc_gym.frozen import FrozenDict
from cnc_gym.toolpath import SegmentMode

if TYPE_CHECKING:
    from cnc_gym.gcode.dialect import Seam

#: #93 interpolation modes: 0 CNC (exact stop), 1-4 X/Y/Z/A master, 256 non-stop between blocks.
CNC_MODE = 0
NON_STOP = 256


@dataclass(frozen=True)
class H4cmOptions:
    """MCM parameters the H4C-M dialect reads (defaults: the manual's table).

    ``interpolation_mode`` (#93): 0 CNC mode (exact stop at every block end, F the vector feed); 1, 2, 3
    master/slave with X, Y or Z the master axis (no stop between blocks, F the master axis's speed); 256
    non-stop between blocks (vector F). ``power_on_feed`` (#112): the G01 feed at power-on, mm/min.
    ``g83_clearance_mm`` (#282): G83's d. ``counter_limit`` (#170): parts until ERROR 03 (0: none).
    ``max_subprogram_nesting``: 5 (§3.39; ERROR 24 speaks of 8, the chapter-3 text of 5).
    ``plc_bits``: the simulated PLC's bit image read by G65 L51-L55: ``{"I": 0b100000, "C": …}`` (bit n of
    the integer = bit n of the area); ``plc_registers``, ``plc_counters``: R and counter values at power-on.
    """

    interpolation_mode: int = CNC_MODE
    power_on_feed: float = 1000.0
    g83_clearance_mm: float = 2.0
    counter_limit: int = 0
    plc_bits: Mapping[str, int] = field(default_factory=FrozenDict)
    plc_registers: Mapping[int, int] = field(default_factory=FrozenDict)
    plc_counters: Mapping[int, int] = field(default_factory=FrozenDict)

    def __post_init__(self) -> None:
        from cnc_gym.errors import ConfigError

        if self.interpolation_mode not in (0, 1, 2, 3, NON_STOP):
            raise ConfigError(f"H4cmOptions.interpolation_mode (#93) is 0, 1, 2, 3 or 256, got "
                              f"{self.interpolation_mode!r}")  # fmt: skip
        areas: dict[str, tuple] = {"plc_bits": tuple("IOCSA"), "plc_registers": tuple(range(256)),
                                   "plc_counters": tuple(range(256))}  # fmt: skip
        for name, keys in areas.items():
            value = getattr(self, name)
            for key, item in dict(value).items():
                if key not in keys or isinstance(item, bool) or not isinstance(item, int):
                    allowed = "I, O, C, S, A" if name == "plc_bits" else "0-255"
                    raise ConfigError(f"H4cmOptions.{name}: {key!r}: {item!r} (keys {allowed}, integers)")
            if not isinstance(value, FrozenDict):
                object.__setattr__(self, name, FrozenDict(value))


@dataclass(eq=False)
class H4cmData:
    """State of the H4C-M's own features during one run (created on first use by :func:`data`)."""

    #: G68/G69 mirror toggles: X mirrored, Y mirrored.
    mirror: list[bool] = field(default_factory=lambda: [False, False])
    #: G51 in force: the scaling centre (program mm) and the factors.
    scaling: tuple | None = None
    #: The program position before the last G28/G30 (G29 returns there), per axis, or None.
    before_reference: list[float | None] = field(default_factory=lambda: [None, None, None])
    #: The last block was an arc (ERROR 25 unless the next motion block is G00/G01).
    arc_open: bool = False
    #: T and D of a groove block (its type and tool radius), taken off the words by blocks.py.
    groove_words: dict = field(default_factory=dict)
    #: Tool table X/Y offsets and wear per group (the Z offset and R radius live in the offset memory).
    xy_offsets: dict = field(default_factory=dict)
    #: The part counter (#169) and its limit (#170; G10 P200).
    parts: int = 0
    counter_limit: int = 0
    #: G01 acc/dec time set by G10 P800 (ms), None: the machine's.
    feed_accel_ms: int | None = None
    #: The simulated PLC: registers R0-R255, counters 0-255, bit areas.
    registers: dict = field(default_factory=dict)
    counters: dict = field(default_factory=dict)


def options(core: Seam) -> H4cmOptions:
    return core.dialect.options if isinstance(core.dialect.options, H4cmOptions) else H4cmOptions()


def data(core: Seam) -> H4cmData:
    """The run's H4C-M state record (created on first use)."""
    st = core.state
    if st.dialect_data is None:
        opts = options(core)
        st.dialect_data = H4cmData(counter_limit=opts.counter_limit, registers=dict(opts.plc_registers),
                                   counters=dict(opts.plc_counters))  # fmt: skip
        if opts.interpolation_mode == CNC_MODE:
            # CNC mode (#93 = 0): "decelerate to a complete stop at the end of" every block (modes.py).
            st.path_mode = st.path_mode | SegmentMode.EXACT_STOP
            core.update_modes()
    return st.dialect_data
