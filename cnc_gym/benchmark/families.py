"""Program families of the benchmark suites: seeded generators of plain GSK 25i G-code.

Each family is one function ``(rng, tier, split) -> (description, lines)`` registered in
:data:`FAMILIES`; :func:`program_text` wraps its moves in the common header and footer. Every program
retracts to Z5, cuts, retracts and ends with M30; every coordinate carries a decimal point and is rounded
to 0.001 mm, as a CAM post-processor writes it (on the short chords of the ``freeform`` family that
rounding is visible as direction noise, as in real CAM output).

The *tier* a generator is asked for only steers its parameter ranges (sharper corners, shorter segments,
tighter curves, higher feeds). The tier a program is filed under is measured afterwards from its tool
path (:func:`cnc_gym.benchmark.suites.path_properties`), so it means the same thing in every family.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path

import numpy as np

SAFE_Z = 5.0
SPINDLE_RPM = 8000
TIERS = ("easy", "medium", "hard")

#: Feed ranges (mm/min) a generator draws from, per requested tier.
FEEDS = {"easy": (800.0, 2000.0), "medium": (2000.0, 3500.0), "hard": (3500.0, 6000.0)}


def fmt(value: float) -> str:
    """A coordinate word's value: 0.001 mm, always with a decimal point, no negative zero."""
    text = f"{value:.3f}"
    return "0.000" if text == "-0.000" else text


def _feed(rng: np.random.Generator, tier: str) -> float:
    lo, hi = FEEDS[tier]
    return float(round(rng.uniform(lo, hi) / 50.0) * 50.0)


def _approach(x: float, y: float, plunge_feed: float = 600.0, depth: float = -1.0) -> list[str]:
    return [f"G00 X{fmt(x)} Y{fmt(y)}", "G00 Z1.000", f"G01 Z{fmt(depth)} F{fmt(plunge_feed)}"]


def _retract() -> str:
    return f"G00 Z{fmt(SAFE_Z)}"


class _Moves:
    """Emits G01/G02/G03 from the current point, writing F only when it changes."""

    def __init__(self, x: float, y: float, z: float) -> None:
        self.x, self.y, self.z = x, y, z
        self.lines: list[str] = []
        self._feed: float | None = None

    def _f(self, feed: float) -> str:
        if feed == self._feed:
            return ""
        self._feed = feed
        return f" F{fmt(feed)}"

    def line(self, x: float, y: float, feed: float, z: float | None = None) -> None:
        words = f"G01 X{fmt(x)} Y{fmt(y)}"
        if z is not None and fmt(z) != fmt(self.z):
            words += f" Z{fmt(z)}"
            self.z = z
        self.lines.append(words + self._f(feed))
        self.x, self.y = x, y

    def arc(self, x: float, y: float, cx: float, cy: float, ccw: bool, feed: float,
            z: float | None = None) -> None:  # fmt: skip
        words = f"{'G03' if ccw else 'G02'} X{fmt(x)} Y{fmt(y)}"
        if z is not None and fmt(z) != fmt(self.z):
            words += f" Z{fmt(z)}"
            self.z = z
        words += f" I{fmt(cx - self.x)} J{fmt(cy - self.y)}"
        self.lines.append(words + self._f(feed))
        self.x, self.y = x, y


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v)


