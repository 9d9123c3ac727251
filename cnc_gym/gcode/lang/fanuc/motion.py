"""Motion of the Fanuc family: the modal motion G00/G01/G02/G03 (and a dialect's own group-01 modes), rotary
axes, and G53 positioning in machine coordinates.

:func:`motion` is the action of every motion code and of axis-only blocks; it is on the interpreter's hot
path, so the plain G00/G01 move is written out here rather than through :meth:`Seam.move_linear`.

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from cnc_gym.gcode.codes import gkey
from cnc_gym.gcode.lang.fanuc import compensation, corners, reference, transforms
from cnc_gym.gcode.lang.fanuc.modal import missing_feed
from cnc_gym.gcode.lang.fanuc.reference import MODAL_POSITIONING

if TYPE_CHECKING:
    from cnc_gym.gcode.codes import CodeSpec
    from cnc_gym.gcode.dialect import Seam

_ARC_WORDS = frozenset("IJKR")


def motion(core: Seam, spec: CodeSpec | None = None, values: dict | None = None) -> None:
    """G00/G01/G02/G03, or an axis-only block in the modal motion. A motion code without axis words only
    sets the mode (§3.2.1)."""
    st = core.state
    if spec is not None and spec.value is not None:
        st.motion = spec.value  # type: ignore[assignment]
        if st.g53:
            return  # G53 makes this block's move (a rapid in machine coordinates)
    if values is None:
        return  # power-on
    x = values.get("X")
    y = values.get("Y")
    z = values.get("Z")
    mode = st.motion
    if st.rotary_axes and any(letter in values for letter in st.rotary_axes):
        return rotary_motion(core, mode, x, y, z, values)
    if st.pending is not None or ",R" in values or ",L" in values or ",C" in values:
        return corners.corner_motion(core, mode, x, y, z, values)  # chamfer / corner R
    if mode >= 2:
        if mode == MODAL_POSITIONING:  # G60 in force as a group-01 mode (1870#0 MDL = 1)
            if x is not None or y is not None or z is not None:
                key = core.dialect.roles.modal_positioning
                reference.single_direction(core, core.dialect.gcodes[key], values)  # type: ignore[index]
            return
        if x is None and y is None and z is None and not _ARC_WORDS.intersection(values):
            return  # no geometry in the block: the arc mode is only (re)selected
        core.dialect.hooks.arc(core, mode, x, y, z, values)  # type: ignore[misc]
        return
    if x is None and y is None and z is None:
        return  # a motion code with no axis words only sets the mode (§3.2.1)
    if st.transformed:
        core.move_linear(mode == 0, core.resolve_target(x, y, z))
        return
    out = st.out
    pos = out.position
    s = st.scale
    if st.incremental:
        target = (pos[0] if x is None else pos[0] + x * s, pos[1] if y is None else pos[1] + y * s,
                  pos[2] if z is None else pos[2] + z * s)  # fmt: skip
    else:
        o = st.offsets.origin
        target = (pos[0] if x is None else x * s + o[0], pos[1] if y is None else y * s + o[1],
                  pos[2] if z is None else z * s + o[2])  # fmt: skip
    if mode == 0:
        out.straight_traverse(target)
    else:
        feed = st.feed
        if not feed:
            raise missing_feed(core, "G01")
        out.straight_feed(target, feed)


def motion_mode(core: Seam, spec: CodeSpec, values: dict) -> None:
    """A motion code that only sets the modal motion: G00/G01 in a block whose axis words another code
    takes, where the dialect allows it (Fanuc's ``G00 G28 G91 Z0``)."""
    st = core.state
    st.motion = spec.value  # type: ignore[assignment]
    st.motion_key = gkey(float(spec.name[1:]))


def rotary_motion(core: Seam, mode: int, x, y, z, values: dict) -> None:
    """A G00/G01 block with rotary axis words (§3.2.2): the rotary axes move linearly with the XYZ
    move (or alone). F is the rate along the composite vector, degrees counted as mm (inch in G20):
    the tool path carries the angles, ``Toolpath.path_feed`` the resulting XYZ feed."""
    st = core.state
    if corners.is_pending_corner(st.pending) or ",L" in values or ",R" in values or ",C" in values:
        raise core.error("chamfer/corner rounding cannot join a block that moves a rotary axis",
                         "rotary-axis-context")  # fmt: skip
    if st.comp.side:
        raise core.error("a rotary axis cannot move in cutter compensation mode (G41/G42): cancel it "
                         "with G40 first", "rotary-axis-context")  # fmt: skip
    out = st.out
    start = out.rotary
    target = list(start)
    for axis, letter in enumerate(st.rotary_axes):
        value = values.get(letter)
        if value is not None:
            target[axis] = start[axis] + value if st.incremental else value + st.rotary_origin[axis]
    out.rotary_next = tuple(target)
    if x is None and y is None and z is None:
        if mode == 1 and not st.feed:
            raise core.error("G01 needs a feed: no F programmed yet" if st.feed is None else
                             "G01 with F0: the feed is zero", "missing-feed")  # fmt: skip
        position = out.position
        if mode == 0:
            out.straight_traverse(position)
        else:
            out.straight_feed(position, st.feed)  # type: ignore[arg-type]
        return
    core.move_linear(mode == 0, core.resolve_target(x, y, z))


def machine_move(core: Seam, spec: CodeSpec, values: dict) -> None:
    """G53 IP_: rapid to machine coordinates; one-shot; ignored in G91 (§3.2.12)."""
    st = core.state
    if st.chain.stages["rotation"] is not None:
        transforms.check_coordinate_command(core, "G53", local=True)  # "G52 to G59" in G68 mode (§3.2.18)
    if st.incremental:
        return
    compensation.before_machine_move(core)
    out = st.out
    pos = out.position
    s = st.scale
    target = tuple(pos[a] if letter not in values else values[letter] * s
                   for a, letter in enumerate(core.dialect.axes))  # fmt: skip
    if any(letter in values for letter in st.rotary_axes):
        current = out.rotary
        out.rotary_next = tuple(values.get(letter, current[a]) for a, letter in enumerate(st.rotary_axes))
    out.straight_traverse(target)  # type: ignore[arg-type]
    core.resync_program_position()


ACTIONS = {"motion": motion, "machine_move": machine_move, "motion_mode": motion_mode}
