"""The Fanuc family's arc rule (G02/G03): I/J/K or R, full circles, helices (the default
:attr:`BlockHooks.arc <cnc_gym.gcode.dialect.BlockHooks.arc>`).

I/J/K are incremental from the start in every distance mode; R > 0 is the arc up to 180°, R < 0 over
180°; R wins over I/J/K; an R arc whose end is its start is 0° (no motion); an I/J/K arc whose end is its
start is a full circle. Within the dialect's radius tolerance the end point moves radially onto the
circle (docs/gcode.md "Arcs").

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from cnc_gym.gcode.lang.fanuc import least_units
from cnc_gym.gcode.lang.fanuc.modal import missing_feed
from cnc_gym.toolpath import PLANE_AXES

if TYPE_CHECKING:
    from cnc_gym.gcode.dialect import Seam

TWO_PI = 2.0 * math.pi
#: In-plane distance below which an arc's end is its start (full circle for I/J/K, 0° arc for R), mm.
SAME_POINT_MM = 1e-7
_IJK = "IJK"


def arc(core: Seam, motion: int, x, y, z, values: dict) -> None:
    """G02/G03 in the selected plane, I/J/K (incremental, §3.2.3) or R (R wins, §1.3.3; R<0 > 180°)."""
    name = "G02" if motion == 2 else "G03"
    st = core.state
    feed = st.feed
    if not feed:
        if feed is None:
            raise missing_feed(core, name)
        raise core.error(f"{name} with F0: zero feed is not allowed on an arc", "zero-feed")
    plane = st.plane
    u, v, w = PLANE_AXES[plane]
    s = st.scale
    transformed = st.transformed
    if transformed:
        # Geometry in program coordinates; move_arc maps it through the chain.
        if st.polar is not None and "R" not in values:
            raise core.error(f"{name} in polar mode (G16) needs R (GSK 25i §3.2.16)", "polar-arc-needs-r")
        pos = st.program_point
        end = [pos[a] if t is None else t for a, t in enumerate(core.resolve_target(x, y, z))]
    elif st.incremental:
        pos = st.out.position
        end = [pos[0] if x is None else pos[0] + x * s, pos[1] if y is None else pos[1] + y * s,
               pos[2] if z is None else pos[2] + z * s]  # fmt: skip
    else:
        pos = st.out.position
        o = st.offsets.origin
        end = [pos[0] if x is None else x * s + o[0], pos[1] if y is None else y * s + o[1],
               pos[2] if z is None else z * s + o[2]]  # fmt: skip
    du = end[u] - pos[u]
    dv = end[v] - pos[v]
    chord = math.hypot(du, dv)
    ccw = motion == 3
    tol = core.dialect.arc_radius_tolerance_mm
    center = [0.0, 0.0, 0.0]
    center[w] = pos[w]
    if "R" in values:
        radius = values["R"] * s
        if chord < SAME_POINT_MM:
            if abs(end[w] - pos[w]) > SAME_POINT_MM:
                raise core.error(f"{name} with R: end point equals start in the plane, so the arc is 0° "
                                 "and cannot carry a helical move (use I/J/K for a full turn)",
                                 "arc-impossible")  # fmt: skip
            return  # "G02 R;": a 0° arc, the tool does not move (§3.2.3)
        if radius == 0:
            raise core.error(f"{name} with R0", "arc-impossible")
        half = chord / 2.0
        r_abs = abs(radius)
        if half > r_abs:
            if half - r_abs > max(tol, 1e-9):
                raise core.error(f"{name}: R{abs(radius) / s:g} is too small for the chord of "
                                 f"{chord / s:.4f} (need |R| >= {half / s:.4f})",
                                 "arc-impossible")  # fmt: skip
            h = 0.0
        else:
            h = math.sqrt(r_abs * r_abs - half * half)
        # Centre on the left of the chord for a CCW minor arc; right for CW; flipped for R < 0.
        side = (1.0 if ccw else -1.0) * (1.0 if radius > 0 else -1.0)
        nu, nv = -dv / chord, du / chord
        center[u] = pos[u] + du / 2.0 + side * h * nu
        center[v] = pos[v] + dv / 2.0 + side * h * nv
        r_start = math.hypot(pos[u] - center[u], pos[v] - center[v])
        full = False
    else:
        letter_u, letter_v, letter_w = _IJK[u], _IJK[v], _IJK[w]
        if letter_w in values:
            raise core.error(f"{name}: {letter_w} is not an axis of the {plane.name} plane (use "
                             f"{letter_u}/{letter_v}, or select the plane with G17/G18/G19)",
                             "arc-bad-offset")  # fmt: skip
        if letter_u not in values and letter_v not in values:
            raise core.error(f"{name} needs R or a centre {letter_u}/{letter_v} in the {plane.name} "
                             "plane",
                             "arc-missing-center")  # fmt: skip
        center[u] = pos[u] + values.get(letter_u, 0.0) * s
        center[v] = pos[v] + values.get(letter_v, 0.0) * s
        r_start = math.hypot(pos[u] - center[u], pos[v] - center[v])
        if r_start < SAME_POINT_MM:
            raise core.error(f"{name}: the centre is the start point (radius 0)", "arc-impossible")
        full = chord < SAME_POINT_MM
        if full:
            end[u], end[v] = pos[u], pos[v]
        else:
            r_end = math.hypot(end[u] - center[u], end[v] - center[v])
            if tol > 0 and abs(r_end - r_start) > tol:
                parameter = core.dialect.arc_tolerance_parameter
                hint = least_units.integer_words_hint(core, core.dialect.axes[u] + core.dialect.axes[v])
                raise core.error(f"{name}: radius at the start {r_start / s:.4f} and at the end "
                                 f"{r_end / s:.4f} differ by {abs(r_end - r_start) / s:.4f}, more than "
                                 f"the tolerance {tol:g} mm{f' ({parameter})' if parameter else ''}{hint}",
                                 "arc-radius-mismatch")  # fmt: skip
            if r_end < SAME_POINT_MM:
                raise core.error(f"{name}: the centre is the end point", "arc-impossible")
            # Within tolerance: keep the centre and the radius, move the end point radially onto the
            # circle (at most the tolerance away from the programmed one). docs/gcode.md.
            k = r_start / r_end
            end[u] = center[u] + (end[u] - center[u]) * k
            end[v] = center[v] + (end[v] - center[v]) * k
    a0 = math.atan2(pos[v] - center[v], pos[u] - center[u])
    if full:
        sweep = TWO_PI if ccw else -TWO_PI
    else:
        a1 = math.atan2(end[v] - center[v], end[u] - center[u])
        sweep = (a1 - a0) % TWO_PI if ccw else -((a0 - a1) % TWO_PI)
        if "R" in values and h == 0.0:
            sweep = math.pi if ccw else -math.pi
    del r_start
    if transformed:
        core.move_arc((end[0], end[1], end[2]), (center[0], center[1], center[2]), plane, sweep, feed)
    else:
        st.out.arc_feed((end[0], end[1], end[2]), (center[0], center[1], center[2]), plane, sweep, feed)