# ---------------------------------------------------------------------------------------------- contour
def contour(rng: np.random.Generator, tier: str, split: str) -> tuple[str, list[str]]:
    """A closed 2-D contour: a star-shaped polygon whose corners turn by 5° to 175°, some rounded by
    fillets of 0.5, 1, 2 or 5 mm (G02/G03), cut once at a constant feed."""
    n = int(rng.integers(5, 13))
    spread = {"easy": 0.15, "medium": 0.35, "hard": 0.6}[tier]
    size = rng.uniform(15.0, 30.0)
    angles = np.sort(rng.uniform(0, 2 * np.pi, n))
    angles = np.sort((angles + np.linspace(0, 2 * np.pi, n, endpoint=False)) / 2)  # not too bunched
    radii = size * (1.0 + spread * rng.uniform(-1, 1, n))
    pts = np.column_stack((radii * np.cos(angles), radii * np.sin(angles)))
    fillet_share = {"easy": 0.7, "medium": 0.5, "hard": 0.25}[tier]
    fillet_radii = np.array([0.5, 1.0, 2.0, 5.0])
    feed = _feed(rng, tier)
    # Corners: incoming/outgoing directions, tangent points of the fillets (radius 0 = sharp).
    d_in = np.array([_unit(pts[i] - pts[i - 1]) for i in range(n)])
    d_out = np.array([_unit(pts[(i + 1) % n] - pts[i]) for i in range(n)])
    edge = np.linalg.norm(pts - np.roll(pts, 1, axis=0), axis=1)  # edge ending at i
    corners = []
    for i in range(n):
        turn = math.acos(float(np.clip(d_in[i] @ d_out[i], -1.0, 1.0)))
        r = float(rng.choice(fillet_radii)) if rng.random() < fillet_share else 0.0
        room = 0.45 * min(edge[i], edge[(i + 1) % n])
        while r > 0 and r * math.tan(turn / 2) > room:
            r = r / 2 if r > 0.5 else 0.0
        if turn < math.radians(1.0):
            r = 0.0
        corners.append((turn, r))
    start = (pts[0] + pts[1]) / 2
    moves = _Moves(*start, -1.0)
    for k in range(1, n + 1):
        i = k % n
        turn, r = corners[i]
        if r <= 0:
            moves.line(*pts[i], feed)
            continue
        t = r * math.tan(turn / 2)
        a, b = pts[i] - d_in[i] * t, pts[i] + d_out[i] * t
        left = d_in[i][0] * d_out[i][1] - d_in[i][1] * d_out[i][0] > 0
        normal = np.array([-d_in[i][1], d_in[i][0]]) * (1 if left else -1)
        centre = a + normal * r
        moves.line(*a, feed)
        moves.arc(*b, *centre, ccw=left, feed=feed)
    moves.line(*start, feed)
    sharp = [math.degrees(t) for t, r in corners if r == 0]
    desc = (f"closed contour, {n} corners turning {math.degrees(min(c[0] for c in corners)):.0f}-"
            f"{math.degrees(max(c[0] for c in corners)):.0f} deg, {n - len(sharp)} fillets, F{feed:g}")
    return desc, _approach(*start) + moves.lines


