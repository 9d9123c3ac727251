"""Coordinate transforms of the GSK 25i dialect: G16 polar input, G51/G51.1 scaling and mirror, G68
rotation, and how arcs go through them.

The stages themselves live in :mod:`cnc_gym.gcode.canonical` (:class:`~cnc_gym.gcode.canonical.
TransformChain`); this module holds the parts that need the interpreter's modal state: polar input (a
block's words → a Cartesian program point) and mapping an arc (given in program coordinates) to
machine coordinates. See docs/gcode.md, "Coordinates and transforms".
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from cnc_gym.toolpath import PLANE_AXES, Plane

if TYPE_CHECKING:
    from cnc_gym.gcode.interpreter import Interpreter

TWO_PI = 2.0 * math.pi
_PLANE_AXES = {int(p): axes for p, axes in PLANE_AXES.items()}


class PolarState:
    """G16 polar input (L1775-L1865): the plane's first axis word is the radius, the second the angle
    (degrees, CCW from the first axis's + direction).

    * radius word in G90: the origin is the work zero; in G91: the origin is the current position
      (L1791-L1801);
    * angle word in G90: the angle itself; in G91: added to the last angle (L1833-L1845);
    * an omitted radius or angle keeps the last one (with the last origin), so ``G91 Y120`` steps round
      the same circle;
    * the plane's normal axis is an ordinary Cartesian word.
    """

    def __init__(self, program_position, plane: Plane) -> None:
        u, v, _ = _PLANE_AXES[int(plane)]
        # Start from the current point seen from the work zero.
        self.origin = (0.0, 0.0)
        self.radius = math.hypot(program_position[u], program_position[v])
        self.angle_deg = math.degrees(math.atan2(program_position[v], program_position[u]))

    def resolve(self, interp: Interpreter, words, plane: Plane | None = None):
        """Program-unit words (x, y, z; None = absent) → program target in mm (None = not commanded).

        ``plane``: the plane whose axes are (radius, angle); canned cycles pass XY whatever the plane
        (L1839-L1841)."""
        u, v, w = _PLANE_AXES[int(interp.plane if plane is None else plane)]
        s = interp.scale
        incremental = interp.incremental
        p = interp.program_position
        out: list[float | None] = [None, None, None]
        radius_word, angle_word = words[u], words[v]
        if radius_word is not None or angle_word is not None:
            if radius_word is not None:
                self.origin = (p[u], p[v]) if incremental else (0.0, 0.0)
                self.radius = radius_word * s
            if angle_word is not None:
                self.angle_deg = self.angle_deg + angle_word if incremental else angle_word
            a = math.radians(self.angle_deg)
            out[u] = self.origin[0] + self.radius * math.cos(a)
            out[v] = self.origin[1] + self.radius * math.sin(a)
        normal = words[w]
        if normal is not None:
            out[w] = p[w] + normal * s if incremental else normal * s
        return tuple(out)


def map_arc(interp: Interpreter, start, end, center, plane: Plane, sweep: float):
    """An arc in program coordinates → (end, centre, sweep) in machine coordinates.

    The chain is affine and keeps the arc's plane (G68 only rotates in the selected plane and a plane
    change in G68 mode is an error). With equal in-plane factors the image of the circle is a circle: the
    sweep keeps its size and flips its sign under a mirror (G02 ↔ G03, L1915). With unequal factors the
    controller traces no ellipse (L1936; the figures are lost): we keep the mapped centre and the mapped
    start, so the radius is the mapped start's distance from the mapped centre, and move the mapped end
    radially onto that circle; a full circle stays a full circle.
    """
    u, v, w = _PLANE_AXES[int(plane)]
    shape = interp.chain.plane_map(plane)
    if shape is None:
        raise interp.error(f"an arc in the {plane.name} plane while G68 rotates another plane",
                           "plane-change-in-rotation")  # fmt: skip
    a, b, c, d, _, similar = shape
    mirror = a * d - b * c < 0
    centre_program = list(center)
    centre_program[w] = start[w]
    start_m = interp.out.position
    end_m = list(interp.to_machine(end))
    centre_m = list(interp.to_machine(centre_program))
    centre_m[w] = start_m[w]
    if similar:
        return tuple(end_m), tuple(centre_m), -sweep if mirror else sweep
    radius = math.hypot(start_m[u] - centre_m[u], start_m[v] - centre_m[v])
    full = abs(abs(sweep) - TWO_PI) < 1e-12
    ccw = (sweep > 0) != mirror
    if full:
        end_m[u], end_m[v] = start_m[u], start_m[v]
        return tuple(end_m), tuple(centre_m), TWO_PI if ccw else -TWO_PI
    r_end = math.hypot(end_m[u] - centre_m[u], end_m[v] - centre_m[v])
    if radius < 1e-9 or r_end < 1e-9:
        raise interp.error("the scaled arc has radius 0", "arc-impossible")
    k = radius / r_end
    end_m[u] = centre_m[u] + (end_m[u] - centre_m[u]) * k
    end_m[v] = centre_m[v] + (end_m[v] - centre_m[v]) * k
    a0 = math.atan2(start_m[v] - centre_m[v], start_m[u] - centre_m[u])
    a1 = math.atan2(end_m[v] - centre_m[v], end_m[u] - centre_m[u])
    turned = (a1 - a0) % TWO_PI if ccw else -((a0 - a1) % TWO_PI)
    return tuple(end_m), tuple(centre_m), turned
