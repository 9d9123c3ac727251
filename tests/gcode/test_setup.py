"""The operator's tables at power-on (a setup): work offsets and tool offsets from ``interpret(setup=)``, a
machine preset's ``setup:`` section, or both (the argument on top), in every dialect; G10 still changes
them at run time; what a dialect cannot hold is one ConfigError line naming the file and the key.

Expected points by hand: machine = program + work origin (+ the tool length on Z).
"""

from __future__ import annotations

import pytest

from cnc_gym.errors import ConfigError
from cnc_gym.gcode import interpret
from cnc_gym.machine import load_setup, machine_from_dict, merge_setups, with_setup

SETUP = {"work_offsets": {"G54": [100.0, 50.0, -200.0], "G55": [300.0, 0.0, -250.0]},
         "tools": {1: {"length_mm": 120.0, "radius_mm": 5.0},
                   2: {"length_mm": 80.0, "length_wear_mm": -0.5}}}  # fmt: skip


def ends(text: str, **kw) -> list[list[float]]:
    return [[round(c, 6) + 0.0 for c in p] for p in interpret(text, **kw).end.tolist()]


FANUC_STYLE = "G54 G00 X0 Y0\nG43 H1 Z10.\nG55 X0 Y0\nG43 H2 Z10.\n"
#: AZ-MC1: no G43/H; the D record carries the length (on Z in G17) and the radius.
AZ_STYLE = "G54 G00 X0 Y0\nD1 Z10\nG55 X0 Y0\nD2 Z10\n"


@pytest.mark.parametrize("dialect", ["gsk25i", "fanuc", "syntec", "h4cm", "azmc1"])
def test_work_offsets_and_tool_lengths_in_every_dialect(dialect):
    text = AZ_STYLE if dialect == "azmc1" else FANUC_STYLE
    expected = [[100.0, 50.0, -200.0], [100.0, 50.0, -70.0],  # G54; Z10 + H1 120 - 200
                [300.0, 0.0, -70.0],  # G55: Z not commanded keeps its machine position
                [300.0, 0.0, -160.5]]  # H2: 10 + 80 - 0.5 - 250  # fmt: skip
    got = ends(text, dialect=dialect, setup=SETUP)
    assert got[1:] == expected[1:] and got[0][:2] == expected[0][:2]


@pytest.mark.parametrize("dialect", ["gsk25i", "fanuc", "syntec", "h4cm"])
def test_the_radius_of_d_is_the_tools_radius(dialect):
    # G41 D1 (r 5) on a line along +X from (-10, 0) into (0, 0) … (20, 0): the tool runs at y = 5 (left).
    # (G41 in a block of its own: the H4C-M keeps one G code per block.)
    text = "G00 X-10. Y0\nG41 D1\nG01 X0 Y0 F100.\nX20.\nG40\nG00 X30. Y-10.\n"
    cut = [p for p in ends(text, dialect=dialect, setup={"tools": {1: {"radius_mm": 5.0}}})]
    assert [0.0, 5.0, 0.0] in cut and [20.0, 5.0, 0.0] in cut


def test_extended_and_external_work_offsets():
    setup = {"work_offsets": {"G54.1 P5": [1.0, 2.0, 3.0], "EXT": [10.0, 0.0, 0.0]}}
    # G54.1 P5: 1 + 10 (EXT is added to every system); G54: 0 + 10.
    assert ends("G54.1 P5 G00 X0 Y0 Z0\nG54 X0 Y0 Z0\n", dialect="fanuc", setup=setup) == [
        [11.0, 2.0, 3.0], [10.0, 0.0, 0.0]]
    syntec = {"work_offsets": {"G59.3": [5.0, 5.0, 0.0]}}
    assert ends("G59.3 G00 X1. Y1.\n", dialect="syntec", setup=syntec) == [[6.0, 6.0, 0.0]]


def test_g10_still_changes_the_tables_at_run_time():
    text = "G54 G00 X0 Y0\nG10 L2 P1 X7.\nG00 X0\nG10 L10 P1 R50.\nG43 H1 Z0\n"
    assert ends(text, dialect="fanuc", setup=SETUP) == [[100.0, 50.0, 0.0], [7.0, 50.0, 0.0],
                                                         [7.0, 50.0, -150.0]]  # fmt: skip


def test_inch_setups_are_converted_and_explicit_tool_offsets_go_on_top():
    inch = {"units": "inch", "work_offsets": {"G54": [1.0, 0.0, 0.0]}, "tools": {1: {"length_mm": 2.0}}}
    assert ends("G54 G00 X0\nG43 H1 Z0\n", dialect="fanuc", setup=inch) == [[25.4, 0.0, 0.0],
                                                                           [25.4, 0.0, 50.8]]  # fmt: skip
    # tool_offsets= (the Python API's tables) over the setup's tools: H1 7 on G54's Z -200
    over = ends("G43 H1 Z0\n", dialect="fanuc", setup=SETUP, tool_offsets={"H": {1: 7.0}})
    assert over == [[0.0, 0.0, -193.0]]


