"""The AZ-MC1's modes and words: dwell, units, feed, block transitions (G09, G60, G63, G36/G37), centre
mode (G161/G162), mirroring (G20-G23), subroutine end (M29), spindle 2, the PLC's transfer parameters
(M25/M112), axis-group wait (M26), H words. Sections (§n) are those of the AMK AZ-MC1 programming manual.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from cnc_gym.defaults import INCH_MM
from cnc_gym.gcode.canonical import scaling_stage
from cnc_gym.gcode.dialects.azmc1.options import data, options
from cnc_gym.gcode.lang.fanuc.modal import spindle_speed as family_spindle_speed
from cnc_gym.toolpath import SegmentMode

if TYPE_CHECKING:
    from cnc_gym.gcode.codes import CodeSpec
    from cnc_gym.gcode.dialect import Seam

#: M codes whose S word is theirs, not a spindle speed (§4.2: the PLC parameter index).
_S_TAKERS = frozenset({25.0, 112.0})
_SPINDLE_ACTIONS = frozenset({"spindle", "spindle_2", "spindle_orient"})


def dwell(core: Seam, spec: CodeSpec, values: dict) -> None:
    """G04: dwell, the time in seconds under the first axis's address (``G04 X 4.13``, §3.1.4)."""
    axes = core.dialect.axes
    first = axes[0]
    for letter in axes[1:]:
        if letter in values:
            raise core.error(f"G04 takes the time under {first} (the first axis), not {letter}",
                             "unused-word")  # fmt: skip
    if first not in values:
        raise core.error(f"G04 needs the dwell time in seconds: G04 {first}<seconds>", "bad-dwell")
    seconds = values[first]
    if seconds < 0:
        raise core.error(f"G04 dwell time {seconds:g} is negative", "bad-dwell")
    core.state.out.dwell(seconds)


def units(core: Seam, spec: CodeSpec, values: dict | None = None) -> None:
    """G70 (inch) / G71 (mm): on "all distance and coordinate data, but not on feed, tool offsets and zero
    offsets" (§3.6): F stays in mm/min, offsets stay in mm. Either may be given at any block."""
    st = core.state
    st.inch = bool(spec.value)
    st.scale = INCH_MM if spec.value else 1.0
    st.increment = core.dialect.least_increment_inch if spec.value else core.dialect.least_increment_mm
    core.update_modes()


def feed(core: Seam, spec: CodeSpec | None, values: dict) -> None:
    """F: the path feed in mm/min whatever G70/G71 (§3.6, §5); in G95 mm per spindle revolution."""
    st = core.state
    f = values["F"]
    if st.feed_per_rev:
        st.feed_programmed = f
        st.feed = f * st.spindle_speed if st.spindle_speed > 0 else None
        return
    st.feed = f


def spindle_speed(core: Seam, spec: CodeSpec | None, values: dict) -> None:
    """S: the spindle speed, unless an M code of the block takes S as its own value (M25/M112 S<n>)."""
    for word in core.state.block_words:
        if word[0] == "M" and word[1] in _S_TAKERS:
            return
    family_spindle_speed(core, spec, values)


def feed_adaptation_end(core: Seam, spec: CodeSpec, values: dict) -> None:
    """G09: "a delay for the feed of the next block takes place already at the end of the current block"
    (§3.2). The motion stage's look-ahead always meets the next block's feed by the end of a block (and so
    at every G00 → G01/G02/G03 change too), which is G09's behaviour; it needs no flag. The controller's
    default, a block entered at the previous block's speed and adapted inside it, is the part the simulation
    does not reproduce (docs/azmc1.md)."""


def override_lock(core: Seam, spec: CodeSpec, values: dict) -> None:
    """G63: the feed override is fixed at 100 % for this motion block (§3.14)."""
    st = core.state
    st.out.modes = st.out.modes | SegmentMode.OVERRIDE_LOCKED
    st.restore_modes = True


def block_rounding(core: Seam, spec: CodeSpec, values: dict | None = None) -> None:
    """G36/G37: rounding of linear blocks on/off (§3.13), recorded on every segment as ``ROUND_BLOCK_END``."""
    st = core.state
    if spec.value:
        st.path_mode = st.path_mode | SegmentMode.ROUND_BLOCK_END
    else:
        st.path_mode = st.path_mode & ~SegmentMode.ROUND_BLOCK_END
    core.update_modes()


def centre_mode(core: Seam, spec: CodeSpec, values: dict | None = None) -> None:
    """G161 (I/J/K absolute) / G162 (relative to the circle's start, the basic state), §3.11."""
    data(core).centre_absolute = bool(spec.value)


