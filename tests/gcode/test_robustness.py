"""Malformed input of any shape gives a ProgramError (never another exception, a hang or a NaN)."""

from __future__ import annotations

import numpy as np
from gcode_helpers import check_outcome, success_share, tally
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from cnc_gym.errors import ProgramError
from cnc_gym.gcode import interpret

# Characters G-code is made of, plus a few that are not.
ALPHABET = "GMXYZIJKRFPLNOST#[]/()=+-*.0123456789 ;%,ABCDHQ\nEIFWHILEGOTOSINQRTANDOR\t$é"
WORDS = st.sampled_from([
    "G00", "G01", "G02", "G03", "G04", "G17", "G18", "G19", "G20", "G21", "G90", "G91", "G92", "G52", "G53",
    "G54", "G55", "G10", "L2", "P1", "P0", "M30", "M03", "X", "Y", "Z", "I", "J", "K", "R", "F", "#1", "=",
    "[", "]", "SIN", "ATAN", "/", "(", ")", ";", "%", "-", ".", "0", "1", "2.5", "10", "-3", "N5", "\n",
])  # fmt: skip


@success_share(0.003)
@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.text(alphabet=ALPHABET, max_size=80))
def test_random_characters(text):
    check_outcome(text)


@success_share(0.03)
@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(WORDS, max_size=30).map(" ".join))
def test_random_word_soup(text):
    check_outcome(text)


# The machine-dependent paths: rotary axis B (gsk25i preset), G37 with a simulated instrument, G31 with a
# simulated probe, and the travel check.
MACHINE_WORDS = st.sampled_from([
    "G00", "G01", "G02", "G90", "G91", "G92", "G53", "G28", "G31", "G37", "G41", "G40", "G20", "G21", "H1",
    "D1", "B", "B45", "B-3.5", "X", "X10", "Y-5", "Z-2", "Z200", "F300", "F0", "R5", "M30", "\n", "\n",
])  # fmt: skip


@success_share(0.08)
@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(MACHINE_WORDS, max_size=30).map(" ".join), st.floats(-300, 300))
def test_random_machine_programs(text, signal):
    from cnc_gym.machine import load_machine

    check_outcome(text, machine=load_machine("gsk25i"), skip_signal={"X": signal},
           tool_measurement={"signal_at": {1: signal}, "decel_mm": 10.0, "band_mm": 5.0})  # fmt: skip


@success_share(0.06)
@settings(max_examples=200, deadline=None)
@given(
    st.sampled_from(["G17", "G18", "G19"]),
    st.sampled_from(["G02", "G03"]),
    st.lists(st.floats(-50, 50, allow_nan=False).map(lambda v: round(v, 3)), min_size=5, max_size=5),
    st.booleans(),
)
def test_random_arcs_are_consistent_or_rejected(plane, code, numbers, use_r):
    # Every accepted arc ends where its geometry says: center + radius at start_angle + sweep (in-plane).
    a, b, c, d, r = numbers
    words = {"G17": ("X", "Y", "I", "J"), "G18": ("Z", "X", "K", "I"), "G19": ("Y", "Z", "J", "K")}[plane]
    tail = f"R{r}" if use_r else f"{words[2]}{c} {words[3]}{d}"
    text = f"G00 X1 Y2 Z3\n{plane} {code} {words[0]}{a} {words[1]}{b} {tail} F100\n"
    try:
        tp = interpret(text)
    except ProgramError as err:
        assert err.code in {"arc-radius-mismatch", "arc-impossible", "arc-missing-center"}
        tally(False)
        return
    tally(True)
    if len(tp) < 2:
        return  # a 0° R arc: no motion
    point, _, _ = tp.evaluate(tp.s_start[2] - 1e-12)
    assert np.allclose(point[0], tp.end[1], atol=1e-6)


def test_a_runaway_transform_loop_ends_in_an_error_not_an_overflow():
    # Found by scripts/fuzz.py: G51 I2 re-applied in a loop doubles the machine X of a G19 arc every pass;
    # after some 1000 passes the coordinate was inf and math.floor raised OverflowError.
    text = ("G00 X-1 Z0\n#3=0\nWHILE[#3LT3000]DO1\nG51 X0 Y0 I2 J1 K1\n"
            "G19 G91 G03 Y-0.4461 Z-0.4946 J19.7558 K-18.2684 F100\nG90\nG50\n#3=#3+1\nEND1\n")  # fmt: skip
    try:
        interpret(text, file="p.nc")
    except ProgramError as err:
        assert (err.code, err.file, err.line) == ("value-out-of-range", "p.nc", 5) and "1e+09" in err.message
    else:
        raise AssertionError("the runaway loop ran to its end")
