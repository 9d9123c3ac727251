"""Tool compensation's actions and hooks: the interpreter's side of G40/G41/G42, G39, G43/G44/G49, G45-G48
and the D and H words.

The state is ``core.state.comp`` (``CompensationState``): the offset memory, the D and H numbers, the
G40-G42 and G43/G44/G49 modes, and the :class:`~cnc_gym.gcode.lang.fanuc.compensation.stage.OffsetStage`,
installed in place of the output stage the first time a program needs it (plain programs keep the direct
path). The tool length vector lives in the offset chain (``OffsetStack.tool_length``).

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from cnc_gym.errors import ProgramError
from cnc_gym.gcode.lang.fanuc.compensation.geometry import Point
from cnc_gym.gcode.lang.fanuc.compensation.stage import OffsetStage
from cnc_gym.toolpath import PLANE_AXES, Plane

if TYPE_CHECKING:
    from cnc_gym.gcode.codes import CodeSpec
    from cnc_gym.gcode.dialect import Seam


def _incremental(core: Seam) -> bool:
    """G91 in force for this block's move: G90/G91 of the block have not run yet at the compensation
    steps (order of execution), but the raw modal table already holds them."""
    roles = core.dialect.roles
    key = core.state.modal.get(roles.distance_group)  # type: ignore[arg-type]
    return core.state.incremental if key is None else key == roles.incremental


_LETTERS = "XYZ"
_IJK = "IJK"


def install(core: Seam) -> OffsetStage:
    """The compensation stage, put in front of the output the first time it is needed."""
    st = core.state
    comp = st.comp
    if comp.stage is None:
        settings = comp.settings
        stage = OffsetStage(st.out, startup_type=settings.startup_type, alarms=core.dialect.alarms,
                            outer_corner_arcs=settings.outer_corner_arcs,
                            correct_interference=settings.correct_interference)  # fmt: skip
        comp.stage = stage
        st.out = stage  # an Output: mypy checks that the stage implements the whole protocol
        st.block_listeners.append(before_block)
    return comp.stage


def before_block(core: Seam, values: dict) -> None:
    """Each block once the stage is installed: the look-ahead counts blocks; after G28/G30 the tool
    length vector comes back with the next block that commands its axis."""
    comp = core.state.comp
    comp.stage.begin_block()
    if comp.length_restore is not None:  # the tool length vector after G28/G30 (§3.5.1)
        restore_length(core, values)


def signed_offset(core: Seam) -> float:
    """The signed compensation offset (left +) for the D and G41/G42 in force.

    A mirror image in the plane (G51.1, or G51 with one negative factor) interchanges G41 and G42, so
    the machine path is the mirror image of the compensated programmed path (Fanuc's rule; GSK's
    manual is silent). The stage sees the mirrored moves, hence the sign. Scaling never scales the
    offset."""
    st = core.state
    comp = st.comp
    if not comp.side:
        return 0.0
    sign = 1.0
    chain = st.chain
    if chain.active:
        u, v, _w = PLANE_AXES[comp.plane if comp.side else st.plane]
        a = chain.linear
        if a[u][u] * a[v][v] - a[u][v] * a[v][u] < 0.0:
            sign = -1.0
    return sign * comp.side * comp.offsets.radius(comp.d_number)


def _direction(core: Seam, values: dict) -> Point | None:
    st = core.state
    u, v, _w = PLANE_AXES[st.plane]
    iu, iv = values.get(_IJK[u]), values.get(_IJK[v])
    if iu is None and iv is None:
        return None
    du, dv = (iu or 0.0) * st.scale, (iv or 0.0) * st.scale
    if du == 0.0 and dv == 0.0:
        raise core.error("the I/J/K direction is zero", "comp-bad-direction")
    return (du, dv)


# ---------------------------------------------------------------------- D and H words
def offset_words(core: Seam, spec: CodeSpec, values: dict) -> None:
    """D and H words: select the offset numbers (D and H are modal, §3.5.3, §3.5.1); D and H in one block
    are one item."""
    if spec.name == "D" or "D" not in values:
        words(core, values)


def words(core: Seam, values: dict) -> None:
    comp = core.state.comp
    if "D" in values:
        comp.d_number = int(values["D"])
        if comp.side and comp.stage is not None:
            # A D change in offset mode applies from this block's end vector (§3.5.3); D00 cancels.
            comp.stage.set_cutter(signed_offset(core), comp.plane)
    if "H" in values:
        comp.length_restore = None  # an H in G43/G44 mode sets the vector afresh
        comp.h_number = int(values["H"])
        if comp.length_sign:
            _apply_length(core, values)


# ---------------------------------------------------------------------- G40 / G41 / G42
def cutter(core: Seam, spec: CodeSpec, values: dict) -> None:
    """G41/G42 (cutter compensation left/right) and G40 (cancel, optional I/J direction)."""
    st = core.state
    comp = st.comp
    side = int(spec.value)  # type: ignore[call-overload]
    if side:
        if comp.side and st.plane != comp.plane:
            raise core.error("G41/G42: the plane changed in cutter compensation mode", "comp-plane-change")
        comp.side = side
        comp.plane = st.plane
        stage = install(core)
        stage.set_cutter(signed_offset(core), comp.plane)
        return
    comp.side = 0
    direction = _direction(core, values)
    if comp.stage is not None:
        comp.stage.set_cutter(0.0, comp.plane, cancel_direction=direction)


def check_plane(core: Seam, plane) -> None:
    """G17/G18/G19 while G41/G42 is in force: a different plane is alarm 37 (§3.5.3)."""
    comp = core.state.comp
    if comp.side and plane != comp.plane:
        raise core.error(f"plane change to {Plane(plane).name} in cutter compensation mode (cancel with G40 "
                         "first)", "comp-plane-change")  # fmt: skip


def corner_arc(core: Seam, spec: CodeSpec, values: dict) -> None:
    """G39 [I_J_]: corner arc of the compensation radius (§3.5.4); only in offset mode."""
    comp = core.state.comp
    if not comp.side or comp.stage is None or not comp.stage.active:
        raise core.error("G39 is only allowed in cutter compensation mode (G41/G42 after start-up)",
                         "g39-without-comp")  # fmt: skip
    comp.stage.corner_arc(_direction(core, values), core.state.feed)


# ---------------------------------------------------------------------- G43 / G44 / G49
def length(core: Seam, spec: CodeSpec, values: dict) -> None:
    """G43/G44 (tool length offset + / -) and G49 (cancel)."""
    st = core.state
    comp = st.comp
    comp.length_restore = None  # G43/G44/G49 set the vector afresh (after a G28/G30 cancel too)
    sign = int(spec.value)  # type: ignore[call-overload]
    deferred = False
    if sign and not any(letter in values for letter in _LETTERS):
        if comp.settings.length_needs_axis:
            raise core.error(f"{spec.name} needs an axis word in its block", "length-no-axis")
        deferred = True  # the next move of the tool axis carries the vector
    if st.modal.get(1) in core.dialect.roles.arcs:  # G02/G03 in force: an arc block with the normal axis …
        # … is a helix
        u, v, w = PLANE_AXES[st.plane]
        arc_words = ("IJK"[u], "IJK"[v], "R", _LETTERS[u], _LETTERS[v])
        if _LETTERS[w] in values and any(letter in values for letter in arc_words):
            raise core.error(f"{spec.name} cannot be given in a helical block (GSK 25i §3.2.3)",
                             "length-helical")  # fmt: skip
    comp.length_sign = sign
    if sign:
        comp.length_axis = 2 if comp.settings.tool_length_type == "A" else PLANE_AXES[st.plane][2]
    if deferred:
        _defer_length(core)
    else:
        _apply_length(core, values)


def _defer_length(core: Seam) -> None:
    """``G43 H_`` without an axis word (where the dialect allows it): the new vector waits, as after a
    G28 cancel, for the next block that commands its axis, whose move carries it in G90 and G91 alike
    (:func:`restore_length`)."""
    st = core.state
    comp = st.comp
    new = [0.0, 0.0, 0.0]
    new[comp.length_axis] = comp.length_sign * comp.offsets.length(comp.h_number)
    old = st.offsets.tool_length
    delta = [new[a] - old[a] for a in range(3)]
    if any(delta):
        comp.length_restore = delta
        install(core)


def cancel_length_at_intermediate(core: Seam, axes) -> None:
    """G28/G30 reached the intermediate point: the tool length vector of the commanded axes is cancelled
    (§3.5.1: "G28 and G30 are canceled after moving into the intermediate point"; the mode stays
    G43/G44). The next block commanding the axis restores it (:func:`restore_length`)."""
    st = core.state
    comp = st.comp
    vector = st.offsets.tool_length
    cancelled = [vector[a] if a in axes else 0.0 for a in range(3)]
    if not any(cancelled):
        return
    st.offsets.tool_length = [vector[a] - cancelled[a] for a in range(3)]
    st.offsets.update()
    restore = comp.length_restore or [0.0, 0.0, 0.0]
    comp.length_restore = [restore[a] + cancelled[a] for a in range(3)]
    install(core)  # its per-block hook lets the restore see the next blocks


def restore_length(core: Seam, values: dict) -> None:
    """At the start of a block after G28/G30: the cancelled vector of each axis the block commands comes
    back, and the block's move of that axis carries it (in G90 and G91 alike: ``length_pending``)."""
    st = core.state
    comp = st.comp
    restore = comp.length_restore
    axes = [a for a in range(3) if restore[a] and _LETTERS[a] in values]  # type: ignore[index]
    if not axes:
        return
    vector = list(st.offsets.tool_length)
    delta = [0.0, 0.0, 0.0]
    for a in axes:
        vector[a] += restore[a]  # type: ignore[index]
        delta[a] = restore[a]  # type: ignore[index]
        restore[a] = 0.0  # type: ignore[index]
    if not any(restore):  # type: ignore[arg-type]
        comp.length_restore = None
    st.offsets.tool_length = vector
    st.offsets.update()
    if not st.transformed and comp.stage is not None:
        # The programmed position moves with the vector, so an incremental move adds to the restored
        # position and an absolute one goes to program + offsets + vector (the transformed path keeps
        # its program position and gets this from the origin by itself).
        comp.stage.length_pending = (delta[0], delta[1], delta[2])


