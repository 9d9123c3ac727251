"""The error-code registry (cnc_gym/error_codes.py): every code raised or noted is in it, and the docs'
code tables are written from it.

Three checks, each catching what the others cannot: the test suite runs in strict mode (tests/conftest.py),
so a code built at run time (from a table, a variable) that is not registered fails the test that reaches
it; a static scan finds the literal codes at every raise and note site, reached by a test or not; and the
docs tables must equal what scripts/error_code_docs.py writes from the registry. The dialects' alarm
tables and the docs' alarm indexes may name registered codes only.
"""

from __future__ import annotations

import ast
import importlib.util
import re
from collections.abc import Iterator
from pathlib import Path

import pytest

from cnc_gym import error_codes
from cnc_gym.error_codes import CODES, ERROR_CODES, Scope, UnregisteredCodeError, codes_of
from cnc_gym.errors import ProgramError, notice_line
from cnc_gym.gcode.dialect import DIALECT_MODULES, get_dialect

REPO = Path(__file__).resolve().parent.parent
PACKAGE = REPO / "cnc_gym"
#: Error and note factories whose name does not end in ``error`` or ``_fail``.
_FACTORIES = {"fail", "notice", "notice_line"}
#: What a code looks like: lower-case words joined by ``-`` (the motion stage's: ``motion.no_feed``).
CODE = re.compile(r"[a-z][a-z0-9]*(?:[-.][a-z0-9_]+)*")


def _literals(node: ast.expr) -> Iterator[ast.Constant]:
    """The string literals an argument can evaluate to (``"a" if c else "b"``, ``x or "a"``)."""
    if isinstance(node, ast.Constant) and isinstance(node.value, str):
        yield node
    elif isinstance(node, ast.IfExp):
        yield from _literals(node.body)
        yield from _literals(node.orelse)
    elif isinstance(node, ast.BoolOp):
        for value in node.values:
            yield from _literals(value)


def _is_error_factory(call: ast.Call) -> bool:
    """A call that builds an error or a note from (message, code, …): ``ProgramError``, ``core.error``,
    ``dialect.error``, ``_error``, ``_fail``, ``config_error``, ``notice``, ``notice_line`` …"""
    func = call.func
    name = func.attr if isinstance(func, ast.Attribute) else getattr(func, "id", "")
    return name.lower().endswith("error") or name.endswith("_fail") or name in _FACTORIES


def literal_codes(root: Path = PACKAGE) -> dict[str, list[str]]:
    """Code → ``file:line`` of each literal code in the package: an argument after the message of an error
    or note factory, a ``code=`` keyword, the default of a parameter named ``code``, and the code of a
    ``(line, level, message, code)`` notice tuple."""
    found: dict[str, list[str]] = {}

    def add(node: ast.Constant, path: Path) -> None:
        if CODE.fullmatch(node.value):
            found.setdefault(node.value, []).append(f"{path.relative_to(REPO)}:{node.lineno}")

    for path in sorted(root.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Call):
                if _is_error_factory(node):
                    arguments = [*node.args[1:], *(k.value for k in node.keywords if k.arg == "code")]
                else:
                    arguments = [k.value for k in node.keywords if k.arg == "code"]
                    if isinstance(node.func, ast.Attribute) and node.func.attr == "append" and node.args:
                        item = node.args[0]  # notices.append((line, level, message, code))
                        if isinstance(item, ast.Tuple) and len(item.elts) == 4:
                            arguments.append(item.elts[3])
                for argument in arguments:
                    for literal in _literals(argument):
                        add(literal, path)
            elif isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                args = node.args
                positional = [*args.posonlyargs, *args.args]
                pairs = [*zip(positional[len(positional) - len(args.defaults):], args.defaults, strict=True),
                         *zip(args.kwonlyargs, args.kw_defaults, strict=True)]  # fmt: skip
                for arg, default in pairs:
                    if arg.arg == "code" and default is not None:
                        for literal in _literals(default):
                            add(literal, path)
    return found


