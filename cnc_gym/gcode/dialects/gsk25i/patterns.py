"""The GSK 25i hole patterns and face milling: G120-G125 (bolt circle, line, arc, grid, rectangle) and
G126/G127 (zig-zag and one-way face milling) (GSK 25i programming manual §3.6, the special canned cycles).

One-shot codes: G120-G125 drill every hole with the modal canned cycle (only positioning when none is
active); G124/G125 take the drilling code of their own block; G126/G127 face-mill. The geometry is pure
(:func:`pattern_holes`, :func:`rectangle_holes`, :func:`face_mill_steps`); the holes are drilled through
the Fanuc family's modal cycle (``lang/fanuc/cycles.py``).

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from cnc_gym.gcode.lang.fanuc import compensation
from cnc_gym.gcode.lang.fanuc.cycles import Step, cycle_block, emit, limit

if TYPE_CHECKING:
    from cnc_gym.gcode.codes import CodeSpec
    from cnc_gym.gcode.dialect import BlockPlan, Seam

#: Words of the pattern codes.
PATTERN_WORDS = {120: "IJK", 121: "IJK", 122: "IJPK", 123: "IJPK", 124: "RIJPK", 125: "RIJPK", 126: "RIJL",
                 127: "RIJL"}  # fmt: skip


def pattern_holes(code: int, x: float, y: float, *, i: float = 0.0, j: float = 0.0, k: int = 0,
                  p: float = 0.0) -> list[tuple[float, float]]:  # fmt: skip
    """Hole positions (XY, mm) of G120-G123 (§3.6.1-§3.6.4). Angles in degrees.

    G120 bolt circle: centre (x, y), radius i, first angle j, k holes 360°/k apart.
    G121 line: start (x, y), spacing i (negative = the other way), angle j, k holes including the start.
    G122 arc: centre (x, y), radius i, first angle j, angular step p (CCW +), k holes.
    G123 grid: start (x, y), Δx i, nx = p holes, Δy j, ny = k rows, row by row alternating direction.
    """
    if code == 120:
        step = 360.0 / k
        return [(x + i * math.cos(math.radians(j + n * step)), y + i * math.sin(math.radians(j + n * step)))
                for n in range(k)]  # fmt: skip
    if code == 121:
        c, s = math.cos(math.radians(j)), math.sin(math.radians(j))
        return [(x + n * i * c, y + n * i * s) for n in range(k)]
    if code == 122:
        return [(x + i * math.cos(math.radians(j + n * p)), y + i * math.sin(math.radians(j + n * p)))
                for n in range(k)]  # fmt: skip
    if code == 123:
        holes: list[tuple[float, float]] = []
        nx = int(p)
        for row in range(k):
            cols = range(nx) if row % 2 == 0 else range(nx - 1, -1, -1)
            holes.extend((x + col * i, y + row * j) for col in cols)
        return holes
    raise ValueError(code)


def rectangle_holes(x: float, y: float, side1: float, side2: float, n1: int, n2: int, ccw: bool,
                    ) -> list[tuple[float, float]]:  # fmt: skip
    """G124 (CW) / G125 (CCW) rectangle drilling: first corner (x, y), side 1 along +X of length
    ``side1``, side 2 of length ``side2`` turning right (CW) or left (CCW). Sides 1 and 3 carry ``n1``
    holes, sides 2 and 4 ``n2``; a side's holes start at its first corner and are ``length / n`` apart
    (its end corner is the next side's first hole). docs/gcode.md explains this reading."""
    turn = 1.0 if ccw else -1.0
    corners = [(x, y), (x + side1, y), (x + side1, y + turn * side2), (x, y + turn * side2)]
    holes: list[tuple[float, float]] = []
    for side, count in enumerate((n1, n2, n1, n2)):
        (ax, ay), (bx, by) = corners[side], corners[(side + 1) % 4]
        holes.extend((ax + (bx - ax) * n / count, ay + (by - ay) * n / count) for n in range(count))
    return holes


def face_mill_steps(x: float, y: float, width_x: float, width_y: float, step: float, level: float,
                    r_level: float, initial: float, feed: float, zigzag: bool) -> list[Step]:  # fmt: skip
    """G126 (zig-zag) / G127 (one-way) face milling (§3.6.6): passes along X of length
    ``width_x`` from (x, y), stepping ``step`` toward +Y (or -Y for a negative width) until ``width_y``
    is covered; the last pass lies exactly on ``y + width_y``. One-way: rapid up to R, back, feed down."""
    n = max(1, math.ceil(abs(width_y) / step - 1e-9))
    ys = [y + width_y * m / n for m in range(n + 1)]
    steps: list[Step] = [("rapid", (x, y, None)), ("rapid", (x, y, r_level)),
                         ("feed", (x, y, level), feed, False)]  # fmt: skip
    forward = True
    for index, py in enumerate(ys):
        if index:
            if zigzag:  # step over at the end of the previous pass
                steps.append(("feed", (steps[-1][1][0], py, level), feed, False))
            else:  # one way: up to R, back to the start side, down again
                steps.append(("rapid", (x + width_x, ys[index - 1], r_level)))
                steps.append(("rapid", (x, py, r_level)))
                steps.append(("feed", (x, py, level), feed, False))
        steps.append(("feed", (x + width_x if forward else x, py, level), feed, False))
        if zigzag:
            forward = not forward
    last = steps[-1][1]
    steps.append(("rapid", (last[0], last[1], r_level)))
    steps.append(("rapid", (last[0], last[1], initial)))
    return steps


def _angle(core: Seam, letter: str, values: dict) -> float:
    """Pattern angles: with a decimal point in degrees, without one in 0.001° (§3.6)."""
    text = core.word_text(letter)
    value = values[letter]
    if text is not None and "." not in text:
        return value / 1000.0
    return value


def _count(core: Seam, letter: str, values: dict, code: int, *, required: bool) -> int:
    if letter not in values:
        if required:
            raise core.error(f"G{code} needs {letter} (number of holes, 1..9999)", "cycle-argument",
                             alarm=225)  # fmt: skip
        return 0
    n = values[letter]
    if code in (124, 125):
        return max(0, int(n))  # negatives invalid, decimals truncated (§3.6.6)
    if n != int(n) or not 1 <= n <= 9999:
        raise core.error(f"G{code} {letter}{n:g}: the number of holes must be 1..9999", "cycle-argument",
                         alarm=225)  # fmt: skip
    return int(n)


def pattern_block(core: Seam, code: int, values: dict, cycle_spec: CodeSpec | None) -> None:
    """G120-G127 (one-shot). G120-G125 drill every hole with the modal canned cycle (only positioning
    when none is active); G124/G125 take the cycle code of their own block; G126/G127 face-mill."""
    state = core.state.cycle
    if code <= 123 and state.kind is not None and state.kind.special:
        # "G110 ... G137 isn't with the function of continuous drilling holes" (§3.6.6): the patterns
        # drill with the standard cycles only (§3.6), never a pocket per hole.
        raise core.error(f"G{code} while the special cycle {state.spec.name} is modal: the hole "  # type: ignore[union-attr]
                         "patterns drill with G73-G89 only; cancel it with G80", "cycle-conflict",
                         alarm=61)  # fmt: skip
    if core.state.comp.side:
        # the radius offset is ignored by the cycles (§3.4.1): see cycles.cycle_block
        compensation.before_machine_move(core)
    s = core.state.scale
    here = core.program_position
    target = core.resolve_target(values.get("X"), values.get("Y"), None)
    x = here[0] if target[0] is None else target[0]
    y = here[1] if target[1] is None else target[1]
    if code in (126, 127):
        for letter in "IJLZR":
            if letter not in values:
                raise core.error(f"G{code} needs {letter}", "cycle-argument", alarm=61)
        step = values["L"] * s
        if step <= 0:
            raise core.error(f"G{code}: L (step over) must be > 0", "cycle-argument", alarm=219)
        initial = here[2]
        r_level = values["R"] * s + (initial if core.state.incremental else 0.0)
        level = values["Z"] * s + (r_level if core.state.incremental else 0.0)
        if level >= r_level:
            raise core.error(f"G{code}: the milling level Z must lie below R", "cycle-levels", alarm=61)
        feed = core.state.feed
        if not feed:
            raise core.error(f"G{code} needs a feed", "missing-feed")
        limit(core, abs(values["J"] * s) / step, f"G{code} passes (J / L)")
        emit(core, face_mill_steps(x, y, values["I"] * s, values["J"] * s, step, level, r_level, initial,
                                   feed, zigzag=code == 126))  # fmt: skip
        return
    if code in (124, 125):
        kind = core.dialect.cycles.get(str(cycle_spec.value)) if cycle_spec is not None else None
        if kind is None or kind.special or kind.shifting:
            raise core.error(f"G{code} needs a drilling-mode G code (G73 G74 G81-G86 G88 G89) in its block",
                             "cycle-argument", alarm=61)  # fmt: skip
        if "J" not in values:
            raise core.error(f"G{code} needs J (length of sides 2 and 4)", "cycle-argument", alarm=216)
        # The block's cycle code, R, Z, Q, P, F are the modal cycle data (stored without drilling).
        data = {k: v for k, v in values.items() if k in "RZQ"}  # P and K are the hole counts here
        data["K"] = 0.0  # store only: the pattern drills the holes
        cycle_block(core, cycle_spec, data)
        n13 = _count(core, "P", values, code, required=False)
        n24 = _count(core, "K", values, code, required=False)
        holes = rectangle_holes(x, y, values.get("I", 0.0) * s, values["J"] * s, n13, n24, ccw=code == 125)
        moves_cutting = core.dialect.cycle_params.pattern_moves_cutting
    else:
        k = _count(core, "K", values, code, required=True)
        for letter in ("I", "J") if code != 123 else ("I", "J", "P"):
            if letter not in values:
                raise core.error(f"G{code} needs {letter}", "cycle-argument", alarm=61)
        if code == 120 and values["I"] <= 0:
            raise core.error("G120: the radius I must be positive", "cycle-argument", alarm=215)
        if code == 122 and "P" not in values:
            raise core.error("G122 needs P (angular step)", "cycle-argument", alarm=61)
        if code == 123:
            limit(core, k * values["P"], "G123 holes (P x K)")
            holes = pattern_holes(123, x, y, i=values["I"] * s, j=values["J"] * s, k=k,
                                  p=float(_count(core, "P", values, code, required=True)))  # fmt: skip
        else:
            holes = pattern_holes(code, x, y, i=values["I"] * s, j=_angle(core, "J", values), k=k,
                                  p=_angle(core, "P", values) if code == 122 else 0.0)  # fmt: skip
        moves_cutting = False
    _drill_holes(core, holes, last_uses_return=code in (124, 125), moves_cutting=moves_cutting)


def _drill_holes(core: Seam, holes: list[tuple[float, float]], *, last_uses_return: bool,
                 moves_cutting: bool) -> None:  # fmt: skip
    """Drill each hole with the modal cycle, or only position when no cycle is active (§3.5.7).
    ``last_uses_return``: G124/G125 return to R between holes, G98/G99 only after the last (§3.6.6)."""
    st = core.state
    state = st.cycle
    roles = core.dialect.roles
    group = roles.return_group
    saved_return = st.modal.get(group)  # type: ignore[arg-type]
    try:
        for index, (hx, hy) in enumerate(holes):
            if moves_cutting and index:
                emit(core, [("feed", (hx, hy, None), core.state.feed, False)])
            if state.spec is None:
                emit(core, [("rapid", (hx, hy, None))])
                continue
            if last_uses_return and index < len(holes) - 1:
                st.modal[group] = roles.return_r  # type: ignore[index,assignment]
            else:
                st.modal[group] = saved_return  # type: ignore[index,assignment]
            cycle_block(core, None, {}, hole_xy=(hx, hy), holes=len(holes))
    finally:
        if saved_return is not None:
            st.modal[group] = saved_return  # type: ignore[index]


def pattern(core: Seam, spec: CodeSpec, values: dict) -> None:
    """The action of G120-G127 (``spec.value`` is the G number)."""
    pattern_block(core, spec.value, values, core.state.cycle.block_spec)  # type: ignore[arg-type]


def check_block(core: Seam, plan: BlockPlan) -> CodeSpec | None:
    """A pattern and a cycle code in one block (block check): G124/G125 take the cycle code as their
    drilling mode (and the axis words); with G120-G123 it is an error (ours: the manual ignores the cycle
    code, §3.6.2)."""
    roles = core.dialect.roles
    cycle_spec = plan.by_group.get(roles.cycle_group)  # type: ignore[arg-type]
    if cycle_spec is None or cycle_spec.action != "cycle":
        return plan.axis_owner
    found = next((spec for spec in plan.items if spec.uses_axes and spec.action == "pattern"), None)
    if found is None:
        return plan.axis_owner
    if found.value not in (124, 125):
        raise core.error(f"{found.name} and the canned cycle {cycle_spec.name} in one block",
                         "cycle-conflict", alarm=61)  # fmt: skip
    core.state.cycle.block_spec = cycle_spec
    plan.items.remove(cycle_spec)
    return found


ACTIONS = {"pattern": pattern}