# ----------------------------------------------------------------------------------------------- pocket
def pocket(rng: np.random.Generator, tier: str, split: str) -> tuple[str, list[str]]:
    """A rectangular pocket cleared zig-zag or by offset loops, entered by a plunge or a ramp, in one or
    two depth levels, with a finishing pass around the wall."""
    w, h = rng.uniform(16.0, 40.0), rng.uniform(12.0, 30.0)
    step = rng.uniform(2.0, 5.0)
    strategy = "zigzag" if rng.random() < 0.5 else "offset"
    ramp = rng.random() < 0.5
    levels = 1 if tier == "easy" else int(rng.integers(1, 3))
    feed = _feed(rng, tier)
    corner_r = {"easy": 3.0, "medium": 1.5, "hard": 0.0}[tier]
    lines: list[str] = []
    x0, y0 = -w / 2 + step, -h / 2 + step
    for level in range(1, levels + 1):
        z = -1.0 * level
        if ramp:  # ramp down along X over 8 mm, back to the start
            lines += [f"G00 X{fmt(x0)} Y{fmt(y0)}", f"G00 Z{fmt(z + 1.0)}",
                      f"G01 X{fmt(x0 + 8.0)} Z{fmt(z + 0.5)} F{fmt(feed / 2)}",
                      f"X{fmt(x0)} Z{fmt(z)}"]  # fmt: skip
        else:
            lines += _approach(x0, y0, depth=z)
        moves = _Moves(x0, y0, z)
        if strategy == "zigzag":
            y, right = y0, True
            while y <= h / 2 - step + 1e-9:
                moves.line(w / 2 - step if right else x0, y, feed)
                right = not right
                y_next = y + step
                if y_next > h / 2 - step + 1e-9:
                    break
                moves.line(moves.x, y_next, feed)
                y = y_next
        else:  # offset loops, inside out, joined by straight step-overs
            loops = max(1, int(min(w, h) / 2 / step) - 1)
            for k in range(loops, 0, -1):
                hx, hy = w / 2 - k * step, h / 2 - k * step
                if hx <= 0.5 or hy <= 0.5:
                    continue
                moves.line(-hx, -hy, feed)
                for cx, cy in ((hx, -hy), (hx, hy), (-hx, hy), (-hx, -hy)):
                    moves.line(cx, cy, feed)
        # finishing pass along the wall (rounded corners unless the tier asks for sharp ones)
        hx, hy = w / 2 - 1.0, h / 2 - 1.0
        moves.line(-hx + corner_r, -hy, feed)
        path = [((hx, -hy), (hx - corner_r, -hy), (hx, -hy + corner_r)),
                ((hx, hy), (hx, hy - corner_r), (hx - corner_r, hy)),
                ((-hx, hy), (-hx + corner_r, hy), (-hx, hy - corner_r)),
                ((-hx, -hy), (-hx, -hy + corner_r), (-hx + corner_r, -hy))]  # fmt: skip
        for (cx, cy), a, b in path:
            if corner_r > 0:
                moves.line(*a, feed)
                centre = (a[0] + b[0] - cx, a[1] + b[1] - cy)
                moves.arc(*b, *centre, ccw=True, feed=feed)
            else:
                moves.line(cx, cy, feed)
        lines += moves.lines
        lines.append("G00 Z1.000")
    desc = (f"pocket {w:.1f} x {h:.1f} mm, {strategy}, step-over {step:.1f} mm, {levels} levels, "
            f"{'ramp' if ramp else 'plunge'} entry, F{feed:g}")
    return desc, lines


# --------------------------------------------------------------------------------------------- freeform
def _closed_spline(rng: np.random.Generator, radius: float, knots: int) -> Callable[[np.ndarray], np.ndarray]:
    from scipy.interpolate import CubicSpline

    theta = np.linspace(0, 2 * np.pi, knots, endpoint=False) + rng.uniform(-0.2, 0.2, knots)
    r = radius * rng.uniform(0.6, 1.2, knots)
    x, y = r * np.cos(theta), r * np.sin(theta)
    t = np.arange(knots + 1)
    return CubicSpline(t, np.column_stack((np.append(x, x[0]), np.append(y, y[0]))), bc_type="periodic")


def _chord_points(curve, knots: int, chord_mm: tuple[float, float], tolerance_mm: float) -> np.ndarray:
    """Points along a closed curve at CAM-like chords: each chord as long as the chord tolerance allows
    at the local curvature (√(8ρδ)), clamped to ``chord_mm``."""
    t = np.linspace(0, knots, 40001)
    p = curve(t)
    d1, d2 = curve(t, 1), curve(t, 2)
    speed = np.linalg.norm(d1, axis=1)
    kappa = np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]) / np.maximum(speed**3, 1e-12)
    s = np.concatenate(([0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))))
    out, here = [0.0], 0.0
    while here < s[-1]:
        k = float(np.interp(here, s, kappa))
        chord = math.sqrt(8.0 * tolerance_mm / k) if k > 1e-9 else chord_mm[1]
        here = min(here + float(np.clip(chord, *chord_mm)), s[-1])
        out.append(here)
    if len(out) > 2 and out[-1] - out[-2] < chord_mm[0]:  # no sliver chord at the closing point
        del out[-2]
    return np.column_stack((np.interp(out, s, p[:, 0]), np.interp(out, s, p[:, 1])))


