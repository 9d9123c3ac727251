"""The tool path as plain records: the ``cnc-gym trace`` JSON Lines contract (docs/architecture.md)."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from cnc_gym.toolpath.segments import Plane, SegmentKind

if TYPE_CHECKING:
    from cnc_gym.toolpath.segments import Toolpath

_KIND_NAMES = {k: k.name.lower() for k in SegmentKind}
_PLANE_NAMES = {p: p.name for p in Plane}
_DIGITS = 6  # 1 nm: far below any machine's resolution, keeps the output stable across platforms


def _r(x: float) -> float:
    y = round(float(x), _DIGITS)
    return 0.0 if y == 0 else y  # no "-0.0" in the output


def _g(x: float) -> float:
    """Dimensionless numbers (NURBS weights, knots): 12 significant digits, stable across platforms."""
    y = float(f"{float(x):.12g}")
    return 0.0 if y == 0 else y


def toolpath_records(tp: Toolpath) -> list[dict]:
    """One dict per row. Extra keys beyond the contract: ``start``, ``radius``, ``file``, ``modes``, NURBS
    data, and on paths with rotary axes ``rotary_end`` (every rapid and line: ``{"B": deg}``, machine
    coordinates) with ``rotary_start`` on the rows that move them; ``smoothing_tolerance_mm`` on rows that
    carry one."""
    records = []
    rotary = tp.rotary_axes
    for i in range(len(tp)):
        kind = SegmentKind(int(tp.kind[i]))
        rec: dict = {"kind": _KIND_NAMES[kind], "line": int(tp.line[i])}
        if tp.file_index[i] != 0:
            rec["file"] = tp.files[int(tp.file_index[i])]
        if kind == SegmentKind.DWELL:
            rec["seconds"] = _r(tp.dwell_s[i])
        else:
            rec["start"] = [_r(x) for x in tp.start[i]]
            rec["end"] = [_r(x) for x in tp.end[i]]
        if kind in (SegmentKind.LINE, SegmentKind.ARC, SegmentKind.NURBS):
            rec["feed"] = _r(tp.feed[i])
        if rotary and kind in (SegmentKind.LINE, SegmentKind.RAPID):
            if np.any(tp.rotary_start[i] != tp.rotary_end[i]):
                rec["rotary_start"] = {a: _r(x) for a, x in zip(rotary, tp.rotary_start[i], strict=True)}
            rec["rotary_end"] = {a: _r(x) for a, x in zip(rotary, tp.rotary_end[i], strict=True)}
        if kind == SegmentKind.ARC:
            rec["center"] = [_r(x) for x in tp.center[i]]
            rec["plane"] = _PLANE_NAMES[Plane(int(tp.plane[i]))]
            rec["sweep_deg"] = _r(math.degrees(tp.sweep[i]))
            rec["radius"] = _r(tp.radius[i])
        if kind == SegmentKind.NURBS:
            curve = tp.nurbs[i]
            rec["order"] = int(curve.order)
            rec["control_points"] = [[_r(x) for x in p] for p in curve.control_points]
            rec["weights"] = [_g(w) for w in curve.weights]
            rec["knots"] = [_g(k) for k in curve.knots]
        if tp.smoothing_tolerance_mm[i]:
            rec["smoothing_tolerance_mm"] = _r(tp.smoothing_tolerance_mm[i])
        if tp.modes[i]:
            rec["modes"] = [m.name.lower() for m in type_modes(int(tp.modes[i]))]
        records.append(rec)
    return records


def type_modes(value: int):
    from cnc_gym.toolpath.segments import SegmentMode

    return [m for m in SegmentMode if m and value & m]
