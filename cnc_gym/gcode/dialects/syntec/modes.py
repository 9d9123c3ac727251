"""Syntec 8.20's modal rules (Syntec 8.20 mill programming manual, each code's section): G04 dwell, G70/G71
units, the default feed, G94/G95, G61-G64 cutting modes, G05 high-speed high-precision mode, G05.1 path
smoothing, G33 thread cutting, G96/G97 constant surface speed with the G92 S clamp, and G06.2's feed.

**Smoothing on the tool path.** G05 P10000 / P1-P5 ("interpolation commands execute the mode of smoothing
curve") and G05.1 Q1 E_ ("the maximum allowable path error while smoothing", G01 only) let the controller
leave the programmed corners by a tolerance. The tool path carries it per row
(``Toolpath.smoothing_tolerance_mm``): in G05 every motion row gets its parameter set's tolerance
(``SyntecOptions.hshp_tolerance_mm``), under G05.1 the G01 rows get E. G05.1 pauses under G61/G63 and
resumes under G62/G64; the first G01 after G43/G44/G49 or a coordinate change (G52, G54-G59.9, G92) is
not smoothed. The controller blends the corners between consecutive G01 rows that carry a tolerance within it
(``cnc_gym.toolpath.smoothing``, docs/motion.md §6).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from cnc_gym.gcode.dialects.syntec.codes import THREAD
from cnc_gym.gcode.dialects.syntec.options import data, options
from cnc_gym.gcode.lang.fanuc import modal, nurbs
from cnc_gym.gcode.lang.fanuc import motion as family_motion
from cnc_gym.gcode.lang.fanuc.least_units import is_whole, whole_count
from cnc_gym.toolpath import SegmentKind, SegmentMode

if TYPE_CHECKING:
    from cnc_gym.gcode.codes import CodeSpec
    from cnc_gym.gcode.dialect import Seam

#: G61-G64 (§G64 "Cutting mode" table): G61 exact stop, G62 no deceleration at block ends (curved
#: surfaces; not Fanuc's automatic corner override), G63 tapping (override and feed hold locked), G64.
PATH_MODES = {
    "exact_stop": SegmentMode.EXACT_STOP,
    "tapping": SegmentMode.OVERRIDE_LOCKED | SegmentMode.TAPPING_MODE,
    "no_decel": SegmentMode.NONE,
    "cutting": SegmentMode.NONE,
}
_SUSPENDING = SegmentMode.EXACT_STOP | SegmentMode.TAPPING_MODE  # G61/G63 pause G05.1
_MOTION_KINDS = (SegmentKind.RAPID, SegmentKind.LINE, SegmentKind.ARC, SegmentKind.NURBS)
#: G37.1's and every tool-length measurement's override: fixed at 100 % (§G37).


# ---------------------------------------------------------------------- literals
def count(core: Seam, letter: str, values: dict) -> float:
    """A count in a length address (K of the canned cycles and hole patterns): the literal's digits
    (``K2`` is 2, not 2 least units)."""
    return whole_count(core, letter, values[letter])


def angle(core: Seam, letter: str, values: dict) -> float:
    """An angle word: degrees with a decimal point, 0.001° without (§G136: ``P15000`` is 15°)."""
    value = values[letter]
    return whole_count(core, letter, value) / 1000.0 if is_whole(core, letter) else value


# ---------------------------------------------------------------------- G04
def dwell(core: Seam, spec: CodeSpec, values: dict) -> None:
    """``G04 X_`` / ``G04 P_`` (§G04): X in seconds with a decimal point (0.001-9999.999 s), in ms
    without (``X2500`` = 2.5 s); P in ms (``P2500`` = 2.5 s), no decimal point: ``P2.5`` is 2 s as the
    manual's own example says (the fraction dropped, the rest seconds; ``SyntecOptions.g04_p_decimal``
    "error" refuses it). Neither word: an exact stop. The dwell stops the tool at the end of the previous
    block (an exact check in the cutting mode)."""
    for letter in "YZ":
        if letter in values:
            raise core.error(f"address {letter} has no meaning with G04", "unused-word")
    out = core.state.out
    if "P" in values:
        raw = values["P"]
        text = core.word_text("P")
        if text is None or "." not in text:
            seconds = round(raw) / 1000.0
        elif options(core).g04_p_decimal == "seconds":
            seconds = float(math.trunc(raw))
        else:
            raise core.error(f"G04 P{text}: P is in milliseconds and takes no decimal point (use X for "
                             "seconds)", "decimal-point-not-allowed")  # fmt: skip
    elif "X" in values:
        raw = values["X"]
        seconds = whole_count(core, "X", raw) / 1000.0 if is_whole(core, "X") else raw
    else:
        out.dwell(0.0, SegmentMode.EXACT_STOP)
        return
    if raw < 0:
        raise core.error(f"G04 dwell time {raw:g} is negative", "bad-dwell")
    if seconds > 9999.999:
        raise core.error(f"G04: {seconds:g} s is longer than 9999.999 s", "bad-dwell")
    out.dwell(seconds, SegmentMode.EXACT_STOP)


# ---------------------------------------------------------------------- units and feed
def units(core: Seam, spec: CodeSpec, values: dict | None = None) -> None:
    """G70 inch / G71 metric (§G70/G71). Offsets, tool data and reference points are kept in mm, so they
    stay right across a switch ("still correct"); the feed and lengths of later blocks read in the new
    unit, and the default feed is 1000 of the new unit per minute until an F is given."""
    st = core.state
    st.inch = bool(spec.value)
    st.scale = modal.INCH_MM if spec.value else 1.0
    st.increment = core.dialect.least_increment_inch if spec.value else core.dialect.least_increment_mm
    core.update_modes()
    _default_feed(core)


def _default_feed(core: Seam) -> None:
    """No F since power-on or the last G94/G95 switch: the default feed of the mode, in the unit in force
    (§G01: 1000 mm/min or inch/min in G94, 1 mm/rev or inch/rev in G95)."""
    st = core.state
    if data(core).feed_programmed:
        return
    opts = options(core)
    if st.feed_per_rev:
        st.feed_programmed = opts.default_feed_per_revolution * st.scale
        st.feed = st.feed_programmed * st.spindle_speed if st.spindle_speed > 0 else None
    else:
        st.feed = opts.default_feed_per_minute * st.scale


def feed(core: Seam, spec: CodeSpec | None, values: dict) -> None:
    """F: the feed (the family's), or in a G33 block the thread lead."""
    st = core.state
    if st.motion_key == _G33:
        data(core).thread_lead_mm = values["F"] * st.scale
        return
    modal.feed(core, spec, values)
    data(core).feed_programmed = True


def feed_mode(core: Seam, spec: CodeSpec, values: dict | None = None) -> None:
    """G94/G95 (§G94/G95): a switch drops the F in force; the new mode's default feed applies."""
    switched = (spec.value == "revolution") != core.state.feed_per_rev
    modal.feed_mode(core, spec, values)
    if switched and values is not None:
        data(core).feed_programmed = False
        _default_feed(core)


# ---------------------------------------------------------------------- G61-G64, G05, G05.1
def path_mode(core: Seam, spec: CodeSpec, values: dict | None = None) -> None:
    """G61/G62/G63/G64 (:data:`PATH_MODES`); G61/G63 pause G05.1 smoothing, G62/G64 resume it."""
    core.state.path_mode = PATH_MODES[spec.value]  # type: ignore[index]
    core.update_modes()
    d = core.state.dialect_data
    if values is not None and d is not None and (d.hshp is not None or d.smoothing_mm is not None):
        apply_smoothing(core)


def apply_smoothing(core: Seam) -> None:
    """Put the tolerances of the modes in force on the tool path from the next row on."""
    st = core.state
    d = data(core)
    tolerances: dict[SegmentKind, float] = {}
    if d.hshp is not None:
        tolerance = options(core).hshp_tolerance_mm.get(d.hshp, 0.0)
        tolerances = dict.fromkeys(_MOTION_KINDS, tolerance)
    if d.smoothing_mm is not None and not st.path_mode & _SUSPENDING:
        tolerances[SegmentKind.LINE] = d.smoothing_mm
    st.builder.smoothing(tolerances)


def contour_control(core: Seam, spec: CodeSpec, values: dict) -> None:
    """``G05 P10000`` (the factory set) or ``G05 P1``-``P5`` (user sets): high-speed, high-precision
    interpolation, the path smoothed within the set's tolerance and F the maximum feed; ``G05 P0`` ends it
    (§G05). Alone in its block; NURBS (G06.2) runs only inside it; compensation must be cancelled before
    P0; M codes other than M30/M99 are refused inside (blocks.py); a program still in G05 at its end must
    end with M30 or M99 (:func:`finish`)."""
    st = core.state
    others = sorted({w[0] for w in st.block_words} - set("GNOP"))
    if others or sum(1 for w in st.block_words if w[0] == "G") > 1:
        raise core.error("G05 must be alone in its block (G05 P10000, G05 P1-P5 / G05 P0)", "bad-g05")
    p = values.get("P")
    d = data(core)
    if p == 0:
        if st.nurbs.curve is not None:
            raise core.error(f"G05 P0 before the NURBS curve of line {st.nurbs.curve.line} is complete",
                             "nurbs-incomplete")  # fmt: skip
        if st.comp.side or st.comp.length_sign:
            raise core.error("G05 P0 with tool compensation in force: cancel G41/G42 (G40) and G43/G44 (G49) "
                             "first (§G05 condition 2)", "hshp-compensation")  # fmt: skip
        d.hshp = None
        st.nurbs.hpcc = False
    elif p is not None and p in (10000, 1, 2, 3, 4, 5):
        d.hshp = int(p)
        d.hshp_block = (st.file, st.out.line)
        st.nurbs.hpcc = True
    else:
        raise core.error("G05 needs P10000 or P1-P5 (on) or P0 (off)" if p is None else
                         f"G05 P{p:g}: the parameter sets are P10000 and P1-P5 (P0 ends the mode)",
                         "bad-g05")  # fmt: skip
    apply_smoothing(core)


def smoothing(core: Seam, spec: CodeSpec, values: dict) -> None:
    """``G05.1 Q1 E_`` path smoothing of G01 blocks within E (mm, inch in G70), ``G05.1 Q0`` off (§G05.1).
    "If command is inadequate (ex: Q or E unspecified), it will be ineffective" (§G05.1 description 1): a
    G05.1 without Q, or Q1 without E, changes nothing, and a note on the tool path says so (the tolerance
    the program meant is lost, so the user hears of it). Starting it under G61/G63 is the manual's alarm."""
    d = data(core)
    q = values.get("Q")
    if q is None:
        core.notice("G05.1 without Q is ineffective (Syntec 8.20 mill programming manual §G05.1): path "
                    "smoothing is unchanged; write G05.1 Q1 E_ (on) or Q0 (off)", "smoothing-ineffective")
        return
    q = whole_count(core, "Q", q)
    if q == 0:
        if "E" in values:
            raise core.error("G05.1 Q0 takes no E", "bad-smoothing")
        d.smoothing_mm = None
    elif q == 1:
        if "E" not in values:
            core.notice("G05.1 Q1 without E is ineffective (Syntec 8.20 mill programming manual §G05.1): "
                        "path smoothing is unchanged; E is the largest path error allowed (mm)",
                        "smoothing-ineffective")  # fmt: skip
            return
        e = values["E"] * core.state.scale
        if not e > 0.0:
            raise core.error(f"G05.1 E{values['E']:g}: the allowed path error must be positive",
                             "bad-smoothing")  # fmt: skip
        if core.state.path_mode & _SUSPENDING:
            raise core.error("G05.1 Q1 under G61/G63: path smoothing cannot start in exact-stop or tapping "
                             "mode (§G05.1 condition 1)", "smoothing-in-exact-stop")  # fmt: skip
        d.smoothing_mm = e
    else:
        raise core.error(f"G05.1 Q{q:g}: Q is 1 (on) or 0 (off)", "bad-smoothing")
    apply_smoothing(core)


def skip_next_line(core: Seam) -> None:
    """The next G01 is not smoothed (after G43/G44/G49 or a coordinate change, §G05.1 condition 3)."""
    d = core.state.dialect_data
    if d is not None and d.smoothing_mm is not None:
        d.skip_next_line = True


def finish(core: Seam) -> None:
    """End of the program (a block hook): still in G05, the program must have ended with M30 or M99."""
    d = core.state.dialect_data
    if d is not None and d.hshp is not None and not (core.state.ended or d.ended_by_code):
        raise core.error("the program ends in high-speed, high-precision mode G05 without M30 or M99 (§G05 "
                         "condition 3)", "hshp-no-end").located(*d.hshp_block)  # fmt: skip


# ---------------------------------------------------------------------- motion
_G33 = 330


def motion(core: Seam, spec: CodeSpec | None = None, values: dict | None = None) -> None:
    """The family's motion (G00-G03), G33 thread cutting, and the unsmoothed first G01 after a length
    compensation or coordinate change."""
    st = core.state
    mode = spec.value if spec is not None and spec.value is not None else st.motion
    if mode == THREAD:
        st.motion = THREAD
        if values is not None:
            thread(core, values)
        return
    d = st.dialect_data
    if d is None or not d.skip_next_line or mode != 1 or not values or not (
            "X" in values or "Y" in values or "Z" in values):  # fmt: skip
        family_motion.motion(core, spec, values)
        return
    d.skip_next_line = False
    saved, d.smoothing_mm = d.smoothing_mm, None
    apply_smoothing(core)
    try:
        family_motion.motion(core, spec, values)
    finally:
        d.smoothing_mm = saved
        apply_smoothing(core)


def thread(core: Seam, values: dict) -> None:
    """``G33 Z_ F_`` (§G33): a feed move at lead × spindle speed, the spindle and the axis synchronised
    (override fixed at 100 %). 1 ≤ S ≤ maximum cutting feed / lead (the machine's feed clamp, Pr405)."""
    st = core.state
    if not ("X" in values or "Y" in values or "Z" in values):
        return
    lead = data(core).thread_lead_mm
    if not lead:
        raise core.error("G33 needs F, the thread lead (mm per revolution)", "missing-feed")
    rpm = st.spindle_speed
    machine = st.machine
    if machine is None:  # the default controller's clamp (loaded here: a trace without a preset needs none)
        from cnc_gym.machine import ControllerConfig

        limit = ControllerConfig().max_feed_mm_min
    else:
        limit = machine.controller.max_feed_mm_min
    if not 1.0 <= rpm <= limit / lead:
        raise core.error(f"G33 at S{rpm:g}: the spindle speed must be 1..{limit / lead:g} r/min (maximum "
                         f"cutting feed {limit:g} / lead {lead:g})", "thread-speed")  # fmt: skip
    out = st.out
    saved = out.modes
    out.modes = saved | SegmentMode.OVERRIDE_LOCKED
    try:
        core.move_linear(False, core.resolve_target(values.get("X"), values.get("Y"), values.get("Z")),
                         feed=lead * rpm)  # fmt: skip
    finally:
        out.modes = saved


def nurbs_start(core: Seam, spec: CodeSpec, values: dict) -> None:
    """G06.2 (the family's NURBS, §G06.2): a curve without F takes the previous curve's feed."""
    st = core.state
    d = data(core)
    saved = st.feed
    if "F" not in values and d.nurbs_feed is not None:
        st.feed = d.nurbs_feed
    try:
        nurbs.start(core, spec, values)
    finally:
        if "F" not in values:
            st.feed = saved
    if st.nurbs.curve is not None:
        d.nurbs_feed = st.nurbs.curve.feed


# ---------------------------------------------------------------------- spindle
def surface_speed(core: Seam, spec: CodeSpec, values: dict | None = None) -> None:
    """G96 (S is the surface speed, m/min or feet/min in G70) / G97 (S is r/min) (§G96/G97)."""
    if values is None:
        return
    d = data(core)
    if spec.value:
        if "S" not in values and d.surface_speed is None:
            raise core.error("G96 needs S, the surface speed (m/min)", "missing-value")
        d.surface_speed = d.surface_speed or 0.0
    else:
        d.surface_speed = None


def spindle_speed(core: Seam, spec: CodeSpec | None, values: dict) -> None:
    """S: r/min in G97; in G96 the surface speed V, turned into N = 1000·V / (π·D) r/min (feet: 12·V /
    (π·D) with D in inch) for the tool diameter D (twice the D offset's radius in force), clamped by
    G92 S_ (§G96/G97)."""
    st = core.state
    d = st.dialect_data
    if d is None or d.surface_speed is None:
        modal.spindle_speed(core, spec, values)
        return
    d.surface_speed = values["S"]
    comp = st.comp
    radius = comp.offsets.radius(comp.d_number) if comp.d_number else 0.0
    if radius <= 0.0:
        raise core.error("G96 constant surface speed needs the tool diameter: select a D offset with the "
                         "tool radius first", "css-no-diameter")  # fmt: skip
    diameter = 2.0 * radius  # mm
    speed_m_min = d.surface_speed * (0.3048 if st.inch else 1.0)
    rpm = 1000.0 * speed_m_min / (math.pi * diameter)
    if d.spindle_clamp_rpm is not None:
        rpm = min(rpm, d.spindle_clamp_rpm)
    modal.spindle_speed(core, spec, {"S": rpm})


def spindle_clamp(core: Seam, value: float) -> None:
    """``G92 S_``: the largest spindle speed of constant surface speed (r/min)."""
    if value <= 0:
        raise core.error(f"G92 S{value:g}: the spindle speed limit must be positive", "value-out-of-range")
    data(core).spindle_clamp_rpm = value


ACTIONS = {
    "dwell": dwell, "units": units, "feed": feed, "feed_mode": feed_mode, "path_mode": path_mode,
    "contour_control": contour_control, "smoothing": smoothing, "motion": motion, "nurbs": nurbs_start,
    "surface_speed": surface_speed, "spindle_speed": spindle_speed,
}  # fmt: skip
