"""The built-in program suite: files up to date, plain G-code only, geometry as designed, loader rules."""

from __future__ import annotations

import math
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from cnc_gym.errors import ConfigError, ProgramError
from cnc_gym.programs import BUILTIN_PROGRAMS, load_program, program_names, program_path
from cnc_gym.toolpath import SegmentKind

ROOT = Path(__file__).resolve().parent.parent


def cutting(tp):
    return (tp.kind == SegmentKind.LINE) | (tp.kind == SegmentKind.ARC)


def test_names_and_files():
    assert program_names() == ["circle", "star", "freeform", "pocket"]
    for name in program_names():
        assert program_path(name).is_file()


def test_shipped_files_match_the_generator():
    # The .nc files are generated; a hand edit (or a generator change without regenerating) fails here.
    result = subprocess.run(
        [sys.executable, str(ROOT / "scripts" / "make_programs.py"), "--check"],
        capture_output=True,
        text=True,
    )
    assert result.returncode == 0, result.stderr


@pytest.mark.parametrize("name", BUILTIN_PROGRAMS)
def test_plain_gcode_only(name):
    # The suite must run on the basic interpreter: only these words and codes (comments stripped).
    allowed_g = {0, 1, 2, 3, 17, 21, 54, 90, 91}
    allowed_m = {3, 5, 30}
    for raw in program_path(name).read_text().splitlines():
        line = re.sub(r"\([^)]*\)", "", raw).strip()
        words = re.findall(r"([A-Z])([-+]?[0-9.]+)", line)
        assert "".join(a + v for a, v in words) == line.replace(" ", ""), f"unexpected text in {raw!r}"
        for address, value in words:
            assert address in "GMXYZIJFS", raw
            if address == "G":
                assert int(value) in allowed_g, raw
            elif address == "M":
                assert int(value) in allowed_m, raw
            elif address in "XYZIJF":
                assert "." in value, f"{raw!r}: coordinate without a decimal point"


def test_circle_geometry():
    _, tp = load_program("circle")
    arcs = np.flatnonzero(tp.kind == SegmentKind.ARC)
    assert len(arcs) == 1
    # Full circle R 30 mm, counter-clockwise: length 2π·30 = 188.496 mm, sweep +2π.
    assert tp.radius[arcs[0]] == pytest.approx(30.0)
    assert tp.sweep[arcs[0]] == pytest.approx(2 * math.pi)
    assert tp.length[arcs[0]] == pytest.approx(188.4956, abs=1e-3)
    assert tp.feed[arcs[0]] == pytest.approx(3000.0)


def test_star_geometry():
    _, tp = load_program("star")
    lines = np.flatnonzero((tp.kind == SegmentKind.LINE) & (tp.feed == 4000.0))
    assert len(lines) == 10
    # Pentagram with tip radius r: edge = r·sin 36°/sin 126° ... for r = 50 the anchors give 36.327 mm,
    # so r = 30 gives 36.327 · 0.6 = 21.796 mm (rounding of the 3-decimal coordinates: ±2 µm).
    np.testing.assert_allclose(tp.length[lines], 21.796, atol=2e-3)
    d = (tp.end[lines] - tp.start[lines])[:, :2]
    heading = np.arctan2(d[:, 1], d[:, 0])
    turn = np.degrees(np.angle(np.exp(1j * (np.roll(heading, -1) - heading))))
    # Closed outline: the turn from the last edge back to the first is a tip as well.
    assert sorted(np.round(turn).astype(int).tolist()) == [-72] * 5 + [144] * 5


def test_freeform_is_short_segments():
    _, tp = load_program("freeform")
    cut = np.flatnonzero(cutting(tp) & (tp.feed == 3000.0))
    assert len(cut) > 200
    assert tp.length[cut].min() > 0.5 and tp.length[cut].max() < 2.0
    # Closed curve: ends where it starts; bounding box ±Ax, ±Ay of the Lissajous.
    assert np.allclose(tp.start[cut[0]], tp.end[cut[-1]], atol=1e-3)
    xy = tp.end[cut][:, :2]
    assert np.abs(xy[:, 0]).max() == pytest.approx(24.0, abs=0.05)
    assert np.abs(xy[:, 1]).max() == pytest.approx(16.0, abs=0.05)


def test_pocket_has_both_arc_directions_and_closed_loops():
    _, tp = load_program("pocket")
    arcs = tp.kind == SegmentKind.ARC
    assert np.count_nonzero(arcs & (tp.sweep > 0)) == 12  # three roughing loops, G03
    assert np.count_nonzero(arcs & (tp.sweep < 0)) == 4  # finishing pass, G02
    np.testing.assert_allclose(np.abs(tp.sweep[arcs]), math.pi / 2)
    # The finishing loop is a 36 × 28 mm rounded rectangle with R 6 corners: 2(36 + 28) − 8·6 + 2π·6.
    finish = np.flatnonzero(cutting(tp) & (tp.feed == 2000.0))
    expected = 2 * (36 + 28) - 8 * 6 + 2 * math.pi * 6
    assert tp.length[finish].sum() == pytest.approx(expected + 2.0, abs=1e-3)  # + the 2 mm step-over


@pytest.mark.parametrize("name", BUILTIN_PROGRAMS)
def test_each_program_starts_at_origin_and_ends_with_a_retract(name):
    _, tp = load_program(name)
    np.testing.assert_allclose(tp.start[0], 0.0)
    last_motion = np.flatnonzero(tp.kind != SegmentKind.DWELL)[-1]
    assert tp.kind[last_motion] == SegmentKind.RAPID
    assert tp.end[last_motion][2] == pytest.approx(5.0)


def test_loader_caches_and_accepts_paths_and_text(tmp_path):
    name, tp = load_program("circle")
    assert name == "circle"
    assert load_program("circle")[1] is tp  # interpreted once
    path = tmp_path / "part.nc"
    path.write_text(program_path("circle").read_text())
    name_p, tp_p = load_program(path)
    assert name_p == "part"
    np.testing.assert_array_equal(tp_p.end, tp.end)
    name_s, _ = load_program(str(path))
    assert name_s == "part"
    text = "G90 G21 G17\nG01 X10.0 Y0.0 F1200.0\nM30\n"
    name_t, tp_t = load_program(text)
    assert name_t.startswith("text-")
    assert tp_t.total_length == pytest.approx(10.0)
    assert load_program(text)[1] is tp_t


def test_loader_errors(tmp_path):
    with pytest.raises(ConfigError, match="unknown program"):
        load_program("circel")
    with pytest.raises(ConfigError, match="not found"):
        load_program(tmp_path / "missing.nc")
    with pytest.raises(ConfigError):
        load_program(42)  # type: ignore[arg-type]
    bad = tmp_path / "bad.nc"
    bad.write_text("G90\nG01 X10.0 Y Z F100.0\n")
    with pytest.raises(ProgramError) as err:
        load_program(bad)
    assert "bad.nc:2" in str(err.value)
