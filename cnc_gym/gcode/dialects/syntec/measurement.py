"""Syntec 8.20's automatic tool length measurement G37 and G37.1 (Syntec 8.20 mill programming manual §G37
"Automatic tool length measurement - I", §G37.1 "- II"), with the simulated instrument of
``interpret(..., tool_measurement=)`` (:class:`~cnc_gym.gcode.settings.ToolMeasurement`: per H number the
work Z where the probe fires; by default exactly at the commanded Z).

``G37 Z_ [R_] [D_] [F_] [P_]`` (H given before, MAR-334; Z required, MAR-330):

1. with P (1-4) a rapid to reference point P (the probe's position, all axes);
2. rapid down to the probe's starting point Z + R; the tool must start above it (MAR-333);
3. skip move (G31) at F toward the probe's end point Z - D, stopping where the probe fires: the signal
   must come below the starting point (else MAR-335: it would have fired during the rapid) and by the end
   point (else MAR-336);
4. the H number's offset changes by (signal Z - Z) (the wear value), as a Fanuc-style G37 does.

R defaults to ``ToolMeasurement.decel_mm`` (Pr4055), D to ``band_mm`` (Pr4056), F to ``feed_mm_min``
(Pr4057). Every move runs with the override fixed at 100 % ("The override is defined a 100 %").

``G37.1 Z_ [R_] [F_] [P_] [Q_]``: Z, Q and the moves in machine coordinates: (M90 air blast on,) the
reference return P, rapid to Z + R, (M91 off,) a skip move at F toward Z, back up 1 mm at rapid on the
signal, a second touch at F50 toward Z, the offset change (signal - Z, work coordinates), then Z up to the
safety point Q or to the machine zero. The air blast has no motion and is not on the tool path.

The manual gives no formula for the stored length: we change the offset by the difference between where
the probe fired and the commanded Z, so a tool whose offset is right measures a change of 0.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from cnc_gym.gcode.dialects.syntec.options import data
from cnc_gym.gcode.lang.fanuc import compensation
from cnc_gym.gcode.lang.fanuc.reference import reference_point
from cnc_gym.toolpath import SegmentMode

if TYPE_CHECKING:
    from cnc_gym.gcode.codes import CodeSpec
    from cnc_gym.gcode.dialect import Seam
    from cnc_gym.gcode.settings import ToolMeasurement

#: G37.1's second touch: feed (mm/min) and the retract before it (mm), fixed by the manual (§G37.1 steps).
SECOND_TOUCH_FEED = 50.0
SECOND_TOUCH_RETRACT_MM = 1.0
_Z = 2


def _check(core: Seam, spec: CodeSpec, values: dict) -> int:
    """The common checks; returns the H number."""
    st = core.state
    if "Z" not in values:
        raise core.error(f"MAR-330 Z min. coordinate set error: {spec.name} needs Z", "g37-no-z")
    for letter in ("X", "Y"):
        if letter in values:
            raise core.error(f"address {letter} has no meaning with {spec.name} (it measures along Z)",
                             "unused-word")  # fmt: skip
    if st.comp.h_number == 0:
        raise core.error(f"MAR-334 without an H code before {spec.name}: select the tool's length offset "
                         "(e.g. H1;) first", "g37-no-h")  # fmt: skip
    if st.comp.side:
        raise core.error(f"{spec.name} in cutter compensation mode: cancel it with G40 first",
                         "bad-combination")  # fmt: skip
    if st.chain.active or st.polar is not None:
        raise core.error(f"{spec.name} under rotation, scaling, mirror or polar input is not supported",
                         "bad-combination")  # fmt: skip
    return st.comp.h_number


def _reference(core: Seam, spec: CodeSpec, values: dict) -> None:
    """Step 1: a rapid to reference point P when P is given."""
    if "P" not in values:
        return
    p = values["P"]
    if p not in (1.0, 2.0, 3.0, 4.0):
        raise core.error(f"{spec.name} P{p:g}: the reference point is P1-P4", "bad-reference")
    core.state.out.straight_traverse(reference_point(core, int(p)))


def _z(core: Seam, z: float) -> None:
    """A rapid of Z alone to machine coordinate ``z``."""
    out = core.state.out
    p = out.position
    out.straight_traverse((p[0], p[1], z))


def _skip(core: Seam, z: float, feed: float, *, stops: bool) -> None:
    """A skip move of Z to machine coordinate ``z`` at ``feed``; ``stops``: it ends on the probe's signal."""
    out = core.state.out
    p = out.position
    saved = out.modes
    out.modes = saved | (SegmentMode.EXACT_STOP if stops else SegmentMode.NONE)
    try:
        out.straight_feed((p[0], p[1], z), feed)
    finally:
        out.modes = saved


