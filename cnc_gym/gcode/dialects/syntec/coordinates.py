"""Syntec 8.20's coordinate systems and transforms (Syntec 8.20 mill programming manual §G54…G59.9, §G52,
§G92, §G10, §G30, §G15/G16, §G68/G69), on the Fanuc family's: fifteen work systems, G10 for tool offsets
only, G30 P1 (the machine origin), polar input with Syntec's increments, G68 whose R replaces the angle.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from cnc_gym.gcode.canonical import PolarState, rotation_stage
from cnc_gym.gcode.dialects.syntec.modes import angle, skip_next_line, spindle_clamp
from cnc_gym.gcode.dialects.syntec.options import data, options
from cnc_gym.gcode.lang.fanuc import compensation, coordinates, corners, reference, transforms
from cnc_gym.gcode.lang.fanuc.least_units import is_whole, whole_count
from cnc_gym.gcode.lang.fanuc.transforms import check_coordinate_command
from cnc_gym.toolpath import PLANE_AXES

if TYPE_CHECKING:
    from cnc_gym.gcode.codes import CodeSpec
    from cnc_gym.gcode.dialect import Seam
    from cnc_gym.toolpath import Plane

#: G54-G59, G59.1-G59.9 (§G54…G59.9: "G59.1: 7th … G59.9: 15th workpiece coordinate system").
WORK_SYSTEMS = 15


def wcs(core: Seam, spec: CodeSpec, values: dict | None = None) -> None:
    """G54-G59 and G59.1-G59.9: work coordinate system ``spec.value`` (1..15); drops a G92 system."""
    st = core.state
    number = spec.value
    if not isinstance(number, int) or not 1 <= number <= WORK_SYSTEMS:
        raise ValueError(f"dialect {core.dialect.name}: {spec.name} selects work system {number!r}")
    if st.chain.active:
        check_coordinate_command(core, spec.name)
    st.offsets.select_wcs(number - 1)  # systems 7-15 use the stack's slots after G59
    st.extra_wcs = 0
    core.resync_program_position()
    if values is not None:
        corners.mark_coordinate_change(core)
        skip_next_line(core)


def local_origin(core: Seam, spec: CodeSpec, values: dict) -> None:
    """G52 (the family's local system); the next G01 is not smoothed."""
    coordinates.local_origin(core, spec, values)
    skip_next_line(core)


def floating_origin(core: Seam, spec: CodeSpec, values: dict) -> None:
    """G92 X_Y_Z_ (the family's floating system) and ``G92 S_``, the spindle limit of constant surface
    speed (§G96/G97; the block normaliser took S off the block's words)."""
    d = core.state.dialect_data
    if d is not None and d.clamp_word is not None:
        spindle_clamp(core, d.clamp_word)
        d.clamp_word = None
    if any(letter in values for letter in core.dialect.axes):
        coordinates.floating_origin(core, spec, values)
        skip_next_line(core)


def length_comp(core: Seam, spec: CodeSpec, values: dict) -> None:
    """G43/G44/G49 (the family's tool length offset); the next G01 is not smoothed."""
    compensation.length(core, spec, values)
    skip_next_line(core)


def data_input(core: Seam, spec: CodeSpec, values: dict) -> None:
    """``G10 L10|L11|L12|L13 P_ R_`` (§G10): H geometry, H wear, D geometry, D wear; G90 sets, G91 adds.
    Syntec sets work offsets in its operation screens: G10 has no L2/L20/L50."""
    kind = values.get("L")
    if kind not in (10.0, 11.0, 12.0, 13.0):
        what = "needs L" if kind is None else f"L{kind:g} does not exist"
        raise core.error(f"G10 {what}: Syntec's G10 writes tool offsets, L10/L11 (H geometry/wear) and "
                         "L12/L13 (D geometry/wear); work offsets are set on the controller's screens",
                         "bad-g10")  # fmt: skip
    coordinates.data_input(core, spec, values)


def reference_return_n(core: Seam, spec: CodeSpec, values: dict) -> None:
    """``G30 Pn X_Y_Z_`` (§G30): via the intermediate point to reference point n, P2 when omitted; P1 is
    the mechanical origin, reference position 1 (the machine preset's ``reference_1_mm``, by default the
    machine zero), as G28."""
    p = values.get("P", 2.0)
    if p not in (1.0, 2.0, 3.0, 4.0):
        raise core.error(f"G30 P{p:g}: the reference point is P1 (mechanical origin) to P4", "bad-reference")
    if p == 1.0:
        reference.reference_return(core, spec, {k: v for k, v in values.items() if k != "P"})
    else:
        reference.reference_return_n(core, spec, values)


def scaling(core: Seam, spec: CodeSpec, values: dict) -> None:
    """``G51 X_Y_Z_ P_`` / ``G51 X_Y_Z_ I_J_K_`` (§G51/G50, the family's scaling): a factor without a
    decimal point is in 0.001 (the general rule of §G70/G71: ``P500`` = 0.5)."""
    factors = {k: whole_count(core, k, values[k]) / 1000.0 for k in "IJKP"
               if k in values and is_whole(core, k)}
    transforms.scaling(core, spec, {**values, **factors} if factors else values)


def _mirror_changed(core: Seam) -> None:
    """A mirror switched in cutter compensation mode: G41/G42 interchange from the next block on (§G51.1/
    G50.1: with one mirrored axis "the direction of compensation … execute reverse"), as a D change does."""
    comp = core.state.comp
    if comp.side and comp.stage is not None:
        comp.stage.set_cutter(compensation.signed_offset(core), comp.plane)


def mirror(core: Seam, spec: CodeSpec, values: dict) -> None:
    """G51.1 (the family's programmable mirror); compensation and a G68 in force follow the new
    handedness."""
    transforms.mirror(core, spec, values)
    _mirror_changed(core)
    _install_rotation(core)


def mirror_cancel(core: Seam, spec: CodeSpec, values: dict) -> None:
    """G50.1 (the family's mirror cancel); compensation and a G68 in force follow the new handedness."""
    transforms.mirror_cancel(core, spec, values)
    _mirror_changed(core)
    _install_rotation(core)


# ---------------------------------------------------------------------- G15/G16
class SyntecPolar(PolarState):
    """G16 polar input with Syntec's reading (§G15/G16): "in increment mode, angle or radius total from
    the last radius or angle" — an incremental radius adds to the last radius about the same origin (the
    Fanuc variant, ``polar_incremental_origin_at_tool``, moves the origin to the tool); the angle is
    counter-clockwise positive unless ``polar_angle_cw`` takes the text's "'+' for CW" literally."""

    def __init__(self, program_position, plane: Plane, *, clockwise: bool, origin_at_tool: bool) -> None:
        super().__init__(program_position, plane)
        self.clockwise = clockwise
        self.origin_at_tool = origin_at_tool

    def resolve(self, words, plane: Plane, scale: float, incremental: bool, position) -> tuple:
        u, v, _ = PLANE_AXES[plane]
        words = list(words)
        if self.clockwise and words[v] is not None:
            words[v] = -words[v]
        if incremental and words[u] is not None and not self.origin_at_tool:
            self.radius += words[u] * scale
            words[u] = None
            if words[v] is None:
                words[v] = 0.0  # the angle stays; the point is recomputed with the new radius
        return super().resolve(tuple(words), plane, scale, incremental, position)


def polar(core: Seam, spec: CodeSpec, values: dict) -> None:
    """G16: polar coordinate input on (:class:`SyntecPolar`)."""
    st = core.state
    if st.polar is None:
        opts = options(core)
        st.polar = SyntecPolar(core.program_position, st.plane, clockwise=opts.polar_angle_cw,
                               origin_at_tool=opts.polar_incremental_origin_at_tool)  # fmt: skip
        core.set_transform_state()


# ---------------------------------------------------------------------- G68/G69
def rotation(core: Seam, spec: CodeSpec, values: dict) -> None:
    """``G68 α_ β_ R_`` (§G68/G69): rotate the program by R degrees (0.001° without a decimal point)
    about the centre (α, β in the plane). Each G68 replaces the rotation in force: the manual's examples
    issue R90, R180, R270 in turn without G69. The centre is absolute: "Rotation center only effective in
    absolute command, if all command is increment, the actual rotation center is the starting point of
    path" — in G91 the centre words are not used (a note says so) and the centre is the start point.
    While one axis of the plane is mirrored (G51.1) the rotation turns the other way (§G51.1)."""
    st = core.state
    u, v, w = PLANE_AXES[st.plane]
    letters = core.dialect.axes
    if letters[w] in values:
        raise core.error(f"G68 in the {st.plane.name} plane takes the centre in {letters[u]}/{letters[v]}; "
                         f"{letters[w]} has no meaning", "unused-word")  # fmt: skip
    named = [letters[a] for a in (u, v) if letters[a] in values]
    if named and st.incremental:
        core.notice(f"G68 {''.join(named)} in G91: the centre words are not used, the rotation centre is the "
                    "start point (Syntec 8.20 mill programming manual §G68/G69)", "rotation-centre-ignored")
        values = {k: v for k, v in values.items() if k not in named}
    if "R" not in values:
        raise core.error("G68 needs R, the angle of rotation", "missing-value")
    degrees = angle(core, "R", values)
    if not -360.0 <= degrees <= 360.0:
        raise core.error(f"G68 R{degrees:g}: the angle is -360..360 degrees", "bad-rotation-angle")
    p = core.program_position
    s = st.scale
    centre = tuple(values[letters[a]] * s if a in (u, v) and letters[a] in values else p[a] for a in range(3))
    st.rotation_deg = round(degrees * 1000.0) / 1000.0
    data(core).rotation = ((centre[0], centre[1], centre[2]), st.rotation_deg)
    _install_rotation(core)


def _install_rotation(core: Seam) -> None:
    """The chain's rotation stage for the G68 in force: the programmed angle, reversed while exactly one
    axis of the plane is mirrored (§G51.1: with one mirrored axis "the direction of coordinate rotation …
    execute reverse"). The chain applies the mirror first and carries the centre through it, so the path is
    the mirror image of the rotated one."""
    rotation = data(core).rotation
    if rotation is None:
        return
    st = core.state
    centre, degrees = rotation
    u, v, _ = PLANE_AXES[st.plane]
    if (u in st.mirror_axes) != (v in st.mirror_axes):
        degrees = -degrees
    st.chain.set("rotation", rotation_stage(st.plane, centre, degrees))
    core.set_transform_state()


def rotation_cancel(core: Seam, spec: CodeSpec, values: dict) -> None:
    """G69: rotation off; the next move starts from the tool's position (absolute or incremental)."""
    st = core.state
    if st.chain.stages["rotation"] is None:
        return
    st.chain.set("rotation", None)
    st.rotation_deg = 0.0
    data(core).rotation = None
    core.resync_program_position()
    core.set_transform_state()


ACTIONS = {
    "wcs": wcs, "local_origin": local_origin, "floating_origin": floating_origin, "length_comp": length_comp,
    "data_input": data_input, "reference_return_n": reference_return_n, "polar": polar, "rotation": rotation,
    "rotation_cancel": rotation_cancel, "scaling": scaling, "mirror": mirror, "mirror_cancel": mirror_cancel,
}  # fmt: skip