def freeform(rng: np.random.Generator, tier: str, split: str) -> tuple[str, list[str]]:
    """CAM-style short-segment freeform: a closed spline written as a G01 chain at 0.02–1 mm chords
    (chord tolerance 1–10 µm), rounded to 0.001 mm. Chords below 0.05 mm appear in the test split only."""
    fine = split == "test" and rng.random() < 0.5
    chords = (0.02, 0.05) if fine else {"easy": (0.5, 1.0), "medium": (0.1, 1.0), "hard": (0.05, 0.5)}[tier]
    tolerance = float(rng.choice([0.001, 0.005, 0.01]))
    knots = int(rng.integers(5, 10))
    radius = rng.uniform(6.0, 9.0) if fine else rng.uniform(12.0, 30.0)
    curve = _closed_spline(rng, radius, knots)
    pts = _chord_points(curve, knots, chords, tolerance)
    feed = _feed(rng, tier)
    moves = _Moves(*pts[0], -1.0)
    for x, y in pts[1:]:
        moves.line(float(x), float(y), feed)
    seg = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    desc = (f"closed spline through {knots} points as {len(seg)} G01 chords of {seg.min():.3f}-"
            f"{seg.max():.3f} mm, chord tolerance {tolerance * 1000:g} um, F{feed:g}")
    return desc, _approach(*pts[0]) + moves.lines


# ------------------------------------------------------------------------------------------------- kirl
def kirl(rng: np.random.Generator, tier: str, split: str) -> tuple[str, list[str]]:
    """KIRL-style planar outline (the shapes of Zhang et al.'s benchmark: a shark is 245 points, 240 mm): a
    closed, elongated organic curve through 8-14 random points, written as about 250 G01 chords of equal
    length (about 1 mm) at F600, KIRL's 10 mm/s. Run it on the ``kirl-planar`` machine. Harder tiers have
    more lobes (sharper turns between chords)."""
    from scipy.interpolate import CubicSpline

    knots = int(rng.integers({"easy": 8, "medium": 10, "hard": 12}[tier], {"easy": 10, "medium": 12,
                                                                            "hard": 15}[tier]))  # fmt: skip
    theta = np.linspace(0, 2 * np.pi, knots, endpoint=False) + rng.uniform(-0.15, 0.15, knots)
    r = rng.uniform(0.55, 1.15, knots)
    aspect = rng.uniform(1.5, 2.8)
    x, y = aspect * r * np.cos(theta), r * np.sin(theta)
    curve = CubicSpline(np.arange(knots + 1), np.column_stack((np.append(x, x[0]), np.append(y, y[0]))),
                        bc_type="periodic")  # fmt: skip
    t = np.linspace(0, knots, 20001)
    p = curve(t)
    s = np.concatenate(([0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))))
    length = float(rng.uniform(200.0, 280.0))
    p = p * (length / s[-1])
    s = s * (length / s[-1])
    n = int(rng.integers(230, 261))
    at = np.linspace(0.0, length, n + 1)
    pts = np.column_stack((np.interp(at, s, p[:, 0]), np.interp(at, s, p[:, 1])))
    pts -= pts.min(axis=0) - 5.0  # in the first quadrant, 5 mm from the axes, as KIRL's data
    moves = _Moves(*pts[0], -1.0)
    for px, py in pts[1:]:
        moves.line(float(px), float(py), 600.0)
    seg = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    desc = (f"KIRL-style closed outline through {knots} points as {n} G01 chords of {seg.mean():.3f} mm, "
            f"{seg.sum():.1f} mm in all, F600")
    return desc, _approach(*pts[0]) + moves.lines


