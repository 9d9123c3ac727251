"""The Syntec alarm index stays complete and true: docs/syntec_alarms.md (the manual's error conditions,
A1-A28). These tests fail when a row is missing, doubled or out of order, when a test a row names disappears
or is renamed, when a code in "Our code" is raised nowhere in cnc_gym/gcode, when a row's codes and alarms
differ from its minimal programs (``CASES`` of test_syntec_alarms.py), or when the counts under the table no
longer add up. The examples index (docs/syntec_examples.md) is checked with every dialect's in
tests/gcode/test_dialect_example_indexes.py.
"""

from __future__ import annotations

import functools
import re

import pytest
from doc_tables import (
    NODE,
    ROOT,
    alarm_kind,
    check_ids,
    check_nodes,
    minimal_cases,
    parse_table,
)

ALARMS_DOC = ROOT / "docs" / "syntec_alarms.md"
ALARMS_TESTS = "tests/gcode/syntec/test_syntec_alarms.py"
ALARMS = [f"A{n}" for n in range(1, 29)]
ERROR_CODE = re.compile(r"`([a-z0-9]+(?:-[a-z0-9]+)*)`")
NONE = "—"


@functools.cache
def alarm_rows() -> list[dict[str, str]]:
    header, table = parse_table(ALARMS_DOC.read_text(encoding="utf-8"))
    assert header == ["#", "Condition", "Manual section", "Syntec alarm", "Our code", "Our alarm", "Status",
                      "Note"]  # fmt: skip
    return table


@functools.cache
def cases() -> dict[str, list[tuple[str, int | None]]]:
    """``CASES`` of the alarms tests, parsed: row → [(code, alarm)]."""
    return minimal_cases(ALARMS_TESTS)


# ---------------------------------------------------------------------- the alarms index
def test_every_condition_has_exactly_one_row_in_order():
    check_ids([row["#"] for row in alarm_rows()], ALARMS)


@pytest.mark.parametrize("row_id", ALARMS)
def test_alarm_rows_are_well_formed(row_id):
    row = next(r for r in alarm_rows() if r["#"] == row_id)
    kind = alarm_kind(row["Status"])
    check_nodes(row["Status"], row_id)
    assert row["Condition"] and row["Manual section"].startswith("§") and row["Syntec alarm"], row
    codes = set() if row["Our code"] == NONE else set(ERROR_CODE.findall(row["Our code"]))
    if kind == "not applicable":
        assert not codes and row["Our alarm"] == NONE, row_id
    alarm = row["Syntec alarm"]
    if alarm.startswith("MAR-"):
        assert row["Our alarm"] == alarm[4:], row_id  # the number is carried as given
    else:
        assert row["Our alarm"] == NONE, row_id  # Syntec numbers nothing else


@pytest.mark.parametrize("row_id", ALARMS)
def test_our_codes_are_raised_by_the_interpreter(row_id):
    row = next(r for r in alarm_rows() if r["#"] == row_id)
    files = sorted((ROOT / "cnc_gym" / "gcode").rglob("*.py"))
    source = "\n".join(p.read_text(encoding="utf-8") for p in files)
    for code in ERROR_CODE.findall(row["Our code"]):
        assert f'"{code}"' in source, f"{row_id}: no code {code!r} in cnc_gym/gcode"


def test_rows_with_minimal_programs_match_them():
    citing = {row["#"] for row in alarm_rows()
              if (ALARMS_TESTS, "test_manual_alarm") in NODE.findall(row["Status"])}
    assert citing == set(cases())
    for row in alarm_rows():
        if row["#"] not in cases():
            continue
        codes = set(ERROR_CODE.findall(row["Our code"]))
        alarms = set() if row["Our alarm"] == NONE else {int(row["Our alarm"])}
        assert codes == {code for code, _ in cases()[row["#"]]}, row["#"]
        assert alarms == {alarm for _, alarm in cases()[row["#"]] if alarm is not None}, row["#"]


def test_alarm_counts_add_up():
    text = ALARMS_DOC.read_text(encoding="utf-8")
    for kind in ("tested", "deviation", "not applicable"):
        count = sum(alarm_kind(row["Status"]) == kind for row in alarm_rows())
        assert f"| {kind} | {count} |" in text, (kind, count)