def test_a_presets_setup_section_and_a_setup_on_top():
    section = {"work_offsets": {"G54": [1.0, 2.0, 3.0], "G55": [4.0, 5.0, 6.0]},
               "tools": {1: {"length_mm": 10.0}}}  # fmt: skip
    preset = machine_from_dict({"setup": section}, source="shop.yaml")
    assert preset.setup.source == "shop.yaml"
    text = "G54 G00 X0 Y0 Z0\nG55 X0 Y0 Z0\nG43 H1 Z0\n"
    assert ends(text, dialect="fanuc", machine=preset) == [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0],
                                                           [4.0, 5.0, 16.0]]  # fmt: skip
    # the argument's G54 and tool 1 win; the preset's G55 stays
    job = {"work_offsets": {"G54": [100.0, 0.0, 0.0]}, "tools": {1: {"length_mm": 20.0}}}
    expected = [[100.0, 0.0, 0.0], [4.0, 5.0, 6.0], [4.0, 5.0, 26.0]]
    assert ends(text, dialect="fanuc", machine=preset, setup=job) == expected
    # with_setup folds a file into the machine record (how run, bench and the envs carry it)
    folded = with_setup(preset, job)
    assert ends(text, dialect="fanuc", machine=folded) == expected
    assert hash(folded) != hash(preset)
    merged = merge_setups(load_setup({"units": "inch", "work_offsets": {"G54": [1, 0, 0]}}), load_setup(job))
    assert merged.units == "mm" and merged.work_offsets["G54"] == (100.0, 0.0, 0.0)


def test_a_setup_file_is_read_and_checked(tmp_path):
    path = tmp_path / "job.yaml"
    path.write_text("work_offsets:\n  g54.1 p05: [1, 2, 3]\ntools:\n  7: {radius_mm: 4}\n")
    setup = load_setup(path)
    assert set(setup.work_offsets) == {"G54.1 P5"} and setup.tools[7].radius_mm == 4.0
    assert ends("G54.1 P5 G00 X0 Y0 Z0\n", dialect="gsk25i", setup=str(path)) == [[1.0, 2.0, 3.0]]


@pytest.mark.parametrize(("text", "problem"), [
    ("work_offsets:\n  G53: [1, 2, 3]\n", "job.yaml: work_offsets key 'G53' is not a work coordinate system"),
    ("work_offsets:\n  G54: [1, 2]\n", "job.yaml: work_offsets.G54 must name at least 3"),
    ("tools:\n  0: {length_mm: 1}\n", "job.yaml: tools key 0 is not an offset number"),
    ("tools:\n  1: {lenght_mm: 1}\n", "job.yaml: unknown key tools.1.lenght_mm"),
    ("tools:\n  1: {length_mm: .nan}\n", "job.yaml: tools.1.length_mm must be finite"),
    ("units: cm\n", "job.yaml: units must be one of mm, inch"),
    ("work_offsets:\n  G54: [1, 2, 3]\n  g54: [4, 5, 6]\n", "job.yaml: work_offsets names G54 twice"),
    ("tool: {}\n", "job.yaml: unknown key tool"),
])  # fmt: skip
def test_a_bad_setup_file_is_one_line_naming_the_key(tmp_path, text, problem):
    path = tmp_path / "job.yaml"
    path.write_text(text)
    with pytest.raises(ConfigError) as info:
        load_setup(path)
    message = str(info.value).replace(str(tmp_path) + "/", "")
    assert message.startswith(problem) and "\n" not in message, message


@pytest.mark.parametrize(("dialect", "setup", "problem"), [
    ("syntec", {"work_offsets": {"G54.1 P1": [0, 0, 0]}}, "work_offsets.G54.1 P1 cannot be set: the Syntec"),
    ("fanuc", {"work_offsets": {"G59.3": [0, 0, 0]}}, "work_offsets.G59.3 cannot be set"),
    ("fanuc", {"work_offsets": {"G54.1 P49": [0, 0, 0]}}, "work_offsets.G54.1 P49 cannot be set"),
    ("h4cm", {"work_offsets": {"EXT": [0, 0, 0]}}, "work_offsets.EXT cannot be set: the HUST"),
    ("gsk25i", {"tools": {300: {"length_mm": 1.0}}}, "tools.300.length_mm cannot be set in the GSK 25i"),
    ("gsk25i", {"tools": {3: {"length_wear_mm": 100.0}}}, "tools.3.length_wear_mm cannot be set in the GSK"),
    ("h4cm", {"tools": {41: {"radius_mm": 1.0}}}, "tools.41.radius_mm cannot be set in the HUST"),
])  # fmt: skip
def test_what_the_dialect_cannot_hold_is_one_line(dialect, setup, problem):
    with pytest.raises(ConfigError) as info:
        interpret("G00 X0\n", dialect=dialect, setup=setup)
    assert str(info.value).startswith(f"setup: {problem}") and "\n" not in str(info.value), str(info.value)
