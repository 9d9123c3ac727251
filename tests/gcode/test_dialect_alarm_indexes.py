"""Every dialect's alarm index (docs/<dialect>_alarms.md: the manual's error conditions A1..An) stays complete
and true, by one set of checks for all. They fail when a row is missing, doubled or out of order, when a test
a row names disappears or is renamed, when a code in "Our code" is raised nowhere in cnc_gym/gcode, when a
row's codes and alarms differ from its minimal programs (``CASES`` of
``tests/gcode/dialects/<dialect>/test_<dialect>_alarms.py``), or when the counts under the table no longer
add up.

What differs per manual is how it numbers its alarms, and so which number "Our alarm" must carry: one small
rule per dialect (``CARRIED``). GSK 25i's index has its own tests in ``test_alarms_index.py``; the examples
indexes are checked in ``test_dialect_example_indexes.py``.
"""

from __future__ import annotations

import functools
import re
from collections.abc import Callable

import pytest
from doc_tables import (
    ERROR_CODE,
    NODE,
    NONE,
    ROOT,
    alarm_kind,
    alarm_numbers,
    check_ids,
    check_nodes,
    minimal_cases,
    parse_table,
    raised_codes_missing,
)

#: dialect → (number of error conditions in its manual's catalogue, the index's column of the manual's alarm)
CATALOGUES = {"syntec": (28, "Syntec alarm"), "h4cm": (34, "H4C-M error"), "azmc1": (22, "AZ-MC1 alarm")}


def _syntec_carried(manual: str, ours: str, kind: str) -> None:
    assert manual
    if manual.startswith("MAR-"):
        assert ours == manual[4:]  # the number is carried as given
    else:
        assert ours == NONE  # Syntec numbers nothing else


def _h4cm_carried(manual: str, ours: str, kind: str) -> None:
    assert manual
    numbered = re.fullmatch(r"ERROR (\d+)", manual)
    if numbered and kind == "tested":
        assert int(numbered.group(1)) in alarm_numbers(ours)  # the manual's number is carried


def _azmc1_carried(manual: str, ours: str, kind: str) -> None:
    assert manual == NONE and ours == NONE  # the manual numbers none


#: dialect → the rule that ties a row's "Our alarm" to the manual's alarm cell (manual, ours, row kind)
CARRIED: dict[str, Callable[[str, str, str], None]] = {
    "syntec": _syntec_carried, "h4cm": _h4cm_carried, "azmc1": _azmc1_carried}  # fmt: skip
ROWS = [(dialect, f"A{n}") for dialect, (count, _) in CATALOGUES.items() for n in range(1, count + 1)]


def _doc(dialect: str):
    return ROOT / "docs" / f"{dialect}_alarms.md"


def _alarm_tests(dialect: str) -> str:
    return f"tests/gcode/dialects/{dialect}/test_{dialect}_alarms.py"


@functools.cache
def alarm_rows(dialect: str) -> list[dict[str, str]]:
    header, table = parse_table(_doc(dialect).read_text(encoding="utf-8"))
    assert header == ["#", "Condition", "Manual section", CATALOGUES[dialect][1], "Our code", "Our alarm",
                      "Status", "Note"]  # fmt: skip
    return table


@functools.cache
def cases(dialect: str) -> dict[str, list[tuple[str, int | None]]]:
    """``CASES`` of the dialect's alarms tests, parsed: row → [(code, alarm)]."""
    return minimal_cases(_alarm_tests(dialect))


@pytest.mark.parametrize("dialect", CATALOGUES)
def test_every_condition_has_exactly_one_row_in_order(dialect):
    expected = [f"A{n}" for n in range(1, CATALOGUES[dialect][0] + 1)]
    check_ids([row["#"] for row in alarm_rows(dialect)], expected)


@pytest.mark.parametrize(("dialect", "row_id"), ROWS)
def test_alarm_rows_are_well_formed_and_their_codes_are_raised(dialect, row_id):
    row = next(r for r in alarm_rows(dialect) if r["#"] == row_id)
    kind = alarm_kind(row["Status"])
    check_nodes(row["Status"], row_id)
    assert row["Condition"] and row["Manual section"].startswith("§"), row
    if kind == "not applicable":
        assert not ERROR_CODE.findall(row["Our code"]) and row["Our alarm"] == NONE, row_id
    try:
        CARRIED[dialect](row[CATALOGUES[dialect][1]], row["Our alarm"], kind)
    except AssertionError:
        pytest.fail(f"{dialect} {row_id}: 'Our alarm' {row['Our alarm']!r} does not carry the manual's alarm")
    assert not raised_codes_missing(row["Our code"]), row_id


@pytest.mark.parametrize("dialect", CATALOGUES)
def test_rows_with_minimal_programs_match_them(dialect):
    minimal = cases(dialect)
    citing = {row["#"] for row in alarm_rows(dialect)
              if (_alarm_tests(dialect), "test_manual_alarm") in NODE.findall(row["Status"])}  # fmt: skip
    assert citing == set(minimal)
    for row in alarm_rows(dialect):
        if row["#"] not in minimal:
            continue
        assert set(ERROR_CODE.findall(row["Our code"])) == {code for code, _ in minimal[row["#"]]}, row["#"]
        found = {alarm for _, alarm in minimal[row["#"]] if alarm is not None}
        ours = alarm_numbers(row["Our alarm"])
        assert found <= ours and bool(found) == bool(ours), row["#"]


@pytest.mark.parametrize("dialect", CATALOGUES)
def test_alarm_counts_add_up(dialect):
    text = _doc(dialect).read_text(encoding="utf-8")
    for kind in ("tested", "deviation", "not applicable"):
        count = sum(alarm_kind(row["Status"]) == kind for row in alarm_rows(dialect))
        assert f"| {kind} | {count} |" in text, (kind, count)
