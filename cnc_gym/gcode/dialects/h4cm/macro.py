"""The H4C-M's program flow: G65 macro instructions, M98/M99 subprograms and the part counter (HUST H4C-M
manual §3.41 G65, §3.39 M98/M99, §3.9.3 the counter).

**G65 Lm P#i A#j B#k** is one integer operation per block over #1-#9999 (``variables.py``); the reader
makes the block a statement ``("hust", m, p, a, b)`` and :class:`HustRunner` executes it. Operands are
``("const", n)`` or ``("var", j, sign)`` (``A-#2`` negates). The operations (Table 3-3, :data:`OPERATIONS`):

===========  ======================================================================================
L1-L7        assign, add, subtract, multiply, divide (truncated), fill #i…#(i+k-1) with #j, copy k
             variables from #j on to #i on
L11-L17      OR, AND, XOR, rotate left/right in 16 bits (the bits above 16 and the sign stay), shift
             left/right
L21-L26      square root (truncated), absolute value, remainder (sign of the dividend), #i = #i×#j/#k
L31-L34      #j×sin(#k), #j×cos(#k), atan(#j/#k); angles in 0.01° (4500 = 45°), results truncated
L50-L56      read a PLC register R, the I/O/C/S/A bit areas (16 bits per #j), a counter
L60, L66     write a PLC register R(#i), a counter(#i): the index is the value held in #i
L80-L86      jump to label P unconditionally, if #j =, ≠, >, <, ≥, ≤ #k
L99          user alarm: P1-P49 → ERROR 50+P, any other P → ERROR 50
===========  ======================================================================================

The PLC (L50-L66) is simulated: registers and counters start from ``H4cmOptions.plc_registers`` /
``plc_counters`` (zero by default) and keep what the program writes; the bit areas are
``H4cmOptions.plc_bits`` (all off by default), the inputs of a machine at rest. Any other L is ERROR 13.

**M98 P L**: program O0-O999, L repeats (default 1), nesting at most 5 (ERROR 24). **M99** returns; in the
main program it restarts the program on the controller (``main_m99="restart"``) and ends the run by
default (one pass is one part). Every M02, M30 and main-program M99 adds one part; when the count reaches
the limit (#170, G10 P200) a restarting program stops with ERROR 03.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING

from cnc_gym.gcode.dialects.h4cm.options import data
from cnc_gym.gcode.dialects.h4cm.reader import BRANCHES, USER_ALARM, label_text
from cnc_gym.gcode.lang.fanuc.flow import FlowRunner

if TYPE_CHECKING:
    from cnc_gym.gcode.codes import CodeSpec
    from cnc_gym.gcode.dialect import Seam
    from cnc_gym.gcode.program import Block

#: Each operation's name and the operands it takes (P result, A, B), for messages and the operand check.
OPERATIONS: dict[int, tuple[str, str]] = {
    1: ("assign", "PA"), 2: ("add", "PAB"), 3: ("subtract", "PAB"), 4: ("multiply", "PAB"),
    5: ("divide", "PAB"), 6: ("fill", "PAB"), 7: ("copy", "PAB"),
    11: ("OR", "PAB"), 12: ("AND", "PAB"), 13: ("XOR", "PAB"), 14: ("rotate left", "PAB"),
    15: ("rotate right", "PAB"), 16: ("shift left", "PAB"), 17: ("shift right", "PAB"),
    21: ("square root", "PA"), 22: ("absolute value", "PA"), 23: ("remainder", "PAB"),
    26: ("multiply-divide", "PAB"),
    31: ("sine", "PAB"), 32: ("cosine", "PAB"), 34: ("arc tangent", "PAB"),
    50: ("read register", "PA"), 51: ("read I bits", "PA"), 52: ("read O bits", "PA"),
    53: ("read C bits", "PA"),
    54: ("read S bits", "PA"), 55: ("read A bits", "PA"), 56: ("read counter", "PA"),
    60: ("write register", "PA"), 66: ("write counter", "PA"),
    80: ("jump", "P"), 81: ("jump if =", "PAB"), 82: ("jump if ≠", "PAB"), 83: ("jump if >", "PAB"),
    84: ("jump if <", "PAB"), 85: ("jump if ≥", "PAB"), 86: ("jump if ≤", "PAB"),
    99: ("user alarm", "P"),
}  # fmt: skip
#: L51-L55: the bit area and how many 16-bit words #j may select (I000-I023: 0-1; O000-O015: 0; …).
BIT_AREAS = {51: ("I", 1), 52: ("O", 0), 53: ("C", 15), 54: ("S", 15), 55: ("A", 15)}
_COMPARE: dict[int, Callable[[int, int], bool]] = {
    81: lambda a, b: a == b, 82: lambda a, b: a != b, 83: lambda a, b: a > b, 84: lambda a, b: a < b,
    85: lambda a, b: a >= b, 86: lambda a, b: a <= b,
}  # fmt: skip
MAX_PROGRAM = 999


def _rotate16(x: int, n: int, left: bool) -> int:
    """Rotate the low 16 bits of ``x`` by ``n``; the bits above (and so the sign) stay (49152 ROL 1 = 32769,
    -2 ROL 1 = -3, 3 ROR 1 = 32769)."""
    low = x & 0xFFFF
    n %= 16
    rotated = ((low << n) | (low >> (16 - n))) & 0xFFFF if left else ((low >> n) | (low << (16 - n))) & 0xFFFF
    return (x & ~0xFFFF) | rotated


def _trunc_div(a: int, b: int) -> int:
    """a / b truncated toward zero (the controller discards the fraction)."""
    q = abs(a) // abs(b)
    return q if (a >= 0) == (b >= 0) else -q


#: The position codes an M98 block may not hold (§3.39.2; §2.3.6: "The position codes are X, Y, Z, U, V, I W,
#: J and R"; U/V/W reach the block as X/Y/Z, the word normaliser's work).
POSITION_CODES = "XYZIJKR"

class HustRunner(FlowRunner):
    """The family's program-counter loop with G65 instructions, string labels, M98 P L and the part counter
    (module docstring)."""

    def _statement(self, block: Block, pc: int) -> int:
        stmt = block.stmt
        if stmt[0] != "hust":
            return super()._statement(block, pc)
        _, op, p, a, b = stmt
        spec = OPERATIONS.get(op)
        if spec is None:
            raise self.dialect.error(f"G65 L{op:02d}: the H4C-M has no such macro operation (L1-L7, L11-L17, "
                                     "L21-L23, L26, L31-L34, L50-L56, L60, L66, L80-L86, L99)",
                                     "unknown-code")  # fmt: skip
        name, needs = spec
        given = {"P": p, "A": a, "B": b}
        for letter in "PAB":
            if letter in needs and given[letter] is None:
                raise self.dialect.error(f"G65 L{op:02d} ({name}) needs {letter}", "missing-operand")
            if letter not in needs and given[letter] is not None:
                raise self.dialect.error(f"address {letter} has no meaning with G65 L{op:02d} ({name})",
                                         "unused-word")  # fmt: skip
        if op in BRANCHES:
            if op == 80 or _COMPARE[op](self._value(a), self._value(b)):
                return self._jump(p[1], pc - 1)
            return pc
        if op == USER_ALARM:
            i = p[1]
            number = 50 + i if 1 <= i <= 49 else 50
            raise self.dialect.error(f"user alarm G65 L99 P{i}: ERROR {number}", "user-alarm", alarm=number)
        self._compute(op, name, p[1], a, b)
        return pc

    def _value(self, operand: tuple) -> int:
        if operand[0] == "const":
            return operand[1]
        return operand[2] * int(self.core.state.variables.read(operand[1]))  # type: ignore[arg-type]

    def _compute(self, op: int, name: str, i: int, a: tuple, b: tuple | None) -> None:
        variables = self.core.state.variables
        j = self._value(a)
        k = self._value(b) if b is not None else 0
        if op == 1:
            result = j
        elif op in (2, 3, 4):
            result = j + k if op == 2 else j - k if op == 3 else j * k
        elif op in (5, 23, 26):
            if k == 0:
                raise self.dialect.error(f"G65 L{op:02d} ({name}): division by zero", "division-by-zero")
            if op == 5:
                result = _trunc_div(j, k)
            elif op == 23:
                result = j - _trunc_div(j, k) * k
            else:
                result = _trunc_div(int(variables.read(i)) * j, k)  # type: ignore[arg-type]
        elif op in (6, 7):
            self._block_move(op, name, i, a, j, k)
            return
        elif op in (11, 12, 13):
            result = j | k if op == 11 else j & k if op == 12 else j ^ k
        elif op in (14, 15):
            result = _rotate16(j, k, left=op == 14)
        elif op in (16, 17):
            if not 0 <= k <= 31:
                raise self.dialect.error(f"G65 L{op} ({name}) by {k}: the shift count is 0-31",
                                         "bad-macro-command")
            result = j << k if op == 16 else j >> k
        elif op == 21:
            if j < 0:
                raise self.dialect.error(f"G65 L21: square root of {j}", "math-domain")
            result = math.isqrt(j)
        elif op == 22:
            result = abs(j)
        elif op in (31, 32):
            angle = math.radians(k / 100.0)
            result = math.trunc(j * (math.sin(angle) if op == 31 else math.cos(angle)))
        elif op == 34:
            if j == 0 and k == 0:
                raise self.dialect.error("G65 L34: arc tangent of 0/0", "math-domain")
            result = math.trunc(math.degrees(math.atan(j / k)) * 100.0) if k else (9000 if j > 0 else -9000)
        else:
            self._plc(op, name, i, j)
            return
        variables.write(i, result)

    def _block_move(self, op: int, name: str, i: int, a: tuple, j: int, k: int) -> None:
        """L6 fill #i…#(i+k-1) with the value #j; L7 copy #(j+n) to #(i+n), n = 0…k-1 (A names a variable)."""
        variables = self.core.state.variables
        if k < 0:
            raise self.dialect.error(f"G65 L{op:02d} ({name}) B{k}: the count is not negative",
                                     "bad-macro-command")
        if op == 7 and a[0] != "var":
            raise self.dialect.error("G65 L07 (copy): A names the first source variable (A#11)",
                                     "bad-macro-command")  # fmt: skip
        values = [j] * k if op == 6 else [int(variables.read(a[1] + n)) for n in range(k)]  # type: ignore[arg-type]
        for n, value in enumerate(values):
            variables.write(i + n, value)

    def _plc(self, op: int, name: str, i: int, j: int) -> None:
        d = data(self.core)
        variables = self.core.state.variables
        if op in (50, 56, 60, 66):
            index = j if op in (50, 56) else int(variables.read(i))  # type: ignore[arg-type]
            if not 0 <= index <= 255:
                raise self.dialect.error(f"G65 L{op} ({name}): index {index} is outside 0-255",
                                         "bad-macro-command")
            store = d.registers if op in (50, 60) else d.counters
            if op in (50, 56):
                variables.write(i, store.get(index, 0))
            else:
                store[index] = j
            return
        area, top = BIT_AREAS[op]
        if not 0 <= j <= top:
            raise self.dialect.error(f"G65 L{op} ({name}) A{j}: the word number is 0-{top}",
                                     "bad-macro-command")
        bits = self.core.dialect.options.plc_bits.get(area, 0)
        variables.write(i, (bits >> (16 * j)) & 0xFFFF)

    def _jump(self, key: int, here: int) -> int:
        unit = self.frames[-1].unit
        target = unit.find(key, here + 1)
        if target is None:
            label = label_text(key)
            raise self.dialect.error(f"G65 jump to {label}: no block {label} in {unit.name} "
                                     "(labels match as written: P0010 finds N0010, not N10)",
                                     "sequence-not-found")  # fmt: skip
        return target

    # ------------------------------------------------------------------ M98 / M99, the part counter
    def subprogram_call(self, values: dict) -> None:
        """``M98 P<program> [L<repeats>]`` (§3.39): no other position words in the block."""
        if "P" not in values:
            raise self.dialect.error("M98 needs P (the program number)", "missing-program-number")
        named = [letter for letter in POSITION_CODES if letter in values]
        if named:
            raise self.dialect.error(f"M98 with {', '.join(named)}: the M98 block can not contain any "
                                     "position code (HUST H4C-M manual §3.39.2); move in a block of its own",
                                     "call-with-position")  # fmt: skip
        p = values["P"]
        if p != int(p) or not 0 <= p <= MAX_PROGRAM:
            raise self.dialect.error(f"M98 P{p:g}: P is a program number 0-{MAX_PROGRAM} (repeats: L)",
                                     "bad-call")
        count = values.get("L", 1.0)
        if count != int(count) or not 1 <= count <= 9999:
            raise self.dialect.error(f"M98 L{count:g}: the repeat count is 1-9999", "bad-call")
        self.core.state.flow_request = ("call", int(p), int(count))

    def _push_subprogram(self, number: int, count: int, pc: int, *, by_code: bool,
                         local: bool = False) -> int:  # fmt: skip
        limit = self.dialect.max_subprogram_nesting
        if self._sub_depth >= limit:
            raise self.dialect.error(f"M98 P{number}: subprograms nest at most {limit} levels (HUST H4C-M "
                                     "manual §3.39.2)", "nesting")  # fmt: skip
        return super()._push_subprogram(number, count, pc, by_code=by_code, local=local)

    def _return(self, pc: int, target: int | None) -> int:
        if len(self.frames) == 1:  # M99 in the main program: one part made
            d = data(self.core)
            self._count_part()
            if self.options.main_m99 == "restart" and d.counter_limit and d.parts >= d.counter_limit:
                raise self.dialect.error(f"part counter {d.parts} reached its limit {d.counter_limit} (#170; "
                                         "G10 P201 clears it)", "part-count-limit")  # fmt: skip
        return super()._return(pc, target)

    def _count_part(self) -> None:
        data(self.core).parts += 1


def g65_from_variable(core: Seam, spec: CodeSpec, values: dict) -> None:
    """G65 reached the core: its code came from a variable (``G#1``), which a macro instruction cannot."""
    raise core.error("G65 must be written as G65 Lm P#i A#j B#k (a macro instruction), not taken from a "
                     "variable", "bad-macro-command")  # fmt: skip


ACTIONS = {"hust_g65": g65_from_variable}
