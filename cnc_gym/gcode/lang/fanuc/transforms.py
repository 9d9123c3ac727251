"""Program-side coordinate transforms of the Fanuc family: G68/G69 rotation, G51/G50 scaling, G51.1/G50.1
programmable mirror, G16/G15 polar input, and the restrictions the transform modes impose.

The stages themselves live in :mod:`cnc_gym.gcode.canonical` (:class:`~cnc_gym.gcode.canonical.
TransformChain`, :class:`~cnc_gym.gcode.canonical.PolarState`); the actions here put them in force from a
block's words. See docs/gcode.md, "Coordinates and transforms".

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from cnc_gym.gcode.canonical import PolarState, rotation_stage, scaling_stage
from cnc_gym.gcode.lang.fanuc import parameters
from cnc_gym.toolpath import PLANE_AXES

if TYPE_CHECKING:
    from cnc_gym.gcode.dialect import Seam
    from cnc_gym.toolpath import Plane


# --------------------------------------------------------------------------- modal restrictions
def check_coordinate_command(core: Seam, name: str, *, reference: bool = False,
                             local: bool = False) -> None:  # fmt: skip
    """Codes the transform modes forbid: G27-G30 (``reference``), G52 (``local``, G68 only), G54-G59,
    G54.1, G92 in G51 mode (alarm 109, §3.2.17) and in G68 mode (§3.2.18)."""
    if core.state.chain.stages["scaling"] is not None and not local:
        raise core.error(f"{name} is not allowed in scaling mode G51: cancel it with G50 first (GSK 25i "
                         "§3.2.17)",
                         "forbidden-in-scaling")  # fmt: skip
    if core.state.chain.stages["rotation"] is not None:
        raise core.error(f"{name} is not allowed in rotation mode G68: cancel it with G69 first (GSK 25i "
                         "§3.2.18)",
                         "forbidden-in-rotation")  # fmt: skip
    del reference


def check_plane_change(core: Seam, plane: Plane) -> None:
    """G17/G18/G19 in G68 mode: alarm (§3.2.18) unless it selects the plane already in use."""
    rotation = core.state.chain.stages["rotation"]
    if rotation is not None and plane != core.state.plane:
        raise core.error(f"plane change to {plane.name} in rotation mode G68 (GSK 25i §3.2.18)",
                         "plane-change-in-rotation")  # fmt: skip


# --------------------------------------------------------------------------- G68 / G69
def _centre(core: Seam, values: dict, axes) -> tuple[float, float, float]:
    """A centre given by absolute axis words whatever G90/G91 (§3.2.17, §3.2.18), Cartesian even in G16;
    an omitted axis takes the current program position."""
    p = core.program_position
    s = core.state.scale
    letters = core.dialect.axes
    return tuple(values[letters[a]] * s if a in axes and letters[a] in values else p[a]
                 for a in range(3))  # type: ignore[return-value]  # fmt: skip


def rotation(core: Seam, spec, values: dict) -> None:
    """``G68 α_ β_ R_`` (§3.2.18): rotate the program about the centre (α, β in the plane, absolute;
    omitted = current position) by R degrees CCW. In G91, R adds to the angle in force (explanation 3,
    §3.2.18: parameter 1850#0 RIN = 1). A G68 in G68 mode replaces the rotation (example 3 re-issues it)."""
    u, v, w = PLANE_AXES[core.state.plane]
    letters = core.dialect.axes
    if letters[w] in values:
        raise core.error(f"G68 in the {core.state.plane.name} plane takes the centre in "
                         f"{letters[u]}/{letters[v]}; {letters[w]} has no meaning",
                         "unused-word")  # fmt: skip
    centre = _centre(core, values, (u, v))
    if "R" in values:
        angle = values["R"]
        if not -360.0 <= angle <= 360.0:
            raise core.error(f"G68 R{angle:g}: the angle is -360..360 degrees", "bad-rotation-angle")
        if core.state.incremental:
            angle += core.state.rotation_deg
    else:
        angle = parameters.rotation_deg(core)  # P1860
    angle = round(angle * 1000.0) / 1000.0  # least increment 0.001° (§3.2.18)
    core.state.rotation_deg = angle
    core.state.chain.set("rotation", rotation_stage(core.state.plane, centre, angle))
    core.set_transform_state()


def rotation_cancel(core: Seam, spec, values: dict) -> None:
    """G69: rotation off. The tool's position is the start of the next move, which must be absolute
    (§3.2.18: an incremental one "will not perform correctly": we make it an error)."""
    if core.state.chain.stages["rotation"] is None:
        return
    core.state.chain.set("rotation", None)
    core.state.rotation_deg = 0.0
    core.resync_program_position()
    core.state.after_g69 = True  # cleared by the next move (resolve_target checks it)
    core.set_transform_state()


# --------------------------------------------------------------------------- G51 / G50, G51.1 / G50.1
SCALE_RANGE = (0.001, 99.999)  # §3.2.17


def _factor(core: Seam, letter: str, value: float) -> float:
    if not SCALE_RANGE[0] <= abs(value) <= SCALE_RANGE[1]:
        raise core.error(f"G51 {letter}{value:g}: the magnification is "
                         f"{SCALE_RANGE[0]:g}..{SCALE_RANGE[1]:g} (negative = mirror)",
                         "bad-scale-factor")  # fmt: skip
    return value


def scaling(core: Seam, spec, values: dict) -> None:
    """``G51 X_Y_Z_ P_`` or ``G51 X_Y_Z_ I_J_K_`` (§3.2.17): scale about the centre (absolute;
    omitted = current position); a negative factor mirrors that axis. Alone in its block (§3.2.17)."""
    letters = [w[0] for w in core.state.block_words]
    if letters.count("G") > 1 or any(letter in "MFSTHD" for letter in letters):
        raise core.error("G51 must be alone in its block (GSK 25i §3.2.17): no other G, M, F, S, T, H or D "
                         "word",
                         "g51-not-alone")  # fmt: skip
    if "P" in values and any(k in values for k in "IJK"):
        raise core.error("G51 takes either P (all axes) or I/J/K (per axis), not both", "bad-combination")
    centre = _centre(core, values, (0, 1, 2))
    if "P" in values:
        factors = (_factor(core, "P", values["P"]),) * 3
    elif any(k in values for k in "IJK"):
        each = [_factor(core, k, values[k]) if k in values else parameters.scale(core, a)
                for a, k in enumerate("IJK")]  # fmt: skip
        factors = (each[0], each[1], each[2])
    else:
        factors = (parameters.scale(core, None),) * 3  # P1861, latched now (§3.2.17)
    core.state.chain.set("scaling", scaling_stage("G51", centre, factors))
    core.set_transform_state()


def scaling_cancel(core: Seam, spec, values: dict) -> None:
    """G50: scaling off; the tool's position is the start of the next move (§3.2.17)."""
    if core.state.chain.stages["scaling"] is None:
        return
    core.state.chain.set("scaling", None)
    core.resync_program_position()
    core.set_transform_state()


def mirror(core: Seam, spec, values: dict) -> None:
    """``G51.1 X_Y_Z_``: programmable mirror of the commanded axes about the given coordinates (absolute);
    mirrors already set on other axes stay. (GSK lists G50.1/G51.1 in #4022 only; Fanuc semantics.)"""
    letters = core.dialect.axes
    if not any(letter in values for letter in letters):
        raise core.error("G51.1 needs the mirror axis coordinates (e.g. G51.1 X50)", "missing-value")
    s = core.state.scale
    for a, letter in enumerate(letters):
        if letter in values:
            core.state.mirror_axes[a] = values[letter] * s
    _install_mirror(core)


def mirror_cancel(core: Seam, spec, values: dict) -> None:
    """``G50.1 X_Y_Z_``: cancel the mirror of the commanded axes (the values are not used); alone = all."""
    letters = core.dialect.axes
    named = [a for a, letter in enumerate(letters) if letter in values]
    for a in named or list(core.state.mirror_axes):
        core.state.mirror_axes.pop(a, None)
    core.resync_program_position()
    _install_mirror(core)


def _install_mirror(core: Seam) -> None:
    if core.state.mirror_axes:
        centre = tuple(core.state.mirror_axes.get(a, 0.0) for a in range(3))
        factors = tuple(-1.0 if a in core.state.mirror_axes else 1.0 for a in range(3))
        core.state.chain.set("mirror", scaling_stage("G51.1", centre, factors))  # type: ignore[arg-type]
    else:
        core.state.chain.set("mirror", None)
        core.resync_program_position()
    core.set_transform_state()


# --------------------------------------------------------------------------- G16 / G15
def polar(core: Seam, spec, values: dict) -> None:
    """G16: polar coordinate input on (§3.2.16)."""
    if core.state.polar is None:
        core.state.polar = PolarState(core.program_position, core.state.plane)
        core.set_transform_state()


def polar_cancel(core: Seam, spec, values: dict) -> None:
    """G15: polar input off; the next move starts from the current tool position (§3.2.16)."""
    if core.state.polar is not None:
        core.state.polar = None
        core.resync_program_position()
        core.set_transform_state()


ACTIONS = {
    "rotation": rotation, "rotation_cancel": rotation_cancel, "scaling": scaling,
    "scaling_cancel": scaling_cancel, "mirror": mirror, "mirror_cancel": mirror_cancel, "polar": polar,
    "polar_cancel": polar_cancel,
}  # fmt: skip