def tro_approach(core: Seam, spec: CodeSpec, values: dict | None = None) -> None:
    """G138 (direct: the approach block runs to the point perpendicular to the next block's start) / G139
    (with transition blocks, the basic state), §3.10, §11.3.1."""
    data(core).approach = str(spec.value)
    stage = core.state.comp.stage
    if stage is not None:
        stage.startup_type = str(spec.value)


def mirror(core: Seam, spec: CodeSpec, values: dict | None = None) -> None:
    """G20 (off), G21 (X), G22 (Y), G23 (X and Y: point mirroring) about the program zero (§3.5). A mirror
    of one axis runs arcs the other way round (the chain's arc mapping) and swaps the TRO side."""
    st = core.state
    axes: tuple[int, ...] = tuple(spec.value)  # type: ignore[arg-type]
    if st.comp.side:
        raise core.error(f"{spec.name}: mirroring cannot change while the tool radius offset is on (G40 "
                         "first)", "mirror-in-tro")  # fmt: skip
    if axes:
        factors = tuple(-1.0 if a in axes else 1.0 for a in range(3))
        st.chain.set("mirror", scaling_stage(spec.name, (0.0, 0.0, 0.0), factors))  # type: ignore[arg-type]
    else:
        if st.chain.stages["mirror"] is None:
            return
        st.chain.set("mirror", None)
        core.resync_program_position()
    core.set_transform_state()


def subroutine_end(core: Seam, spec: CodeSpec, values: dict) -> None:
    """M29: the end of a subroutine (§4.1.4); the runner returns to the caller."""
    core.state.flow_request = ("return",)


def spindle_2(core: Seam, spec: CodeSpec, values: dict) -> None:
    """M13/M14/M15: spindle 2 CW, CCW, stop (§4.1.7); recorded (spindle 2 drives no path axis)."""
    data(core).spindle2 = int(spec.value)  # type: ignore[call-overload]


def plc_read(core: Seam, spec: CodeSpec, values: dict) -> None:
    """M25/M112 S<n>: copy the PLC's transfer parameter n into R1000+n; S-1 copies all of them (§4.2). The
    simulated PLC's transfer parameters are ``AzOptions.plc_transfer`` (0 where not given); M112's wait for
    the PLC's acknowledgement takes no time in simulation."""
    if "S" not in values:
        raise core.error(f"{spec.name} needs S<n> (the transfer parameter) or S-1 (all)", "missing-value")
    n = values["S"]
    store = core.state.variables
    transfer = options(core).plc_transfer
    if n == -1:
        for number, value in transfer.items():
            store.write(1000 + number, value)
        return
    if n != int(n) or not 0 <= n <= 8999:
        raise core.error(f"{spec.name} S{n:g}: the transfer parameter is 0..8999 (R1000+n) or -1 (all)",
                         "value-out-of-range")  # fmt: skip
    store.write(1000 + int(n), float(transfer.get(int(n), 0.0)))


def axis_group_wait(core: Seam, spec: CodeSpec, values: dict) -> None:
    """M26: the next path block waits for the other axis groups (§4.1.5). The simulated machine has one axis
    group (X, Y, Z move as one path), so nothing is left to wait for."""


def auxiliary(core: Seam, spec: CodeSpec | None, values: dict) -> None:
    """H: an auxiliary function passed to the PLC (§4.3), kept until the next H."""
    data(core).h_word = int(values["H"])


def check_spindle_with_homing(core: Seam, plan) -> CodeSpec | None:
    """Block check: spindle M functions may not share a block with G74 (§3.1.5)."""
    if any(spec.action == "homing" for spec in plan.items):
        spindle = [spec.name for spec in plan.items if spec.action in _SPINDLE_ACTIONS]
        if spindle:
            raise core.error(f"{spindle[0]} in the block of G74: spindle functions are not allowed with the "
                             "homing cycle (AMK AZ-MC1 programming manual §3.1.5)",
                             "bad-combination")  # fmt: skip
    return plan.axis_owner


ACTIONS = {
    "dwell": dwell, "units": units, "feed": feed, "spindle_speed": spindle_speed,
    "feed_adaptation_end": feed_adaptation_end, "override_lock": override_lock,
    "block_rounding": block_rounding, "centre_mode": centre_mode, "tro_approach": tro_approach,
    "mirror": mirror, "subroutine_end": subroutine_end, "spindle_2": spindle_2, "plc_read": plc_read,
    "axis_group_wait": axis_group_wait, "auxiliary": auxiliary,
}  # fmt: skip

__all__ = ["ACTIONS", "check_spindle_with_homing"]
