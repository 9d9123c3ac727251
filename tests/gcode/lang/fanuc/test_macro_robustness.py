"""Random and mutated macro programs give a ProgramError or a finite tool path: never another exception,
never a hang (the ``max_blocks`` bound), never a NaN."""

from __future__ import annotations

from gcode_helpers import check_outcome, success_share
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

MAX_BLOCKS = 3000

VARIABLE = st.sampled_from(["#1", "#2", "#3", "#24", "#100", "#101", "#500", "#0", "#[#1]", "#[#2+1]",
                            "#5001", "#4001", "#3001", "#2001", "#11001", "#2501", "#3004"])  # fmt: skip
NUMBER = st.sampled_from(["0", "1", "2", "-1", "3.5", "10", "0.1", "1000000", "1E5", "360"])
FUNCTION = st.sampled_from(["SIN", "COS", "TAN", "ATAN", "SQRT", "ABS", "ROUND", "FIX", "FUP", "BIN", "BCD",
                            "LN"])  # fmt: skip
OPERATOR = st.sampled_from(["+", "-", "*", "/", "MOD", "AND", "OR", "XOR"])
COMPARE = st.sampled_from(["EQ", "NE", "GT", "GE", "LT", "LE"])


def expression(depth: int = 2):
    atom = st.one_of(VARIABLE, NUMBER)
    if depth == 0:
        return atom
    inner = expression(depth - 1)
    return st.one_of(
        atom,
        st.tuples(inner, OPERATOR, inner).map(lambda t: f"{t[0]}{t[1]}{t[2]}"),
        st.tuples(FUNCTION, inner).map(lambda t: f"{t[0]}[{t[1]}]"),
        inner.map(lambda e: f"[{e}]"),
    )


CONDITION = st.tuples(expression(1), COMPARE, expression(1)).map(lambda t: f"[{t[0]}{t[1]}{t[2]}]")
SEQUENCE = st.sampled_from(["1", "2", "3", "10", "#1", "[#2+1]"])
LOOP = st.sampled_from(["1", "2", "3"])
STATEMENT = st.one_of(
    st.tuples(VARIABLE, expression()).map(lambda t: f"{t[0]}={t[1]}"),
    st.tuples(CONDITION, SEQUENCE).map(lambda t: f"IF{t[0]}GOTO{t[1]}"),
    st.tuples(CONDITION, VARIABLE, expression(1)).map(lambda t: f"IF{t[0]}THEN{t[1]}={t[2]}"),
    SEQUENCE.map(lambda n: f"GOTO{n}"),
    st.tuples(CONDITION, LOOP).map(lambda t: f"WHILE{t[0]}DO{t[1]}"),
    LOOP.map(lambda m: f"DO{m}"),
    LOOP.map(lambda m: f"END{m}"),
    st.tuples(expression(1), expression(1)).map(lambda t: f"G01 X[{t[0]}] Y[{t[1]}] F100"),
    st.tuples(expression(1)).map(lambda t: f"G91 G00 X[{t[0]}]"),
    st.sampled_from(["M98 P1", "M98 P21", "M98 P1 L2", "G65 P2 A1 I2 J3 I4", "G65 P2 L2 X#1", "G66 P2 R1",
                     "G67", "M99", "M99 P2", "G90", "G91", "M30", "G02 X1 R1 F100", "G04 P10", "#3000=1"]),
)  # fmt: skip
LINE = st.tuples(st.sampled_from(["", "", "N1 ", "N2 ", "N3 ", "N10 "]), STATEMENT).map("".join)


@success_share(0.05)
@settings(max_examples=250, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(LINE, max_size=14), st.lists(LINE, max_size=6), st.lists(LINE, max_size=6))
def test_random_macro_programs(main, sub, macro):
    text = "\n".join(main) + "\nM30\nO1\n" + "\n".join(sub) + "\nM99\nO2\n" + "\n".join(macro) + "\nM99\n"
    check_outcome(text, max_blocks=MAX_BLOCKS)


SEEDS = [
    "#1=0\nWHILE[#1LT3]DO1\nG01 X#1 F100\n#1=#1+1\nEND1\nM98 P5\nG65 P6 A1 I2 I3\nM30\n"
    "O5\nG91 G01 Y1\nG90\nM99\nO6\nIF[#1EQ#0]GOTO9\nG00 Z#4\nN9 M99\n",
    "G66 P7 R-2 Z-1\nG91 G00 X10\nY10\nG67\nM30\nO7\nG00 Z#18\nG01 Z#26 F50\nG00 Z-[#18+#26]\nM99\n",
    "#100=0\nN1 #100=#100+1\nIF[#100LT4]GOTO1\nDO2\nIF[#100GT6]GOTO5\n#100=#100+1\nEND2\nN5 G00 X#100\n",
]


FRAGMENT = st.sampled_from(["", "#", "[", "]", "1", "0", "D", "O", "N", "GOTO", "END", "DO", "\n", "-", "P",
                            "L", "=", "M99", "G65"])  # fmt: skip


# Most mutations break a macro program (2 to 4 % of 300 ran to a tool path over six fresh seeds, and one
# fresh seed gave 2): the floor asks for one, which still catches a regression that rejects them all.
@success_share(0.003)
@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.sampled_from(SEEDS), st.lists(st.tuples(st.integers(0, 10_000), FRAGMENT), min_size=1, max_size=6))
def test_mutated_macro_programs(seed, edits):
    text = seed
    for position, insert in edits:
        i = position % (len(text) + 1)
        # Replace one character (or insert at the end) with the fragment.
        text = text[:i] + insert + text[i + 1 :]
    check_outcome(text, max_blocks=MAX_BLOCKS)