# ------------------------------------------------------------------------------------------------- arcs
def arcs(rng: np.random.Generator, tier: str, split: str) -> tuple[str, list[str]]:
    """A helical entry (G02/G03 with Z) then a tangent chain of arcs of many radii, turning both ways."""
    r_lo, r_hi = {"easy": (8.0, 25.0), "medium": (2.0, 15.0), "hard": (0.5, 8.0)}[tier]
    feed = _feed(rng, tier)
    helix_r = rng.uniform(2.0, 6.0)
    turns = int(rng.integers(1, 3))
    lines = [f"G00 X{fmt(helix_r)} Y0.000", "G00 Z1.000"]
    moves = _Moves(helix_r, 0.0, 1.0)
    depth = -1.0
    for k in range(2 * turns):  # half turns down to the depth
        z = 1.0 + (depth - 1.0) * (k + 1) / (2 * turns)
        x = -helix_r if k % 2 == 0 else helix_r
        moves.arc(x, 0.0, 0.0, 0.0, ccw=True, feed=feed / 2, z=z)
    heading = np.array([0.0, 1.0])  # tangent of a CCW circle at (R, 0)
    count = int(rng.integers(4, 9))
    for _ in range(count):
        r = float(math.exp(rng.uniform(math.log(r_lo), math.log(r_hi))))
        ccw = bool(rng.random() < 0.5)
        sweep = math.radians(rng.uniform(20.0, 150.0))
        normal = np.array([-heading[1], heading[0]]) * (1 if ccw else -1)
        here = np.array([moves.x, moves.y])
        centre = here + normal * r
        start = math.atan2(here[1] - centre[1], here[0] - centre[0])
        end_angle = start + (sweep if ccw else -sweep)
        end = centre + r * np.array([math.cos(end_angle), math.sin(end_angle)])
        moves.arc(*end, *centre, ccw=ccw, feed=feed)
        radial = (end - centre) / r
        heading = np.array([-radial[1], radial[0]]) * (1 if ccw else -1)
        # The rounded end point is the next arc's start: recompute from it (the centre stays exact).
        moves.x, moves.y = float(fmt(end[0])), float(fmt(end[1]))
    desc = (f"helical entry R{helix_r:.1f} {turns} turns, then {count} tangent arcs of R{r_lo:g}-{r_hi:g} "
            f"mm, F{feed:g}")
    return desc, lines + moves.lines


# ------------------------------------------------------------------------------------------------ holes
def holes(rng: np.random.Generator, tier: str, split: str) -> tuple[str, list[str]]:
    """A hole pattern (grid or bolt circle) drilled with a canned cycle: G81, G83 (peck) or G73 (chip
    breaking), G98/G99 return, then G80."""
    cycle = str(rng.choice(["G81", "G83", "G73"]))
    feed = float(round(rng.uniform(150.0, 600.0) / 10.0) * 10.0)
    depth = -rng.uniform(2.0, 8.0)
    if rng.random() < 0.5:
        rows, cols = int(rng.integers(2, 4)), int(rng.integers(2, 5))
        pitch = rng.uniform(6.0, 15.0)
        pts = [(c * pitch, r * pitch) for r in range(rows) for c in range(cols)]
        pattern = f"{rows} x {cols} grid, pitch {pitch:.1f} mm"
    else:
        n, radius = int(rng.integers(3, 9)), rng.uniform(10.0, 25.0)
        angles = [2 * math.pi * k / n for k in range(n)]
        pts = [(radius * math.cos(a), radius * math.sin(a)) for a in angles]
        pattern = f"bolt circle of {n} on R{radius:.1f} mm"
    ret = "G98" if rng.random() < 0.5 else "G99"
    peck = f" Q{fmt(rng.uniform(1.0, 3.0))}" if cycle != "G81" else ""
    lines = [f"G00 X{fmt(pts[0][0])} Y{fmt(pts[0][1])}",
             f"{ret} {cycle} X{fmt(pts[0][0])} Y{fmt(pts[0][1])} Z{fmt(depth)} R2.000{peck} F{fmt(feed)}"]
    lines += [f"X{fmt(x)} Y{fmt(y)}" for x, y in pts[1:]]
    lines.append("G80")
    return f"{pattern}, {cycle} {ret} to Z{depth:.1f}, F{feed:g}", lines


