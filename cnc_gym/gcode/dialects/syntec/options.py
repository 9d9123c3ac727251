"""Syntec 8.20's own parameters (:class:`SyntecOptions`, ``Dialect.options``) and the state of its own
features (:class:`SyntecData`, ``State.dialect_data``).

The parameters are the controller settings the Syntec 8.20 mill programming manual names where it
describes a code (Pr4001 peck-tapping type, Pr4002 peck return, Pr4020 shift direction, Pr411 …) and the
readings this dialect makes where the manual contradicts itself (the polar angle's sign, ``G04 P2.5``).
A variant of the dialect is ``dataclasses.replace(DIALECT, options=replace(DIALECT.options, …))``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from cnc_gym.errors import ConfigError

if TYPE_CHECKING:
    from cnc_gym.gcode.dialect import Seam

#: ``G04 P`` with a decimal point (§G04: "decimal point not permitted", yet ``G04 P2.5; //delay 2 sec``).
G04_P_DECIMAL = ("seconds", "error")


@dataclass(frozen=True)
class SyntecOptions:
    """Syntec 8.20 parameters and readings (docs/syntec.md "Choices")."""

    #: ``G04 P2.5``: ``"seconds"`` — the manual's own example: the fraction is dropped and what remains is
    #: seconds (2 s); ``"error"`` — refuse the decimal point (``decimal-point-not-allowed``).
    g04_p_decimal: str = "seconds"
    #: G16 polar angle sign. False: counter-clockwise positive, as the manual's own G135/G136 ("CCW is
    #: positive") and its polar drilling example need; True: the §G15/G16 text's literal "'+' for CW".
    polar_angle_cw: bool = False
    #: G16 in G91: False (the §G15/G16 text): radius and angle increments add to the last radius and angle
    #: about the same origin; True (the Fanuc variant): an incremental radius puts the origin at the tool.
    polar_incremental_origin_at_tool: bool = False
    #: Pr4001: G84/G74 with Q. 1 = high-speed peck tapping (back by d after each peck); 0 = general peck
    #: tapping (back to R after each peck).
    peck_tapping_type: int = 0
    #: Smoothing tolerance (mm) of each G05 high-speed, high-precision parameter set (P10000 the factory
    #: set, P1-P5 the user sets). The manual gives the sets' contents nowhere; these are our settings.
    hshp_tolerance_mm: Mapping[int, float] = field(
        default_factory=lambda: {10000: 0.01, 1: 0.01, 2: 0.01, 3: 0.01, 4: 0.01, 5: 0.01})
    #: The feed in force before any F: G94 1000 mm/min (inch/min in G70), G95 1 mm/rev (inch/rev).
    default_feed_per_minute: float = 1000.0
    default_feed_per_revolution: float = 1.0

    def __post_init__(self) -> None:
        if self.g04_p_decimal not in G04_P_DECIMAL:
            raise ConfigError(f"syntec option g04_p_decimal {self.g04_p_decimal!r}: one of {G04_P_DECIMAL}")
        if self.peck_tapping_type not in (0, 1):
            raise ConfigError(f"syntec option peck_tapping_type (Pr4001) {self.peck_tapping_type!r}: 0 or 1")
        for number, tolerance in self.hshp_tolerance_mm.items():
            if number not in (10000, 1, 2, 3, 4, 5) or not tolerance >= 0.0:
                raise ConfigError(f"syntec option hshp_tolerance_mm[{number!r}] = {tolerance!r}: the sets "
                                  "are P10000 and P1-P5, tolerances >= 0 mm")  # fmt: skip
        for name in ("default_feed_per_minute", "default_feed_per_revolution"):
            if not getattr(self, name) > 0.0:
                raise ConfigError(f"syntec option {name} must be positive")


@dataclass(eq=False)
class SyntecData:
    """The state of Syntec's own features in one run (``State.dialect_data``)."""

    #: G05 parameter set in force (10000, 1-5), None: high-speed, high-precision mode off.
    hshp: int | None = None
    #: File and line of the G05 block that turned the mode on (for the end-of-program error).
    hshp_block: tuple[str, int] = ("<program>", 0)
    #: G05.1 Q1 E_: the smoothing tolerance in force (mm), None: off.
    smoothing_mm: float | None = None
    #: The next G01 block is not smoothed (the first after G43/G44/G49 or a coordinate change, §G05.1).
    skip_next_line: bool = False
    #: An F word has set the feed since power-on or the last G94/G95 switch (else the default feed).
    feed_programmed: bool = False
    #: G33's thread lead (mm): F of a G33 block.
    thread_lead_mm: float | None = None
    #: G92 S_: the spindle speed limit of constant surface speed (r/min), None: none.
    spindle_clamp_rpm: float | None = None
    #: G96 S_: the surface speed (m/min, feet/min in G70) in force, None: G97 (S is r/min).
    surface_speed: float | None = None
    #: The label an M98 H_ block names (read off the block by the word normaliser, blocks.py).
    call_label: float | None = None
    #: The G92 S_ of the block (read off the block by the word normaliser: S is then no spindle speed).
    clamp_word: float | None = None
    #: D and F of a G37/G37.1 block: probe over-travel and measuring feed (program units).
    measure_words: dict = field(default_factory=dict)
    #: G06.2 F: the feed of the last NURBS curve (a curve without F takes it, §G06.2).
    nurbs_feed: float | None = None
    #: M99 ended the main program (a program in G05 mode must end with M30 or M99).
    ended_by_code: bool = False
    #: G68 in force as programmed: (centre, program mm; angle, degrees), None: G69. The chain's rotation
    #: stage turns the other way while one axis of the plane is mirrored (§G51.1).
    rotation: tuple[tuple[float, float, float], float] | None = None


def data(core: Seam) -> SyntecData:
    """This run's :class:`SyntecData` (created on first use)."""
    st = core.state
    found = st.dialect_data
    if found is None:
        found = st.dialect_data = SyntecData()
    return found


def options(core: Seam) -> SyntecOptions:
    return core.dialect.options
