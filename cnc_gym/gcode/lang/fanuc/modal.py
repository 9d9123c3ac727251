"""Modal states and words of the Fanuc family: plane, distance mode, units, path modes, F S T, spindle,
coolant, tool change, program stops, dwell.

Each function is an action of the registry (``lang/fanuc/__init__.py``): ``action(core, spec, values)``,
with ``values`` None when the code is put in force at power-on.

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from cnc_gym.defaults import INCH_MM
from cnc_gym.gcode.lang.fanuc import compensation, corners, least_units, transforms
from cnc_gym.toolpath import SegmentMode

if TYPE_CHECKING:
    from cnc_gym.errors import ProgramError
    from cnc_gym.gcode.codes import CodeSpec
    from cnc_gym.gcode.dialect import Seam

#: Path modes (group 15) → the flags every segment carries for the controller.
PATH_MODES = {
    "exact_stop": SegmentMode.EXACT_STOP,
    "tapping": SegmentMode.OVERRIDE_LOCKED | SegmentMode.TAPPING_MODE,
    "auto_corner": SegmentMode.AUTO_CORNER,
    "cutting": SegmentMode.NONE,
}


def missing_feed(core: Seam, name: str) -> ProgramError:
    """The error of a feed move without a feed (G95: F and S both needed)."""
    st = core.state
    if st.feed_per_rev and st.feed is None:
        what = "no F in G95 yet" if st.feed_programmed is None else "the spindle speed S is 0"
        return core.error(f"{name} in G95 (feed per revolution) needs F (mm/rev) and a spindle speed S: "
                          f"{what}", "missing-feed")  # fmt: skip
    return core.error(f"{name} needs a feed: no F programmed yet" if st.feed is None else
                      f"{name} with F0: the feed is zero", "missing-feed")  # fmt: skip


def record(core: Seam, spec: CodeSpec, values: dict | None = None) -> None:
    """A code whose only effect is its entry in the modal table (G23, G97, G98/G99 …)."""


def plane(core: Seam, spec: CodeSpec, values: dict | None = None) -> None:
    """G17/G18/G19: the plane of arcs, cutter compensation and polar input."""
    st = core.state
    if st.chain.active:
        transforms.check_plane_change(core, spec.value)  # type: ignore[arg-type]
    if st.comp.side:
        compensation.check_plane(core, spec.value)
    if spec.value != st.plane:
        corners.mark_coordinate_change(core)  # no chamfer/corner R in the next block
    st.plane = spec.value  # type: ignore[assignment]


def distance(core: Seam, spec: CodeSpec, values: dict | None = None) -> None:
    """G90/G91: absolute or incremental axis words."""
    core.state.incremental = spec.value  # type: ignore[assignment]


def units(core: Seam, spec: CodeSpec, values: dict | None = None) -> None:
    """G20/G21: inch or mm input. Every length of the program is read in the unit in force."""
    st = core.state
    if values is not None and spec.value != st.inch and (
            len(st.builder) or st.offsets.floating is not None or any(st.offsets.local)):  # fmt: skip
        # §3.2.19: G20/G21 go at the start, before the work coordinate system is set, and must not
        # switch in the middle of a program (positions and offsets already given would change meaning).
        where = core.dialect.cite("§3.2.19")
        raise core.error(f"{spec.name}: inch/metric input cannot switch after the program has moved or set a "
                         f"coordinate system (give it alone at the start{', ' + where if where else ''})",
                         "units-switch")  # fmt: skip
    st.inch = bool(spec.value)
    st.scale = INCH_MM if spec.value else 1.0
    dialect = core.dialect
    st.increment = dialect.least_increment_inch if spec.value else dialect.least_increment_mm
    core.update_modes()


def exact_stop_once(core: Seam, spec: CodeSpec, values: dict) -> None:
    """G09: exact stop at the end of this block's move only (one-shot)."""
    st = core.state
    st.out.modes = st.out.modes | SegmentMode.EXACT_STOP
    st.restore_modes = True


def path_mode(core: Seam, spec: CodeSpec, values: dict | None = None) -> None:
    """G61-G64: the path mode every later segment carries (:data:`PATH_MODES`)."""
    core.state.path_mode = PATH_MODES[spec.value]  # type: ignore[index]
    core.update_modes()


# ---------------------------------------------------------------------- words
def feed(core: Seam, spec: CodeSpec | None, values: dict) -> None:
    """F: the feed, mm/min (inch/min in G20, converted); in G95 mm/rev (inch/rev), the feed being F × S."""
    st = core.state
    if st.feed_per_rev:
        st.feed_programmed = values["F"] * st.scale
        st.feed = _per_minute(st.feed_programmed, st.spindle_speed)
        return
    st.feed = values["F"] * st.scale


def spindle_speed(core: Seam, spec: CodeSpec | None, values: dict) -> None:
    """S: spindle speed (r/min), recorded on every segment signed by the direction (in G95 the feed follows
    it)."""
    st = core.state
    st.spindle_speed = values["S"]
    st.out.spindle_rpm = st.spindle_speed * st.spindle_direction
    if st.feed_per_rev and st.feed_programmed is not None:
        st.feed = _per_minute(st.feed_programmed, st.spindle_speed)


