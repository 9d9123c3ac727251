"""Controller parameters written by the program: G10 L50 parameter input … G11 (GSK 25i programming manual
§3.2.9, programmable parameter input), and what the features read from them.

Inside G10 L50 mode every block is ``N<number> [P<axis>] R<value>``: parameter number, axis (P1..P5 for
an axis parameter), raw value. R takes no decimal point, so a value is an integer in the parameter's unit.
Every write is kept (:class:`~cnc_gym.gcode.state.Parameters`); the features read a parameter by its
*meaning* (:data:`MEANINGS`), which the dialect maps to its own number (``Dialect.parameter_numbers``:
GSK 25i P1051-P1053 reference positions 2-4, P1860 rotation angle, P1861/P1862 magnifications, P1880 G60
overrun, P2651-P2653 G37 feed, deceleration distance and band).

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from cnc_gym.gcode.codes import CodeSpec
    from cnc_gym.gcode.dialect import Seam
    from cnc_gym.gcode.program import Block

#: Meaning → (an axis parameter: P1..P5 per axis, unit of the raw value).
MEANINGS: dict[str, tuple[bool, float]] = {
    "reference_2": (True, 0.0001),  # 2nd-4th reference positions, 0.0001 mm per axis
    "reference_3": (True, 0.0001),
    "reference_4": (True, 0.0001),
    "rotation_angle": (False, 0.001),  # G68 without R, 0.001°
    "scale": (False, 0.001),  # G51 without P/I/J/K, 0.001×
    "scale_axis": (True, 0.001),  # G51 I/J/K omitted for an axis, 0.001×
    "positioning_overrun": (True, 0.0001),  # G60 overrun per axis, 0.0001 mm
    "measure_feed": (False, 1.0),  # G37 measurement feed, mm/min
    "measure_decel": (False, 0.0001),  # G37 deceleration distance r
    "measure_band": (False, 0.0001),  # G37 signal band e
}
#: Meanings whose parameter is refused with a P (not an axis parameter) and may not be 0.
_NOT_AXIS = frozenset({"rotation_angle", "scale"})
_NONZERO = frozenset({"scale", "scale_axis"})


def _meaning(core: Seam, number: int) -> str | None:
    for meaning, n in core.dialect.parameter_numbers.items():
        if n == number:
            return meaning
    return None


def write(core: Seam, number: int, axis: int, value: int) -> None:
    """Store one parameter write, with the checks the parameters the features read need."""
    meaning = _meaning(core, number)
    per_axis = meaning is not None and MEANINGS[meaning][0]
    if (per_axis and not 1 <= axis <= 5) or not 0 <= axis <= 5:
        raise core.error(f"parameter {number} is an axis parameter: give P1..P5", "bad-g10")
    if meaning in _NOT_AXIS and axis:  # other numbers: we do not know, P1..P5 accepted
        raise core.error(f"parameter {number} is not an axis parameter: P has no meaning", "unused-word")
    limit = core.dialect.parameter_ranges.get(number)
    if limit is not None and abs(value) > limit:
        raise core.error(f"parameter {number} value {value} is out of range ±{limit}", "bad-parameter")
    if meaning in _NONZERO and value == 0:
        raise core.error(f"parameter {number}: a magnification of 0 is not allowed", "bad-parameter")
    core.state.parameters.raw[(number, axis)] = value


def raw(core: Seam, meaning: str, axis: int | None = None) -> int | None:
    """The raw value of the parameter with ``meaning`` (``axis`` 0-based for an axis parameter), None when
    the program has not written it (or the dialect has no such parameter)."""
    number = core.dialect.parameter_numbers.get(meaning)
    if number is None:
        return None
    return core.state.parameters.raw.get((number, 0 if axis is None else axis + 1))


def value(core: Seam, meaning: str, default: float, axis: int | None = None) -> float:
    """The parameter in its unit (mm, degrees, a factor, mm/min), or ``default`` when not written."""
    stored = raw(core, meaning, axis)
    return default if stored is None else stored * MEANINGS[meaning][1]


def rotation_deg(core: Seam) -> float:
    """G68's angle when R is omitted (standard 0)."""
    return value(core, "rotation_angle", 0.0)


def scale(core: Seam, axis: int | None) -> float:
    """G51's factor when none is programmed: uniform (``axis`` None) or per axis; standard 1."""
    return value(core, "scale", 1.0) if axis is None else value(core, "scale_axis", 1.0, axis)


# ---------------------------------------------------------------------- G10 L50 … G11
def open_input(core: Seam, values: dict) -> None:
    """``G10 L50;`` opens parameter input; it must be alone in its block (§3.2.9)."""
    words = core.state.block_words
    others = [w[0] for w in words if w[0] not in "GLNO"]
    gs = [w for w in words if w[0] == "G"]
    if others or len(gs) > 1:
        raise core.error("G10 L50 must be alone in its block (GSK 25i §3.2.9)", "bad-g10")
    roles = core.dialect.roles
    if core.state.modal.get(roles.cycle_group, roles.cycle_cancel) != roles.cycle_cancel:  # type: ignore[arg-type]
        raise core.error("G10 L50 in a canned cycle: cancel it with G80 first (GSK 25i §3.2.9)", "bad-g10")
    core.state.block_hook = parameter_hook


def parameter_hook(core: Seam, block: Block) -> bool:
    """Inside G10 L50 … G11 every block is a parameter block (the state's block hook)."""
    parameter_block(core, block)
    return True


def parameter_block(core: Seam, block: Block) -> None:
    """A block inside G10 L50 mode: ``N_ R_`` or ``N_ P_ R_``, or ``G11`` (§3.2.9)."""
    # (letter, digits) or (letter, value, text), text None = an expression; a plain block keeps its N word.
    words = [w for w in block.words if w[0] not in "NO"]
    letters = [w[0] for w in words]
    end = core.dialect.roles.parameter_input_end
    if letters == ["G"] and words[0][-1] is not None and round(float(words[0][-1]) * 10) == end:
        core.state.block_hook = None
        return
    if block.number is None or not set(letters) <= {"P", "R"} or "R" not in letters:
        raise core.error("inside G10 L50 only parameter blocks N_ R_ / N_ P_ R_ and G11 are allowed "
                         "(GSK 25i §3.2.9)", "bad-g10")  # fmt: skip
    fields = {}
    wide = core.dialect.parameter_input_r
    for word in words:
        letter, text = word[0], word[-1]
        if text is None and wide is not None and isinstance(word[1], tuple) and word[1][0] == "deferred":
            text = word[1][2]  # a literal beyond the R address's range (reader.py): the parameter rule's
            if "." not in text and not wide.low <= float(text) <= wide.high:
                raise core.error(f"{letter}{text}: out of range {wide.low:.0f} to {wide.high:.0f}",
                                 "value-out-of-range", alarm=wide.alarm)  # fmt: skip
        if text is None:
            raise core.error(f"{letter} of a parameter block takes a plain number (no variable: R has no "
                             "decimal point even from a variable, GSK 25i §3.2.9)", "bad-g10")  # fmt: skip
        if "." in text:
            raise core.error(f"{letter}{text}: no decimal point in a parameter block (GSK 25i §3.2.9)",
                             "decimal-point-not-allowed")  # fmt: skip
        fields[letter] = int(float(text))
    write(core, int(block.number), fields.get("P", 0), fields["R"])


def parameter_input_end(core: Seam, spec: CodeSpec, values: dict | None = None) -> None:
    """G11 outside parameter input: the power-on state, nothing to end (inside, the block hook takes it)."""


ACTIONS = {"parameter_input_end": parameter_input_end}