def _signal(core: Seam, number: int, nominal_work: float) -> float:
    settings: ToolMeasurement = core.state.tool_measurement
    return float(settings.signal_at.get(number, nominal_work))


def _store(core: Seam, number: int, signal_work: float, nominal_work: float) -> None:
    offsets = core.state.comp.offsets
    offsets.set("H", number, offsets.get("H", number, wear=True) + (signal_work - nominal_work), wear=True,
                error=lambda message, code: core.error(message, code))  # fmt: skip
    core.resync_program_position()


def _measure(core: Seam, spec: CodeSpec, values: dict, *, machine_z: bool) -> None:
    st = core.state
    number = _check(core, spec, values)
    words = data(core).measure_words
    data(core).measure_words = {}
    settings: ToolMeasurement = st.tool_measurement
    s = st.scale
    origin = st.offsets.origin[_Z]
    z = values["Z"] * s + (0.0 if machine_z else origin)  # machine coordinates from here on
    r = values["R"] * s if "R" in values else settings.decel_mm
    feed = words["F"] * s if "F" in words else settings.feed_mm_min
    if r < 0 or not feed > 0:
        raise core.error(f"{spec.name}: R (measuring distance) must be >= 0 and F (measuring feed) > 0",
                         "value-out-of-range")  # fmt: skip
    end = z
    if not machine_z:
        overtravel = words["D"] * s if "D" in words else settings.band_mm
        if overtravel < 0:
            raise core.error(f"{spec.name} D{words['D']:g}: the probe over-travel must be >= 0",
                             "value-out-of-range")  # fmt: skip
        end = z - overtravel
    elif "D" in words:
        raise core.error(f"address D has no meaning with {spec.name}", "unused-word")
    compensation.before_machine_move(core)
    _reference(core, spec, values)
    start = z + r
    initial = st.out.position[_Z]
    if initial < start - 1e-9:
        raise core.error(f"MAR-333 Z start point error: the tool (machine Z{initial:g}) is below the probe's "
                         f"starting point (Z{start:g} = Z + R)", "g37-start-point")  # fmt: skip
    signal = _signal(core, number, z - origin) + origin
    if signal > start + 1e-9:
        raise core.error(f"MAR-335 measure position setting error: the probe fires at machine Z{signal:g}, "
                         f"above the starting point Z{start:g}", "g37-early-signal")  # fmt: skip
    if signal < end - 1e-9:
        raise core.error(f"MAR-336 the measure signal is not triggered by the end point (machine Z{end:g}; "
                         f"it fires at Z{signal:g})", "g37-no-signal")  # fmt: skip
    out = st.out
    saved = out.modes
    out.modes = saved | SegmentMode.OVERRIDE_LOCKED  # the override is 100 % while measuring
    try:
        _z(core, start)
        _skip(core, signal, feed, stops=True)
        if machine_z:  # G37.1: back 1 mm, second touch at F50, then up to the safety point
            _z(core, min(signal + SECOND_TOUCH_RETRACT_MM, start))
            _skip(core, signal, SECOND_TOUCH_FEED, stops=True)
            _store(core, number, signal - origin, z - origin)
            _z(core, values["Q"] * s if "Q" in values else 0.0)
        else:
            _store(core, number, signal - origin, z - origin)
    finally:
        out.modes = saved
    core.resync_program_position()


def measure(core: Seam, spec: CodeSpec, values: dict) -> None:
    """G37 (module docstring): Z in program (work) coordinates."""
    _measure(core, spec, values, machine_z=False)


def measure_2(core: Seam, spec: CodeSpec, values: dict) -> None:
    """G37.1 (module docstring): Z and Q in machine coordinates, a double touch."""
    _measure(core, spec, values, machine_z=True)


ACTIONS = {"tool_length_measure": measure, "tool_length_measure_2": measure_2}
