"""Subprograms: M98 / M99, programs in the file and in the program folder, nesting (§1.3,
manual §1.3.1, §4.1.2). Expected paths are worked out by hand in each test.

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import pytest
from gcode_helpers import moves, program_error

from cnc_gym.errors import ConfigError, ProgramError
from cnc_gym.gcode import interpret, interpret_file


def ends(text: str, **kw) -> list[tuple[float, ...]]:
    return [tuple(round(v, 6) for v in r["end"]) for r in moves(text, **kw)]


SUB_STEP = "O1002\nG91 G01 X1 F100\nG90\nM99\n"  # one call = +1 in X


def test_p_count_prefix_calls_five_times():
    # §1.3.1: M98 P51002 calls O1002 five times: X1 … X5.
    assert [e[0] for e in ends("M98 P51002\nM30\n" + SUB_STEP)] == [1.0, 2.0, 3.0, 4.0, 5.0]


def test_p_and_l_form_and_l0():
    # M98 P1002 L3 (§3.2.18 "P2200L7"): three times; L0 is no call; P without a count is once.
    assert len(ends("M98 P1002 L3\nM30\n" + SUB_STEP)) == 3
    assert ends("M98 P1002 L0\nG00 Y1\nM30\n" + SUB_STEP) == [(0.0, 1.0, 0.0)]
    assert len(ends("M98 P1002\nM30\n" + SUB_STEP)) == 1


def test_move_in_the_m98_block_runs_before_the_call():
    # §3.7.6: G01 X100.0 M98 Pp moves first, then calls. The subprogram's G91 X1 then starts at X10.
    assert ends("G01 X10 F100 M98 P1002\nM30\n" + SUB_STEP) == [(10.0, 0.0, 0.0), (11.0, 0.0, 0.0)]


def test_m99_returns_to_the_block_after_the_call():
    text = "M98 P1002\nG00 Y5\nM30\n" + SUB_STEP
    assert ends(text) == [(1.0, 0.0, 0.0), (1.0, 5.0, 0.0)]


def test_m99_p_returns_to_sequence_number_in_the_caller():
    # M99 P30 skips the caller's N20 block (inferred from §1.3 and the Fanuc convention).
    text = "M98 P7\nN20 G00 Y20\nN30 G00 Z30\nM30\nO7\nG00 X7\nM99 P30\n"
    assert ends(text) == [(7.0, 0.0, 0.0), (7.0, 0.0, 30.0)]


def test_m99_p_to_a_missing_sequence_number_is_alarm_60():
    err = program_error("M98 P7\nM30\nO7\nM99 P55\n")
    assert (err.code, err.alarm) == ("sequence-not-found", 60)


def test_subprograms_share_the_callers_locals():
    # M98 does not open a local level (§3.7.7): the subprogram reads and changes the caller's #1.
    text = "#1=3\nM98 P8\nG00 Y#1\nM30\nO8\nG00 X#1\n#1=4\nM99\n"
    assert ends(text) == [(3.0, 0.0, 0.0), (3.0, 4.0, 0.0)]


def test_subprogram_that_ends_without_m99_returns():
    # The text of O8 ends at the next O block: treated as M99 (docs/gcode.md).
    text = "M98 P8\nG00 Y1\nM30\nO8\nG00 X1\nO9\nG00 Z9\nM99\n"
    assert ends(text) == [(1.0, 0.0, 0.0), (1.0, 1.0, 0.0)]


def test_main_program_stops_at_the_next_o_block():
    # The main program's text ends where the next program starts: O9 is never run on its own.
    assert ends("G00 X1\nO9\nG00 Z9\nM99\n") == [(1.0, 0.0, 0.0)]


def test_nesting_four_levels_runs_and_five_is_alarm_77():
    # Main → O1 → O2 → O3 → O4 is four levels (§1.3): fine. One more is alarm 77.
    links = "".join(f"O{i}\nG91 G00 X1\nM98 P{i + 1}\nM99\n" for i in range(1, 4))
    chain = "M98 P1\nM30\n" + links + "O4\nG00 X1\nM99\n"
    assert [e[0] for e in ends(chain)] == [1.0, 2.0, 3.0, 4.0]
    deeper = chain.replace("O4\nG00 X1\nM99\n", "O4\nM98 P5\nM99\nO5\nG00 X1\nM99\n")
    err = program_error(deeper)
    assert (err.code, err.alarm) == ("nesting", 77)


def test_recursion_is_bounded_by_the_nesting_limit():
    err = program_error("M98 P1\nM30\nO1\nM98 P1\nM99\n")
    assert err.alarm == 77


@pytest.mark.parametrize(
    ("text", "code", "alarm"),
    [
        ("M98 P4321\n", "program-not-found", 59),
        ("M98\n", "missing-program-number", 76),
        ("M98 P51002 L2\nO1002\nM99\n", "bad-call", 17),  # count twice
        ("M98 P10001002\nO1002\nM99\n", "bad-call", 17),  # 1000 repeats > 999 (§1.3)
        ("M98 P0\n", "bad-call", 17),
        ("M98 P1002 L10000\nO1002\nM99\n", "value-out-of-range", 8),  # L beyond 9999
        ("O1\nM99\nO1\nM99\n", "duplicate-program", 73),
    ],
)  # fmt: skip
def test_call_errors(text, code, alarm):
    err = program_error(text)
    assert (err.code, err.alarm) == (code, alarm)


def test_m99_in_the_main_program_ends_by_default_and_restarts_on_request():
    # §1.3.1: M99 at the end of a main program restarts it. By default one pass (one part) ends the run;
    # main_m99="restart" loops, and a macro counter (#500 kept across passes) exits to M30 after 3 passes.
    text = "#500=#500+1\nG91 G01 X1 F100\nIF[#500GE3]GOTO9\nM99\nN9 M30\n"
    assert [e[0] for e in ends(text)] == [1.0]
    assert [e[0] for e in ends(text, main_m99="restart")] == [1.0, 2.0, 3.0]
    # M99 P n in the main program jumps to N n of the main program.
    text_p = "#500=#500+1\nN5 G91 G01 X1 F100\n#501=#501+1\nIF[#501GE2]GOTO9\nM99 P5\nN9 M30\n"
    assert [e[0] for e in ends(text_p, main_m99="restart")] == [1.0, 2.0]
    assert program_error("M99\n", main_m99="restart", max_blocks=100).code == "too-many-blocks"
    with pytest.raises(ConfigError):
        interpret("M99\n", main_m99="loop")


def test_block_skip_applies_to_m99():
    # §1.3.3: /M99 is skipped like any other block when the switch is on: the subprogram runs on to its end.
    text = "M98 P7\nM30\nO7\n/M99\nG00 X5\nM99\n"
    assert ends(text) == []
    assert ends(text, block_skip={1}) == [(5.0, 0.0, 0.0)]


# --------------------------------------------------------------------------- program files
def test_subprogram_files_in_the_program_folder(tmp_path):
    # O1002 in "O1002.nc", O7 in "7.nc" (no O line at all), O0033 in "O0033": all found next to the main file.
    (tmp_path / "O1002.nc").write_text("%\nO1002\nG91 G01 X1 F100\nG90\nM99\n%\n")
    (tmp_path / "7.nc").write_text("G00 Y7\nM99\n")
    (tmp_path / "O0033").write_text("O0033\nG00 Z3\nM99\n")
    main = tmp_path / "main.nc"
    main.write_text("O0001\nM98 P21002\nM98 P7\nM98 P33\nM30\n")
    tp = interpret_file(main)
    assert [tuple(e) for e in tp.end.tolist()] == [(1, 0, 0), (2, 0, 0), (2, 7, 0), (2, 7, 3)]
    # Each segment names its own file and line (the trace contract): O1002 line 3, 7.nc line 1, O0033 line 2.
    sources = [tp.source(i) for i in range(len(tp))]
    assert sources == [(str(tmp_path / "O1002.nc"), 3)] * 2 + [(str(tmp_path / "7.nc"), 1),
                                                               (str(tmp_path / "O0033"), 2)]  # fmt: skip
    assert tp.files[0] == str(main)
    records = tp.to_records()
    assert all("file" in r for r in records)


def test_program_dir_option_and_errors_name_the_subprogram_file(tmp_path):
    folder = tmp_path / "programs"
    folder.mkdir()
    (folder / "O0005.nc").write_text("O0005\nG00 X1\nG01 X2\nM99\n")
    err = program_error("M98 P5\nM30\n", program_dir=folder)  # G01 without F inside O0005
    assert err.file == str(folder / "O0005.nc") and err.line == 3 and err.code == "missing-feed"
    # Not there: alarm 59 naming the folder.
    err = program_error("M98 P6\n", program_dir=folder)
    assert err.alarm == 59 and str(folder) in err.message


def test_a_file_holding_other_programs_only_is_not_the_one_called(tmp_path):
    (tmp_path / "O0005.nc").write_text("O0006\nG00 X1\nM99\n")
    err = program_error("M98 P5\n", program_dir=tmp_path)
    assert err.alarm == 59


def test_programs_in_the_same_file_win_over_the_folder(tmp_path):
    (tmp_path / "O0005.nc").write_text("O0005\nG00 X99\nM99\n")
    assert ends("M98 P5\nM30\nO5\nG00 X1\nM99\n", program_dir=tmp_path) == [(1.0, 0.0, 0.0)]


def test_trace_command_finds_subprograms_and_names_their_file(tmp_path, capsys):
    import json

    from cnc_gym.cli import main

    folder = tmp_path / "subs"
    folder.mkdir()
    (folder / "O0008.nc").write_text("O0008\nG00 X8\nM99\n")
    program = tmp_path / "main.nc"
    program.write_text("G00 Y1\nM98 P8\nM30\n")
    assert main(["trace", str(program), "--program-dir", str(folder)]) == 0
    records = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    # The main file's segment has no "file"; the subprogram's names O0008.nc and its line 2.
    assert "file" not in records[0]
    assert (records[1]["file"], records[1]["line"]) == (str(folder / "O0008.nc"), 2)
    # Without --program-dir the subprogram is looked for next to main.nc: alarm 59, exit status 2.
    assert main(["trace", str(program)]) == 2
    assert "O0008 not found" in capsys.readouterr().err


def test_unreadable_subprogram_file_is_a_program_error(tmp_path, monkeypatch):
    from cnc_gym.gcode.lang.fanuc import flow

    (tmp_path / "O0005.nc").write_text("O0005\nM99\n")

    def refuse(path, **_):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(flow, "read_regular_file", refuse)
    err = program_error("M98 P5\n", program_dir=tmp_path)
    assert err.alarm == 59 and "cannot read" in err.message and "Permission denied" in err.message


# --------------------------------------------------------------------------- links out of the folder
def _outside(tmp_path):
    """A main program in ``tmp_path/job`` and O0005 in ``tmp_path/elsewhere``."""
    job, elsewhere = tmp_path / "job", tmp_path / "elsewhere"
    job.mkdir()
    elsewhere.mkdir()
    (elsewhere / "O0005.nc").write_text("O0005\nG00 X5\nM99\n")
    main = job / "main.nc"
    main.write_text("M98 P5\nM30\n")
    return job, elsewhere, main


@pytest.mark.parametrize("link", ["absolute", "dotdot"])
def test_a_called_program_may_not_lead_out_of_the_folder_through_a_link(tmp_path, link):
    job, elsewhere, main = _outside(tmp_path)
    target = elsewhere / "O0005.nc" if link == "absolute" else "../elsewhere/O0005.nc"
    (job / "O0005.nc").symlink_to(target)
    with pytest.raises(ProgramError) as info:
        interpret_file(main)
    err = info.value
    assert (err.code, err.alarm, err.file, err.line) == ("program-not-found", 59, str(main), 1)
    assert "leads out of the folder" in err.message and str(elsewhere / "O0005.nc") in err.message
    # The user may allow it.
    assert interpret_file(main, follow_links=True).end.tolist() == [[5.0, 0.0, 0.0]]


def test_a_link_inside_the_folder_and_a_folder_reached_through_a_link_are_fine(tmp_path):
    job, elsewhere, main = _outside(tmp_path)
    (job / "O0006.nc").write_text("O0006\nG00 Y6\nM99\n")
    (job / "O0005.nc").symlink_to(job / "O0006.nc")  # O0005 is O0006's text: the file holds no O0005
    main.write_text("M98 P6\nM30\n")
    assert interpret_file(main).end.tolist() == [[0.0, 6.0, 0.0]]
    linked = tmp_path / "linked"
    linked.symlink_to(elsewhere)  # the whole folder through a link: its files are inside it
    assert ends("M98 P5\nM30\n", program_dir=linked) == [(5.0, 0.0, 0.0)]


def test_program_dir_is_the_boundary_too_and_trace_has_the_option(tmp_path, capsys):
    from cnc_gym.cli import main as cli

    _, elsewhere, main = _outside(tmp_path)
    subs = tmp_path / "subs"
    subs.mkdir()
    (subs / "O0005.nc").symlink_to(elsewhere / "O0005.nc")
    err = program_error("M98 P5\n", program_dir=subs)
    assert err.code == "program-not-found" and "leads out of the folder" in err.message
    assert cli(["trace", str(main), "--program-dir", str(subs)]) == 2
    out = capsys.readouterr()
    assert out.out == "" and out.err.count("\n") == 1 and "--follow-links" in out.err
    assert cli(["trace", str(main), "--program-dir", str(subs), "--follow-links"]) == 0


def test_the_din_family_takes_the_same_rule(tmp_path):
    job, elsewhere = tmp_path / "job", tmp_path / "elsewhere"
    job.mkdir()
    elsewhere.mkdir()
    (elsewhere / "100").write_text("%100\nN1 G1 X5 F100\nN9 M29\n")
    (job / "100").symlink_to(elsewhere / "100")
    main = job / "333"
    main.write_text("%333\nN100 G0 X0\nN200 L100\nN300 M30\n")
    with pytest.raises(ProgramError) as info:
        interpret(main.read_text(), dialect="azmc1", file=str(main))
    assert info.value.code == "program-not-found" and "leads out of the folder" in info.value.message
    tp = interpret(main.read_text(), dialect="azmc1", file=str(main), follow_links=True)
    assert tp.end.tolist()[-1] == [5.0, 0.0, 0.0]
