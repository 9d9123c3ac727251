"""The tool path as plain records: the ``cnc-gym trace`` JSON Lines contract (docs/architecture.md).

:func:`toolpath_records` gives one dict per row; :func:`toolpath_jsonl` the same records as JSON Lines
text, written directly for the rows of the usual kinds (rounding and printing each number as
``json.dumps`` would) and through ``json.dumps`` for the others, so the two are the same text.
"""

from __future__ import annotations

import json
import math

import numpy as np

from cnc_gym.errors import CncGymError
from cnc_gym.toolpath.kinds import Plane, SegmentKind, SegmentMode, ToolpathRows

_KIND_NAMES = {k: k.name.lower() for k in SegmentKind}
_PLANE_NAMES = {p: p.name for p in Plane}
_PLANE_TEXT = {int(p): name for p, name in _PLANE_NAMES.items()}
_DIGITS = 6  # 1 nm: far below any machine's resolution, keeps the output stable across platforms


def _r(x: float) -> float:
    y = round(float(x), _DIGITS)
    return 0.0 if y == 0 else y  # no "-0.0" in the output


def _g(x: float) -> float:
    """Dimensionless numbers (NURBS weights, knots): 12 significant digits, stable across platforms."""
    y = float(f"{float(x):.12g}")
    return 0.0 if y == 0 else y


def toolpath_records(tp: ToolpathRows) -> list[dict]:
    """One dict per row. Extra keys beyond the contract: ``start``, ``radius``, ``file``, ``modes``, NURBS
    data, and on paths with rotary axes ``rotary_end`` (every rapid and line: ``{"B": deg}``, machine
    coordinates) with ``rotary_start`` on the rows that move them; ``smoothing_tolerance_mm`` on rows that
    carry one; ``machine_function`` (``"M13"``) on a dwell row that stands for an M code the control hands
    to the machine."""
    return [_record(tp, i) for i in range(len(tp))]


def _record(tp: ToolpathRows, i: int) -> dict:
    """The record of row i (see :func:`toolpath_records`)."""
    rotary = tp.rotary_axes
    kind = SegmentKind(int(tp.kind[i]))
    rec: dict = {"kind": _KIND_NAMES[kind], "line": int(tp.line[i])}
    if tp.file_index[i] != 0:
        rec["file"] = tp.files[int(tp.file_index[i])]
    if kind == SegmentKind.DWELL:
        rec["seconds"] = _r(tp.dwell_s[i])
        if i in tp.machine_functions:
            rec["machine_function"] = tp.machine_functions[i]
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
    """A rounded number's text as json.dumps prints it, made on first use (coordinates repeat: a row
    starts where the last one ended)."""

    def __missing__(self, x: float) -> str:
        text = self[x] = repr(x)
        return text


#: Largest ``|x| * 10**_DIGITS`` rounded in numpy: below 2**52 the scaled value's fraction is exact.
_EXACT_SCALED = 2.0**52


def rounded(values: np.ndarray) -> list[float]:
    """:func:`_r` of every (finite) value, vectorised: ``rint(x * 1e6) / 1e6`` is the double ``round(x, 6)``
    gives whenever the scaled product cannot straddle a rounding boundary (a half-integer) through its own
    rounding error (at most ``|x| * 1e6 * 2**-53``); the few values near one, ties included, and huge ones
    go through :func:`_r`. ``+ 0.0`` turns ``-0.0`` into ``0.0``."""
    with np.errstate(over="ignore", invalid="ignore"):  # huge and non-finite values are unsure
        scaled = values * 10.0**_DIGITS
        fraction = scaled - np.floor(scaled)
        unsure = (np.abs(fraction - 0.5) <= np.abs(scaled) * 2.0**-51) | ~(np.abs(scaled) < _EXACT_SCALED)
        out = (np.rint(scaled) / 10.0**_DIGITS + 0.0).tolist()
    for i in np.flatnonzero(unsure).tolist():
        out[i] = _r(values[i])
    return out


