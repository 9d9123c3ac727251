"""Helpers of the tests that check the docs' index tables (worked examples, alarms) against the tests."""

from __future__ import annotations

import ast
import functools
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
#: A test node as the tables write it: `tests/<path>.py::<function>`.
NODE = re.compile(r"`(tests/[\w/]+\.py)::(\w+)`")


def split_row(line: str) -> list[str]:
    """The cells of one Markdown table row (``\\|`` inside a cell is a literal bar)."""
    cells = re.split(r"(?<!\\)\|", line.strip())[1:-1]
    return [cell.strip().replace("\\|", "|") for cell in cells]


def parse_table(text: str) -> tuple[list[str], list[dict[str, str]]]:
    """The first table whose header starts ``| # |``: its column names and one dict per row."""
    lines = text.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("| # |"))
    header = split_row(lines[start])
    table = []
    for line in lines[start + 2:]:
        if not line.startswith("|"):
            break
        cells = split_row(line)
        assert len(cells) == len(header), f"wrong number of cells: {line}"
        table.append(dict(zip(header, cells, strict=True)))
    return header, table


def check_ids(ids: list[str], expected: list[str]) -> None:
    """The table has each expected id exactly once, nothing else, in the expected order."""
    missing = [x for x in expected if x not in ids]
    doubled = sorted({x for x in ids if ids.count(x) > 1})
    unknown = [x for x in ids if x not in expected]
    assert not missing and not doubled and not unknown, (missing, doubled, unknown)
    assert ids == expected  # in order, so a reader finds them


@functools.cache
def module_tests(path: str) -> dict[str, ast.FunctionDef]:
    """Module-level test functions of a test file (relative to the repository), by parsing it."""
    tree = ast.parse((ROOT / path).read_text(encoding="utf-8"))
    return {node.name: node for node in tree.body
            if isinstance(node, ast.FunctionDef) and node.name.startswith("test_")}  # fmt: skip


def only_nodes(status: str) -> bool:
    """Whether a Status cell is nothing but test nodes."""
    return bool(NODE.search(status)) and NODE.sub("", status).replace(",", "").strip() == ""


def alarm_kind(status: str) -> str:
    """An alarms-index Status cell's kind: ``tested`` (test nodes), ``deviation`` or ``not applicable`` (each
    with its reason)."""
    for kind in ("deviation", "not applicable"):
        if status.startswith(f"{kind}: "):
            assert len(status) > len(kind) + 20, f"{kind} without a reason: {status!r}"
            return kind
    assert only_nodes(status), f"status is neither test nodes, deviation nor not applicable: {status!r}"
    return "tested"


def check_nodes(status: str, row: str) -> None:
    """Every test node a cell names exists."""
    for path, name in NODE.findall(status):
        assert (ROOT / path).is_file(), f"{row}: {path} does not exist"
        assert name in module_tests(path), f"{row}: {path} has no test function {name}"


def minimal_cases(path: str) -> dict[str, list[tuple[str, int | None]]]:
    """The ``CASES`` table of an alarms test file (row → [(program, code, alarm, line, …)]), parsed: row →
    [(code, alarm)]."""
    tree = ast.parse((ROOT / path).read_text(encoding="utf-8"))
    node = next(n for n in tree.body if isinstance(n, ast.AnnAssign) and ast.unparse(n.target) == "CASES")
    out: dict[str, list[tuple[str, int | None]]] = {}
    for key, value in zip(node.value.keys, node.value.values, strict=True):  # type: ignore[union-attr]
        out[key.value] = [(case.elts[1].value, case.elts[2].value) for case in value.elts]  # type: ignore
    return out


#: An error code in backticks in an index's "Our code" cell.
ERROR_CODE = re.compile(r"`([a-z0-9]+(?:-[a-z0-9]+)*)`")
#: An empty cell.
NONE = "—"


def raised_codes_missing(codes_cell: str) -> list[str]:
    """The codes of an "Our code" cell that no module of cnc_gym/gcode raises."""
    files = sorted((ROOT / "cnc_gym" / "gcode").rglob("*.py"))
    source = "\n".join(p.read_text(encoding="utf-8") for p in files)
    return [code for code in ERROR_CODE.findall(codes_cell) if f'"{code}"' not in source]


def alarm_numbers(cell: str) -> set[int]:
    """An "Our alarm" cell's numbers: "—" → none; "25" → {25}; "500, 501" → {500, 501}; "50-99" → 50..99."""
    if cell == NONE:
        return set()
    out: set[int] = set()
    for part in cell.split(","):
        low, _, high = part.strip().partition("-")
        out.update(range(int(low), int(high or low) + 1))
    return out
