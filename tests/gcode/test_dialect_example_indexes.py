"""Every dialect's worked-examples index (docs/<dialect>_examples.md) stays complete and true, by one set of
checks for all: one row per example of the manual's catalogue, in order; well-formed rows that name test
nodes which exist; every golden test indexed; the counts under the table adding up. Test nodes are found by
parsing the test files (no pytest subprocess). The alarm indexes are checked in
``test_dialect_alarm_indexes.py``; GSK 25i's index has its own tests in ``test_examples_index.py``.
"""

from __future__ import annotations

import functools

import pytest
from doc_tables import NODE, ROOT, check_ids, check_nodes, module_tests, only_nodes, parse_table

#: dialect → number of worked examples in its manual's catalogue (E1..En)
CATALOGUES = {"syntec": 46, "h4cm": 44, "azmc1": 30}
HEADER = ["#", "Manual section", "What it tests", "Quality", "Status", "Reading"]


def _doc(dialect: str):
    return ROOT / "docs" / f"{dialect}_examples.md"


def _golden_tests(dialect: str) -> str:
    return f"tests/gcode/dialects/{dialect}/test_{dialect}_examples.py"


@functools.cache
def example_rows(dialect: str) -> list[dict[str, str]]:
    header, table = parse_table(_doc(dialect).read_text(encoding="utf-8"))
    assert header == HEADER, dialect
    return table


@pytest.mark.parametrize("dialect", CATALOGUES)
def test_every_example_has_exactly_one_row_in_order(dialect):
    expected = [f"E{n}" for n in range(1, CATALOGUES[dialect] + 1)]
    check_ids([row["#"] for row in example_rows(dialect)], expected)


@pytest.mark.parametrize("dialect", CATALOGUES)
def test_example_rows_are_well_formed_and_name_existing_tests(dialect):
    for row in example_rows(dialect):
        assert row["Quality"] in {"A", "B", "C"} and row["Manual section"].startswith("§"), row
        assert row["What it tests"] and row["Reading"], row
        assert only_nodes(row["Status"]), row["#"]
        check_nodes(row["Status"], row["#"])


@pytest.mark.parametrize("dialect", CATALOGUES)
def test_every_golden_test_is_indexed(dialect):
    golden = _golden_tests(dialect)
    named = {name for row in example_rows(dialect) for path, name in NODE.findall(row["Status"])
             if path == golden}  # fmt: skip
    assert set(module_tests(golden)) == named


@pytest.mark.parametrize("dialect", CATALOGUES)
def test_example_counts_add_up(dialect):
    counts = [sum(row["Quality"] == q for row in example_rows(dialect)) for q in "ABC"]
    line = "| tested | " + " | ".join(map(str, counts)) + f" | {sum(counts)} |"
    assert line in _doc(dialect).read_text(encoding="utf-8"), line