# ----------------------------------------------------------------------------------------------- raster
def raster(rng: np.random.Generator, tier: str, split: str) -> tuple[str, list[str]]:
    """3-D raster finishing of a smooth surface (Gaussian bumps): zig-zag rows of G01 moves along X,
    Z following the surface, rows joined along Y on the surface."""
    w, h = rng.uniform(20.0, 40.0), rng.uniform(8.0, 20.0)
    dx = {"easy": (0.6, 1.0), "medium": (0.3, 0.6), "hard": (0.15, 0.3)}[tier]
    step_x = rng.uniform(*dx)
    step_y = rng.uniform(1.5, 3.0)
    amp = {"easy": 1.0, "medium": 2.5, "hard": 4.0}[tier] * rng.uniform(0.6, 1.0)
    bumps = [(rng.uniform(0, w), rng.uniform(0, h), rng.uniform(4.0, 10.0), rng.uniform(-1, 1))
             for _ in range(3)]

    def z_at(x: float, y: float) -> float:
        z = sum(a * amp * math.exp(-((x - bx) ** 2 + (y - by) ** 2) / (2 * s * s)) for bx, by, s, a in bumps)
        return z - amp - 1.0  # always below the stock top (Z0)

    feed = _feed(rng, tier)
    xs = np.linspace(0.0, w, max(2, round(w / step_x) + 1))
    ys = np.arange(0.0, h + 1e-9, step_y)
    lines = ["G00 X0.000 Y0.000", "G00 Z1.000", f"G01 Z{fmt(z_at(0.0, 0.0))} F{fmt(feed / 3)}"]
    moves = _Moves(0.0, 0.0, z_at(0.0, 0.0))
    for row, y in enumerate(ys):
        if row:
            for yy in np.linspace(ys[row - 1], y, 4)[1:]:
                moves.line(moves.x, float(yy), feed, z=z_at(moves.x, float(yy)))
        order = xs if row % 2 == 0 else xs[::-1]
        for x in order[1:]:
            moves.line(float(x), float(y), feed, z=z_at(float(x), float(y)))
    desc = (f"raster finishing {w:.1f} x {h:.1f} mm, {len(ys)} rows, {step_x:.2f} mm steps, surface "
            f"amplitude {amp:.1f} mm, F{feed:g}")
    return desc, lines + moves.lines


# -------------------------------------------------------------------------------------------- engraving
def engraving(rng: np.random.Generator, tier: str, split: str) -> tuple[str, list[str]]:
    """Engraving-like polylines: glyph strokes of 3–7 points with sharp corners, 0.2 mm deep, lifted
    between strokes (held out of the train split)."""
    glyphs = int(rng.integers(2, 5))
    cell = rng.uniform(5.0, 10.0)
    feed = _feed(rng, tier) / 2
    lines: list[str] = []
    strokes = 0
    for g in range(glyphs):
        for _ in range(int(rng.integers(1, 4))):
            k = int(rng.integers(3, 8))
            pts = np.column_stack((g * cell * 1.2 + rng.uniform(0, cell, k), rng.uniform(0, cell * 1.4, k)))
            lines += [f"G00 X{fmt(pts[0, 0])} Y{fmt(pts[0, 1])}", "G00 Z0.500",
                      f"G01 Z-0.200 F{fmt(300.0)}"]  # fmt: skip
            moves = _Moves(*pts[0], -0.2)
            for x, y in pts[1:]:
                moves.line(float(x), float(y), feed)
            lines += [*moves.lines, "G00 Z0.500"]
            strokes += 1
    return f"{glyphs} engraved glyphs, {strokes} strokes, cell {cell:.1f} mm, F{feed:g}", lines


Generator = Callable[[np.random.Generator, str, str], tuple[str, list[str]]]

#: Family name → generator (the registry the suite builder reads).
FAMILIES: dict[str, Generator] = {
    "contour": contour,
    "pocket": pocket,
    "freeform": freeform,
    "arcs": arcs,
    "holes": holes,
    "raster": raster,
    "engraving": engraving,
    "kirl": kirl,
}


def program_text(name: str, family: str, description: str, body: list[str]) -> str:
    """The whole program: header comments, set-up, ``body``, retract, spindle stop, M30."""
    for text in (name, family, description):
        if "(" in text or ")" in text:
            raise ValueError(f"no parentheses inside a comment: {text!r}")
    lines = [f"(cnc-gym benchmark program {name}, family {family})", f"({description})",
             "G90 G54 G17 G21", f"S{SPINDLE_RPM} M03", _retract(), *body,
             _retract(), "M05", "M30"]  # fmt: skip
    return "\n".join(lines) + "\n"


def builtin_text(name: str) -> str:
    """A built-in program (``cnc_gym/programs``) as it ships."""
    from cnc_gym.programs import program_path

    return Path(program_path(name)).read_text()
