"""Random and mutated DIN programs end only in the project's own errors: a ProgramError with one line and a
code, or a finite tool path — never another exception, a hang or a NaN (issue 16, point 10)."""

from __future__ import annotations

from gcode_helpers import check_outcome, success_share
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from cnc_gym.gcode import interpret

#: Characters DIN programs are made of, plus a few that are not.
ALPHABET = "GMXYZIJKRFPLNDTSH$%()[]=+-*/<>!.,0123456789 \nIFWHLEDOSINMODABC\té;#"
WORDS = st.sampled_from([
    "G0", "G1", "G2", "G3", "G4", "G17", "G18", "G20", "G21", "G23", "G36", "G41", "G40", "G53", "G54", "G60",
    "G63", "G70", "G71", "G74", "G90", "G91", "G92", "G98", "G99", "G161", "G162", "M3", "M5", "M29", "M30",
    "X", "Y", "Z", "I", "J", "F", "F100", "D1", "D0", "R1", "R2", "=", "==", ">=", "<", "P1", "[", "]",
    "SIN", "SQRT", "MOD", "**", "*", "/", "-", "+", ",", "0", "1", "2.5", "-3", "0.5", "100", "N5", "LL1",
    "L9", "%1", "%L1", "(", ")", "$IF", "$ELSE", "$ENDIF", "$WHILE", "$ENDWHILE", "$FOR", "$ENDFOR", "$DO",
    "$ENDDO", "$BREAK", "$CONTINUE", "$SWITCH", "$CASE", "$DEFAULT", "$ENDSWITCH", "$TIME", "TLOC", "\n",
])  # fmt: skip

#: A valid program to mutate: loops, a local call, arcs, offsets, TRO.
BASE = """%L1
G1 X R1 Y R2 F500
M29
%100
R1 = 0 R2 = 5
G0 X0 Y0 Z5 D1
$FOR R3 = 1, 3, 1
R1 = R1 + 10
LL1
$IF R3 MOD 2 == 1
G2 X R1 + 5 Y R2 I2.5 J0
$ELSE
G1 X R1 + 5
$ENDIF
$ENDFOR
G0 X-10 Y-10
G41 G1 X0 Y0
X10
G40 X20 Y-5
$TIME 0.5
M30
"""


def _check(text: str, **options) -> None:
    check_outcome(text, dialect="azmc1", max_blocks=20_000, **options)


def test_the_base_program_runs():
    tp = interpret(BASE, dialect="azmc1", tool_offsets={"D": {1: 1.0}})
    assert len(tp) > 10


@success_share(0.001)  # 4 % under CI's examples
@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.text(alphabet=ALPHABET, max_size=80))
def test_random_characters(text):
    _check(text)


@success_share(0.01)  # 7 % under CI's examples
@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(WORDS, max_size=30).map(" ".join))
def test_random_word_soup(text):
    _check(text)


@success_share(0.03)  # 13 % under CI's examples
@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.data())
def test_mutated_programs(data):
    # Delete, duplicate, swap or overwrite a few characters or lines of the valid base program.
    text = BASE
    for _ in range(data.draw(st.integers(1, 4))):
        lines = text.split("\n")
        kind = data.draw(st.sampled_from(["char", "insert", "drop-line", "dup-line", "swap-lines"]))
        if kind in ("char", "insert") and text:
            i = data.draw(st.integers(0, len(text) - 1))
            c = data.draw(st.sampled_from(ALPHABET))
            text = text[:i] + c + text[i + (1 if kind == "char" else 0):]
        elif kind == "drop-line":
            del lines[data.draw(st.integers(0, len(lines) - 1))]
            text = "\n".join(lines)
        elif kind == "dup-line":
            i = data.draw(st.integers(0, len(lines) - 1))
            lines.insert(i, lines[i])
            text = "\n".join(lines)
        else:
            i, j = data.draw(st.integers(0, len(lines) - 1)), data.draw(st.integers(0, len(lines) - 1))
            lines[i], lines[j] = lines[j], lines[i]
            text = "\n".join(lines)
    _check(text, tool_offsets={"D": {1: 1.0}})
