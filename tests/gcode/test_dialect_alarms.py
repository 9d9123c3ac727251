"""Alarm numbers are per dialect: the Fanuc family's checks name a condition, each dialect's table numbers
it (or not). The ``fanuc`` dialect never prints a GSK 25i number for a condition Fanuc numbers otherwise
or not at all; Syntec prints only its own (MAR-330..336); the error codes ``[code]`` are the same in all.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from cnc_gym.errors import ProgramError
from cnc_gym.gcode import get_dialect, interpret
from cnc_gym.machine import machine_from_dict

ROOT = Path(__file__).resolve().parents[2]
SMALL = machine_from_dict({"axis_defaults": {"min_position_mm": -100, "max_position_mm": 100}},
                          source="small.yaml")  # fmt: skip
NONE = None

# (program, code, GSK 25i alarm, fanuc alarm, options). GSK's are its alarm list's (docs/gsk25i_alarms.md);
# fanuc's are the Fanuc 0i-M PS/OT numbers of the same condition, None where Fanuc's list has none.
CASES = [
    # Stored stroke limit 1: GSK 500/501 "OVER TRAVEL:±n", Fanuc OT500/OT501.
    ("G00 X150.\n", "travel-limit", 500, 500, {"machine": SMALL}),
    ("G00 Y-150.\n", "travel-limit", 501, 501, {"machine": SMALL}),
    # A second decimal point: 7 ILLEGAL USE OF DECIMAL POINT in both.
    ("G00 X1.2.3\n", "bad-number", 7, 7, {}),
    # DO4: GSK 97 ILLEGAL CYCLE NUMBER, Fanuc 126 ILLEGAL LOOP NUMBER.
    ("WHILE[1LT2]DO4\nEND4\n", "do-end", 97, 126, {}),
    # G27 off the reference position: GSK 46, Fanuc 092 ZERO RETURN CHECK (G27) ERROR.
    ("G27 X10\n", "reference-check-failed", 46, 92, {}),
    # G30 P5: 46 ILLEGAL REFERENCE RETURN COMMAND in both.
    ("G30 P5 X0\n", "bad-reference", 46, 46, {}),
    # G29 with no intermediate point: GSK 46; Fanuc's list has no such alarm.
    ("G29 X0\n", "bad-reference", 46, NONE, {}),
    # G31 in cutter compensation: 36 in both (Fanuc CAN NOT COMMANDED G31).
    ("G41 D1 G01 X10 F100\nG31 X20\n", "g31-in-cutter-compensation", 36, 36,
     {"tool_offsets": {"D": {1: 1.0}}}),
    # G28 in canned-cycle mode: 44 in both; G10 there: GSK 61, no Fanuc number.
    ("G81 Z-10 R2 F100\nG28 X0\n", "cycle-not-allowed", 44, 44, {}),
    ("G81 X0 Y0 Z-5 R1 F10\nG10 L2 P1 X0\n", "cycle-not-allowed", 61, NONE, {}),
    # Rigid tapping above the gear's maximum speed: 200 in both (Fanuc ILLEGAL S CODE COMMAND); a cycle
    # without R and Z: GSK 61, no Fanuc number.
    ("M3 S500\nM29 S1200\nG84 Z-10 R-2 F100\n", "rigid-tap", 200, 200, {}),
    ("G81 X0 Y0 F100\n", "cycle-missing-data", 61, NONE, {}),
    # Offset values written: GSK 29 through #10001, 32 by G10; Fanuc 032 for both.
    ("#10001=100000\n", "bad-offset-value", 29, 32, {}),
    ("G10 L10 P1 R10000.\n", "bad-offset-value", 32, 32, {}),
    # #3000 = n: alarm 3000 + n in both.
    ("G00 X1\n#3000=1 (BOOM)\n", "user-alarm", 3001, 3001, {}),
]


def raised(text: str, dialect: str, options: dict) -> ProgramError:
    with pytest.raises(ProgramError) as err:
        interpret(text, dialect=dialect, **options)
    return err.value


@pytest.mark.parametrize(("text", "code", "gsk", "fanuc", "options"), CASES)
def test_each_dialect_prints_its_own_alarm_number(text, code, gsk, fanuc, options):
    for dialect, number in (("gsk25i", gsk), ("fanuc", fanuc)):
        err = raised(text, dialect, options)
        assert (err.code, err.alarm) == (code, number), (dialect, str(err))
        suffix = f" (controller alarm {number}) [{code}]" if number is not None else f" [{code}]"
        assert str(err).endswith(suffix)
        assert ("(controller alarm" in str(err)) == (number is not None)


@pytest.mark.parametrize(("text", "code", "options"), [(t, c, o) for t, c, _, _, o in CASES])
def test_syntec_prints_only_its_own_numbers(text, code, options):
    # The same conditions in Syntec (G41 needs its own setup; the rest read the same): none of them is in
    # Syntec's alarm list (MAR-330..336 only), so none carries a number. A few are not errors there.
    syntec = get_dialect("syntec")
    try:
        interpret(text, dialect="syntec", **options)
    except ProgramError as err:
        assert err.alarm is None or err.alarm in syntec.alarms.values(), str(err)


def test_the_family_names_conditions_never_numbers():
    # lang/<family>/ raises with a code and at most a condition name: a literal number there would be one
    # controller's number printed for every dialect of the family.
    literal = re.compile(r"alarm\s*=\s*\d")
    family = sorted((ROOT / "cnc_gym/gcode/lang").rglob("*.py"))
    offenders = [f"{path.relative_to(ROOT)}:{n}" for path in family
                 for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1)
                 if literal.search(line)]  # fmt: skip
    assert offenders == []


def test_every_condition_the_family_names_is_a_code_and_what():
    # A condition is "<code>/<what>"; every dialect's table keys are codes or such conditions, and every
    # condition GSK numbers is one the family really raises.
    named = set()
    for path in (ROOT / "cnc_gym/gcode").rglob("*.py"):
        named |= set(re.findall(r'"([a-z0-9-]+/[a-z0-9+-]+)"', path.read_text(encoding="utf-8")))
    named |= {"travel-limit/+", "travel-limit/-"}  # built from the side (gcode/__init__.py)
    for name in ("gsk25i", "fanuc", "syntec"):
        for key in get_dialect(name).alarms:
            assert "/" not in key or key in named, (name, key)
    gsk = get_dialect("gsk25i").alarms
    assert {k for k in named if k.split("/")[0] in {"bad-number", "do-end", "cycle-argument", "rigid-tap",
                                                     "cycle-not-allowed", "bad-reference", "bad-offset-value",
                                                     "travel-limit"}} <= set(gsk)  # fmt: skip


def test_a_dialect_without_a_number_for_a_condition_falls_back_to_none_not_the_codes():
    fanuc = get_dialect("fanuc")
    assert fanuc.alarm("cycle-not-allowed") == 44
    assert fanuc.alarm("cycle-not-allowed", "cycle-not-allowed/other") is None
    assert fanuc.alarm("bad-reference", "bad-reference/no-intermediate") is None
    assert get_dialect("gsk25i").alarm("bad-reference", "bad-reference/no-intermediate") == 46
