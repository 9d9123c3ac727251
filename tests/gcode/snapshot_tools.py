"""The tool-path snapshot's digest and runner (``scripts/gcode_snapshot.py`` writes, ``test_snapshot.py``
checks; made importable by conftest.py)."""

from __future__ import annotations

import ast
import hashlib
import json
import math
from pathlib import Path

SNAPSHOT = Path(__file__).resolve().parent / "snapshots" / "toolpaths.json.gz"
_FIELDS = ("kind", "start", "end", "center", "plane", "radius", "start_angle", "sweep", "feed", "dwell_s",
           "line", "file_index", "modes", "tool", "spindle_rpm")  # fmt: skip


def _canonical(values) -> list:
    """Numbers rounded to 1e-9 (no -0.0; NaN as None) as nested lists."""
    import numpy as np

    array = np.asarray(values, dtype=float)
    out = []
    for x in array.ravel().tolist():
        if math.isnan(x):
            out.append(None)
        else:
            y = round(x, 9)
            out.append(0.0 if y == 0 else y)
    return [list(array.shape), out]


def toolpath_digest(toolpath) -> str:
    h = hashlib.sha256()
    for name in _FIELDS:
        h.update(name.encode())
        h.update(json.dumps(_canonical(getattr(toolpath, name))).encode())
    h.update(json.dumps(list(toolpath.files)).encode())
    h.update(toolpath.rotary_axes.encode())
    if toolpath.rotary_axes:
        h.update(json.dumps(_canonical(toolpath.rotary_start)).encode())
        h.update(json.dumps(_canonical(toolpath.rotary_end)).encode())
    for index in sorted(toolpath.nurbs):
        curve = toolpath.nurbs[index]
        h.update(json.dumps([index, int(curve.order), _canonical(curve.control_points),
                             _canonical(curve.weights), _canonical(curve.knots)]).encode())  # fmt: skip
    return h.hexdigest()


def run_input(item: dict) -> dict:
    """Interpret one captured input; the outcome as ``{"segments", "digest"}`` or ``{"error"}``."""
    from cnc_gym.errors import CncGymError
    from cnc_gym.gcode import interpret
    from cnc_gym.machine import load_machine

    options = ast.literal_eval(item["options"])  # plain literals only (never eval)
    if "block_skip" in options:
        options["block_skip"] = frozenset(options["block_skip"])
    if "machine" in options:
        options["machine"] = load_machine(options["machine"])
    try:
        toolpath = interpret(item["text"], **options)
    except CncGymError as err:
        return {"error": f"{type(err).__name__}: {err}"}
    return {"segments": len(toolpath), "digest": toolpath_digest(toolpath)}
