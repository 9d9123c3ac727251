"""The tool path as plain records: the ``cnc-gym trace`` JSON Lines contract (docs/architecture.md).

:func:`toolpath_records` gives one dict per row; :func:`toolpath_jsonl` the same records as JSON Lines
text, written directly for the rows of the usual kinds (rounding and printing each number as
``json.dumps`` would) and through ``json.dumps`` for the others, so the two are the same text.
"""

from __future__ import annotations

import json
import math
from typing import TYPE_CHECKING

import numpy as np

from cnc_gym.toolpath.segments import Plane, SegmentKind

if TYPE_CHECKING:
    from cnc_gym.toolpath.segments import Toolpath

_KIND_NAMES = {k: k.name.lower() for k in SegmentKind}
_PLANE_NAMES = {p: p.name for p in Plane}
_KIND_TEXT = {int(k): name for k, name in _KIND_NAMES.items()}
_KIND_TEXT_FAST = frozenset(int(k) for k in (SegmentKind.RAPID, SegmentKind.LINE, SegmentKind.ARC,
                                             SegmentKind.DWELL))  # fmt: skip
_PLANE_TEXT = {int(p): name for p, name in _PLANE_NAMES.items()}
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
    return [_record(tp, i) for i in range(len(tp))]


def _record(tp: Toolpath, i: int) -> dict:
    """The record of row i (see :func:`toolpath_records`)."""
    rotary = tp.rotary_axes
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
        assert tp.rotary_start is not None and tp.rotary_end is not None  # a path with rotary axes has both
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
    return rec


class _NumberTexts(dict):
    """A number's text as json.dumps prints it after rounding (:func:`_r`), made on first use."""

    def __missing__(self, x: float) -> str:
        text = self[x] = repr(_r(x))
        return text


def toolpath_jsonl(tp: Toolpath) -> str:
    """The records as JSON Lines: ``"".join(json.dumps(r) + "\\n" for r in toolpath_records(tp))``, built
    without the dicts for rapids, lines, arcs and dwells (the bulk of a program; ``cnc-gym trace``'s hot
    path). Rows with a file, rotary axes, NURBS data, a smoothing tolerance or a number that is not finite
    go through ``json.dumps``."""
    n = len(tp)
    points = np.column_stack((tp.start, tp.end))
    general = (tp.file_index != 0) | (tp.kind == SegmentKind.NURBS) | ~np.all(np.isfinite(points), axis=1)
    general |= tp.smoothing_tolerance_mm != 0
    general |= (tp.kind == SegmentKind.ARC) & ~np.all(np.isfinite(tp.center), axis=1)
    cutting = np.isin(tp.kind, (SegmentKind.LINE, SegmentKind.ARC))
    general |= cutting & ~np.isfinite(tp.feed)
    general |= (tp.kind == SegmentKind.ARC) & ~(np.isfinite(tp.radius) & np.isfinite(tp.sweep))
    general |= (tp.kind == SegmentKind.DWELL) & ~np.isfinite(tp.dwell_s)
    if tp.rotary_axes:
        general |= (tp.kind == SegmentKind.LINE) | (tp.kind == SegmentKind.RAPID)
    general_rows = general.tolist()
    # Each number as json.dumps prints it after rounding, formatted once per distinct value (coordinates
    # repeat: a row starts where the last one ended).
    sweep_deg = [math.degrees(x) for x in tp.sweep.tolist()]
    columns = np.column_stack((tp.start, tp.end, tp.center, tp.feed, sweep_deg, tp.radius, tp.dwell_s)) if n \
        else np.zeros((0, 13))  # fmt: skip
    columns = np.where(np.isfinite(columns), columns, 0.0)  # (rows using a value that is not are general)
    memo = _NumberTexts()
    (sx, sy, sz, ex, ey, ez, cx, cy, cz, feed_t, sweep_t, radius_t,
     dwell_t) = ([memo[x] for x in column] for column in columns.T.tolist())  # fmt: skip
    kinds, lines, modes, plane = tp.kind.tolist(), tp.line.tolist(), tp.modes.tolist(), tp.plane.tolist()
    mode_text: dict[int, str] = {}
    out = []
    line, arc, dwell = (int(k) for k in (SegmentKind.LINE, SegmentKind.ARC,
                                                  SegmentKind.DWELL))  # fmt: skip
    for i in range(n):
        k = kinds[i]
        if general_rows[i] or k not in _KIND_TEXT_FAST:
            out.append(json.dumps(_record(tp, i)))
            continue
        if k == dwell:
            text = f'{{"kind": "dwell", "line": {lines[i]}, "seconds": {dwell_t[i]}'
        else:
            text = (f'{{"kind": "{_KIND_TEXT[k]}", "line": {lines[i]}, "start": [{sx[i]}, {sy[i]}, {sz[i]}], '
                    f'"end": [{ex[i]}, {ey[i]}, {ez[i]}]')  # fmt: skip
            if k == line:
                text += f', "feed": {feed_t[i]}'
            elif k == arc:
                text += (f', "feed": {feed_t[i]}, "center": [{cx[i]}, {cy[i]}, {cz[i]}], "plane": '
                         f'"{_PLANE_TEXT[plane[i]]}", "sweep_deg": {sweep_t[i]}, "radius": {radius_t[i]}')
        m = modes[i]
        if m:
            if m not in mode_text:
                mode_text[m] = ', "modes": ' + json.dumps([x.name.lower() for x in type_modes(m)])
            text += mode_text[m]
        out.append(text + "}")
    out.append("")
    return "\n".join(out)


def type_modes(value: int):
    from cnc_gym.toolpath.segments import SegmentMode

    return [m for m in SegmentMode if m and value & m]
