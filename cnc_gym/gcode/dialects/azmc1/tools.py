"""The AZ-MC1's tool offsets, arcs and tool management (AMK AZ-MC1 programming manual §3.1.3, §11, §12).

**Tool offset record, D.** ``D<n>`` (n = 1..40) selects a record of tool length and radius; D00 deselects
(§11.1). There is no G43/H: the D word alone puts the length in force, along the tool axis of the plane
(G17 Z, G18 Y, G19 X), carried by that axis's first move (§11.2: "calculated for each axis only if a travel
has been programmed with this axis"). The record's length is the offset memory's H entry of the same number
and its radius the D entry (``tool_offsets={"H": {10: 50.0}, "D": {10: 5.0}}`` is D10). A new D in TRO takes
effect without a new G41/G42 (§11.3).

**Tool radius offset, TRO.** G41/G42 run on the family's compensation stage (intersections at inner
corners; straight intermediate blocks at outer ones: the offset lines' intersection up to a 90° turn, two
extension points beyond — the manual's 180°-270° and 270°-360° ranges, §11.3.2); G138 approaches directly
(to the point perpendicular to the next block's start), G139 with transition blocks (§11.3.1). Selection on
a circle, a G41↔G42 change without G40, a G40 without a travel in the plane, and G41/G42 without a D are
errors (§11.3.1, §11.3.3, §11.3.4). A contour violation — a compensated block that would run against its
programmed direction, found with the current and the next two relevant blocks — is an error at once
(``comp-interference``, §11.3.5), where the Fanuc family first corrects it.

**Arcs.** I/J/K only (R is a parameter): G162 (the basic state) relative to the start, G161 absolute in
program coordinates; the centre words are not modal (§3.1.3, §3.11).

**Tool table.** ``TLIFE[n] TWARN[n] TRES[n] TLOC[n] TALT[n]`` read the simulated tool table
(``AzOptions.tools``) by D number; ``TRESDEL[n]`` deletes the residual life (tool breakage, §12.2).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from cnc_gym.errors import ProgramError
from cnc_gym.gcode.codes import CodeSpec
from cnc_gym.gcode.dialects.azmc1.options import AzOptions, ToolRecord, data
from cnc_gym.gcode.lang.din import DinReader, ParameterStore
from cnc_gym.gcode.lang.fanuc import arcs, compensation
from cnc_gym.gcode.lang.fanuc.motion import motion as family_motion
from cnc_gym.toolpath import PLANE_AXES

if TYPE_CHECKING:
    from cnc_gym.gcode.dialect import Dialect, Seam

_LETTERS = "XYZ"
_IJK = "IJK"
#: The length part of a D word, run as the family's tool length action (the record's sign is +).
_LENGTH_ON = CodeSpec("D", 8, "length_comp", 1, step="tool")
_LENGTH_OFF = CodeSpec("D00", 8, "length_comp", 0, step="tool")


# --------------------------------------------------------------------------- D word, TRO
def tool_offset(core: Seam, spec: CodeSpec | None, values: dict) -> None:
    """``D<n>``: select tool offset record n (length and radius); D00 deselects (module docstring)."""
    st = core.state
    comp = st.comp
    number = int(values["D"])
    comp.h_number = number
    compensation.words(core, {"D": number})  # the radius; in TRO from this block's end vector (§11.3)
    tool_axis = _LETTERS[PLANE_AXES[st.plane][2]]
    # The length rides on the tool axis's first move: this block's, if it moves that axis, else a later one.
    own = {tool_axis: values[tool_axis]} if tool_axis in values else {}
    core.run_action("length_comp", _LENGTH_ON if number else _LENGTH_OFF, own)


def cutter(core: Seam, spec: CodeSpec, values: dict) -> None:
    """G40/G41/G42 with the AZ-MC1's rules (module docstring), then the family's compensation."""
    st = core.state
    comp = st.comp
    side = int(spec.value)  # type: ignore[call-overload]
    u, v, _w = PLANE_AXES[st.plane]
    if side:
        if comp.side and side != comp.side:
            raise core.error(f"{spec.name}: a direct change between G41 and G42 is not allowed; deselect "
                             "with G40 first (AMK AZ-MC1 programming manual §11.3.3)",
                             "tro-direct-change")  # fmt: skip
        if comp.d_number == 0:
            raise core.error(f"{spec.name} needs a tool offset record: program D<n> (D00 is no offset)",
                             "tro-no-d")  # fmt: skip
    elif comp.side and _LETTERS[u] not in values and _LETTERS[v] not in values:
        raise core.error("G40: the deselection block must travel in the plane (AMK AZ-MC1 programming manual "
                         "§11.3.4)", "tro-deselect-no-travel")  # fmt: skip
    before = comp.side
    core.run_action("family_cutter_comp", spec, values)
    if comp.stage is not None:
        comp.stage.startup_type = data(core).approach
    if bool(side) != bool(before):
        data(core).tro_transition = "selection" if side else "withdrawal"


def motion(core: Seam, spec: CodeSpec | None, values: dict) -> None:
    """The family's motion; the first straight travel in the plane after a TRO selection or withdrawal
    completes it (a circle there is refused by :func:`arc`)."""
    d = core.state.dialect_data
    if d is not None and d.tro_transition is not None and values:
        st = core.state
        mode = spec.value if spec is not None and spec.value is not None else st.motion
        u, v, _ = PLANE_AXES[st.plane]
        if mode in (0, 1) and (_LETTERS[u] in values or _LETTERS[v] in values):
            d.tro_transition = None
    family_motion(core, spec, values)


# --------------------------------------------------------------------------- arcs
def arc(core: Seam, motion: int, x, y, z, values: dict) -> None:
    """G02/G03 by I/J/K: G162 relative to the start, G161 absolute (module docstring). A circle may not be
    the selection or the withdrawal block of the TRO, whatever the radius of the D record (§11.3.1:
    "Selection of the TRO with a contour combination Circle - Straight line, Circle - Circle leads to an
    error message"; §11.3.4)."""
    st = core.state
    name = "G02" if motion == 2 else "G03"
    transition = st.dialect_data.tro_transition if st.dialect_data is not None else None
    if transition is not None:
        section = "§11.3.1" if transition == "selection" else "§11.3.4"
        raise core.error(f"{name}: the TRO {transition} block must be a straight line, not a circle, "
                         f"whatever the tool radius (AMK AZ-MC1 programming manual {section})",
                         "comp-arc-startup")  # fmt: skip
    u, v, w = PLANE_AXES[st.plane]
    lu, lv, lw = _IJK[u], _IJK[v], _IJK[w]
    if lw in values:
        raise core.error(f"{name}: {lw} is not an axis of the {st.plane.name} plane (the centre is "
                         f"{lu}/{lv})", "arc-bad-offset")  # fmt: skip
    if data(core).centre_absolute:
        if lu not in values or lv not in values:
            raise core.error(f"{name} in G161 (absolute centre) needs both {lu} and {lv}",
                             "arc-missing-center")  # fmt: skip
        position = core.program_position
        s = st.scale
        values = {**values, lu: values[lu] - position[u] / s, lv: values[lv] - position[v] / s}
    elif lu not in values and lv not in values:
        raise core.error(f"{name} needs the circle centre {lu}/{lv} (relative to the start in G162; the "
                         "AZ-MC1 has no radius programming)", "arc-missing-center")  # fmt: skip
    arcs.arc(core, motion, x, y, z, values)


# --------------------------------------------------------------------------- tool table
_FIELDS = {"TLIFE": "life", "TWARN": "warn", "TRES": "residual", "TLOC": "location", "TALT": "alternative"}


class AzParameters(ParameterStore):
    """The DIN family's R parameters plus the AZ-MC1's simulated tool table (by D number)."""

    __slots__ = ("tools",)

    def __init__(self, dialect: Dialect | None = None) -> None:
        super().__init__(dialect)
        opts = dialect.options if dialect is not None and isinstance(dialect.options, AzOptions) else None
        given = dict(opts.tools) if opts is not None else {}
        self.tools: dict[int, dict[str, float]] = {
            n: {**vars(given.get(n, ToolRecord(location=float(n))))} for n in range(1, 41)
        }

    def _record(self, name: str, argument: float) -> dict[str, float]:
        n = round(argument)
        if abs(argument - n) > 1e-9 or not 1 <= n <= 40:
            raise ProgramError(f"{name}[{argument:g}]: the argument is a D number 1..40", code="bad-tool")
        return self.tools[n]

    def data_function(self, name: str, argument: float) -> float:
        return float(self._record(name, argument)[_FIELDS[name]])

    def procedure(self, name: str, argument: float) -> None:
        """TRESDEL[n]: the residual life becomes 0 (the elapsed time equals the maximum life, §12.2)."""
        self._record(name, argument)["residual"] = 0.0


class AzReader(DinReader):
    """The DIN reader with the AZ-MC1's tool-table functions and ``TRESDEL``."""

    DATA_FUNCTIONS = frozenset(_FIELDS)
    PROCEDURES = frozenset({"TRESDEL"})


ACTIONS = {"tool_offset": tool_offset, "cutter_comp": cutter, "family_cutter_comp": compensation.cutter,
           "motion": motion}
