"""Syntec 8.20's canned cycles (Syntec 8.20 mill programming manual §Cycle perform function, §G73-§G89) on
the Fanuc family's modal cycle (``lang/fanuc/cycles.py``).

What differs from the family:

* **P is a dwell in seconds**: ``P2.`` = 2 s, ``P2.5`` = 2.5 s; without a decimal point ms (the general
  rule of §G70/G71: an integer is the least unit);
* **Q and R are stored only by a block that drills** (a block with an axis word, K0 included), and R alone
  does not drill ("If a Block is not included movement command of any axes, then drilling can not be
  executed"); Q is modal and shared by G73/G83 (peck), G76/G87 (shift) and G74/G84 (peck tapping), its
  sign ignored; K repeats 0-9999;
* **G74/G84 tapping** dwells P and reverses the spindle at the bottom *and* back at R; with Q it pecks
  (Pr4001, ``SyntecOptions.peck_tapping_type``): type II back up by d after each peck, type III back to
  R; the tapping feeds run with the override fixed at 100 %;
* **G87** shifts *against* the Pr4020 direction to pass the bore ("shift amount a Q distance in reverse
  direction"), G76 along it;
* **G88**: after the operator's manual retract the program feeds back to R (G01), then G98/G99.

The drilling axis follows the plane (G17 Z, G18 Y, G19 X); d (Pr4002) is ``CycleParameters.
g73_retract_mm`` for G73, G83 and peck tapping.
"""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING

from cnc_gym.gcode.dialect import CycleKind
from cnc_gym.gcode.dialects.syntec.modes import count
from cnc_gym.gcode.dialects.syntec.options import options
from cnc_gym.gcode.lang.fanuc import cycles as family
from cnc_gym.gcode.lang.fanuc.cycles import Step

if TYPE_CHECKING:
    from cnc_gym.gcode.codes import CodeSpec
    from cnc_gym.gcode.dialect import Hole, Seam


def _at(h: Hole, level: float) -> tuple[float, float, float]:
    p = list(h.hole)
    p[h.w] = level
    return (p[0], p[1], p[2])


def _reverse_at(h: Hole, direction: int) -> list[Step]:
    """Dwell P, then the spindle turns ``direction`` (+1 CW, -1 CCW)."""
    steps: list[Step] = [("dwell", h.dwell_s)] if h.dwell_s > 0 else []
    return [*steps, ("spindle", direction)]


def _tapping(core: Seam, h: Hole, tap: int) -> list[Step]:
    """Tapping with the spindle turning ``tap`` on the way in (module docstring)."""
    locked = True  # "F and S are not controlled by the turning switch (fixed at 100 %)"
    steps: list[Step] = [("rapid", _at(h, h.r_level)), ("spindle", tap)]
    if h.q > 0:  # peck tapping
        d = h.params.g73_retract_mm
        high_speed = options(core).peck_tapping_type == 1
        depth = h.r_level
        while True:
            target = max(depth - h.q, h.bottom)
            steps.append(("feed", _at(h, target), h.feed, locked))
            if target <= h.bottom:
                break
            steps.extend(_reverse_at(h, -tap))
            back = min(target + d, h.r_level) if high_speed else h.r_level
            steps.append(("feed", _at(h, back), h.feed, locked))
            steps.extend(_reverse_at(h, tap))
            depth = target
    else:
        steps.append(("feed", _at(h, h.bottom), h.feed, locked))
    steps.extend(_reverse_at(h, -tap))
    steps.append(("feed", _at(h, h.r_level), h.feed, locked))
    steps.extend(_reverse_at(h, tap))
    if h.return_initial:
        steps.append(("rapid", _at(h, h.initial)))
    return steps


def tap(core: Seam, h: Hole) -> list[Step]:
    """G84 tapping (§G84), spindle CW in: 1. rapid to R; 2. feed to Z (type I), or with Q peck Q deeper
    each time, between pecks dwell P, reverse, feed back up by d (type II, Pr4001 = 1) or to R (type III,
    Pr4001 = 0), dwell P, reverse; 3. at Z dwell P and reverse; 4. feed to R; 5. dwell P and reverse again;
    6. with G98 rapid to the initial level. Every feed with the override fixed at 100 %."""
    return _tapping(core, h, 1)


def tap_left(core: Seam, h: Hole) -> list[Step]:
    """G74 left-hand tapping (§G74): the steps of G84 with the spindle CCW on the way in."""
    return _tapping(core, h, -1)


def back_bore(core: Seam, h: Hole) -> list[Step]:
    """G87 back boring (§G87): 1. at the initial level oriented stop and shift Q *against* the Pr4020
    direction; 2. rapid to R (below the part); 3. shift back, spindle CW; 4. feed up to Z; 5. dwell P,
    oriented stop, shift against the direction; 6. rapid to the initial level (G98 and G99 alike);
    7. shift back, spindle CW."""
    shift = h.shift
    return family.back_bore(core, replace(h, shift=(-shift[0], -shift[1], -shift[2])))


def bore_manual(core: Seam, h: Hole) -> list[Step]:
    """G88 semi-automatic boring (§G88): 1. rapid to R; 2. feed to Z; 3. dwell P, spindle stop; 4. feed
    hold: the operator takes the tool out by hand and restarts (not simulated: the tool path goes on from
    the bottom); 5. feed to R; 6. with G98 rapid to the initial level; 7. spindle CW."""
    steps: list[Step] = [("rapid", _at(h, h.r_level)), ("feed", _at(h, h.bottom), h.feed, False)]
    if h.dwell_s > 0:
        steps.append(("dwell", h.dwell_s))
    steps += [("spindle", 0), ("hold",), ("feed", _at(h, h.r_level), h.feed, False)]
    if h.return_initial:
        steps.append(("rapid", _at(h, h.initial)))
    steps.append(("spindle", 1))
    return steps


#: Syntec's cycle library: the family's with its own tapping, back boring and manual boring.
CYCLES = {
    **family.CYCLES,
    "tap": CycleKind("tap", tap, tapping=1),
    "tap_left": CycleKind("tap_left", tap_left, tapping=-1),
    "back_bore": CycleKind("back_bore", back_bore, shifting=True, back_boring=True),
    "bore_manual": CycleKind("bore_manual", bore_manual),
}


def dwell_seconds(core: Seam, values: dict) -> float:
    """Cycle P: seconds with a decimal point (``P2.5`` = 2.5 s), ms without (``P2500``)."""
    p = values["P"]
    if p < 0:
        raise core.error(f"P{p:g}: negative dwell", "bad-dwell")
    text = core.word_text("P")
    return p if text is not None and "." in text else round(p) / 1000.0


def cycle(core: Seam, spec: CodeSpec, values: dict) -> None:
    """A cycle code or an axis-only block in the cycle mode (module docstring), then the family's cycle."""
    state = core.state.cycle
    drills = any(letter in values for letter in core.dialect.axes)
    if "K" in values or "P" in values or (not drills and ("R" in values or "Q" in values)):
        values = dict(values)
        if "K" in values:
            values["K"] = repeats = count(core, "K", values)
            if repeats != int(repeats) or not 0 <= abs(repeats) <= 9999:
                raise core.error(f"K{repeats:g}: the repeat count is a whole number 0..9999", "bad-cycle")
        if "P" in values:
            state.dwell_s = dwell_seconds(core, values)
            del values["P"]
        if not drills:  # "Q and R … only be set in the block we execute drilling"
            values.pop("R", None)
            values.pop("Q", None)
    family.cycle(core, spec, values)


ACTIONS = {"cycle": cycle}
