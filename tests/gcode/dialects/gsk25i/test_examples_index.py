"""The index of the manual's worked examples (docs/gsk25i_examples.md) stays complete and true.

The table lists X1-X80 of docs/gsk25i_examples.md with the tests that check each one. These tests fail when a
row is missing or doubled, when a test the table names disappears or is renamed, when a quality-A example
is called out of scope without naming a code the dialect really rejects, or when the counts under the
table no longer add up. Test nodes are found by parsing the test files (no pytest subprocess).
"""

from __future__ import annotations

import functools
import re

import pytest
from doc_tables import NODE, ROOT, check_ids, module_tests, parse_table

from cnc_gym.errors import ProgramError
from cnc_gym.gcode import interpret

INDEX = ROOT / "docs" / "gsk25i_examples.md"
EXAMPLES = [f"X{n}" for n in range(1, 81)]
# Examples whose feature is still being built may be marked pending; none is now (X8, X27 and X61 were the
# last, with rotary axes, G37 and the G20 ordering).
MAY_BE_PENDING: set[str] = set()
CODE = re.compile(r"`(G\d+(?:\.\d)?)`")


@functools.cache
def rows() -> list[dict[str, str]]:
    header, table = parse_table(INDEX.read_text(encoding="utf-8"))
    assert header == ["#", "Manual section", "What it tests", "Quality", "Status", "Reading"]
    return table


def row_of(example: str) -> dict[str, str]:
    return next(row for row in rows() if row["#"] == example)


def status_kind(status: str) -> str:
    if status.startswith("out of scope"):
        return "out of scope"
    if status == "pending (LEAD)":
        return "pending"
    assert NODE.search(status), f"status is neither test nodes, out of scope nor pending: {status!r}"
    # Nothing but test nodes and separators: a typo in a node would otherwise hide in the text.
    assert NODE.sub("", status).replace(",", "").strip() == "", f"stray text in a status: {status!r}"
    return "tested"


def test_every_example_has_exactly_one_row():
    check_ids([row["#"] for row in rows()], EXAMPLES)


def test_rows_are_well_formed():
    for row in rows():
        assert row["Quality"] in {"A", "B", "C"}, row
        assert re.fullmatch(r"§[\d.]+(-§[\d.]+)?(, §[\d.]+(-§[\d.]+)?)*", row["Manual section"]), row
        assert row["What it tests"] and row["Reading"], row
        status_kind(row["Status"])


@pytest.mark.parametrize("example", EXAMPLES)
def test_every_referenced_test_exists(example):
    status = row_of(example)["Status"]
    for path, name in NODE.findall(status):
        assert (ROOT / path).is_file(), f"{example}: {path} does not exist"
        assert name in module_tests(path), f"{example}: {path} has no test function {name}"


def test_no_example_is_left_pending():
    pending = {row["#"] for row in rows() if status_kind(row["Status"]) == "pending"}
    assert pending <= MAY_BE_PENDING, pending - MAY_BE_PENDING


@pytest.mark.parametrize("example", EXAMPLES)
def test_out_of_scope_names_codes_the_dialect_rejects(example):
    """An example is out of scope only for codes the dialect refuses by name (``not-implemented``); a
    quality-A example must name one (a B/C example may instead give its reason only)."""
    row = row_of(example)
    if status_kind(row["Status"]) != "out of scope":
        return
    codes = CODE.findall(row["Status"])
    assert codes or row["Quality"] != "A", f"{example} is quality A and out of scope without a rejected code"
    for code in codes:
        with pytest.raises(ProgramError) as info:
            interpret(f"{code}\n", file="index.nc")
        assert info.value.code == "not-implemented" and code in str(info.value), (example, str(info.value))


def test_counts_under_the_table_add_up():
    counts: dict[tuple[str, str], int] = {}
    for row in rows():
        key = (status_kind(row["Status"]), row["Quality"])
        counts[key] = counts.get(key, 0) + 1
    text = INDEX.read_text(encoding="utf-8")
    for kind in ("tested", "out of scope", "pending"):
        per_quality = [counts.get((kind, q), 0) for q in "ABC"]
        line = f"| {kind} | " + " | ".join(map(str, per_quality)) + f" | {sum(per_quality)} |"
        assert line in text, f"counts table out of date: expected the line {line!r}"


def test_every_new_example_test_is_indexed():
    """Each test in test_manual_examples.py is there for an example, so the table must name it."""
    path = "tests/gcode/dialects/gsk25i/test_manual_examples.py"
    named = {name for row in rows() for p, name in NODE.findall(row["Status"]) if p == path}
    assert set(module_tests(path)) <= named, sorted(set(module_tests(path)) - named)
