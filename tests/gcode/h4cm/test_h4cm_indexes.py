"""The H4C-M alarm index stays complete and true: docs/h4cm_alarms.md (the manual's error conditions,
A1-A33). These tests fail when a row is missing, doubled or out of order, when a test a row names disappears
or is renamed, when a code in "Our code" is raised nowhere in cnc_gym/gcode, when a row's codes and alarms
differ from its minimal programs (``CASES`` of test_h4cm_alarms.py), or when the counts under the table no
longer add up. The examples index (docs/h4cm_examples.md) is checked with every dialect's in
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

ALARMS_DOC = ROOT / "docs" / "h4cm_alarms.md"
ALARMS_TESTS = "tests/gcode/h4cm/test_h4cm_alarms.py"
ALARMS = [f"A{n}" for n in range(1, 34)]
ERROR_CODE = re.compile(r"`([a-z0-9]+(?:-[a-z0-9]+)*)`")
NONE = "—"


@functools.cache
def alarm_rows() -> list[dict[str, str]]:
    header, table = parse_table(ALARMS_DOC.read_text(encoding="utf-8"))
    assert header == ["#", "Condition", "Manual section", "H4C-M error", "Our code", "Our alarm", "Status",
                      "Note"]  # fmt: skip
    return table


def numbers(cell: str) -> set[int]:
    """"—" → none; "25" → {25}; "500, 501" → {500, 501}; "50-99" → 50..99."""
    if cell == NONE:
        return set()
    out: set[int] = set()
    for part in cell.split(","):
        low, _, high = part.strip().partition("-")
        out.update(range(int(low), int(high or low) + 1))
    return out


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
    assert row["Condition"] and row["Manual section"].startswith("§") and row["H4C-M error"], row
    codes = set() if row["Our code"] == NONE else set(ERROR_CODE.findall(row["Our code"]))
    if kind == "not applicable":
        assert not codes and row["Our alarm"] == NONE, row_id
    manual = re.fullmatch(r"ERROR (\d+)", row["H4C-M error"])
    if manual and kind == "tested":
        assert int(manual.group(1)) in numbers(row["Our alarm"]), row_id  # the manual's number is carried


@pytest.mark.parametrize("row_id", ALARMS)
def test_our_codes_are_raised_by_the_interpreter(row_id):
    row = next(r for r in alarm_rows() if r["#"] == row_id)
    files = sorted((ROOT / "cnc_gym" / "gcode").rglob("*.py"))
    source = "\n".join(p.read_text(encoding="utf-8") for p in files)
    for code in ERROR_CODE.findall(row["Our code"]):
        assert f'"{code}"' in source, f"{row_id}: no code {code!r} in cnc_gym/gcode"


def test_rows_with_minimal_programs_match_them():
    citing = {row["#"] for row in alarm_rows()
              if (ALARMS_TESTS, "test_manual_alarm") in NODE.findall(row["Status"])}  # fmt: skip
    assert citing == set(cases())
    for row in alarm_rows():
        if row["#"] not in cases():
            continue
        assert set(ERROR_CODE.findall(row["Our code"])) == {code for code, _ in cases()[row["#"]]}, row["#"]
        found = {alarm for _, alarm in cases()[row["#"]] if alarm is not None}
        assert found <= numbers(row["Our alarm"]) and bool(found) == bool(numbers(row["Our alarm"])), row["#"]


def test_alarm_counts_add_up():
    text = ALARMS_DOC.read_text(encoding="utf-8")
    for kind in ("tested", "deviation", "not applicable"):
        count = sum(alarm_kind(row["Status"]) == kind for row in alarm_rows())
        assert f"| {kind} | {count} |" in text, (kind, count)
