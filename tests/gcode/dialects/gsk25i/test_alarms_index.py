"""The index of the manual's program alarms (docs/gsk25i_alarms.md) stays complete and true.

The table lists the error conditions the manual states in its text (E1-E11, M1-M23, D1-D7, C1-C10, T1-T12,
S1-S15) and the alarm-list classes those lack (L1-L25) with the tests that check each one. These tests fail
when a row is missing, doubled or out of order; when a test the table names disappears or is renamed; when a
"missing check" row's test is no longer a strict xfail (the check was built: update the row) or a strict xfail
is not indexed; when a rejected code is not refused by name; when a code in "Our code" is raised nowhere in
cnc_gym/gcode; when a row's codes and alarms differ from the minimal programs of
tests/gcode/dialects/gsk25i/test_manual_alarms.py's ``CASES``; or when the counts under the table no
longer add up. Test nodes
are found by parsing the test files (no pytest subprocess, no imports of test modules).

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import ast
import functools
import re

import pytest
from doc_tables import NODE, ROOT, check_ids, module_tests, parse_table

from cnc_gym.errors import ProgramError
from cnc_gym.gcode import interpret

INDEX = ROOT / "docs" / "gsk25i_alarms.md"
MANUAL_ALARMS = "tests/gcode/dialects/gsk25i/test_manual_alarms.py"
CASES_TEST = "test_manual_alarm"
# The row ids of the conditions the manual states in its text, then the alarm-list rows.
CONDITIONS = [f"{prefix}{n}" for prefix, count in (("E", 11), ("M", 23), ("D", 7), ("C", 10), ("T", 12),
                                                  ("S", 15)) for n in range(1, count + 1)]  # fmt: skip
ALARM_LIST = [f"L{n}" for n in range(1, 26)]
ROWS = CONDITIONS + ALARM_LIST
HEADER = ["#", "Condition", "Manual section", "GSK alarm", "Our code", "Our alarm", "Status", "Note"]
KINDS = ("tested", "missing check", "deviation", "not applicable", "rejected")
CODE = re.compile(r"`(G\d+(?:\.\d)?)`")
ERROR_CODE = re.compile(r"`([a-z0-9]+(?:-[a-z0-9]+)*)`")
SECTIONS = re.compile(r"-|(GSK 25i [a-z]+ manual )?§\d+(\.\d+)*(, §\d+(\.\d+)*)*")
NONE = "—"


@functools.cache
def rows() -> list[dict[str, str]]:
    header, table = parse_table(INDEX.read_text(encoding="utf-8"))
    assert header == HEADER
    return table


def row_of(row_id: str) -> dict[str, str]:
    return next(row for row in rows() if row["#"] == row_id)


def is_strict_xfail(function: ast.FunctionDef) -> bool:
    """``@pytest.mark.xfail(strict=True, ...)`` on the function."""
    return any(
        isinstance(decorator, ast.Call) and ast.unparse(decorator.func) == "pytest.mark.xfail"
        and any(k.arg == "strict" and isinstance(k.value, ast.Constant) and k.value.value is True
                for k in decorator.keywords)
        for decorator in function.decorator_list
    )  # fmt: skip


@functools.cache
def cases() -> dict[str, list[tuple[str, int | None]]]:
    """``CASES`` of test_manual_alarms.py, parsed: row id -> [(error code, alarm or None)] per program."""
    tree = ast.parse((ROOT / MANUAL_ALARMS).read_text(encoding="utf-8"))
    node = next(n for n in tree.body if isinstance(n, ast.AnnAssign) and ast.unparse(n.target) == "CASES")
    assert isinstance(node.value, ast.Dict)
    parsed: dict[str, list[tuple[str, int | None]]] = {}
    for key, value in zip(node.value.keys, node.value.values, strict=True):
        assert isinstance(key, ast.Constant) and isinstance(value, ast.List), ast.unparse(key)
        entries = []
        for case in value.elts:
            assert isinstance(case, ast.Tuple) and len(case.elts) == 4, ast.unparse(case)
            code, alarm = case.elts[1], case.elts[2]
            assert isinstance(code, ast.Constant) and isinstance(code.value, str), ast.unparse(case)
            assert (isinstance(alarm, ast.Constant) and isinstance(alarm.value, int | None)) or (
                isinstance(alarm, ast.Name) and alarm.id == "NO_ALARM"), ast.unparse(case)  # fmt: skip
            entries.append((code.value, alarm.value if isinstance(alarm, ast.Constant) else None))
        assert key.value not in parsed, f"CASES names {key.value} twice"
        parsed[key.value] = entries
    return parsed


def status_kind(status: str) -> str:
    for kind in ("deviation", "not applicable", "rejected"):
        if status.startswith(f"{kind}: "):
            # A deviation or non-applicability says why; a rejection names the refused codes.
            assert kind == "rejected" or len(status) > len(kind) + 20, f"{kind} with no reason: {status!r}"
            return kind
    assert NODE.search(status), f"status is not test nodes, deviation, not applicable or rejected: {status!r}"
    # Nothing but test nodes and separators: a typo in a node would otherwise hide in the text.
    assert NODE.sub("", status).replace(",", "").strip() == "", f"stray text in a status: {status!r}"
    xfails = [name for path, name in NODE.findall(status)
              if path == MANUAL_ALARMS and is_strict_xfail(module_tests(path)[name])]  # fmt: skip
    return "missing check" if xfails else "tested"


@functools.cache
def raised_codes_source() -> str:
    files = sorted((ROOT / "cnc_gym" / "gcode").rglob("*.py"))
    return "\n".join(path.read_text(encoding="utf-8") for path in files)


def our_codes(row: dict[str, str]) -> set[str]:
    if row["Our code"] == NONE:
        return set()
    codes = ERROR_CODE.findall(row["Our code"])
    assert codes and ERROR_CODE.sub("", row["Our code"]).replace(",", "").strip() == "", row["Our code"]
    return set(codes)


def our_alarms(row: dict[str, str]) -> set[int]:
    if row["Our alarm"] == NONE:
        return set()
    assert re.fullmatch(r"\d+(, \d+)*", row["Our alarm"]), row["Our alarm"]
    return {int(n) for n in row["Our alarm"].split(", ")}


def test_every_condition_has_exactly_one_row_in_order():
    check_ids([row["#"] for row in rows()], ROWS)


def test_rows_are_well_formed():
    for row in rows():
        assert row["Condition"] and row["GSK alarm"], row
        assert SECTIONS.fullmatch(row["Manual section"]), row
        kind = status_kind(row["Status"])
        codes, alarms = our_codes(row), our_alarms(row)
        if kind == "not applicable":
            assert not codes and not alarms, f"{row['#']}: not applicable but names an error"
        if kind == "rejected":
            assert (codes, alarms) == ({"not-implemented"}, {10}), row["#"]
        if kind == "missing check" or "Missing check" in row["Note"]:
            assert kind == "missing check" and "**Missing check" in row["Note"], (
                f"{row['#']}: a missing check is both an xfail node in the status and said in the note")


@pytest.mark.parametrize("row_id", ROWS)
def test_every_referenced_test_exists(row_id):
    for path, name in NODE.findall(row_of(row_id)["Status"]):
        assert (ROOT / path).is_file(), f"{row_id}: {path} does not exist"
        assert name in module_tests(path), f"{row_id}: {path} has no test function {name}"


def test_every_strict_xfail_of_the_manual_alarms_is_indexed():
    """A missing check (strict xfail) in test_manual_alarms.py is named by a row, so the LEAD finds it."""
    xfails = {name for name, fn in module_tests(MANUAL_ALARMS).items() if is_strict_xfail(fn)}
    named = {name for row in rows() for path, name in NODE.findall(row["Status"]) if path == MANUAL_ALARMS}
    assert xfails <= named, sorted(xfails - named)
    assert named <= set(module_tests(MANUAL_ALARMS)), sorted(named - set(module_tests(MANUAL_ALARMS)))


@pytest.mark.parametrize("row_id", ROWS)
def test_our_codes_are_raised_by_the_interpreter(row_id):
    """Every code in "Our code" is a string literal somewhere in cnc_gym/gcode (a renamed code shows here)."""
    source = raised_codes_source()
    for code in our_codes(row_of(row_id)):
        assert f'"{code}"' in source, f"{row_id}: no code {code!r} in cnc_gym/gcode"


def test_cases_and_the_table_name_the_same_rows():
    """Rows citing test_manual_alarm have programs in CASES, and every CASES key is such a row."""
    citing = {row["#"] for row in rows() if (MANUAL_ALARMS, CASES_TEST) in NODE.findall(row["Status"])}
    assert citing == set(cases()), (sorted(citing - set(cases())), sorted(set(cases()) - citing))


@pytest.mark.parametrize("row_id", ROWS)
def test_codes_and_alarms_of_a_row_match_its_cases(row_id):
    """A row's "Our code" and "Our alarm" are exactly the codes and alarms its minimal programs end in."""
    if row_id not in cases():
        return
    row = row_of(row_id)
    assert our_codes(row) == {code for code, _ in cases()[row_id]}, row_id
    assert our_alarms(row) == {alarm for _, alarm in cases()[row_id] if alarm is not None}, row_id


@pytest.mark.parametrize("row_id", ROWS)
def test_rejected_codes_are_refused_by_name(row_id):
    row = row_of(row_id)
    if status_kind(row["Status"]) != "rejected":
        return
    codes = CODE.findall(row["Status"])
    assert codes, f"{row_id} is rejected without naming a code"
    for code in codes:
        with pytest.raises(ProgramError) as info:
            interpret(f"{code}\n", file="index.nc")
        assert info.value.code == "not-implemented" and code in str(info.value), (row_id, str(info.value))


def test_counts_under_the_table_add_up():
    counts: dict[tuple[str, str], int] = {}
    for row in rows():
        group = "conditions" if row["#"] in CONDITIONS else "alarm list"
        key = (status_kind(row["Status"]), group)
        counts[key] = counts.get(key, 0) + 1
    text = INDEX.read_text(encoding="utf-8")
    for kind in KINDS:
        per_group = [counts.get((kind, group), 0) for group in ("conditions", "alarm list")]
        line = f"| {kind} | " + " | ".join(map(str, per_group)) + f" | {sum(per_group)} |"
        assert line in text, f"counts table out of date: expected the line {line!r}"
