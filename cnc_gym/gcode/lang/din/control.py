"""Structured control flow of the DIN family, compiled once per program unit to jump tables (AMK AZ-MC1
programming manual §9 "Program control", §10.1 "$TIME").

The reader leaves each control block as ``(KEYWORD, *expressions)``; :func:`compile_unit` pairs the
blocks of one unit (a main program or a subroutine) and replaces each by an *op* with absolute block
indices, so the runner never searches:

=============================  ================================================================
``$IF e`` … ``$ELSEIF e`` …    ``("if", ((cond, body), …), else)``: the first true condition's body, else
``$ELSE`` … ``$ENDIF``         the ``$ELSE`` body or past ``$ENDIF``; ``$ELSEIF``/``$ELSE`` reached from
                               the branch above jump past ``$ENDIF``
``$SWITCH e`` ``$CASE e`` …    ``("switch", e, ((case, body), …), default)``: the first case equal within
``$DEFAULT`` ``$ENDSWITCH``    the dialect's tolerance; cases fall through to the next (C), ``$BREAK`` leaves
``$FOR Rn = a, b, c``          ``("for", target, a, b, c, exit)``: Rn = a, run while Rn ≤ b (c > 0) or
… ``$ENDFOR``                  Rn ≥ b (c < 0); ``$ENDFOR`` adds c and tests again (b and c are evaluated at
                               each test, as C's ``for``)
``$WHILE e`` … ``$ENDWHILE``   tested before each pass
``$DO`` … ``$ENDDO e``         tested after each pass; runs again while e is true
``$BREAK``, ``$CONTINUE``      ``("jump", target)``: past the innermost loop or switch; to the test of the
                               innermost loop (``$FOR``: its increment)
``$TIME e``                    ``("time", e)``: dwell e seconds
=============================  ================================================================

Unbalanced structures, a ``$CASE`` outside a ``$SWITCH``, ``$BREAK``/``$CONTINUE`` outside a loop are
``control-structure`` errors at read time, naming the line.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from cnc_gym.errors import ProgramError

if TYPE_CHECKING:
    from cnc_gym.gcode.program import Program

#: The control statements, as the manual lists them (§9, §10).
LISTED = ("IF", "ELSEIF", "ELSE", "ENDIF", "SWITCH", "CASE", "DEFAULT", "ENDSWITCH", "FOR", "ENDFOR", "WHILE",
          "ENDWHILE", "DO", "ENDDO", "BREAK", "CONTINUE", "TIME")  # fmt: skip
#: Other spellings the manual uses once (§9.1.1 writes ``$ELSIF``).
ALIASES = {"ELSIF": "ELSEIF"}
KEYWORDS = frozenset(LISTED) | frozenset(ALIASES)
#: Statements followed by one expression.
WITH_EXPRESSION = frozenset({"IF", "ELSEIF", "SWITCH", "CASE", "WHILE", "ENDDO", "TIME"})
_OPENERS = {"ENDIF": "IF", "ENDSWITCH": "SWITCH", "ENDFOR": "FOR", "ENDWHILE": "WHILE", "ENDDO": "DO"}
_LOOPS = frozenset({"FOR", "WHILE", "DO"})


def _error(message: str, line: int) -> ProgramError:
    return ProgramError(message, code="control-structure", line=line)


class _Open:
    """One structure being compiled: its opening block and what its closing block must patch."""

    __slots__ = ("at", "branches", "breaks", "cases", "continues", "default", "else_at", "kind")

    def __init__(self, kind: str, at: int) -> None:
        self.kind = kind
        self.at = at
        self.branches: list[tuple] = []  # IF: (cond, body); the ELSEIF/ELSE blocks to patch
        self.else_at: int | None = None
        self.cases: list[tuple] = []
        self.default: int | None = None
        self.breaks: list[int] = []  # $BREAK blocks to patch with the exit
        self.continues: list[int] = []  # $CONTINUE blocks to patch with the loop's test


def compile_unit(program: Program, start: int, end: int) -> None:
    """Pair the control blocks of ``program.blocks[start:end]`` and replace each by its op (module
    docstring). Raises ``control-structure`` ProgramError (file and line filled in)."""
    blocks = program.blocks
    stack: list[_Open] = []
    patch_jump: list[tuple[int, _Open]] = []  # ELSEIF/ELSE blocks: jump past the ENDIF
    try:
        for index in range(start, end):
            block = blocks[index]
            if block.kind != "stmt" or block.stmt[0] == "proc":
                if stack and stack[-1].kind == "SWITCH" and not stack[-1].cases and stack[-1].default is None:
                    raise _error("a block between $SWITCH and its first $CASE never runs", block.line)
                continue
            keyword, *args = block.stmt
            line = block.line
            if keyword == "IF":
                frame = _Open("IF", index)
                frame.branches.append((args[0], index + 1))
                stack.append(frame)
                block.stmt = ("pending",)
            elif keyword in ("ELSEIF", "ELSE"):
                frame = _top(stack, "IF", f"${keyword} without $IF", line)
                if frame.else_at is not None:
                    raise _error(f"${keyword} after $ELSE", line)
                if keyword == "ELSE":
                    frame.else_at = index
                else:
                    frame.branches.append((args[0], index + 1))
                patch_jump.append((index, frame))
            elif keyword == "ENDIF":
                frame = _close(stack, "IF", line)
                after = index + 1
                else_pc = frame.else_at + 1 if frame.else_at is not None else after
                blocks[frame.at].stmt = ("if", tuple(frame.branches), else_pc)
                _patch_branches(blocks, patch_jump, frame, after)
                block.stmt = ("nop",)
            elif keyword == "SWITCH":
                frame = _Open("SWITCH", index)
                frame.branches.append((args[0],))
                stack.append(frame)
                block.stmt = ("pending",)
            elif keyword in ("CASE", "DEFAULT"):
                frame = _top(stack, "SWITCH", f"${keyword} outside $SWITCH", line)
                if frame.default is not None:
                    raise _error(f"${keyword} after $DEFAULT", line)
                if keyword == "CASE":
                    frame.cases.append((args[0], index + 1))
                else:
                    frame.default = index + 1
                block.stmt = ("nop",)
            elif keyword == "ENDSWITCH":
                frame = _close(stack, "SWITCH", line)
                after = index + 1
                blocks[frame.at].stmt = ("switch", frame.branches[0][0], tuple(frame.cases),
                                         frame.default if frame.default is not None else after)  # fmt: skip
                for at in frame.breaks:
                    blocks[at].stmt = ("jump", after)
                block.stmt = ("nop",)
            elif keyword in ("FOR", "WHILE", "DO"):
                frame = _Open(keyword, index)
                frame.branches.append(tuple(args))
                stack.append(frame)
                block.stmt = ("nop",) if keyword == "DO" else ("pending",)
            elif keyword in ("ENDFOR", "ENDWHILE", "ENDDO"):
                frame = _close(stack, _OPENERS[keyword], line)
                after = index + 1
                body = frame.at + 1
                if keyword == "ENDFOR":
                    target, first, last, step = frame.branches[0]
                    blocks[frame.at].stmt = ("for", target, first, last, step, after)
                    block.stmt = ("endfor", target, last, step, body)
                    test = index
                elif keyword == "ENDWHILE":
                    blocks[frame.at].stmt = ("while", frame.branches[0][0], after)
                    block.stmt = ("jump", frame.at)
                    test = frame.at
                else:
                    block.stmt = ("enddo", args[0], body)
                    test = index
                for at in frame.breaks:
                    blocks[at].stmt = ("jump", after)
                for at in frame.continues:
                    blocks[at].stmt = ("jump", test)
            elif keyword == "BREAK":
                frame = _innermost(stack, _LOOPS | {"SWITCH"}, "$BREAK outside a loop or $SWITCH", line)
                frame.breaks.append(index)
                block.stmt = ("pending",)
            elif keyword == "CONTINUE":
                frame = _innermost(stack, _LOOPS, "$CONTINUE outside a loop", line)
                frame.continues.append(index)
                block.stmt = ("pending",)
            elif keyword == "TIME":
                block.stmt = ("time", args[0])
            else:  # pragma: no cover - the reader admits only the keywords above
                raise _error(f"${keyword} is not a control statement", line)
        if stack:
            frame = stack[-1]
            closer = next(k for k, v in _OPENERS.items() if v == frame.kind)
            raise _error(f"${frame.kind} is not closed by ${closer} before the end of its program",
                         blocks[frame.at].line)  # fmt: skip
    except ProgramError as err:
        raise err.located(program.file, err.line) from None


def _patch_branches(blocks, patch_jump: list[tuple[int, _Open]], frame: _Open, after: int) -> None:
    for at, owner in patch_jump:
        if owner is frame:
            blocks[at].stmt = ("jump", after)
    patch_jump[:] = [(at, owner) for at, owner in patch_jump if owner is not frame]


def _top(stack: list[_Open], kind: str, message: str, line: int) -> _Open:
    if not stack or stack[-1].kind != kind:
        if stack:
            message += f" (the open structure is ${stack[-1].kind})"
        raise _error(message, line)
    return stack[-1]


def _close(stack: list[_Open], kind: str, line: int) -> _Open:
    closer = next(k for k, v in _OPENERS.items() if v == kind)
    if not stack:
        raise _error(f"${closer} without ${kind}", line)
    if stack[-1].kind != kind:
        raise _error(f"${closer} closes ${kind}, but the open structure is ${stack[-1].kind}", line)
    return stack.pop()


def _innermost(stack: list[_Open], kinds: frozenset[str], message: str, line: int) -> _Open:
    for frame in reversed(stack):
        if frame.kind in kinds:
            return frame
    raise _error(message, line)
