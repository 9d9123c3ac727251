"""The H4C-M's groove cycles G22-G25 (HUST H4C-M manual §3.29-§3.32): one-shot codes, absolute mode only
("limited by absolute mode"). X, Y are the start point (G25: the circle's centre), Z the groove bottom, R
the "height of outer part" (the clearance level the tool plunges from and returns to), F the groove feed.

* ``G22 X Y Z R I J F`` linear groove: rapid to (X, Y), rapid to R, feed to Z, feed to (X+I, Y+J), rapid
  to R.
* ``G23 X Y Z R I J K T F`` arc groove: as G22 with an arc of radius K to (X+I, Y+J), clockwise for T0,
  counter-clockwise for T1; K > 0 for an arc under 180°, K < 0 over 180°.
* ``G24 X Y Z R I J D T F`` rectangular groove, (X, Y) and (X+I, Y+J) opposite corners. T0 (the manual's
  move list): the tool centre runs once round the rectangle, X first. T1 (pocket; the figure is lost, the
  text says "through the S type of groove in the inner square first and groove the edge once again"):
  our reading is a zig-zag over the rectangle, passes along X stepping D (the tool radius: neighbouring
  passes overlap by half the cutter) towards Y+J, the last pass on the far edge, then the T0 lap round
  the edge.
* ``G25 X Y Z R K D T F`` circular groove about the centre (X, Y), radius K (the manual prints the format
  of G24; its move list uses K). T0: from (X-K, Y) one full clockwise circle. T1 (pocket): circles of
  radius K, K-D, K-2D … while the radius left exceeds D, stepping inward along +X by D at depth between
  them (the printed loop moves by D and re-enters the circle at the old K, so its centre would drift; we
  keep it on (X, Y)).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from cnc_gym.gcode.dialects.h4cm.options import data
from cnc_gym.gcode.lang.fanuc.cycles import MAX_STEPS, emit

if TYPE_CHECKING:
    from cnc_gym.gcode.codes import CodeSpec
    from cnc_gym.gcode.dialect import Seam

Point = tuple[float, float]
_NEEDS = {22: "XYZRIJ", 23: "XYZRIJK", 24: "XYZRIJ", 25: "XYZRK"}


def _r_centre(start: Point, end: Point, r: float, ccw: bool) -> Point:
    """Centre of the arc of radius |r| from ``start`` to ``end`` (r > 0 the short way, r < 0 the long way)."""
    dx, dy = end[0] - start[0], end[1] - start[1]
    chord = math.hypot(dx, dy)
    h = math.sqrt(max(r * r - chord * chord / 4.0, 0.0))
    side = (1.0 if ccw else -1.0) * (1.0 if r > 0 else -1.0)
    return (start[0] + dx / 2.0 - side * h * dy / chord, start[1] + dy / 2.0 + side * h * dx / chord)


def _sweep(centre, start, end, ccw: bool) -> float:
    a0 = math.atan2(start[1] - centre[1], start[0] - centre[0])
    a1 = math.atan2(end[1] - centre[1], end[0] - centre[0])
    return (a1 - a0) % (2 * math.pi) if ccw else -((a0 - a1) % (2 * math.pi))


def groove(core: Seam, spec: CodeSpec, values: dict) -> None:
    """G22-G25 (``spec.value`` the G number; module docstring)."""
    code = int(spec.value)  # type: ignore[call-overload]
    st = core.state
    extra = data(core).groove_words
    data(core).groove_words = {}
    if st.incremental:
        raise core.error(f"{spec.name} works in absolute mode only (G90; HUST H4C-M manual §3.29-§3.32)",
                         "groove-absolute-only")  # fmt: skip
    for letter in _NEEDS[code]:
        if letter not in values:
            raise core.error(f"{spec.name} needs {letter}", "cycle-argument")
    if code == 22 and ("T" in extra or "D" in extra):
        raise core.error(f"address {'T' if 'T' in extra else 'D'} has no meaning with G22", "unused-word")
    if code == 23 and "D" in extra:
        raise core.error("address D has no meaning with G23", "unused-word")
    kind = int(extra.get("T", 0))
    if extra.get("T", 0) not in (0, 1):
        raise core.error(f"{spec.name} T{extra['T']:g}: the groove type is T0 or T1", "cycle-argument")
    feed = st.feed
    if not feed:
        raise core.error(f"{spec.name} needs a feed F", "missing-feed")
    s = st.scale
    x, y, z, r = (values[k] * s for k in "XYZR")
    if z >= r:
        raise core.error(f"{spec.name}: the groove bottom Z must lie below R", "cycle-levels")
    down = [("rapid", (x if code != 25 else x - values["K"] * s, y, None)), ("rapid", (None, None, r)),
            ("feed", (None, None, z), feed, False)]  # fmt: skip
    if code in (22, 23, 24):
        i, j = values["I"] * s, values["J"] * s
        end = (x + i, y + j)
    path: list[tuple]
    if code == 22:
        path = [("feed", (end[0], end[1], z), feed, False)]
    elif code == 23:
        k = values["K"] * s
        chord = math.hypot(i, j)
        if chord == 0.0 or abs(k) < chord / 2.0 - 1e-9:
            raise core.error(f"G23 K{values['K']:g}: the radius is too small for the chord {chord:.4f}",
                             "arc-impossible")  # fmt: skip
        ccw = kind == 1
        centre = _r_centre((x, y), end, k, ccw)
        sweep = _sweep(centre, (x, y), end, ccw)
        path = [("arc", (end[0], end[1], z), (centre[0], centre[1], z), sweep, feed)]
    elif code == 24:
        lap = [("feed", (x + i, y, z), feed, False), ("feed", (x + i, y + j, z), feed, False),
               ("feed", (x, y + j, z), feed, False), ("feed", (x, y, z), feed, False)]  # fmt: skip
        path = (_zigzag(core, spec, x, y, i, j, _step(core, spec, extra), z, feed) if kind == 1 else []) + lap
    else:
        k = values["K"] * s
        if k <= 0:
            raise core.error(f"G25 K{values['K']:g}: the circle radius must be positive", "cycle-argument")
        path = [_circle(x, y, k, z, feed)]
        if kind == 1:
            step = _step(core, spec, extra)
            if k / step > MAX_STEPS:
                raise core.error(f"G25 D{step:g}: {k / step:.0f} laps is more than {MAX_STEPS}",
                                 "cycle-too-long")
            while k > step:
                k -= step
                path.append(("feed", (x - k, y, z), feed, False))
                path.append(_circle(x, y, k, z, feed))
    emit(core, [*down, *path, ("rapid", (None, None, r))])


def _step(core: Seam, spec: CodeSpec, extra: dict) -> float:
    if "D" not in extra:
        raise core.error(f"{spec.name} T1 needs D (the tool radius, the step between passes)",
                         "cycle-argument")
    step = extra["D"] * core.state.scale
    if step <= 0:
        raise core.error(f"{spec.name} D{extra['D']:g}: the tool radius must be positive", "cycle-argument")
    return step


def _circle(cx: float, cy: float, k: float, z: float, feed: float) -> tuple:
    """A full clockwise circle of radius k about (cx, cy) from its leftmost point."""
    return ("arc", (cx - k, cy, z), (cx, cy, z), -2.0 * math.pi, feed)


def _zigzag(core: Seam, spec: CodeSpec, x: float, y: float, i: float, j: float, step: float, z: float,
            feed: float) -> list:  # fmt: skip
    """G24 T1: passes along X from (x, y) stepping ``step`` towards y + j, the last on the far edge."""
    passes = math.ceil(abs(j) / step) if j else 0
    if passes > MAX_STEPS:
        raise core.error(f"{spec.name} D{step:g}: {passes} passes is more than {MAX_STEPS}", "cycle-too-long")
    moves: list = [("feed", (x + i, y, z), feed, False)]
    side = 1
    for n in range(1, passes + 1):
        yn = y + math.copysign(min(n * step, abs(j)), j)
        here_x = x + i if side else x
        moves.append(("feed", (here_x, yn, z), feed, False))
        side ^= 1
        moves.append(("feed", (x + i if side else x, yn, z), feed, False))
    moves.append(("feed", (x, y + j, z), feed, False))
    moves.append(("feed", (x, y, z), feed, False))
    return moves
