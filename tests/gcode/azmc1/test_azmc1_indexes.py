"""The AZ-MC1 alarm index stays complete and true: docs/azmc1_alarms.md (the manual's error conditions,
A1-A22). These tests fail when a row is missing, doubled or out of order, when a test a row names disappears
or is renamed, when a code in "Our code" is raised nowhere in cnc_gym/gcode, when a row's codes and alarms
differ from its minimal programs (``CASES`` of test_azmc1_alarms.py), or when the counts under the table no
longer add up. The examples index (docs/azmc1_examples.md) is checked with every dialect's in
tests/gcode/test_dialect_example_indexes.py.
"""

from __future__ import annotations

import functools

import pytest
from doc_tables import (
    ERROR_CODE,
    NODE,
    NONE,
    ROOT,
    alarm_kind,
    check_ids,
    check_nodes,
    minimal_cases,
    parse_table,
    raised_codes_missing,
)

ALARMS_DOC = ROOT / "docs" / "azmc1_alarms.md"
ALARMS_TESTS = "tests/gcode/azmc1/test_azmc1_alarms.py"
ALARMS = [f"A{n}" for n in range(1, 23)]


@functools.cache
def alarm_rows() -> list[dict[str, str]]:
    header, table = parse_table(ALARMS_DOC.read_text(encoding="utf-8"))
    assert header == ["#", "Condition", "Manual section", "AZ-MC1 alarm", "Our code", "Our alarm", "Status",
                      "Note"]  # fmt: skip
    return table


# ---------------------------------------------------------------------- the alarms index
def test_every_condition_has_exactly_one_row_in_order():
    check_ids([row["#"] for row in alarm_rows()], ALARMS)


@pytest.mark.parametrize("row_id", ALARMS)
def test_alarm_rows_are_well_formed_and_their_codes_are_raised(row_id):
    row = next(r for r in alarm_rows() if r["#"] == row_id)
    kind = alarm_kind(row["Status"])
    check_nodes(row["Status"], row_id)
    assert row["Condition"] and row["Manual section"].startswith("§"), row
    assert row["AZ-MC1 alarm"] == NONE and row["Our alarm"] == NONE, row_id  # the manual numbers none
    if kind == "not applicable":
        assert row["Our code"] == NONE, row_id
    assert not raised_codes_missing(row["Our code"]), row_id


def test_rows_with_minimal_programs_match_them():
    cases = minimal_cases(ALARMS_TESTS)
    citing = {row["#"] for row in alarm_rows()
              if (ALARMS_TESTS, "test_manual_alarm") in NODE.findall(row["Status"])}  # fmt: skip
    assert citing == set(cases)
    for row in alarm_rows():
        if row["#"] in cases:
            assert set(ERROR_CODE.findall(row["Our code"])) == {code for code, _ in cases[row["#"]]}, row["#"]
            assert all(alarm is None for _, alarm in cases[row["#"]]), row["#"]


def test_alarm_counts_add_up():
    text = ALARMS_DOC.read_text(encoding="utf-8")
    for kind in ("tested", "deviation", "not applicable"):
        count = sum(alarm_kind(row["Status"]) == kind for row in alarm_rows())
        assert f"| {kind} | {count} |" in text, (kind, count)