def toolpath_jsonl(tp: ToolpathRows) -> str:
    """The records as JSON Lines: ``"".join(json.dumps(r) + "\\n" for r in toolpath_records(tp))``, built
    without the dicts for rapids, lines, arcs and dwells (the bulk of a program; ``cnc-gym trace``'s hot
    path): each kind's rows are filled into one text template, column by column. Rows with a file, rotary
    axes, NURBS data, a smoothing tolerance or a number that is not finite go through ``json.dumps``
    (the last: a CncGymError naming the line, since NaN and Infinity are not JSON)."""
    n = len(tp)
    if n == 0:
        return ""
    kind = tp.kind
    coordinates = np.column_stack((tp.start, tp.end))
    general = (tp.file_index != 0) | (kind == SegmentKind.NURBS) | ~np.all(np.isfinite(coordinates), axis=1)
    general |= tp.smoothing_tolerance_mm != 0
    general |= (kind == SegmentKind.ARC) & ~np.all(np.isfinite(tp.center), axis=1)
    cutting = (kind == SegmentKind.LINE) | (kind == SegmentKind.ARC)
    general |= cutting & ~np.isfinite(tp.feed)
    general |= (kind == SegmentKind.ARC) & ~(np.isfinite(tp.radius) & np.isfinite(tp.sweep))
    general |= (kind == SegmentKind.DWELL) & ~np.isfinite(tp.dwell_s)
    if tp.machine_functions:
        general[list(tp.machine_functions)] = True
    if tp.rotary_axes:
        general |= (kind == SegmentKind.LINE) | (kind == SegmentKind.RAPID)
    fast = ~general
    memo = _NumberTexts()
    text = memo.__getitem__

    def texts(column: np.ndarray) -> list[str]:
        return list(map(text, rounded(column)))

    def points(xyz: np.ndarray) -> list[str]:
        return list(map(_POINT.__mod__, zip(*(texts(c) for c in xyz.T), strict=True)))

    # Point texts "x, y, z": one per row's end; a start is its row's previous end, or made on its own.
    ends = np.empty(n, dtype=object)
    ends[:] = points(tp.end)
    starts = np.empty(n, dtype=object)
    starts[1:] = ends[:-1]
    own = np.flatnonzero(np.any(tp.start[1:] != tp.end[:-1], axis=1)) + 1
    own = np.concatenate(([0], own))
    starts[own] = points(tp.start[own])
    out = np.empty(n, dtype=object)  # each row's text without its closing brace
    for segment_kind, template in _TEMPLATES.items():
        rows = np.flatnonzero((kind == segment_kind) & fast)
        if not rows.size:
            continue
        fields: list[list] = [tp.line[rows].tolist()]
        if segment_kind == SegmentKind.DWELL:
            fields.append(texts(tp.dwell_s[rows]))
        else:
            fields += [starts[rows].tolist(), ends[rows].tolist()]
        if segment_kind in (SegmentKind.LINE, SegmentKind.ARC):
            fields.append(texts(tp.feed[rows]))
        if segment_kind == SegmentKind.ARC:
            fields.append(points(tp.center[rows]))
            fields.append([_PLANE_TEXT[p] for p in tp.plane[rows].tolist()])
            fields.append(texts(np.degrees(tp.sweep[rows])))
            fields.append(texts(tp.radius[rows]))
        out[rows] = list(map(template.__mod__, zip(*fields, strict=True)))
    for i in np.flatnonzero(general).tolist():
        out[i] = _json_record(tp, i)[:-1]
    fast_modes = np.flatnonzero((tp.modes != 0) & ~general)
    if fast_modes.size:
        mode_text: dict[int, str] = {}
        for i, m in zip(fast_modes.tolist(), tp.modes[fast_modes].tolist(), strict=True):
            if m not in mode_text:
                mode_text[m] = ', "modes": ' + json.dumps([x.name.lower() for x in type_modes(m)])
            out[i] += mode_text[m]
    return "}\n".join(out.tolist()) + "}\n"


def _json_record(tp: ToolpathRows, i: int) -> str:
    """Row ``i``'s record as JSON; a number that is not finite (NaN, Infinity: not JSON) is one clear error
    naming its line, never printed."""
    record = _record(tp, i)
    try:
        return json.dumps(record, allow_nan=False)
    except ValueError:
        raise CncGymError(f"line {record.get('line', '?')}: the tool path holds a number that is not finite; "
                          "it cannot be written as JSON") from None  # fmt: skip


_POINT = "%s, %s, %s"
_POINTS = '"start": [%s], "end": [%s]'
#: The fast rows' text up to the closing brace (the key order of :func:`_record`).
_TEMPLATES = {
    SegmentKind.RAPID: '{"kind": "rapid", "line": %d, ' + _POINTS,
    SegmentKind.LINE: '{"kind": "line", "line": %d, ' + _POINTS + ', "feed": %s',
    SegmentKind.ARC: (
        '{"kind": "arc", "line": %d, ' + _POINTS + ', "feed": %s, "center": [%s], "plane": "%s", '
        '"sweep_deg": %s, "radius": %s'
    ),
    SegmentKind.DWELL: '{"kind": "dwell", "line": %d, "seconds": %s',
}


def type_modes(value: int):
    return [m for m in SegmentMode if m and value & m]