def _apply_length(core: Seam, values: dict) -> None:
    """Put the tool length vector into the offset chain (OffsetStack.tool_length, canonical.py): the
    next absolute move of the axis goes to program + offsets + vector; H replaces, never adds (§3.5.1)."""
    st = core.state
    comp = st.comp
    new = [0.0, 0.0, 0.0]
    if comp.length_sign:
        new[comp.length_axis] = comp.length_sign * comp.offsets.length(comp.h_number)
    old = st.offsets.tool_length
    if new == list(old):
        return
    delta = (new[0] - old[0], new[1] - old[1], new[2] - old[2])
    st.offsets.tool_length = new
    st.offsets.update()
    if (
        _incremental(core)
        and not st.transformed
        and any(_LETTERS[a] in values and delta[a] != 0.0 for a in range(3))
    ):
        # G91 with the axis in this block: the move carries the change (G43 G91 Z0 H_, §3.5.1). The
        # transformed path does this by itself (its program position ignores the machine's).
        stage = install(core)
        moved = [delta[a] if _LETTERS[a] in values else 0.0 for a in range(3)]
        stage.length_pending = (moved[0], moved[1], moved[2])


# ---------------------------------------------------------------------- G45-G48
def position_offset(core: Seam, spec: CodeSpec, values: dict) -> None:
    """G45/G46/G47/G48: the block's travel on each commanded axis grows or shrinks by 1x or 2x the D
    value (§3.5.7). Not in G41/G42 mode (§3.5.7); ignored in canned-cycle mode (§3.5.7)."""
    comp = core.state.comp
    if comp.side:
        raise core.error(f"{spec.name} cannot be used in cutter compensation mode G41/G42 (GSK 25i §3.5.7)",
                         "position-offset-in-comp")  # fmt: skip
    if core.state.cycle.spec is not None:
        return
    axes = frozenset(a for a in range(3) if _LETTERS[a] in values)
    amount = comp.offsets.position_offset(comp.d_number)
    install(core).set_position_offset(int(spec.value), amount, axes, _incremental(core))  # type: ignore[call-overload]


# ---------------------------------------------------------------------- G53, G27-G30, end
def before_machine_move(core: Seam) -> None:
    """G53 (and G27-G30, G60) are about to move: compensation is suspended for this block."""
    stage = core.state.comp.stage
    if stage is not None:
        stage.suspend()


def finish(core: Seam) -> None:
    """End of the program (a block hook): emit what the look-ahead still holds (the vector stays, §3.5.3)."""
    stage = core.state.comp.stage
    if stage is not None:
        try:
            stage.flush()
        except ProgramError as err:
            raise err.located(core.state.file, stage.line) from None


ACTIONS = {
    "offset_words": offset_words, "cutter_comp": cutter, "length_comp": length,
    "position_offset": position_offset, "corner_arc": corner_arc,
}  # fmt: skip
