"""Error lines are safe to print: one line, control characters escaped, a bounded excerpt of the text."""

from __future__ import annotations

from pathlib import Path

import pytest

from cnc_gym.cli import main
from cnc_gym.errors import MAX_LINE_CHARS, MAX_MESSAGE_CHARS, ConfigError, ProgramError, printable
from cnc_gym.gcode import interpret

ESC = "\x1b"


def test_printable_escapes_controls_and_collapses_whitespace():
    assert printable(f"a{ESC}[2Jb") == "a\\x1b[2Jb"
    assert printable("bell\x07 del\x7f c1\x9b") == "bell\\x07 del\\x7f c1\\x9b"
    assert printable("right\u202eto left, zero\u200bwidth") == "right\\u202eto left, zero\\u200bwidth"
    assert printable("one\nline\r\n\tonly") == "one line only"
    assert printable("Maß X1.5 (ok)") == "Maß X1.5 (ok)"  # printable text is left alone
    assert printable(printable(f"{ESC}x")) == printable(f"{ESC}x")  # idempotent


def test_printable_cuts_long_text_and_says_how_much_was_left_out():
    text = "X" + "1" * 10_000_000
    out = printable(text)
    assert len(out) == MAX_MESSAGE_CHARS and out.startswith("X111")
    assert out.endswith("1… (10000001 characters in all)")
    assert printable("a" * 50, limit=30) == "aaaaaa… (50 characters in all)"


def test_program_error_line_is_bounded_and_keeps_its_code():
    err = ProgramError("bad number X" + "9" * 5_000_000, code="bad-number", file="p\x1b.nc", line=7, alarm=7)
    line = str(err)
    assert line.startswith("p\\x1b.nc:7: bad number X999")
    assert line.endswith("(controller alarm 7) [bad-number]")
    assert len(line) < 700 and "\n" not in line
    assert str(ConfigError(f"machine.yaml: key {ESC}]0;title{ESC}\\")).count(ESC) == 0


def test_a_10_mb_word_gives_a_short_error_line():
    with pytest.raises(ProgramError) as info:
        interpret("G01 X" + "1" * 10_000_000 + " F100\n")
    assert info.value.code == "word-too-long" and len(str(info.value)) <= 700


def test_user_alarm_message_cannot_drive_the_terminal(tmp_path: Path, capsys):
    # #3000's message is the block's comment: an escape sequence there must reach stderr escaped.
    program = tmp_path / "alarm.nc"
    program.write_text(f"#3000=1 ({ESC}[2J{ESC}[H)\n")
    assert main(["trace", str(program)]) == 2
    out, err = capsys.readouterr()
    assert out == "" and ESC not in err and err.count("\n") == 1
    assert err.strip().endswith("[user-alarm]") and "\\x1b[2J" in err
    assert len(err) <= MAX_LINE_CHARS
