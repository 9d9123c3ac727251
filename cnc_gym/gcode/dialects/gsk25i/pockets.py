"""The GSK 25i special canned cycles: circular and rectangular pockets and bosses, roughing and finishing,
G110-G117 and G130-G137 (GSK 25i programming manual §3.4.16-§3.4.23; group 09).

Each code is a kind of the dialect's cycle library (:data:`CYCLES`), run by the Fanuc family's modal
cycle (``lang/fanuc/cycles.py``: levels, G98/G99, K, the hole position) like any drilling cycle. The
figures are lost (the manual gives step lists only): the tool-centre paths below are designed from
those lists and described in docs/gsk25i.md; :func:`check_pocket` holds the argument checks with their
alarm numbers 210-228. The geometry is pure: :func:`pocket_steps` returns steps in program coordinates.

===========  ==========================  ===========================================================
Code         Kind (``_ccw`` / ``_cw``)   Path
===========  ==========================  ===========================================================
G110 / G111  ``circle_pocket_rough``     concentric circles from the centre out, step L, to I - r
G112 / G113  ``circle_pocket_finish``    finishing circle I - r, half-circle lead-in from J
G114 / G115  ``circle_boss_rough``       circles from the stock J + r in to I + r
G116 / G117  ``circle_boss_finish``      finishing circle I + r, lead-in from J
G130 / G131  ``rect_pocket_rough``       nested rounded rectangles from the centre out
G132 / G133  ``rect_pocket_finish``      finishing rectangle, lead-in from L
G134 / G135  ``rect_boss_rough``         rectangles from the stock E·(I, J) in
G136 / G137  ``rect_boss_finish``        finishing rectangle around the boss
===========  ==========================  ===========================================================

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from cnc_gym.gcode.dialect import CycleKind
from cnc_gym.gcode.lang.fanuc.cycles import limit, times

if TYPE_CHECKING:
    from cnc_gym.gcode.dialect import Hole, Seam

Step = tuple
#: The words the special cycles give a meaning to (besides the axis words, F, S, T, O).
POCKET_WORDS = {
    110: "RIKLWQVDP", 111: "RIKLWQVDP", 114: "RIJKLWQVDP", 115: "RIJKLWQVDP",
    112: "RIJDKQPL", 113: "RIJDKQPL", 116: "RIJDKQPL", 117: "RIJDKQPL",
    130: "RIJLWQVUDKP", 131: "RIJLWQVUDKP", 132: "RIJDLUKQP", 133: "RIJDLUKQP",
    134: "RIJLWQVEUDKP", 135: "RIJLWQVEUDKP", 136: "RIJDLUKQP", 137: "RIJDLUKQP",
}  # fmt: skip
_SHAPES = {110: "circle_pocket_rough", 112: "circle_pocket_finish", 114: "circle_boss_rough",
           116: "circle_boss_finish", 130: "rect_pocket_rough", 132: "rect_pocket_finish",
           134: "rect_boss_rough", 136: "rect_boss_finish"}  # fmt: skip
#: Kind name → G code (the even code turns CCW, the odd one CW).
KIND_CODES = {f"{shape}_{turn}": base + (turn == "cw")
              for base, shape in _SHAPES.items() for turn in ("ccw", "cw")}  # fmt: skip
_ROUGHING = frozenset({110, 111, 114, 115, 130, 131, 134, 135})


def _loop_rect(cx: float, cy: float, hx: float, hy: float, corner: float, ccw: bool, z: float,
               feed: float) -> list[Step]:  # fmt: skip
    """Closed rounded-rectangle loop about (cx, cy), half-widths hx, hy, corner radius ``corner``
    (clipped to the half-widths), from the middle of the +X side back to it."""
    rho = max(0.0, min(corner, hx, hy))
    # The CCW walk in local coordinates: (side end, corner end, corner centre) per corner; the CW walk
    # from the same start is its mirror image (y -> -y), in the same order.
    walk = [
        ((hx, hy - rho), (hx - rho, hy), (hx - rho, hy - rho)),
        ((-hx + rho, hy), (-hx, hy - rho), (-hx + rho, hy - rho)),
        ((-hx, -hy + rho), (-hx + rho, -hy), (-hx + rho, -hy + rho)),
        ((hx - rho, -hy), (hx, -hy + rho), (hx - rho, -hy + rho)),
    ]
    sign = 1.0 if ccw else -1.0
    if not ccw:
        walk = [((a[0], -a[1]), (b[0], -b[1]), (c[0], -c[1])) for a, b, c in walk]
    steps: list[Step] = []
    for enter, leave, centre in walk:
        steps.append(("feed", (cx + enter[0], cy + enter[1], z), feed, False))
        if rho > 1e-9:
            steps.append(("arc", (cx + leave[0], cy + leave[1], z), (cx + centre[0], cy + centre[1], z),
                          sign * math.pi / 2.0, feed))  # fmt: skip
    steps.append(("feed", (cx + hx, cy, z), feed, False))
    return steps


def _circle(cx: float, cy: float, radius: float, ccw: bool, z: float, feed: float) -> list[Step]:
    """Full circle from (cx + radius, cy) as two half arcs (each record is an unambiguous half turn)."""
    sweep = math.pi if ccw else -math.pi
    return [("arc", (cx - radius, cy, z), (cx, cy, z), sweep, feed),
            ("arc", (cx + radius, cy, z), (cx, cy, z), sweep, feed)]  # fmt: skip


def _layers(r_level: float, bottom: float, first: float, step: float) -> list[float]:
    """Cut levels: ``first`` below R (clipped to the bottom), then ``step`` deeper each, the last = bottom."""
    levels = [max(r_level - first, bottom)]
    while levels[-1] > bottom + 1e-9:
        levels.append(max(levels[-1] - step, bottom))
    return levels


def pocket_steps(code: int, cx: float, cy: float, r_level: float, bottom: float, initial: float, *,
                 return_initial: bool, feed: float, tool_radius: float, i: float, j: float = 0.0,
                 l_step: float = 0.0, w_first: float = 0.0, q_step: float = 0.0, v_clear: float = 0.0,
                 u_corner: float = 0.0, e_stock: float = 0.0) -> list[Step]:  # fmt: skip
    """Tool-centre path of the special cycles G110-G117, G130-G137 in the XY plane (values already
    checked by :func:`check_pocket`). The figures are lost (§3.4.16): the geometry below is
    our design, described in docs/gcode.md. Every cycle ends over (cx, cy) at the return level."""
    ccw = code % 2 == 0
    retract = initial if return_initial else r_level
    rt = tool_radius
    steps: list[Step] = []
    if code in (110, 111, 114, 115, 130, 131, 134, 135):
        if code in (110, 111):
            outer = i - rt
            radii = [min(outer, n * l_step) for n in range(1, math.ceil(outer / l_step - 1e-9) + 1)]
            start = (cx, cy)
            rings: list[tuple] = [("circle", rad) for rad in radii]
        elif code in (114, 115):
            first, last = j + rt, i + rt
            count = math.ceil((first - last) / l_step - 1e-9)
            rings = [("circle", max(last, first - n * l_step)) for n in range(1, count + 1)]
            start = (cx + first, cy)
        else:
            hx, hy = i / 2.0, j / 2.0
            if code in (130, 131):
                ax, ay, rho = hx - rt, hy - rt, max(u_corner - rt, 0.0)
                m = min(ax, ay)
                offsets = [max(m - n * l_step, 0.0) for n in range(math.ceil(m / l_step - 1e-9) + 1)]
                rings = [("rect", ax - o, ay - o, max(rho - o, 0.0)) for o in offsets]
                start = (cx, cy)
            else:
                ax, ay, rho = hx + rt, hy + rt, u_corner + rt
                grow = (e_stock - 1.0) * max(hx, hy)
                count = max(1, math.ceil(grow / l_step - 1e-9))
                offsets = [max(grow - n * l_step, 0.0) for n in range(1, count + 1)]
                rings = [("rect", ax + o, ay + o, rho + o) for o in offsets]
                start = (cx + ax + grow, cy)
        levels = _layers(r_level, bottom, w_first, q_step)
        steps.append(("rapid", (start[0], start[1], None)))
        steps.append(("rapid", (start[0], start[1], r_level)))
        for index, level in enumerate(levels):
            if index:
                steps.append(("rapid", (start[0], start[1], min(levels[index - 1] + v_clear, r_level))))
            steps.append(("feed", (start[0], start[1], level), feed, False))
            for ring in rings:
                if ring[0] == "circle":
                    rad = ring[1]
                    steps.append(("feed", (cx + rad, cy, level), feed, False))
                    steps.extend(_circle(cx, cy, rad, ccw, level, feed))
                else:
                    _, hx_, hy_, rho_ = ring
                    steps.append(("feed", (cx + hx_, cy, level), feed, False))
                    steps.extend(_loop_rect(cx, cy, hx_, hy_, rho_, ccw, level, feed))
            last = steps[-1][1]
            steps.append(("rapid", (last[0], last[1], r_level)))
            steps.append(("rapid", (start[0], start[1], r_level)))
        steps.pop()  # no move back to the start after the last layer
    else:
        inside = code in (112, 113, 132, 133)
        if code in (112, 113, 116, 117):
            path = i - rt if inside else i + rt
            start_x = cx + j
            loop = _circle(cx, cy, path, ccw, bottom, feed)
            contact = cx + path
        else:
            hx, hy = i / 2.0 + (-rt if inside else rt), j / 2.0 + (-rt if inside else rt)
            rho = u_corner - rt if inside else u_corner + rt
            start_x = cx + i / 2.0 + (-l_step if inside else l_step)
            loop = _loop_rect(cx, cy, hx, hy, rho, ccw, bottom, feed)
            contact = cx + hx
        # Tangential half-circle lead-in and lead-out between the start point and the contact point on
        # the +X side: inside the pocket they turn the finishing way, outside the boss the other way
        # (§3.4.19, §3.4.23).
        mid = ((start_x + contact) / 2.0, cy, bottom)
        lead = math.pi if ccw else -math.pi
        if not inside:
            lead = -lead
        steps.append(("rapid", (start_x, cy, None)))
        steps.append(("rapid", (start_x, cy, r_level)))
        steps.append(("feed", (start_x, cy, bottom), feed, False))
        steps.append(("arc", (contact, cy, bottom), mid, lead, feed))
        steps.extend(loop)
        steps.append(("arc", (start_x, cy, bottom), mid, lead, feed))
        start = (start_x, cy)
    last = steps[-1][1]
    steps.append(("rapid", (last[0], last[1], retract)))
    steps.append(("rapid", (cx, cy, retract)))
    return steps


def check_pocket(code: int, *, tool_radius: float, i: float | None, j: float | None, l_step: float | None,
                 w_first: float | None, q_step: float | None, v_clear: float | None, u_corner: float | None,
                 e_stock: float | None) -> tuple[str, int] | None:  # fmt: skip
    """The special-cycle argument checks (alarms 210-228, §3.4.20): ``(message, alarm)`` or None."""
    rt = tool_radius
    rough = code in (110, 111, 114, 115, 130, 131, 134, 135)
    rect = code >= 130
    if not i:
        return "I (radius or X width) is missing or 0", 215
    if (rect or code not in (110, 111)) and j is None:
        return "J is missing", 216
    if rect and not j:
        return "J (Y width) is 0", 216
    if u_corner is not None and u_corner < 0:
        return f"U{u_corner:g} < 0", 224
    if rough:
        if w_first is None or w_first <= 0:
            return "W (first cut depth below R) is missing or not positive", 217
        if q_step is None or q_step <= 0:
            return "Q (depth per layer) is missing or not positive", 218
        if v_clear is None or v_clear <= 0:
            return "V (clearance above the uncut face) is missing or not positive", 220
        # "Less than the tool diameter" (G114: "radius"), yet every example steps L10 with D1 = 5: the
        # examples' reading, L up to the tool diameter, is the rule (docs/gcode.md).
        if l_step is None or l_step <= 0 or (rt > 0 and l_step > 2.0 * rt):
            return f"L (step over) must be > 0 and at most the tool diameter {2.0 * rt:g}", 219
    j = 0.0 if j is None else j  # given wherever the checks below read it (the "J is missing" check above)
    if code in (110, 111, 112, 113):
        if rt >= i:
            return f"tool radius {rt:g} is not smaller than the circle radius I{i:g}", 222
        if code in (112, 113) and abs(j) >= i - rt:
            return f"J{abs(j):g} leaves no room for the lead-in arc inside radius {i - rt:g}", 212
    if code in (114, 115) and j <= i:
        return f"the stock radius J{j:g} must be larger than the boss radius I{i:g}", 212
    if code in (116, 117) and abs(j) <= i + rt:
        return f"the start distance J{abs(j):g} must be larger than I + tool radius = {i + rt:g}", 212
    if rect:
        i, j = abs(i), abs(j)
        u = u_corner or 0.0
        if 2.0 * u > min(i, j):
            return f"corner radius U{u:g} is bigger than half of I{i:g}/J{j:g}", 210
        inside = code in (130, 131, 132, 133)
        if inside and 2.0 * rt >= min(i, j):
            return f"tool diameter {2 * rt:g} does not fit in I{i:g} x J{j:g}", 222
        if code in (132, 133) and rt > 0 and u < rt:
            return f"corner radius U{u:g} is smaller than the tool radius {rt:g}", 211
        if code in (130, 131) and u_corner and u_corner < rt:
            return f"corner radius U{u_corner:g} is smaller than the tool radius {rt:g}", 211
        if code in (132, 133, 136, 137):
            if l_step is None or l_step <= rt:
                return f"L (start distance from the side) must be larger than the tool radius {rt:g}", 213
            if inside and (l_step > i / 2.0 or (l_step - rt) / 2.0 > j / 2.0 - rt):
                return f"L{l_step:g}: the lead-in does not fit inside the pocket", 213
        if code in (134, 135):
            if not e_stock:
                return "E (stock size as a multiple of I and J) is missing or 0", 228
            if e_stock <= 1.0:
                return f"E{e_stock:g} must be more than 1", 226
    return None


def tool_radius(core: Seam, values: dict, stored: dict) -> float:
    """Tool radius from the D offset number (D0 = radius 0, §3.4.16); D missing is alarm 221."""
    if "D" in values:
        stored["D"] = int(values["D"])
    if "D" not in stored:
        raise core.error("the special cycle needs D (tool radius offset number)", "cycle-argument",
                         alarm=221)  # fmt: skip
    number = stored["D"]
    if number == 0:
        return 0.0
    return abs(core.state.comp.offsets.radius(number))


def pocket(core: Seam, h: Hole) -> list[Step]:
    """One special cycle at one position (the kind of ``h.spec``): the arguments are checked (alarms
    210-228), then :func:`pocket_steps` gives the path."""
    state = core.state.cycle
    code = KIND_CODES[h.spec.value]  # type: ignore[index]
    name = h.spec.name
    words = state.words
    radius = tool_radius(core, h.values, words)
    i, j = words.get("I"), words.get("J")
    problem = check_pocket(code, tool_radius=radius, i=None if i is None else abs(i),
                           j=None if j is None else abs(j), l_step=words.get("L"), w_first=words.get("W"),
                           q_step=state.q, v_clear=words.get("V"), u_corner=words.get("U"),
                           e_stock=words.get("E"))  # fmt: skip
    if problem is not None:
        raise core.error(f"{name}: {problem[0]}", "cycle-argument", alarm=problem[1])
    if code in _ROUGHING:
        span = max(abs(i), abs(j or 0.0)) * max(words.get("E", 1.0), 1.0)  # type: ignore[arg-type]
        passes = (1 + (h.r_level - h.bottom) / state.q) * (1 + span / words["L"])  # type: ignore[operator]
        limit(core, passes * h.repeats * h.holes, f"{name} passes{times(h.repeats, h.holes)}")
    return pocket_steps(code, h.hole[0], h.hole[1], h.r_level, h.bottom, h.initial,
                        return_initial=h.return_initial, feed=h.feed, tool_radius=radius, i=abs(i),  # type: ignore[arg-type]
                        j=abs(j or 0.0), l_step=words.get("L", 0.0), w_first=words.get("W", 0.0),
                        q_step=state.q or 0.0, v_clear=words.get("V", 0.0), u_corner=words.get("U", 0.0),
                        e_stock=words.get("E", 0.0))  # fmt: skip


#: The special cycles as kinds of the cycle library.
CYCLES = {name: CycleKind(name, pocket, special=True) for name in KIND_CODES}