def _per_minute(per_rev: float, rpm: float) -> float | None:
    """Feed per revolution × spindle speed; None while the spindle speed is 0 (no feed yet)."""
    return per_rev * rpm if rpm > 0 else None


def feed_mode(core: Seam, spec: CodeSpec, values: dict | None = None) -> None:
    """G94 (feed per minute) / G95 (feed per revolution, ``spec.value`` ``"revolution"``): in G95 F is mm/rev
    (inch/rev) and the feed is F × S, following S. A switch drops the F in force (its unit changed): the
    program gives F again (Fanuc 0i)."""
    st = core.state
    per_rev = spec.value == "revolution"
    if per_rev != st.feed_per_rev:
        st.feed_per_rev = per_rev
        st.feed_programmed = None
        if values is not None:
            st.feed = None


def spindle_orient(core: Seam, spec: CodeSpec, values: dict) -> None:
    """M19 oriented spindle stop: the spindle stops at its orientation angle (a 0 s exact-stop dwell, spindle
    speed 0 on the segments; counted in ``State.spindle_orients``)."""
    st = core.state
    st.spindle_direction = 0
    st.out.spindle_rpm = 0.0
    st.out.dwell(0.0, SegmentMode.EXACT_STOP)
    st.spindle_orients += 1


def tool(core: Seam, spec: CodeSpec | None, values: dict) -> None:
    """T: the tool number every later segment carries (the tool change itself is M06)."""
    st = core.state
    st.tool = int(values["T"])
    st.out.tool = st.tool


def tool_change(core: Seam, spec: CodeSpec, values: dict) -> None:
    """M06: counted (the machine builder's tool change has no motion in the program)."""
    core.state.tool_changes += 1


def spindle(core: Seam, spec: CodeSpec, values: dict) -> None:
    """M03/M04/M05: spindle CW, CCW, stop."""
    st = core.state
    st.spindle_direction = spec.value  # type: ignore[assignment]
    st.out.spindle_rpm = st.spindle_speed * st.spindle_direction


def coolant(core: Seam, spec: CodeSpec, values: dict) -> None:
    """M08/M09: coolant on/off, recorded."""
    core.state.coolant = bool(spec.value)


def stop(core: Seam, spec: CodeSpec, values: dict) -> None:
    """M00/M01/M02/M30: program stop (a 0 s exact-stop dwell), optional stop (the switch is off in
    simulation, so the program runs on), end."""
    st = core.state
    st.stops.append((st.out.line, spec.value))  # type: ignore[arg-type]
    if spec.value == "program_stop":
        # M00: the machine stops with an in-position check; a 0 s dwell carries that to the controller.
        st.out.dwell(0.0, SegmentMode.EXACT_STOP)
    elif spec.value == "end":
        st.ended = True


def dwell(core: Seam, spec: CodeSpec, values: dict) -> None:
    """G04: P in ms (integer), X in s; P wins; neither = exact stop (§3.2.6). Where numbers without a
    decimal point are least units (DPI = 0), X without one is in ms whatever the length unit in force
    (``G04 X1500`` is 1.5 s in G20 too)."""
    for letter in "YZ":
        if letter in values:
            raise core.error(f"address {letter} has no meaning with G04", "unused-word")
    out = core.state.out
    if "P" in values:
        text = core.word_text("P")
        raw = values["P"]
        seconds = round(raw) / 1000.0
        if text is not None and "." in text:
            if not core.dialect.dwell_p_decimal_seconds:
                raise core.error(f"G04 P{text}: P is in milliseconds and takes no decimal point (use X for "
                                 "seconds)", "decimal-point-not-allowed")  # fmt: skip
            seconds = float(text)  # Haas: P10. is 10 seconds
    elif "X" in values:
        raw = values["X"]
        whole = not core.dialect.integer_is_unit and least_units.is_whole(core, "X")
        seconds = least_units.whole_count(core, "X", raw) / 1000.0 if whole else raw
    else:
        out.dwell(0.0, SegmentMode.EXACT_STOP)
        return
    if raw < 0:
        raise core.error(f"G04 dwell time {raw:g} is negative", "bad-dwell")
    out.dwell(seconds)


def machine_function(core: Seam, spec: CodeSpec, values: dict) -> None:
    """An M code the control hands to the machine (coolant variants, clamps, conveyors …; the machine
    builder's list): no motion of the program, the block ends when the machine answers — a 0 s exact-stop
    dwell flagged MACHINE_FUNCTION, its code on the tool path (``Toolpath.machine_functions``)."""
    st = core.state
    st.out.dwell(0.0, SegmentMode.EXACT_STOP | SegmentMode.MACHINE_FUNCTION)
    st.builder.machine_functions.append(spec.name)


ACTIONS = {
    "record": record, "plane": plane, "distance": distance, "units": units, "path_mode": path_mode,
    "exact_stop_once": exact_stop_once, "feed": feed, "spindle_speed": spindle_speed, "tool": tool,
    "tool_change": tool_change, "spindle": spindle, "coolant": coolant, "stop": stop, "dwell": dwell,
    "cycle_return": record, "feed_mode": feed_mode, "spindle_orient": spindle_orient,
    "machine_function": machine_function,
}  # fmt: skip
