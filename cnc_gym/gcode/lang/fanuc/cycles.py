"""Canned cycles of the Fanuc family (group 09): G73, G74, G76, G80-G89, G98/G99 return levels, M29 rigid
tapping (GSK 25i programming manual §3.4, canned cycles).

**Where is G83?** The dialect's code table maps each cycle code onto a *kind* (its ``value``): G83 →
``"peck_deep"``. The kind's function below lists the cycle's steps in its docstring and returns them;
:data:`CYCLES` is the Fanuc family's cycle library, which a dialect extends with its own kinds (the GSK
25i pocket cycles live in ``dialects/gsk25i/pockets.py``).

A kind's function is pure geometry: it takes a :class:`~cnc_gym.gcode.dialect.Hole` (the hole position
and the levels in program coordinates, mm, after G20 scaling, before work offsets and transforms) and
returns a list of *steps*; :func:`emit` sends them through the coordinate seam (``move_linear`` /
``move_arc``), so G52/G54/G92, scaling, rotation and tool offsets apply to cycle moves as to programmed
ones. The modal cycle data live in ``State.cycle`` (:class:`~cnc_gym.gcode.state.CycleState`).

Steps are tuples (cheap to build, easy to compare in tests):

``("rapid", (x, y, z))``                 rapid; a ``None`` coordinate keeps the axis where it is
``("feed", (x, y, z), feed, locked)``    feed move at ``feed`` mm/min; ``locked`` = override fixed at 100 %
``("arc", (x, y, z), (cx, cy, cz), sweep, feed)``  XY arc (sweep in rad, + = CCW) to the end
``("dwell", seconds)``
``("spindle", direction)``               spindle +1 CW (M03), -1 CCW (M04), 0 stop (M05)
``("orient",)``                          oriented spindle stop (M19): a 0 s exact-stop dwell, spindle 0
``("hold",)``                            feed hold for an operator action (G88, G87 I): a 0 s exact-stop dwell

Modality: the cycle code, Z, R, Q, P are modal until G80 or a group-01 code; a block in cycle mode drills
when it has an axis word or R; the initial level is latched when the mode is entered; G98 returns to it,
G99 to R; K repeats the block. docs/gcode.md "Canned cycles".

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import TYPE_CHECKING

from cnc_gym.gcode.codes import CodeSpec
from cnc_gym.gcode.dialect import CycleKind, Hole
from cnc_gym.gcode.lang.fanuc import compensation, least_units
from cnc_gym.toolpath import PLANE_AXES, Plane, SegmentMode

if TYPE_CHECKING:
    from cnc_gym.gcode.dialect import BlockPlan, Seam
    from cnc_gym.gcode.settings import CycleParameters

Vec = tuple[float, float, float]
Step = tuple
#: Most pecks, passes or holes one cycle block may generate, counted across its K repeats and its pattern's
#: holes (a bound against a tiny Q or L, or a huge K, filling the memory: G73 Q0.011 K9999 made 60 million
#: moves).
MAX_STEPS = 100_000


# ====================================================================== the cycle library
def _at(hole: Vec, w: int, level: float) -> Vec:
    p = list(hole)
    p[w] = level
    return (p[0], p[1], p[2])


def _retract(h: Hole) -> float:
    return h.initial if h.return_initial else h.r_level


def drill(core: Seam, h: Hole) -> list[Step]:
    """G81 drilling: 1. rapid to R; 2. feed to Z; 3. rapid to the return level (initial with G98, R with
    G99)."""
    return [("rapid", _at(h.hole, h.w, h.r_level)), ("feed", _at(h.hole, h.w, h.bottom), h.feed, False),
            ("rapid", _at(h.hole, h.w, _retract(h)))]  # fmt: skip


def drill_dwell(core: Seam, h: Hole) -> list[Step]:
    """G82 drilling with dwell (spot facing, counterboring): 1. rapid to R; 2. feed to Z; 3. dwell P;
    4. rapid to the return level."""
    hole, w = h.hole, h.w
    steps: list[Step] = [("rapid", _at(hole, w, h.r_level)), ("feed", _at(hole, w, h.bottom), h.feed, False)]
    if h.dwell_s > 0:
        steps.append(("dwell", h.dwell_s))
    steps.append(("rapid", _at(hole, w, _retract(h))))
    return steps


def _peck(h: Hole, high_speed: bool) -> list[Step]:
    p = h.params
    d = p.g73_retract_mm if high_speed else p.g83_clearance_mm
    hole, w = h.hole, h.w
    steps: list[Step] = [("rapid", _at(hole, w, h.r_level))]
    depth = h.r_level
    while True:
        target = max(depth - h.q, h.bottom)
        steps.append(("feed", _at(hole, w, target), h.feed, False))
        if target <= h.bottom:
            break
        if high_speed:
            steps.append(("rapid", _at(hole, w, target + d)))  # up by d, the next feed starts there
        else:
            steps.append(("rapid", _at(hole, w, h.r_level)))  # back to R, then down to d above the depth
            steps.append(("rapid", _at(hole, w, min(target + d, h.r_level))))
        depth = target
    steps.append(("rapid", _at(hole, w, _retract(h))))
    return steps


def peck_high_speed(core: Seam, h: Hole) -> list[Step]:
    """G73 high-speed peck drilling: 1. rapid to R; 2. feed Q deeper; 3. rapid up by d (P2010, 0.5 mm);
    4. repeat 2-3 from there, the last peck clipped at Z; 5. rapid to the return level."""
    return _peck(h, high_speed=True)


def peck_deep(core: Seam, h: Hole) -> list[Step]:
    """G83 deep-hole peck drilling: 1. rapid to R; 2. feed Q deeper; 3. rapid back to R; 4. rapid down to
    d (P2011, 0.5 mm) above the depth already cut; 5. repeat 2-4, the last peck clipped at Z; 6. rapid to
    the return level."""
    return _peck(h, high_speed=False)


def _tapping(h: Hole, tap: int) -> list[Step]:
    hole, w = h.hole, h.w
    steps: list[Step] = [("rapid", _at(hole, w, h.r_level)), ("spindle", tap),
                         ("feed", _at(hole, w, h.bottom), h.feed, True)]  # fmt: skip
    if h.rigid:
        steps.append(("spindle", 0))
    if h.dwell_s > 0:
        steps.append(("dwell", h.dwell_s))
    steps.append(("spindle", -tap))
    steps.append(("feed", _at(hole, w, h.r_level), h.feed, True))
    steps.append(("spindle", 0 if h.rigid else tap))
    if h.return_initial:
        steps.append(("rapid", _at(hole, w, h.initial)))
    return steps


def tap(core: Seam, h: Hole) -> list[Step]:
    """G84 right-hand tapping: 1. rapid to R; 2. spindle CW; 3. feed to Z with the override locked
    (after M29 rigid tapping: spindle stop at the bottom); 4. dwell P; 5. spindle CCW; 6. feed back to R
    (locked); 7. spindle CW again (rigid: stop); 8. with G98 rapid to the initial level."""
    return _tapping(h, 1)


def tap_left(core: Seam, h: Hole) -> list[Step]:
    """G74 left-hand (counter) tapping: the steps of G84 with the spindle directions reversed."""
    return _tapping(h, -1)


def _oriented_stop(params: CycleParameters) -> list[Step]:
    """Spindle stop (unless 2000#6 M5B) and oriented stop, before a G76/G87 shift."""
    return [("orient",)] if params.no_m05_before_orient else [("spindle", 0), ("orient",)]


def _shift_move(target: Vec, shift_feed: float | None) -> Step:
    """A G76/G87 shift or shift back: rapid (Q form) or linear at F (the I/J form, 022#6 SIJ)."""
    return ("rapid", target) if shift_feed is None else ("feed", target, shift_feed, False)


def _shifted(h: Hole) -> Vec:
    return (h.hole[0] + h.shift[0], h.hole[1] + h.shift[1], h.hole[2] + h.shift[2])


def fine_bore(core: Seam, h: Hole) -> list[Step]:
    """G76 fine boring: 1. rapid to R; 2. feed to Z; 3. dwell P; 4. spindle stop (unless 2000#6 M5B) and
    oriented stop; 5. shift off the wall (|Q| in the 2000#4/#5 direction at rapid, or the I/J vector at F);
    6. rapid to the return level; 7. shift back; 8. spindle CW."""
    hole, w = h.hole, h.w
    steps: list[Step] = [("rapid", _at(hole, w, h.r_level)), ("feed", _at(hole, w, h.bottom), h.feed, False)]
    if h.dwell_s > 0:
        steps.append(("dwell", h.dwell_s))
    steps.extend(_oriented_stop(h.params))
    shifted = _shifted(h)
    retract = _retract(h)
    steps.append(_shift_move(_at(shifted, w, h.bottom), h.shift_feed))
    steps.append(("rapid", _at(shifted, w, retract)))
    steps.append(_shift_move(_at(hole, w, retract), h.shift_feed))
    steps.append(("spindle", 1))  # M03 after the shift back
    return steps


def bore(core: Seam, h: Hole) -> list[Step]:
    """G85 boring: 1. rapid to R; 2. feed to Z; 3. feed back to R; 4. with G98 rapid to the initial level."""
    return _bore_feed_out(h, dwell=False)


def bore_dwell(core: Seam, h: Hole) -> list[Step]:
    """G89 boring with dwell: 1. rapid to R; 2. feed to Z; 3. dwell P; 4. feed back to R; 5. with G98
    rapid to the initial level."""
    return _bore_feed_out(h, dwell=True)


def _bore_feed_out(h: Hole, dwell: bool) -> list[Step]:
    hole, w = h.hole, h.w
    steps: list[Step] = [("rapid", _at(hole, w, h.r_level)), ("feed", _at(hole, w, h.bottom), h.feed, False)]
    if dwell and h.dwell_s > 0:
        steps.append(("dwell", h.dwell_s))
    steps.append(("feed", _at(hole, w, h.r_level), h.feed, False))
    if h.return_initial:
        steps.append(("rapid", _at(hole, w, h.initial)))
    return steps


def bore_spindle_stop(core: Seam, h: Hole) -> list[Step]:
    """G86 boring: 1. rapid to R; 2. feed to Z; 3. spindle stop; 4. rapid to the return level; 5. spindle
    restarts in its programmed direction."""
    hole, w = h.hole, h.w
    return [("rapid", _at(hole, w, h.r_level)), ("feed", _at(hole, w, h.bottom), h.feed, False),
            ("spindle", 0), ("rapid", _at(hole, w, _retract(h))), ("spindle", h.spindle)]  # fmt: skip


def bore_manual(core: Seam, h: Hole) -> list[Step]:
    """G88 boring with manual retract: 1. rapid to R; 2. feed to Z; 3. dwell P; 4. spindle stop; 5. feed
    hold (the operator retracts: modelled as a rapid to the return level); 6. spindle CW."""
    hole, w = h.hole, h.w
    steps: list[Step] = [("rapid", _at(hole, w, h.r_level)), ("feed", _at(hole, w, h.bottom), h.feed, False)]
    if h.dwell_s > 0:
        steps.append(("dwell", h.dwell_s))
    steps.extend([("spindle", 0), ("hold",), ("rapid", _at(hole, w, _retract(h))), ("spindle", 1)])
    return steps


def back_bore(core: Seam, h: Hole) -> list[Step]:
    """G87 back boring (variant II, ``CycleParameters.g87_variant`` 2; R is the hole bottom below the part,
    Z the top; always back to the initial level): 1. at the initial level spindle stop, oriented stop,
    shift; 2. rapid to R; 3. shift back, spindle CW; 4. feed up to Z; 5. dwell P; 6. spindle stop,
    oriented stop, shift; 7. rapid to the initial level; 8. shift back, spindle CW.

    Variant I (``g87_variant`` 1): boring with a feed hold and manual retract at the bottom, as G88."""
    if h.params.g87_variant != 2:
        return bore_manual(core, h)
    hole, w, params = h.hole, h.w, h.params
    shifted = _shifted(h)
    steps: list[Step] = []
    steps.extend(_oriented_stop(params))
    steps.append(_shift_move(_at(shifted, w, h.initial), h.shift_feed))
    steps.append(("rapid", _at(shifted, w, h.r_level)))
    steps.append(_shift_move(_at(hole, w, h.r_level), h.shift_feed))
    steps.append(("spindle", 1))
    steps.append(("feed", _at(hole, w, h.bottom), h.feed, False))
    if h.dwell_s > 0:
        steps.append(("dwell", h.dwell_s))
    steps.extend(_oriented_stop(params))
    steps.append(_shift_move(_at(shifted, w, h.bottom), h.shift_feed))
    steps.append(("rapid", _at(shifted, w, h.initial)))
    steps.append(_shift_move(_at(hole, w, h.initial), h.shift_feed))
    steps.append(("spindle", 1))
    return steps


#: The Fanuc family's cycle library: kind → :class:`CycleKind` (a dialect's code table maps codes to kinds).
CYCLES: dict[str, CycleKind] = {
    "drill": CycleKind("drill", drill),
    "drill_dwell": CycleKind("drill_dwell", drill_dwell),
    "peck_high_speed": CycleKind("peck_high_speed", peck_high_speed, pecking=True),
    "peck_deep": CycleKind("peck_deep", peck_deep, pecking=True),
    "tap": CycleKind("tap", tap, tapping=1),
    "tap_left": CycleKind("tap_left", tap_left, tapping=-1),
    "fine_bore": CycleKind("fine_bore", fine_bore, shifting=True),
    "bore": CycleKind("bore", bore),
    "bore_dwell": CycleKind("bore_dwell", bore_dwell),
    "bore_spindle_stop": CycleKind("bore_spindle_stop", bore_spindle_stop),
    "back_bore": CycleKind("back_bore", back_bore, shifting=True, back_boring=True),
    "bore_manual": CycleKind("bore_manual", bore_manual),
}


def shift_vector(q: float, plane_u: int, plane_v: int, direction: int) -> Vec:
    """The G76/G87 shift: |q| along the plane's 1st (direction 0/1) or 2nd (2/3) axis, + or - (P2000#4/#5)."""
    axis = plane_v if direction >= 2 else plane_u
    out = [0.0, 0.0, 0.0]
    out[axis] = -abs(q) if direction % 2 else abs(q)
    return (out[0], out[1], out[2])


# ====================================================================== the seam side
def emit(core: Seam, steps: list[Step]) -> None:
    """Send steps through the coordinate seam (program coordinates → transforms → offsets → machine)."""
    core.check_budget()  # a cycle block may drill thousands of holes: keep the run's bounds
    st = core.state
    out = st.out
    for step in steps:
        kind = step[0]
        if kind == "rapid":
            core.move_linear(True, step[1])
        elif kind == "feed":
            if step[3]:  # tapping: override fixed at 100 % (§3.4.2, §3.4.14)
                saved = out.modes
                out.modes = saved | SegmentMode.OVERRIDE_LOCKED
                try:
                    core.move_linear(False, step[1], feed=step[2])
                finally:
                    out.modes = saved
            else:
                core.move_linear(False, step[1], feed=step[2])
        elif kind == "arc":
            core.move_arc(step[1], step[2], Plane.XY, step[3], step[4])
        elif kind == "dwell":
            out.dwell(step[1])
        elif kind == "spindle":
            st.spindle_direction = step[1]
            out.spindle_rpm = st.spindle_speed * step[1]
        elif kind == "orient":
            st.spindle_direction = 0
            out.spindle_rpm = 0.0
            out.dwell(0.0, SegmentMode.EXACT_STOP)
            st.spindle_orients += 1
        elif kind == "hold":
            out.dwell(0.0, SegmentMode.EXACT_STOP)
            st.stops.append((out.line, "feed_hold"))
        else:  # pragma: no cover - the generators emit only the kinds above
            raise ValueError(kind)


def drilling_axes(core: Seam) -> tuple[int, int, int]:
    """(u, v, w): the positioning axes and the drilling axis (P2000#0 FXY)."""
    if core.dialect.cycle_params.drilling_axis_follows_plane:
        return PLANE_AXES[core.state.plane]
    return (0, 1, 2)


def limit(core: Seam, count: float, what: str) -> None:
    """A cycle block may make at most :data:`MAX_STEPS` pecks, passes or holes (``cycle-too-long``)."""
    if not count <= MAX_STEPS:  # also catches NaN
        raise core.error(f"{what}: {count:.0f} is more than the {MAX_STEPS} one block may make",
                         "cycle-too-long")  # fmt: skip


def times(repeats: int, holes: int) -> str:
    """How a per-hole count is multiplied in a block: `` x 99 repeats x 9801 holes``."""
    return (f" x {repeats} repeats" if repeats > 1 else "") + (f" x {holes} holes" if holes > 1 else "")


def _dwell_from_p(core: Seam, values: dict) -> float:
    """Cycle P: dwell in ms, an integer like G04 P (§3.4); with a decimal point in seconds where the dialect
    says so (``Dialect.dwell_p_decimal_seconds``, Haas)."""
    text = core.word_text("P")
    if values["P"] < 0:
        raise core.error(f"P{values['P']:g}: negative dwell", "bad-dwell")
    if text is not None and "." in text:
        if core.dialect.dwell_p_decimal_seconds:
            return float(text)
        raise core.error(f"P{text}: the cycle dwell P is in milliseconds and takes no decimal point",
                         "decimal-point-not-allowed")  # fmt: skip
    return round(values["P"]) / 1000.0


def _repeats(core: Seam, values: dict) -> int:
    """K: repeat count of this block only; default 1, |K| for a negative K, K0 stores data only (§3.4).
    A count, not a length, where numbers without a decimal point are least units (``K3`` is 3). Where the
    dialect says so, L is the repeat count too (``CycleParameters.l_repeats``: Haas ``L3``)."""
    letter = "K"
    if "L" in values and core.dialect.cycle_params.l_repeats:
        if "K" in values:
            raise core.error("K and L both give the repeat count: give one", "bad-cycle")
        letter = "L"
    if letter not in values:
        return 1
    raw = values[letter]
    k = raw if core.dialect.integer_is_unit or letter == "L" else least_units.whole_count(core, "K", raw)
    k = abs(k)
    if k != int(k) or k > 99999:
        raise core.error(f"{letter}{raw:g}: the repeat count must be a whole number 0..99999", "bad-cycle")
    return int(k)


def _store_shift_ij(core: Seam, spec: CodeSpec, values: dict, scale: float) -> None:
    """I/J of G76/G87: the shift increment when 022#6 SIJ is set (§3.4.3), modal in the cycle mode (a block
    with only I/J stores them, it does not bore); without SIJ they mean nothing (``unused-word``). I is the
    X and J the Y increment ("X and Y axes move"); one along the drilling axis (2000#0 FXY in G18/G19)
    would move the tool in the hole, which the shift never does: an error."""
    if "I" not in values and "J" not in values:
        return
    letter = "I" if "I" in values else "J"
    if not core.dialect.cycle_params.shift_by_ij:
        raise core.error(f"address {letter} has no meaning with {spec.name}: the I/J shift needs parameter "
                         "022#6 SIJ (CycleParameters.shift_by_ij); the standard shift is Q", "unused-word")
    w = drilling_axes(core)[2]
    for axis, letter in ((0, "I"), (1, "J")):
        if letter in values and axis == w and values[letter] != 0.0:
            raise core.error(f"{spec.name} {letter}{values[letter]:g}: {letter} would shift along the "
                             f"drilling axis {core.dialect.axes[w]}", "cycle-argument")  # fmt: skip
    state = core.state.cycle
    if "I" in values:
        state.shift_i = values["I"] * scale
    if "J" in values:
        state.shift_j = values["J"] * scale


def _modal_item(spec: CodeSpec) -> CodeSpec:
    """What an axis-only block executes in the cycle mode: the modal cycle, with its words."""
    return CodeSpec("(modal canned cycle)", -1, "cycle", None, step="motion", words=spec.words,
                    address_rules=spec.address_rules)  # fmt: skip


def _sync_general_path(core: Seam) -> None:
    """In cycle mode (and between M29 and its cycle) every block takes the core's general path."""
    st = core.state
    if st.cycle.spec is not None or st.cycle.rigid_pending:
        st.general_path.add("cycle")
    else:
        st.general_path.discard("cycle")


def enter(core: Seam, spec: CodeSpec) -> None:
    """The block's cycle code (group 09): checks against the mode in force, then the cycle mode."""
    st = core.state
    state = st.cycle
    kind = core.dialect.cycles[spec.value]  # type: ignore[index]
    if state.rigid_pending and not kind.tapping:
        raise core.error(f"M29 rigid tapping is followed by {spec.name}, not G74/G84", "rigid-tap")
    if state.rigid and state.kind is not None and state.kind.tapping and spec != state.spec:
        raise core.error(f"{spec.name} in rigid tapping mode: cancel with G80 first", "rigid-tap")
    if kind.special and state.kind is not None and not state.kind.special:
        # Alarm 214 "CANNED CYCLE PUNCHING G73-G89 DEFINED": a special cycle while a drilling cycle is
        # modal (our reading of the alarm text; the manual's examples always start them from G80).
        raise core.error(f"{spec.name} while the drilling cycle {state.spec.name} is active: cancel it with "  # type: ignore[union-attr]
                         "G80", "cycle-argument", alarm="cycle-argument/special-in-drilling")  # fmt: skip
    if state.spec is None:
        state.initial = core.program_position[drilling_axes(core)[2]]  # latched on entering the mode (§3.4)
    state.spec = spec
    state.kind = kind
    st.modal_item = _modal_item(spec)
    if state.rigid_pending:
        state.rigid, state.rigid_pending = True, False
    _sync_general_path(core)


def cycle_block(core: Seam, spec: CodeSpec | None, values: dict,
                hole_xy: tuple[float, float] | None = None, holes: int = 1) -> None:  # fmt: skip
    """One block in canned-cycle mode: ``spec`` is the block's cycle code (None: the modal one). Stores
    the hole data, then drills at the block's position (K times) if the block has an axis word or R
    (§3.4.3); otherwise the block only updates data. ``hole_xy``: a pattern's hole (program mm) instead of
    the block's axis words; ``holes``: how many holes the pattern drills in all (the bound on the block's
    moves counts them)."""
    st = core.state
    state = st.cycle
    u, v, w = drilling_axes(core)
    if spec is not None:
        enter(core, spec)
    spec, kind = state.spec, state.kind
    assert spec is not None and kind is not None  # enter() or the modal cycle set them
    if kind.special and st.plane != Plane.XY:
        raise core.error(f"{spec.name} works in the G17 plane only", "cycle-argument",
                         alarm="cycle-argument/special-plane")  # fmt: skip
    s = st.scale
    letters = core.dialect.axes
    bottom_letter = letters[w]
    if "R" in values:
        state.r = values["R"] * s + (state.initial if st.incremental else 0.0)
    if bottom_letter in values:
        state.z = values[bottom_letter] * s
        state.z_from_r = st.incremental
    if "P" in values:
        state.dwell_s = _dwell_from_p(core, values)
    drills = hole_xy is not None or "R" in values or any(letter in values for letter in letters)
    if "Q" in values and (drills or not kind.pecking):
        state.q = abs(values["Q"]) * s  # the sign of Q is ignored; stored only when drilling (§3.4.7)
    if kind.shifting:
        _store_shift_ij(core, spec, values, s)
    else:
        for letter in "IJLWVUE":
            if letter in values and not (letter == "L" and core.dialect.cycle_params.l_repeats):
                state.words[letter] = values[letter] * (s if letter != "E" else 1.0)
    repeats = _repeats(core, values)
    if not drills or repeats == 0:
        return
    if state.r is None and core.dialect.cycle_params.r_defaults_to_initial:
        state.r = state.initial  # no R: the cycle drills from the initial level (Haas)
    if state.r is None or state.z is None:
        missing = " and ".join(n for n, val in (("R", state.r), (bottom_letter, state.z)) if val is None)
        raise core.error(f"{spec.name} needs {missing}: the first drilling block gives all the hole data",
                         "cycle-missing-data")  # fmt: skip
    if st.comp.side:
        # "In the canned cycle mode, the tool offset is ignored" (§3.4.1): compensation is suspended for the
        # block like for G53/G27-G30 (compensation.py: the last compensated block ends with its vector
        # perpendicular, the cycle's moves run uncompensated, and the next move in the plane after the cycle
        # starts the compensation up again).
        compensation.before_machine_move(core)
    feed = st.feed
    if not feed:
        raise core.error(f"{spec.name} needs a feed: no F programmed yet" if feed is None else
                         f"{spec.name} with F0: the feed is zero", "missing-feed")  # fmt: skip
    if kind.pecking and not state.q:
        raise core.error(f"{spec.name} needs Q (peck depth) in a drilling block", "cycle-missing-q")
    cycle_params = core.dialect.cycle_params
    if state.rigid:
        if st.spindle_speed > cycle_params.rigid_tap_max_rpm:
            raise core.error(f"rigid tapping at S{st.spindle_speed:g} exceeds the gear maximum "
                             f"{cycle_params.rigid_tap_max_rpm:g} r/min (P2140-P2142)", "rigid-tap",
                             alarm="rigid-tap/spindle-speed")  # fmt: skip
        if feed > cycle_params.max_cutting_feed:
            raise core.error(f"rigid tapping F{feed:g} mm/min exceeds the cutting-feed limit "
                             f"{cycle_params.max_cutting_feed:g} (P1225)", "rigid-tap")  # fmt: skip
    roles = core.dialect.roles
    return_initial = st.modal.get(roles.return_group) != roles.return_r  # type: ignore[arg-type]
    axis_words = [None if a == w else values.get(letter) for a, letter in enumerate("XYZ")]
    words = (axis_words[0], axis_words[1], axis_words[2])
    for _ in range(repeats):
        initial = state.initial
        r_level = state.r
        bottom = state.z + (r_level if state.z_from_r else 0.0)
        if kind.back_boring and cycle_params.g87_variant == 2:
            if bottom <= r_level:
                raise core.error(f"{spec.name} back boring needs {bottom_letter} above R", "cycle-levels")
        elif bottom >= r_level:
            raise core.error(f"{spec.name}: the hole bottom {bottom_letter} must lie below the R level",
                             "cycle-levels")  # fmt: skip
        here = core.program_position
        target = (hole_xy[0], hole_xy[1], None) if hole_xy is not None else core.resolve_target(*words)
        hole = (here[0] if target[0] is None else target[0], here[1] if target[1] is None else target[1],
                here[2] if target[2] is None else target[2])  # fmt: skip
        position = list(hole)
        position[w] = None  # type: ignore[call-overload]
        emit(core, [("rapid", tuple(position))])
        h = Hole(spec, hole, w, initial, r_level, bottom, return_initial, feed, state.q or 0.0, state.dwell_s,
                 cycle_params, st.spindle_direction or 1, state.rigid, values=values, repeats=repeats,
                 holes=holes)  # fmt: skip
        if not kind.special:
            _machine_amounts(core, h, u, v)
            if kind.pecking:
                limit(core, (r_level - bottom) / h.q * repeats * holes,
                      f"{spec.name} pecks (depth / Q){times(repeats, holes)}")  # fmt: skip
            else:
                limit(core, repeats * holes, f"{spec.name} holes{times(repeats, holes)}")
        emit(core, kind.steps(core, h))


def _machine_amounts(core: Seam, h: Hole, u: int, v: int) -> None:
    """The shift of G76/G87 and, under a transform, Q, d and the shift as program amounts."""
    st = core.state
    state = st.cycle
    params = h.params
    if params.shift_by_ij:
        # SIJ (§3.4.3): the shift is the programmed increment I (X), J (Y), cut at F.
        h.shift = (state.shift_i or 0.0, state.shift_j or 0.0, 0.0)
        h.shift_feed = h.feed
    else:
        h.shift = shift_vector(h.q, u, v, params.shift_direction)
    chain = st.chain
    if chain.active:
        # Scaling does not scale Q, d or the shift (§3.2.17): they are machine amounts, so in program
        # coordinates they are divided by the map's factor along the drilling axis. The Q shift is the
        # program vector the map sends onto the machine-axis shift (2000#4/#5 name a machine direction);
        # the I/J shift is a programmed increment, so it turns and mirrors with the map like any other but
        # keeps its length.
        w = h.w
        k = math.sqrt(sum(chain.linear[a][w] ** 2 for a in range(3))) or 1.0
        h.q = h.q / k
        h.params = replace(params, g73_retract_mm=params.g73_retract_mm / k,
                           g83_clearance_mm=params.g83_clearance_mm / k)  # fmt: skip
        shift = h.shift
        if h.shift_feed is None:
            inv = chain.inverse_linear
            h.shift = tuple(sum(inv[a][b] * shift[b] for b in range(3)) for a in range(3))  # type: ignore[assignment]
        else:
            lin = chain.linear
            mapped = math.hypot(*(sum(lin[a][b] * shift[b] for b in range(3)) for a in range(3)))
            if mapped > 0.0:
                factor = math.hypot(*shift) / mapped
                h.shift = (shift[0] * factor, shift[1] * factor, shift[2] * factor)


def cancel(core: Seam) -> None:
    """G80 / a group-01 code: the cycle mode ends and its data are cleared."""
    st = core.state
    st.cycle.cancel()
    st.modal_item = None
    roles = core.dialect.roles
    st.modal[roles.cycle_group] = roles.cycle_cancel  # type: ignore[index,assignment]
    _sync_general_path(core)


# ====================================================================== actions and block checks
def cycle(core: Seam, spec: CodeSpec, values: dict) -> None:
    """A cycle code (G73, G81 …), or an axis-only block in the cycle mode (``spec.value`` None)."""
    cycle_block(core, None if spec.value is None else spec, values)


def cycle_cancel(core: Seam, spec: CodeSpec, values: dict | None = None) -> None:
    """G80 (the block check has already ended the mode; at power-on it is the state)."""
    cancel(core)


def rigid_tap(core: Seam, spec: CodeSpec, values: dict) -> None:
    """M29: rigid tapping for the next G74/G84 (§3.4.14)."""
    state = core.state.cycle
    if state.rigid or state.rigid_pending:
        raise core.error("M29 while rigid tapping is already selected", "rigid-tap")
    state.rigid_pending = True
    _sync_general_path(core)


def check_codes(core: Seam, plan: BlockPlan) -> CodeSpec | None:
    """A group-01 code in the block of a cycle code is alarm 61 (§3.4.1). (Block check.)"""
    roles = core.dialect.roles
    core.state.cycle.block_spec = None
    cycle_spec = plan.by_group.get(roles.cycle_group)  # type: ignore[arg-type]
    if cycle_spec is not None and cycle_spec.action == "cycle":
        group01 = plan.by_group.get(1)  # G00-G03, also G06.2 (not a "motion" action)
        if group01 is not None:
            raise core.error(f"{group01.name} (group 01) in the block of the canned cycle "
                             f"{cycle_spec.name}", "cycle-group01")  # fmt: skip
    return plan.axis_owner


#: Codes refused in the cycle mode, by action, with their alarm condition (GSK: G27-G30 44, G10 61).
_NOT_IN_CYCLE = {"reference_check": "cycle-not-allowed", "reference_return": "cycle-not-allowed",
                 "reference_return_from": "cycle-not-allowed", "reference_return_n": "cycle-not-allowed",
                 "data_input": "cycle-not-allowed/other"}  # fmt: skip


def check_mode(core: Seam, plan: BlockPlan) -> CodeSpec | None:
    """The cycle mode's block rules (block check): between M29 and G74/G84 no S and no axis move (§3.4.14);
    G80 or a group-01 code ends the mode (§3.4.4); G27-G30 in cycle mode are alarm 44, G10 must cancel
    first (§3.2.9); with FXY the plane may not change (§3.4.3)."""
    st = core.state
    state = st.cycle
    roles = core.dialect.roles
    by_group = plan.by_group
    cycle_spec = by_group.get(roles.cycle_group)  # type: ignore[arg-type]
    group01 = by_group.get(1)
    if state.rigid_pending:
        cycle_code = cycle_spec.value if cycle_spec is not None else None
        if cycle_code is None and ("S" in plan.values or any(a in plan.values for a in core.dialect.axes)):
            raise core.error("S or an axis move between M29 and G74/G84", "rigid-tap")
    if (cycle_spec is not None and cycle_spec.action == "cycle_cancel") or group01 is not None:
        cancel(core)
    elif state.spec is not None:
        one_shot = by_group.get(0)
        alarm = _NOT_IN_CYCLE.get(one_shot.action) if one_shot is not None else None
        if alarm is not None:
            raise core.error(f"{one_shot.name} in canned-cycle mode: cancel the cycle with G80 first",  # type: ignore[union-attr]
                             "cycle-not-allowed", alarm=alarm)  # fmt: skip
        plane = by_group.get(2)
        follows = core.dialect.cycle_params.drilling_axis_follows_plane
        if plane is not None and follows and plane.value != st.plane:
            # With FXY = 1 the plane picks the drilling axis, which may not change in a cycle (§3.4.3).
            raise core.error(f"{plane.name} changes the drilling axis in canned-cycle mode: cancel the "
                             "cycle with G80 first", "cycle-not-allowed",
                             alarm="cycle-not-allowed/other")  # fmt: skip
    return plan.axis_owner


ACTIONS = {"cycle": cycle, "cycle_cancel": cycle_cancel, "rigid_tap": rigid_tap}