def test_the_suite_runs_in_strict_mode():
    assert error_codes._STRICT, "tests/conftest.py must set CNC_GYM_STRICT_CODES=1 before cnc_gym is imported"
    with pytest.raises(UnregisteredCodeError, match="no-such-code"):
        ProgramError("message", code="no-such-code")
    with pytest.raises(UnregisteredCodeError, match="no-such-note"):
        notice_line("a.nc", 1, "message", "no-such-note")
    error = ProgramError("X1.2.3", code="bad-number", file="a.nc", line=3)
    assert str(error) == "a.nc:3: X1.2.3 [bad-number]"


def test_every_literal_code_at_a_raise_or_note_site_is_registered():
    found = literal_codes()
    assert len(found) > 100, f"the scan found only {len(found)} codes: has the way errors are raised changed?"
    unknown = {code: sites[:3] for code, sites in found.items() if code not in CODES}
    assert not unknown, f"codes missing from cnc_gym/error_codes.py: {unknown}"


def test_every_registered_code_is_used_in_the_package():
    # Written somewhere outside the registry (a raise site, a notice, a dialect's alarm table …).
    text = "\n".join(p.read_text() for p in PACKAGE.rglob("*.py") if p.name != "error_codes.py")
    unused = sorted(code for code in CODES if f'"{code}"' not in text and f"'{code}'" not in text)
    assert not unused, f"registered but never used: {unused}"


def test_each_code_is_listed_once_per_scope_and_has_a_meaning():
    keys = [(e.code, e.scope) for e in ERROR_CODES]
    assert len(keys) == len(set(keys))
    for entry in ERROR_CODES:
        assert CODE.fullmatch(entry.code), entry.code
        assert entry.meaning.strip() and "\n" not in entry.meaning, entry.code
        assert not entry.gsk25i_alarm or entry.scope is Scope.GCODE, entry.code
    assert all(codes_of(scope) for scope in Scope)


@pytest.mark.parametrize("name", sorted(DIALECT_MODULES))
def test_dialect_alarm_tables_name_registered_codes(name):
    # The keys are codes, or conditions "<code>/<what>" (docs/dialects.md).
    keys = get_dialect(name).alarms
    unknown = sorted(key for key in keys if key.split("/")[0] not in CODES)
    assert not unknown, f"{name}: alarm table keys that are no registered code: {unknown}"


def test_the_gsk25i_alarm_column_shows_the_dialect_s_numbers():
    # The GCODE table's "GSK alarm" column is prose ("8 (N 16, S 200 …)"); each number the gsk25i dialect
    # gives a code itself (not a condition of it) must be in it.
    alarms = get_dialect("gsk25i").alarms
    for entry in codes_of(Scope.GCODE):
        number = alarms.get(entry.code)
        if number is not None:
            assert str(number) in re.findall(r"\d+", entry.gsk25i_alarm), (entry.code, number)


def test_the_docs_tables_are_written_from_the_registry():
    path = REPO / "scripts" / "error_code_docs.py"
    module_spec = importlib.util.spec_from_file_location("error_code_docs", path)
    assert module_spec is not None and module_spec.loader is not None
    module = importlib.util.module_from_spec(module_spec)
    module_spec.loader.exec_module(module)
    stale = "docs tables are stale: run .venv/bin/python scripts/error_code_docs.py"
    assert module.main(["--check"]) == 0, stale


@pytest.mark.parametrize("index", sorted(p.name for p in (REPO / "docs").glob("*_alarms.md")))
def test_the_alarm_indexes_name_registered_codes(index):
    # The "Our code" column of each dialect's alarm index (docs/*_alarms.md).
    column, named = None, set()
    for line in (REPO / "docs" / index).read_text().splitlines():
        cells = [cell.strip() for cell in line.strip().strip("|").split("|")]
        if not line.startswith("|"):
            continue
        if "Our code" in cells:
            column = cells.index("Our code")
        elif column is not None and len(cells) > column:
            named |= {code.split("/")[0] for code in re.findall(r"`([^`]+)`", cells[column])}
    assert column is not None and named, f"{index} has no 'Our code' column, or no code in it"
    assert named <= CODES, f"{index} names codes that are not registered: {sorted(named - CODES)}"
