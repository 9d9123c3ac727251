"""Every code cnc-gym prints in brackets (``FILE:LINE: message [code]``): one registry, a meaning each.

A code is the stable, machine-readable name of what went wrong in a program (:class:`~cnc_gym.errors.
ProgramError`) or of what a note about a program says (:func:`~cnc_gym.errors.notice_line`). Scripts and
tests match on it, so it is part of the interface: each one is declared here once, with the part of the
project it belongs to (:class:`Scope`) and its meaning. A code may be listed under two scopes where the
DIN family gives it a meaning of its own (``bad-character``, ``nesting`` …).

The docs' code tables are written from this registry (``scripts/error_code_docs.py``; its ``--check`` runs
in ``tests/test_error_codes.py``), and the test suite runs with ``CNC_GYM_STRICT_CODES=1``
(``tests/conftest.py``), under which raising or noting a code that is not here fails at once. Without
that variable nothing is checked at run time: a user never sees the check.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from enum import Enum


class Scope(Enum):
    """The part of the project a code belongs to, and so the docs table that explains it."""

    #: The interpreter's codes, shared by every dialect of the Fanuc family (docs/gcode.md "Error codes").
    GCODE = "gcode"
    #: The DIN family and the AZ-MC1 (docs/azmc1.md "Error codes of the DIN family and the AZ-MC1").
    DIN = "din"
    #: Codes of one dialect of the Fanuc family (docs/gcode.md "Codes of one dialect").
    FANUC = "fanuc"
    SYNTEC = "syntec"
    H4CM = "h4cm"
    #: The motion stage's checks of a tool path against a machine (docs/motion.md "Error codes").
    MOTION = "motion"
    #: Notes and warnings about a program, printed before its run or its error (docs/gcode.md "Notes").
    NOTE = "note"


@dataclass(frozen=True)
class ErrorCode:
    """One code under one scope: ``meaning`` is the docs table's line; ``gsk25i_alarm`` the GSK 25i alarm
    number(s) as the GCODE table shows them (empty: the GSK 25i has none)."""

    code: str
    meaning: str
    gsk25i_alarm: str = ""
    scope: Scope = Scope.GCODE


def _scoped(scope: Scope, *entries: ErrorCode) -> tuple[ErrorCode, ...]:
    return tuple(ErrorCode(e.code, e.meaning, e.gsk25i_alarm, scope) for e in entries)


#: The interpreter's common codes, in the order of docs/gcode.md's table.
_GCODE = _scoped(
    Scope.GCODE,
    ErrorCode("bad-number", "malformed number: a second or lone decimal point (`X1.2.3`, `X1.23456.7`, "
              "`X.`: 7), other (8)", "7 / 8"),
    ErrorCode("too-many-digits", "a constant in an expression, a variable number or a GOTO target of more "
              "than 8 digits (±99999999)", "3"),
    ErrorCode("missing-value", "address without a value (`X F100`), G10 without L", "5"),
    ErrorCode("missing-address", "a number without an address (`123`)", "4"),
    ErrorCode("bad-sign", "negative value where the address has none (F, S, T, N …), `-0` included (`N-0`); "
              "a sign inside a number or without digits (`X1-2`, `X-`)", "6"),
    ErrorCode("word-too-long", "a literal word longer than 16 characters (`X0000000000000001.0`; expression "
              "words exempt)", "13"),
    ErrorCode("decimal-point-not-allowed", "point in N, O, T, M, L, H, D or G04 P", "7"),
    ErrorCode("value-out-of-range", "beyond the address range of Table 1-1; a move to a machine coordinate "
              "beyond ±1e9 mm (a runaway offset or transform chain)",
              "8 (N 16, S 200, T 202, M 201, H/D 30)"),
    ErrorCode("bad-character", "illegal character, stray `)` or `%`; any non-ASCII character outside a "
              "comment (`²`, `١`), also in a block ending in `;`", "9"),
    ErrorCode("unknown-address", "a letter that is no address of the dialect (the H4C-M's `E`, `X1e3`; the "
              "AZ-MC1's `O`)"),
    ErrorCode("unclosed-comment", "`(` not closed on its line"),
    ErrorCode("bad-block-skip", "`//3`, `/0`"),
    ErrorCode("variable-not-allowed", "`/#2`, `N#3` (§3.7.2)", "205"),
    ErrorCode("misplaced-word", "O or N not at the head of the block"),
    ErrorCode("duplicate-word", "one address twice"),
    ErrorCode("unknown-code", "G or M code the controller does not have", "10 / 201"),
    ErrorCode("not-implemented", "a real controller feature this simulator does not model (named in the "
              "message)", "10"),
    ErrorCode("group-conflict", "two codes of one modal group in a block"),
    ErrorCode("axis-word-conflict", "two codes want the axis words (`G92 G01 X1`)"),
    ErrorCode("bad-combination", "G53 with G02/G03"),
    ErrorCode("unused-word", "a word that means nothing in its block"),
    ErrorCode("unsupported-axis", "U, V, W; A, B, C on a machine without that rotary axis", "15"),
    ErrorCode("rotary-axis-context", "a rotary axis word outside G00/G01/G92/G53, in cutter compensation or "
              "with a chamfer/corner"),
    ErrorCode("units-switch", "G20/G21 switching the unit system after a move or G92/G52"),
    ErrorCode("g37-signal", "G37: approach-end signal during the rapid, before M − e, or not by M + e; G37 "
              "starting at M", "80"),
    ErrorCode("g37-h-in-block", "G37: H in the same block", "80"),
    ErrorCode("g37-no-h", "G37: no H number given before", "80"),
    ErrorCode("g37-axis", "G37 with no or two axis words"),
    ErrorCode("g37-incremental", "G37 in G91"),
    ErrorCode("too-many-words", "more than 32 words in one block", "12"),
    ErrorCode("too-many-m-codes", "more than 3 M codes in one block", "201"),
    ErrorCode("missing-feed", "G01/G02/G03 with no F ever, or G01 with F0", "11"),
    ErrorCode("zero-feed", "G02/G03 with F0", "25"),
    ErrorCode("arc-radius-mismatch", "start and end radius differ by more than P1810", "20"),
    ErrorCode("arc-impossible", "R too small, radius 0, centre on the start or end, 0° R arc with a helical "
              "move", "22"),
    ErrorCode("arc-missing-center", "neither R nor an in-plane I/J/K", "22"),
    ErrorCode("arc-bad-offset", "the normal axis's I/J/K", "21"),
    ErrorCode("bad-dwell", "negative G04 time", "18"),
    ErrorCode("bad-g10", "bad G10 L or P", "31"),
    ErrorCode("length-no-axis", "G43/G44 without an axis word", "27"),
    ErrorCode("bad-offset-number", "H/D number 0 or beyond 256 in G10 L10-L13 / a system variable", "30"),
    ErrorCode("bad-offset-value", "tool offset beyond ±999.999 mm (geometry) / ±99.999 mm (wear): by G10 "
              "(32), by an offset variable (29)", "32 / 29"),
    ErrorCode("comp-no-intersection", "no intersection of the offset paths at an inner corner", "33"),
    ErrorCode("comp-arc-startup", "G02/G03 in the start-up or cancel block of cutter compensation", "34"),
    ErrorCode("comp-plane-change", "plane change while G41/G42 is in force", "37"),
    ErrorCode("comp-arc-centre", "compensated arc of radius 0 (centre = start = end)", "38"),
    ErrorCode("comp-interference", "the compensated path would overcut (checks (a)/(b), inner arc < offset)",
              "41"),
    ErrorCode("g39-without-comp", "G39 outside cutter compensation (offset mode)"),
    ErrorCode("comp-bad-direction", "zero I/J direction in G39/G40"),
    ErrorCode("length-helical", "G43/G44/G49 in a helical block"),
    ErrorCode("position-offset-in-comp", "G45-G48 in G41/G42"),
    ErrorCode("position-offset-arc", "G45-G48 on an arc other than a 1/4 or 3/4 I/J/K circle"),
    ErrorCode("bad-expression", "malformed expression or assignment", "206"),
    ErrorCode("missing-operand", "operand missing in an expression", "207"),
    ErrorCode("division-by-zero", "`/` or `MOD` by 0, TAN[90]", "208"),
    ErrorCode("bracket-nesting", "brackets deeper than 5", "209"),
    ErrorCode("math-domain", "SQRT of a negative, ASIN[2], AND of a non-integer"),
    ErrorCode("overflow", "non-finite result", "102"),
    ErrorCode("bad-variable", "writing #0, a variable that does not exist, a non-integer number, a system "
              "variable's value out of its range", "107"),
    ErrorCode("read-only-variable", "writing #1000-#1035, #3011, #3012, #4001-#5105 (§3.7.3)", "107"),
    ErrorCode("user-alarm", "`#3000=n (MESSAGE)`, n = 0..200", "3000+n"),
    ErrorCode("sequence-not-found", "GOTO / M99 P to a sequence number not in the program, or a null / "
              "non-integer target", "60"),
    ErrorCode("do-end", "DO/END not paired, crossing, nested deeper than 3, GOTO into a DO range (96); "
              "identifier not 1-3 (97)", "96 / 97"),
    ErrorCode("program-not-found", "M98 / G65 / G66 / code call to a program in neither the file nor the "
              "program folder", "59"),
    ErrorCode("missing-program-number", "M98, G65 or G66 without P", "76"),
    ErrorCode("bad-call", "bad P or L (program 0, count in P and L, > 999 repeats), words that cannot be "
              "arguments, > 10 I/J/K groups, G65 from a variable", "17"),
    ErrorCode("nesting", "more than 4 subprogram levels or 4 macro levels", "77"),
    ErrorCode("duplicate-program", "one O number twice in a file", "73"),
    ErrorCode("bad-macro-command", "a malformed statement: IF without GOTO/THEN, THEN without an "
              "assignment, WHILE without DO, a statement not alone in its block", "205"),
    ErrorCode("too-many-blocks", "more than `max_blocks` blocks executed (a runaway loop)"),
    ErrorCode("time-budget", "the interpretation took more than `max_seconds` of CPU time (default 60 s)"),
    ErrorCode("segment-budget", "the tool path has more than `max_segments` segments (default 2 000 000)"),
    ErrorCode("forbidden-in-scaling", "G27-G30, G54-G59, G54.1, G92 in G51 mode", "109"),
    ErrorCode("forbidden-in-rotation", "G27-G30, G52-G59, G54.1, G92 in G68 mode"),
    ErrorCode("plane-change-in-rotation", "G17/G18/G19 to another plane in G68 mode"),
    ErrorCode("incremental-after-g69", "the first move after G69 in G91"),
    ErrorCode("bad-scale-factor", "G51 factor 0 or beyond 0.001..99.999", "110"),
    ErrorCode("bad-rotation-angle", "G68 R beyond ±360"),
    ErrorCode("g51-not-alone", "G51 with another G, M, F, S, T, H, D word"),
    ErrorCode("polar-arc-needs-r", "G02/G03 with I/J/K in G16"),
    ErrorCode("bad-reference", "G29 with no stored point, G30 P not 2-4", "46"),
    ErrorCode("reference-check-failed", "G27 off the reference", "46"),
    ErrorCode("g31-in-cutter-compensation", "G31 in G41/G42", "36"),
    ErrorCode("bad-parameter", "G10 L50 value out of a known parameter's range"),
    ErrorCode("bad-corner", "chamfer/corner R restrictions (§3.2.11, §3.2.16)"),
    ErrorCode("travel-limit", "the path leaves the machine's travel (only with `machine=` / `--machine`): "
              "line ends, and arcs also at the axis extremes they pass; stored stroke limit 1, + side (500) "
              "or − side (501)", "500 / 501"),
    ErrorCode("cycle-group01", "G00-G03 in the block of a canned-cycle code", "61"),
    ErrorCode("cycle-missing-data", "a drilling block without a stored R or Z", "61"),
    ErrorCode("cycle-missing-q", "G73/G83 without Q (or Q0)", "45"),
    ErrorCode("cycle-levels", "bottom not below R; G87 back boring with Z not above R, G87 variant I with Z "
              "not below R; G126/G127 Z not below R", "61"),
    ErrorCode("cycle-not-allowed", "G27-G30 (44), G10, a drilling-axis change (FXY = 1) in canned-cycle mode",
              "44 / 61"),
    ErrorCode("cycle-conflict", "G120-G123 with a cycle code in one block, or while G110-G137 is active",
              "61"),
    ErrorCode("cycle-argument", "special-cycle and pattern arguments (I, J, L, W, Q, V, U, D, E, K, G17); "
              "G76/G87 I/J along the drilling axis (SIJ)", "210-228, 225, 61"),
    ErrorCode("cycle-too-long", "a cycle block that would make more than 100 000 pecks, passes or holes "
              "(pecks × K repeats × pattern holes)", "61"),
    ErrorCode("rigid-tap", "M29 rules: S or an axis move before G74/G84, M29 twice, a non-tapping cycle; F "
              "above P1225 (61); S above P2141/P2142 (200)", "61 / 200"),
    ErrorCode("bad-cycle", "K not a whole number 0..99999", "61"),
    ErrorCode("bad-g05", "G05 without P10000/P0, or not alone in its block"),
    ErrorCode("nurbs-outside-hpcc", "G06.2 without G05 P10000; a move in G06.2 mode after G05 P0"),
    ErrorCode("nurbs-in-compensation", "G06.2 while G41/G42 is in force (§3.2.5)"),
    ErrorCode("nurbs-start-point", "the first control point is not the current position (§3.2.5)"),
    ErrorCode("nurbs-bad-rank", "G06.2 P (the rank) not 2-4"),
    ErrorCode("nurbs-bad-knot", "a decreasing NURBS knot"),
    ErrorCode("nurbs-bad-weight", "a NURBS weight ≤ 0, or the weights of one curve more than a factor 1e6 "
              "apart"),
    ErrorCode("nurbs-missing-knot", "a block without K; a control point after the knot-only blocks"),
    ErrorCode("nurbs-axes", "an axis not named in the first control point (§3.2.5)"),
    ErrorCode("nurbs-forbidden", "G, M, S, T, F, P, D, H … in NURBS mode (§3.2.5)"),
    ErrorCode("nurbs-incomplete", "a group-01 code, G06.2, G05 or the program end before the curve's "
              "knot-only blocks"),
    ErrorCode("nurbs-bad-curve", "knots not clamped, too few control points (`NurbsCurve`'s checks)"),
    ErrorCode("nurbs-too-long", "a curve of more than P1407 = 200 blocks"),
    ErrorCode("nurbs", "a NURBS block after a complete curve without G06.2; G06.2 in G16"),
)

_DIN = _scoped(
    Scope.DIN,
    ErrorCode("syntax", "a word, expression, header or control block that does not read (the message says "
              "what and where)"),
    ErrorCode("bad-character", "a character outside the controller's ASCII set"),
    ErrorCode("unknown-address", "a letter that is not an address (`O10`, `E5`)"),
    ErrorCode("math-error", "division or MOD by zero, LN/LOG of x ≤ 0, SQRT of x < 0, ASIN/ACOS outside ±1, "
              "TAN at ±90°, an overflow"),
    ErrorCode("bad-parameter", "a computed parameter number that is not a whole number 0…9999"),
    ErrorCode("program-structure", "blocks before the first `%`, a local subroutine after the main program, "
              "two main programs, a `%L<n>` twice, subroutines without a main program"),
    ErrorCode("control-structure", "unbalanced `$` blocks, `$CASE`/`$BREAK`/`$CONTINUE` out of place, a "
              "block between `$SWITCH` and its first `$CASE`, `$FOR` with step 0"),
    ErrorCode("bad-call", "a local subroutine calling a local subroutine"),
    ErrorCode("program-not-found", "`LL<n>` without `%L<n>` in the file, `L<n>` without a file named n"),
    ErrorCode("bad-subroutine-end", "M29 in the main program; a global subroutine that ends without M29"),
    ErrorCode("nesting", "an 11th subroutine level"),
    ErrorCode("soft-limit", "a segment beyond a G98/G99 software limit; G98 above G99"),
    ErrorCode("bad-homing", "G74 without axes or with an index below 1"),
    ErrorCode("tro-direct-change", "G41 ↔ G42 without G40"),
    ErrorCode("tro-deselect-no-travel", "G40 without a travel in the plane"),
    ErrorCode("tro-no-d", "G41/G42 without a D"),
    ErrorCode("mirror-in-tro", "G20-G23 while TRO is on"),
    ErrorCode("bad-tool", "a tool-table function's D number outside 1…40"),
    ErrorCode("unknown-function", "a run-data function or write command this controller has no data or "
              "meaning for"),
)

_FANUC = _scoped(
    Scope.FANUC,
    ErrorCode("engrave-no-text", "G47 P0 without a comment to engrave, G47 P1 without a `(####)` comment"),
    ErrorCode("bad-engrave", "G47: P not 0, 1 or an ASCII code 32-126, too many characters, one outside the "
              "font, in G91 or cutter compensation, a height ≤ 0, the depth not below R, a plunge feed ≤ 0"),
)

_SYNTEC = _scoped(
    Scope.SYNTEC,
    ErrorCode("hshp-compensation", "G05 P0 with tool compensation in force (§G05 condition 2)"),
    ErrorCode("hshp-m-code", "an M code other than M30/M99 in high-speed, high-precision mode G05"),
    ErrorCode("hshp-no-end", "the program ends in G05 mode without M30 or M99 (§G05 condition 3)"),
    ErrorCode("bad-smoothing", "G05.1: Q0 with E, an allowed path error E ≤ 0"),
    ErrorCode("smoothing-in-exact-stop", "G05.1 Q1 under G61/G63 (§G05.1 condition 1)"),
    ErrorCode("css-no-diameter", "G96 constant surface speed without a D offset giving the tool radius"),
    ErrorCode("thread-speed", "G33 spindle speed outside 1 r/min … the maximum cutting feed / lead"),
    ErrorCode("pattern-no-cycle", "a hole pattern without a stored canned cycle"),
    ErrorCode("g37-no-z", "G37/G37.1 without Z (MAR-330)"),
    ErrorCode("g37-start-point", "G37: the tool below the probe's starting point (MAR-333)"),
    ErrorCode("g37-early-signal", "G37: the probe fires above the starting point (MAR-335)"),
    ErrorCode("g37-no-signal", "G37: the probe does not fire by the end point (MAR-336)"),
)

_H4CM = _scoped(
    Scope.H4CM,
    ErrorCode("block-too-long", "more than 64 characters in one block (§2.3.6, ERROR 8)"),
    ErrorCode("arc-mode", "a block after an arc that is not G00 or G01 (§3.5)"),
    ErrorCode("arc-r-sweep", "an R arc whose sweep is not within -10°…+10° or 179°…181° (§3.5)"),
    ErrorCode("comp-d-change", "a new D while radius compensation is on (§3.40)"),
    ErrorCode("comp-switch", "G41 ↔ G42 without G40 (§3.40)"),
    ErrorCode("comp-not-cancelled", "a canned cycle or a code that needs compensation off, with G41/G42 on"),
    ErrorCode("groove-absolute-only", "G22-G25 in G91 (§3.29-§3.32)"),
    ErrorCode("call-with-position", "an M98 block with a position word (§3.39.2)"),
    ErrorCode("part-count-limit", "the part counter #170 reached its limit (ERROR 03)"),
)

_MOTION = _scoped(
    Scope.MOTION,
    ErrorCode("motion.no_feed", "a cutting move without a positive feed reaches the motion stage"),
    ErrorCode("motion.no_rotary_axis", "the tool path moves a rotary axis the machine does not have"),
)

_NOTE = _scoped(
    Scope.NOTE,
    ErrorCode("leader-skipped", "the leader section before a first `%` line is not read"),
    ErrorCode("after-end-of-tape", "the lines after the end-of-tape `%` are not read"),
    ErrorCode("mixed-decimal-point", "warning: one axis has words with and without a decimal point (a "
              "program written for calculator-type input?)"),
    ErrorCode("uncalled-program", "a program of the file was never called"),
    ErrorCode("machine-function", "an M code not on the machine's list, run as a machine function without "
              "motion"),
    ErrorCode("smoothing-ineffective", "Syntec G05.1 without Q, or Q1 without E: smoothing unchanged"),
    ErrorCode("rotation-centre-ignored", "Syntec G68 centre words in G91: the centre is the start point"),
)

#: Every registered code under every scope it has, in docs order.
ERROR_CODES: tuple[ErrorCode, ...] = _GCODE + _DIN + _FANUC + _SYNTEC + _H4CM + _MOTION + _NOTE
#: The set of registered codes.
CODES: frozenset[str] = frozenset(e.code for e in ERROR_CODES)

#: The environment variable that turns on the run-time check (the test suite sets it).
STRICT_ENV = "CNC_GYM_STRICT_CODES"
_STRICT = os.environ.get(STRICT_ENV) == "1"


class UnregisteredCodeError(AssertionError):
    """A code raised or noted that is not in :data:`ERROR_CODES` (only under ``CNC_GYM_STRICT_CODES=1``)."""


def check(code: str) -> None:
    """Under ``CNC_GYM_STRICT_CODES=1``, fail on a code that is not registered; otherwise nothing."""
    if _STRICT and code not in CODES:
        raise UnregisteredCodeError(f"error code {code!r} is not in cnc_gym/error_codes.py")


def codes_of(scope: Scope) -> tuple[ErrorCode, ...]:
    """The entries of one scope, in registry order."""
    return tuple(e for e in ERROR_CODES if e.scope is scope)


#: Dialect names of the scopes of one dialect, as the docs table shows them.
_DIALECT_NAMES = {Scope.FANUC: "fanuc", Scope.SYNTEC: "syntec", Scope.H4CM: "h4cm"}


def _cell(text: str) -> str:
    return text.replace("|", "\\|")


def markdown_table(*scopes: Scope) -> str:
    """The docs table of the codes of ``scopes``: ``Code | Meaning | GSK alarm`` for :attr:`Scope.GCODE`,
    ``Code | Dialect | Meaning`` for several dialects' scopes, else ``Code | Meaning``."""
    entries = [e for scope in scopes for e in codes_of(scope)]
    if scopes == (Scope.GCODE,):
        rows = ["| Code | Meaning | GSK alarm |", "|---|---|---|"]
        rows += [f"| `{e.code}` | {_cell(e.meaning)} | {e.gsk25i_alarm or '—'} |" for e in entries]
    elif len(scopes) > 1:
        rows = ["| Code | Dialect | Meaning |", "|---|---|---|"]
        rows += [f"| `{e.code}` | `{_DIALECT_NAMES[e.scope]}` | {_cell(e.meaning)} |" for e in entries]
    else:
        rows = ["| Code | Meaning |", "|---|---|"]
        rows += [f"| `{e.code}` | {_cell(e.meaning)} |" for e in entries]
    return "\n".join(rows)
