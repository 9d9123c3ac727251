"""Random and mutated H4C-M programs end only in the project's own errors: a ProgramError with one line and
a code, or a finite tool path — never another exception, never a hang (the ``max_blocks`` bound), never a
NaN. The words are the H4C-M's: integer words in least increments, U/V/W, G65 instructions with string
labels, G10 forms, grooves, hole patterns, mirror toggles, subprograms."""

from __future__ import annotations

from gcode_helpers import check_outcome, success_share
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

MAX_BLOCKS = 3000
OFFSETS = {"D": {1: 2.0, 2: 1.0}}
NUMBER = st.sampled_from(["0", "1", "-1", "2500", "10.", "-7.5", "0.001", "100", "9999.999", "45."])
AXIS = st.tuples(st.sampled_from("XYZUVW"), NUMBER).map("".join)
VAR = st.sampled_from(["#1", "#2", "#3", "#10", "#9999", "-#1", "#1", "#2", "#0"])
RESULT = st.sampled_from(["#1", "#2", "#3", "#10", "#1", "#2", "#3", "#10", "#10000", "5"])
OPERAND = st.one_of(VAR, st.sampled_from(["0", "1", "-1", "2500", "100", "45", "-7", "3.5"]))
LABEL = st.sampled_from(["1", "01", "10", "010", "99"])
G65 = st.one_of(
    st.tuples(st.sampled_from([1, 2, 3, 4, 5, 6, 7, 11, 12, 13, 14, 15, 16, 17, 21, 22, 23, 26, 31, 32, 34,
                               50, 51, 56, 60, 66, 8]), RESULT, OPERAND, OPERAND)
    .map(lambda t: f"G65 L{t[0]:02d} P{t[1]} A{t[2]} B{t[3]}"),
    st.tuples(st.sampled_from([1, 1, 22, 50, 56]), RESULT, OPERAND)
    .map(lambda t: f"G65 L{t[0]} P{t[1]} A{t[2]}"),
    st.tuples(st.sampled_from(range(81, 87)), LABEL, OPERAND, OPERAND)
    .map(lambda t: f"G65 L{t[0]} P{t[1]} A{t[2]} B{t[3]}"),
    st.tuples(LABEL).map(lambda t: f"G65 L80 P{t[0]}"),
    st.sampled_from(["G65 L99 P3", "G65 L99 P77"]),
)  # fmt: skip
MOTION = st.tuples(st.sampled_from(["", "G00 ", "G01 ", "G02 ", "G03 ", "G00 G01 ", "G91 G01 "]),
                   st.lists(AXIS, max_size=3),
                   st.sampled_from(["", " F100", " F#3", " R10.", " I5.", " J-3."]))  # fmt: skip
STATEMENT = st.one_of(
    MOTION.map(lambda t: t[0] + " ".join(t[1]) + t[2]),
    G65,
    st.sampled_from([
        "G90", "G91", "G04 X1.", "G04 X1", "G28", "G28 X0", "G29", "G30 Z0", "G68", "G69", "G51 I2. J2.",
        "G50",
        "G41 D1 X1.", "G42 D2 Y1.", "G40", "G40 X0 Y0", "G10 X0 Y0", "G10 Z1. P101", "G10 W0.1 P102",
        "G10 K0.1 P103", "G10 P200 L2", "G10 P201", "G10 P800 L30", "G10 P2002",
        "G81 X1. Y1. Z-5. R1. F100", "G81 Z-5. R1. K0 F100", "G83 X2. Z-9. R1. Q2. F100", "G86 X3. Z-2. R1.",
        "G80", "G34 X0 Y0 I10. J0 K4", "G35 X0 Y0 I5. J30. K3", "G36 X0 Y0 I5. J0 P30. K3",
        "G37 X0 Y0 I2. P3 J2. K2", "G22 X0 Y0 Z-1. R1. I5. J0 F100", "G23 X0 Y0 Z-1. R1. I5. J0 K3. T1 F100",
        "G24 X0 Y0 Z-1. R1. I6. J4. D1. T1 F100", "G25 X0 Y0 Z-1. R1. K4. D1. T1 F100", "G01 U#1 V#2 F#3",
        "M98 P5", "M98 P5 L2", "M98 P6", "M99", "M02", "M03 S1000", "M05", "G17", "G18", "G19", "G20", "G21",
        "G43 H1", "G49", "G08", "G84 X0", "G99", "G54", "G55 X0 Y0",
    ]),
)  # fmt: skip
LINE = st.tuples(st.sampled_from(["", "", "N1 ", "N01 ", "N10 ", "N010 ", "N99 "]), STATEMENT).map("".join)


@success_share(0.08)  # 26 % under CI's examples
@settings(max_examples=250, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(LINE, max_size=14), st.lists(LINE, max_size=5), st.lists(LINE, max_size=5),
       st.sampled_from(["end", "restart"]))  # fmt: skip
def test_random_h4cm_programs(main, five, six, m99):
    text = "\n".join(main) + "\nM02\nO5\n" + "\n".join(five) + "\nM99\nO6\n" + "\n".join(six) + "\nM99\n"
    check_outcome(text, dialect="h4cm", max_blocks=MAX_BLOCKS, tool_offsets=OFFSETS, main_m99=m99)


SEEDS = [
    "O001\nN001 G65 L01 P#1 A150\nN002 G65 L85 P005 A#1 B100\nG01 X1. F100\nM02\nN005 G01 U#1 V2500\n"
    "G02 X10. Y10. R10.\nG01 Y20.\nM02\n",
    "G91\nG01 Z-2.5 F150.\nG17 F300.\nG41 D1 Y30.\nY100.\nX30. Y40.\nG02 X100. I50.\nG01 X30. Y-40.\nG40\n",
    "G81 Z-100. R-50. K0 F100\nG34 X100. Y100. I50. J45. K4\nG80\nG68\nM98 P5\nG69\nM02\nO5\nG00 X10. Y5.\n"
    "G24 X0 Y0 Z-1. R1. I5. J5. D1. T1 F100\nM99\n",
    "G10 P200 L3\nG65 L01 P#2 A0\nN1 G65 L02 P#2 A#2 B1\nG65 L84 P1 A#2 B5\nG51 I2. J2.\nG01 X4. F100\nG50\n"
    "G28\nG29\nM99\n",
]
FRAGMENT = st.sampled_from(["", "#", "1", "0", "N", "P", "L", "G", "U", "-", ".", "\n", "G65", "M99", "R",
                            "A#", "B", " ", "G02", "0010"])  # fmt: skip


@success_share(0.005)  # 1-3 % under CI's examples (the derandomized draws shift with the suite around them)
@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.sampled_from(SEEDS), st.lists(st.tuples(st.integers(0, 10_000), FRAGMENT), min_size=1, max_size=6),
       st.sampled_from(["end", "restart"]))  # fmt: skip
def test_mutated_h4cm_programs(seed, edits, m99):
    text = seed
    for position, insert in edits:
        i = position % (len(text) + 1)
        text = text[:i] + insert + text[i + 1 :]
    check_outcome(text, dialect="h4cm", max_blocks=MAX_BLOCKS, tool_offsets=OFFSETS, main_m99=m99)
