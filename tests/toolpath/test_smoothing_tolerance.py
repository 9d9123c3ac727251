"""The tool path's per-row smoothing tolerance (``Toolpath.smoothing_tolerance_mm``)."""

from __future__ import annotations

import numpy as np
import pytest

from cnc_gym.toolpath import SegmentKind, Toolpath, ToolpathBuilder


def _path() -> Toolpath:
    b = ToolpathBuilder()
    b.line((0, 0, 0), (1, 0, 0), 100.0, line=1)  # before any smoothing: 0
    b.smoothing({SegmentKind.LINE: 0.01})
    b.rapid((1, 0, 0), (2, 0, 0), line=2)  # a rapid: not a smoothed kind
    b.line((2, 0, 0), (3, 0, 0), 100.0, line=3)
    b.arc((3, 0, 0), (5, 0, 0), (4, 0, 0), 0, np.pi, 100.0, line=4)
    b.smoothing({SegmentKind.LINE: 0.05, SegmentKind.ARC: 0.002})
    b.arc((5, 0, 0), (7, 0, 0), (6, 0, 0), 0, np.pi, 100.0, line=5)
    b.line((7, 0, 0), (8, 0, 0), 100.0, line=6)
    b.smoothing({})
    b.line((8, 0, 0), (9, 0, 0), 100.0, line=7)
    return b.build()


def test_rows_carry_the_tolerance_in_force_for_their_kind():
    tp = _path()
    assert tp.smoothing_tolerance_mm.tolist() == [0.0, 0.0, 0.01, 0.0, 0.002, 0.05, 0.0]
    assert not tp.smoothing_tolerance_mm.flags.writeable


def test_paths_without_smoothing_are_all_zero_and_records_omit_the_key():
    b = ToolpathBuilder()
    b.line((0, 0, 0), (1, 0, 0), 100.0, line=1)
    tp = b.build()
    assert tp.smoothing_tolerance_mm.tolist() == [0.0]
    assert "smoothing_tolerance_mm" not in tp.to_records()[0]
    assert [r.get("smoothing_tolerance_mm") for r in _path().to_records()] == [
        None, None, 0.01, None, 0.002, 0.05, None]


def test_a_negative_or_nan_tolerance_is_refused():
    tp = _path()
    fields = {name: getattr(tp, name) for name in ("kind", "start", "end", "center", "plane", "radius",
                                                    "start_angle", "sweep", "feed", "dwell_s", "line",
                                                    "file_index", "modes", "tool", "spindle_rpm")}
    for bad in (-1.0, float("nan")):
        with pytest.raises(ValueError, match="smoothing"):
            Toolpath(**fields, smoothing_tolerance_mm=np.full(len(tp), bad))
