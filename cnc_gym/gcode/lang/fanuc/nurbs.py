"""G05 P10000 / G05 P0 high-precision contour control and G06.2 NURBS interpolation (manual §3.2.5).

Program format (one curve)::

    G05 P10000;                          high-precision contour control on (NURBS only runs inside it)
    G06.2 [P_] K_ X_ Y_ Z_ [R_] [F_];    first control point = the current position; P = rank 2..4 (4)
    K_ X_ Y_ Z_ [R_];                    one control point, its knot and weight (R, default 1.0) per block
    …
    K_; (rank times)                     the last `rank` knots, one knot-only block each
    G01 …  / G05 P0;                     a group-01 code ends NURBS mode; G05 P0 ends contour control

The curve is carried to the tool path as one exact :class:`~cnc_gym.toolpath.NurbsCurve` segment (kind
``nurbs``): its control points go through the active transforms and offsets (``Interpreter.to_machine``:
mirror, scaling, rotation, work offsets and tool length). An affine map of the control points maps the
curve exactly (a NURBS curve is an affine combination of its control points, since its rational basis sums
to 1), so unequal scaling gives the exact image curve too (unlike arcs, §3.2.17).

K and R of NURBS blocks are plain numbers, not lengths: ``K0.008286`` keeps its six decimals (the address
rule of K as a length would truncate it to 0.0001, §2.5) and R is a weight, never converted by G20. The
G06.2 code's ``address_rules`` carry that (dialect.py); the blocks after the G06.2 block have no code, so
this module re-reads K and R with those rules (:func:`word_value`).

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from cnc_gym.gcode.codes import gkey
from cnc_gym.gcode.program import split_words
from cnc_gym.gcode.state import CurveInProgress
from cnc_gym.toolpath.nurbs import MAX_WEIGHT_RATIO, NurbsCurve

if TYPE_CHECKING:
    from cnc_gym.gcode.codes import AddressRule, CodeSpec
    from cnc_gym.gcode.dialect import Seam

#: Words of the G06.2 block: P rank, K knot, R weight, F feed (plus the axes).
NURBS_WORDS = "PKRF"


def _error(core: Seam, message: str, code: str = "nurbs"):
    return core.error(message, code)


def word_value(core: Seam, letter: str, rule: AddressRule, words) -> float | None:
    """The value of ``letter`` in ``words`` read with ``rule`` (the code's own number format): the
    literal text, or the expression evaluated without the address's rounding. None when absent or null."""
    for word in words:
        if word[0] != letter:
            continue
        text = word[-1]
        value: float | None
        if text is not None:
            value = float(text)
        else:
            value = core.dialect.language.evaluate(word[1], core.state.variables, core.dialect, None)
            if value is None:
                return None
        if not rule.low <= value <= rule.high:
            raise core.error(f"{letter}={value:g} is out of range {rule.low:g} to {rule.high:g}",
                             "value-out-of-range")  # fmt: skip
        return value
    return None


def _reread(core: Seam, values: dict, words) -> dict:
    """``values`` with the words G06.2 gives its own number format (its CodeSpec's ``address_rules``:
    K and R plain numbers in GSK 25i) read again with that format."""
    rules = core.dialect.gcodes[core.dialect.roles.nurbs].address_rules  # type: ignore[index]
    if not rules or rules.keys().isdisjoint(values):
        return values
    out = dict(values)
    for letter, rule in rules.items():
        if letter in out:
            out[letter] = word_value(core, letter, rule, words)
    return out


# ---------------------------------------------------------------------- G05
def contour_control(core: Seam, spec: CodeSpec, values: dict) -> None:
    """``G05 P10000`` / ``G05 P0``: high-precision contour control on / off (§3.2.5). Alone in its
    block; a NURBS curve must be complete before P0."""
    others = sorted({w[0] for w in core.state.block_words} - set("GNOP"))
    if others or sum(1 for w in core.state.block_words if w[0] == "G") > 1:
        raise _error(core, "G05 must be alone in its block (G05 P10000 / G05 P0)", "bad-g05")
    p = values.get("P")
    state = core.state.nurbs
    if p == 10000:
        state.hpcc = True
    elif p == 0:
        if state.curve is not None:
            raise _error(core, f"G05 P0 before the NURBS curve of line {state.curve.line} is complete "
                         f"(it needs {state.curve.rank} knot-only blocks after its control points, "
                         "GSK 25i §3.2.5)", "nurbs-incomplete")  # fmt: skip
        state.hpcc = False
    else:
        raise _error(core, "G05 needs P10000 (high-precision contour control on) or P0 (off)"
                     if p is None else f"G05 P{p:g}: only P10000 (on) and P0 (off) exist", "bad-g05")


# ---------------------------------------------------------------------- G06.2
def start(core: Seam, spec: CodeSpec, values: dict) -> None:
    """The G06.2 block: checks, rank, feed; opens a curve (and reads its first control point)."""
    state = core.state.nurbs
    if not state.hpcc:
        raise _error(core, "G06.2 NURBS needs high-precision contour control: program G05 P10000 first "
                     "(GSK 25i §3.2.5)", "nurbs-outside-hpcc")  # fmt: skip
    if core.state.comp.side:
        raise _error(core, "G06.2 cannot be used with cutter compensation: cancel G41/G42 with G40 first "
                     "(GSK 25i §3.2.5)", "nurbs-in-compensation")  # fmt: skip
    if core.state.polar is not None:
        raise _error(core, "G06.2 in polar coordinate mode G16: cancel it with G15 first", "nurbs")
    forbidden = sorted({w[0] for w in core.state.block_words} - set("GNO" + NURBS_WORDS + core.dialect.axes))
    if forbidden:
        raise _error(core, f"address {forbidden[0]} cannot be given in a G06.2 block (GSK 25i §3.2.5: "
                     "no M, S, T, B, D, H in NURBS mode)", "nurbs-forbidden")  # fmt: skip
    rank = values.get("P", 4.0)
    if rank not in (2.0, 3.0, 4.0):
        raise _error(core, f"G06.2 P{rank:g}: the NURBS rank P is 2, 3 or 4 (GSK 25i §3.2.5)",
                     "nurbs-bad-rank")  # fmt: skip
    feed = core.state.feed
    if not feed:
        raise core.error("G06.2 needs a feed: no F programmed yet" if feed is None else
                         "G06.2 with F0: the feed is zero", "missing-feed")  # fmt: skip
    curve = CurveInProgress(int(rank), feed, core.state.out.line, core.state.out.file_index)
    state.curve = curve
    core.state.block_hook = block_hook  # every later block in G06.2 mode comes here first
    data = {k: v for k, v in _reread(core, values, core.state.block_words).items() if k not in "PF"}
    if data:
        _add_block(core, curve, data)


def block_hook(core: Seam, block) -> bool:
    """A block while G06.2 is the modal motion. True: handled here (a NURBS data block); False: run it as
    an ordinary block (one that ends NURBS mode, G05, or a block without NURBS data)."""
    if block.assign is not None:
        return False
    state = core.state.nurbs
    curve = state.curve
    if block.has_expr:
        gs, ms, values = split_words(core.evaluate_words(block.words))
    else:
        gs, ms, values = block.split()
    gcodes = core.dialect.gcodes
    if gs:
        keys = [gkey(g) for g in gs]
        if core.dialect.roles.nurbs in keys:
            if curve is not None:
                raise _error(core, f"G06.2 before the NURBS curve of line {curve.line} is complete (it "
                             f"needs {curve.rank} knot-only blocks after its control points)",
                             "nurbs-incomplete")  # fmt: skip
            return False  # a new curve: the G06.2 action starts it
        group01 = [k for k in keys if k in gcodes and gcodes[k].group == 1]
        if group01:
            if curve is not None:
                raise _error(core, f"{gcodes[group01[0]].name} before the NURBS curve of line {curve.line} "
                             f"is complete (it needs {curve.rank} knot-only blocks after its control points)",
                             "nurbs-incomplete")  # fmt: skip
            core.state.block_hook = None  # another group-01 code ends NURBS mode (§3.2.5)
            return False
        if keys == [core.dialect.roles.contour_control]:
            if curve is not None:
                raise _error(core, f"G05 before the NURBS curve of line {curve.line} is complete (it needs "
                             f"{curve.rank} knot-only blocks after its control points)",
                             "nurbs-incomplete")  # fmt: skip
            return False  # G05 P0 after a complete curve (G05 checks its P)
        name = gcodes[keys[0]].name if keys[0] in gcodes else f"G{gs[0]:g}"
        raise _error(core, f"{name} in NURBS mode: no other G code may be given until a group-01 code "
                     "(G00-G03) ends G06.2 (GSK 25i §3.2.5)", "nurbs-forbidden")  # fmt: skip
    if not state.hpcc:
        # G06.2 is still the modal motion after G05 P0, but NURBS cannot run outside contour control.
        if "K" in values or any(letter in values for letter in core.dialect.axes):
            raise _error(core, "a move in G06.2 mode after G05 P0: select G00/G01/G02/G03 (or G05 P10000 "
                         "and a new G06.2)", "nurbs-outside-hpcc")  # fmt: skip
        return False
    if ms:
        raise _error(core, "M codes cannot be given in NURBS mode (GSK 25i §3.2.5)", "nurbs-forbidden")
    for letter in values:
        if letter not in "KR" and letter not in core.dialect.axes:
            what = "the feed cannot change" if letter == "F" else f"address {letter} cannot be given"
            raise _error(core, f"{what} in NURBS mode (GSK 25i §3.2.5)", "nurbs-forbidden")
    if not values:
        return True  # N only: nothing to do
    if curve is None:
        raise _error(core, "the NURBS curve is complete: start a new one with G06.2 (or end NURBS mode "
                     "with a group-01 code)", "nurbs")  # fmt: skip
    core.state.block_words = block.words
    _add_block(core, curve, _reread(core, values, block.words))
    return True


def _add_block(core: Seam, curve: CurveInProgress, values: dict) -> None:
    """One control-point block (axes, K, optional R) or knot-only block (K) of ``curve``."""
    letters = core.dialect.axes
    named = frozenset(a for a, letter in enumerate(letters) if letter in values)
    if "K" not in values:
        raise _error(core, "every NURBS block carries its knot K (GSK 25i §3.2.5)", "nurbs-missing-knot")
    knot = values["K"]
    if curve.knots and knot < curve.knots[-1]:
        raise _error(core, f"K{knot:g} is smaller than the previous knot {curve.knots[-1]:g}: knots never "
                     "decrease (GSK 25i §3.2.5)", "nurbs-bad-knot")  # fmt: skip
    limit = core.dialect.nurbs_params.max_blocks
    if len(curve.knots) + 1 > limit:  # every block of the curve carries one knot
        raise _error(core, f"the NURBS curve of line {curve.line} has more than {limit} blocks (P1407)",
                     "nurbs-too-long")  # fmt: skip
    if named:
        if curve.knot_only:
            raise _error(core, "a control point after the knot-only blocks: the last `rank` blocks carry "
                         "only a knot (GSK 25i §3.2.5)", "nurbs-missing-knot")  # fmt: skip
        weight = values.get("R", 1.0)
        if not weight > 0.0 or not math.isfinite(weight):
            raise _error(core, f"R{weight:g}: a NURBS weight must be positive", "nurbs-bad-weight")
        low, high = min([weight, *curve.weights]), max([weight, *curve.weights])
        if high > MAX_WEIGHT_RATIO * low:
            raise _error(core, f"R{weight:g}: the weights of one NURBS curve may differ by a factor of at "
                         f"most {MAX_WEIGHT_RATIO:g} (R{low:g} beside R{high:g}): the curve could not be "
                         "evaluated to the tool path's accuracy", "nurbs-bad-weight")  # fmt: skip
        s = core.state.scale
        if curve.axes is None:
            # The first control point: all the NURBS axes are named here (§3.2.5) and it must be the
            # current position (§3.2.5).
            curve.axes = named
            here = core.program_position
            point = [here[a] if a not in named else
                     (here[a] + values[letters[a]] * s if core.state.incremental else values[letters[a]] * s)
                     for a in range(3)]  # fmt: skip
            tolerance = 0.5 * core.state.increment * s + 1e-9
            if max(abs(point[a] - here[a]) for a in range(3)) > tolerance:
                where = ", ".join(f"{letters[a]}{point[a] / s:g}" for a in sorted(named))
                now = ", ".join(f"{letters[a]}{here[a] / s:.4f}" for a in range(3))
                raise _error(core, f"the first NURBS control point ({where}) is not the current position "
                             f"({now}) (GSK 25i §3.2.5; in G91 write G06.2 X0 Y0 Z0 K_)", "nurbs-start-point")
            point = list(here)
            start = core.to_machine(here)
            tool = core.state.out.position
            if max(abs(start[a] - tool[a]) for a in range(3)) > tolerance:
                # G51/G68/G51.1 came into force since the last move: the tool is not yet at the image of
                # its program position (the transforms keep it where it is, §3.2.17).
                raise _error(core, "the tool is not at the start of the NURBS curve: a transform came into "
                             "force since the last move; move to the first control point first",
                             "nurbs-start-point")  # fmt: skip
        else:
            extra = named - curve.axes
            if extra:
                raise _error(core, f"axis {letters[min(extra)]} was not named in the first NURBS control "
                             "point: every NURBS axis is given there (GSK 25i §3.2.5)",
                             "nurbs-axes")  # fmt: skip
            prev = curve.points[-1]
            point = [prev[a] if a not in named else
                     (prev[a] + values[letters[a]] * s if core.state.incremental else values[letters[a]] * s)
                     for a in range(3)]  # fmt: skip
        curve.points.append(point)
        curve.weights.append(weight)
    else:
        if "R" in values:
            raise _error(core, "R (weight) without a control point", "nurbs-bad-weight")
        if not curve.points:
            raise _error(core, "a knot-only block before the first NURBS control point (GSK 25i §3.2.5)",
                         "nurbs-missing-knot")  # fmt: skip
        curve.knot_only += 1
    curve.knots.append(knot)
    if curve.knot_only == curve.rank:
        _finish(core, curve)


def _finish(core: Seam, curve: CurveInProgress) -> None:
    """The last knot-only block: build the exact curve in machine coordinates and emit it."""
    state = core.state.nurbs
    state.curve = None
    machine = [core.to_machine((p[0], p[1], p[2])) for p in curve.points]
    machine[0] = core.state.out.position  # the path stays joined exactly
    try:
        exact = NurbsCurve(np.array(machine, dtype=float), np.array(curve.weights), np.array(curve.knots),
                           curve.rank)  # fmt: skip
    except ValueError as exc:
        raise _error(core, f"the NURBS curve of line {curve.line}: {exc}", "nurbs-bad-curve") from None
    core.check_budget()  # curves are plain blocks: keep the run's time bound between them
    if core.state.transformed:
        last = curve.points[-1]
        core.state.program_point = (last[0], last[1], last[2])
    if exact.length <= 1e-9:
        return  # all control points at the current position: nothing to move
    out = core.state.out
    line, file_index = out.line, out.file_index
    out.line, out.file_index = curve.line, curve.file_index  # the segment belongs to the G06.2 block
    try:
        out.nurbs_feed(exact, curve.feed)
    finally:
        out.line, out.file_index = line, file_index
    state.curves += 1


def finish(core: Seam) -> None:
    """End of the program (a block hook): a G06.2 curve must be complete."""
    curve = core.state.nurbs.curve
    if curve is not None:
        raise core.error(f"the program ends before the NURBS curve of line {curve.line} is complete (it "
                         f"needs {curve.rank} knot-only blocks after its control points, GSK 25i §3.2.5)",
                         "nurbs-incomplete").located(core.state.builder.files[curve.file_index], curve.line)


ACTIONS = {"contour_control": contour_control, "nurbs": start}
