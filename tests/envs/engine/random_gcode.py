"""Random GSK 25i programs for the env's property tests: every motion the env handles, in G-code text.

Rapids, lines (some with G09 exact stops), arcs and helices in the three planes (G17/G18/G19, I/J/K
centres, some full circles), dwells (G04 X), cubic NURBS blocks (G05 P10000 / G06.2) and short polyline
runs. Coordinates are printed with 4 decimals; every arc's end point is computed from its centre so the
interpreter's radius check passes. The programs stay within ±200 mm of the origin. :func:`bench_program`
gives the benchmark's helix- and NURBS-rich programs.
"""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path

import numpy as np

_PLANES = (("G17", 0, 1, 2, "IJ"), ("G18", 2, 0, 1, "KI"), ("G19", 1, 2, 0, "JK"))
_AXES = "XYZ"


def _fmt(x: float) -> str:
    return f"{x:.4f}"


def _words(p: np.ndarray) -> str:
    return " ".join(f"{a}{_fmt(v)}" for a, v in zip(_AXES, p, strict=True))


def random_gcode(rng: np.random.Generator, n_blocks: int, *, helix_p: float = 0.15, nurbs_p: float = 0.05,
                 step_mm: float = 4.0) -> str:  # fmt: skip
    """A random program of about ``n_blocks`` motion blocks (see the module docstring)."""
    lines = ["G90 G21 G17 G94"]
    p = np.zeros(3)
    plane_word = "G17"
    for _ in range(n_blocks):
        r = rng.random()
        feed = float(rng.uniform(300.0, 9000.0))
        if r < 0.06:  # rapid
            q = np.clip(p + rng.normal(size=3) * step_mm * 2, -200, 200)
            q = np.round(q, 4)
            lines.append(f"G00 {_words(q)}")
            p = q
        elif r < 0.10:  # dwell
            lines.append(f"G04 X{rng.uniform(0.0, 0.05):.3f}")
        elif r < 0.10 + nurbs_p:  # a cubic NURBS block (G05 P10000 mode around it)
            n_ctrl = int(rng.integers(4, 7))
            steps = rng.normal(size=(n_ctrl - 1, 3)) * np.array([1.0, 1.0, 0.2]) * step_mm
            ctrl = np.round(np.vstack((p, p + np.cumsum(steps, axis=0))), 4)
            weights = rng.uniform(0.5, 2.0, size=n_ctrl)
            inner = np.sort(rng.uniform(0.05, 0.95, size=n_ctrl - 4))
            knots = np.concatenate((np.zeros(4), inner, np.ones(4)))
            p = np.round(p + np.array([0.5, 0.0, 0.0]), 4)  # a line first: the curve starts where it ends
            lines.append(f"G01 {_words(p)} F{feed:.1f}")
            ctrl[0] = p
            ctrl[1:] += 0.5 * np.array([1.0, 0.0, 0.0])
            lines.append("G05 P10000")
            lines.append(f"G06.2 P4 K{knots[0]:.4f} {_words(ctrl[0])} R{weights[0]:.4f} F{feed:.1f}")
            for i in range(1, n_ctrl):
                lines.append(f"K{knots[i]:.4f} {_words(ctrl[i])} R{weights[i]:.4f}")
            for k in knots[n_ctrl:]:
                lines.append(f"K{k:.4f}")
            p = np.round(ctrl[-1] + np.array([0.0, 0.5, 0.0]), 4)  # a group-01 block ends NURBS mode
            lines.append(f"G01 {_words(p)}")
            lines.append("G05 P0")
        elif r < 0.45:  # arc or helix
            word, iu, iv, iw, letters = _PLANES[0] if rng.random() < 0.6 else _PLANES[int(rng.integers(0, 3))]
            if word != plane_word:
                lines.append(word)
                plane_word = word
            radius = float(rng.uniform(0.5, 3.0) * step_mm)
            phi = rng.uniform(-math.pi, math.pi)
            center = p.copy()
            center[iu] = round(p[iu] - radius * math.cos(phi), 4)
            center[iv] = round(p[iv] - radius * math.sin(phi), 4)
            radius = math.hypot(p[iu] - center[iu], p[iv] - center[iv])
            phi = math.atan2(p[iv] - center[iv], p[iu] - center[iu])
            ccw = rng.random() < 0.5
            full = rng.random() < 0.08
            sweep = 2 * math.pi if full else float(rng.uniform(0.2, 1.8 * math.pi))
            q = p.copy()
            if not full:
                ang = phi + (sweep if ccw else -sweep)
                q[iu] = round(center[iu] + radius * math.cos(ang), 4)
                q[iv] = round(center[iv] + radius * math.sin(ang), 4)
            if rng.random() < helix_p / 0.35:
                q[iw] = round(p[iw] + float(rng.normal() * step_mm), 4)
            offsets = {iu: center[iu] - p[iu], iv: center[iv] - p[iv]}
            centre_words = " ".join(f"{letters[j]}{_fmt(offsets[ax])}" for j, ax in enumerate((iu, iv)))
            exact = "G09 " if rng.random() < 0.1 else ""
            lines.append(f"{exact}{'G03' if ccw else 'G02'} {_words(q)} {centre_words} F{feed:.1f}")
            p = q
        elif r < 0.55:  # a polyline run of short segments
            heading = rng.uniform(0, 2 * math.pi)
            for _ in range(int(rng.integers(3, 12))):
                heading += rng.normal() * 0.2
                q = np.round(p + 0.5 * np.array([math.cos(heading), math.sin(heading), 0.0]), 4)
                lines.append(f"G01 {_words(q)} F{feed:.1f}")
                p = q
        else:  # line
            d = rng.normal(size=3)
            if rng.random() < 0.5:
                d[2] = 0.0
            d /= max(np.linalg.norm(d), 1e-9)
            q = np.round(np.clip(p + d * (rng.exponential(step_mm) + 0.01), -200, 200), 4)
            exact = "G09 " if rng.random() < 0.1 else ""
            lines.append(f"{exact}G01 {_words(q)} F{feed:.1f}")
            p = q
    lines.append("M30")
    return "\n".join(lines) + "\n"


def bench_program(family: str) -> str:
    """The benchmark's program of a family (``helix``: a helical bore; ``nurbs``: a chain of cubic curves),
    from ``scripts/bench_env.py``, so that the tests run what the benchmark times."""
    path = Path(__file__).resolve().parents[3] / "scripts" / "bench_env.py"
    spec = importlib.util.spec_from_file_location("bench_env", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.FAMILIES[family]()[0]
