"""The operator's tables at power-on: a setup (:class:`~cnc_gym.machine.SetupConfig`) written into a run's
work offsets and tool offset memory before its first block.

A setup names work coordinate systems by their codes (``G54``, ``G54.1 P5``, Syntec's ``G59.3``, ``EXT``
for the external offset) and tools by offset number (``length_mm`` → H, ``radius_mm`` → D, and their
wear). Which systems and numbers exist is the dialect's: the work systems are found in its code table
(the ``wcs`` and ``wcs_extra`` actions and their values), the tool numbers and limits in its offset memory
(:class:`~cnc_gym.gcode.offsets.ToolOffsets`). A setup the dialect cannot hold is one ConfigError line that
names the setup's file and key. The program's G10 still changes every table while it runs.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from cnc_gym.errors import ConfigError
from cnc_gym.gcode.codes import gkey

if TYPE_CHECKING:
    from cnc_gym.gcode.dialect import Dialect, Seam
    from cnc_gym.machine import SetupConfig

#: ToolSetup field → (offset table letter, wear?)
_TOOL_FIELDS = (("length_mm", "H", False), ("radius_mm", "D", False), ("length_wear_mm", "H", True),
                ("radius_wear_mm", "D", True))  # fmt: skip


def work_offset_slot(dialect: Dialect, key: str, extra_systems: int) -> int | None:
    """The offset stack's index of work system ``key`` (a canonical setup key, not ``EXT``) in ``dialect``,
    or None when the dialect has no such system. ``extra_systems``: how many G54.1 P systems the stack
    holds."""
    if key.startswith("G54.1 P"):
        spec = dialect.gcodes.get(gkey(54.1))
        number = int(key[7:])
        if spec is None or spec.action != "wcs_extra" or not 1 <= number <= extra_systems:
            return None
        return standard_systems(dialect) + number - 1
    spec = dialect.gcodes.get(gkey(float(key[1:])))
    first = dialect.gcodes.get(gkey(54))
    if spec is None or first is None or spec.action != "wcs" or not isinstance(spec.value, int):
        return None
    if not isinstance(first.value, int):
        return None
    return spec.value - first.value  # G54's value is the first slot's


def standard_systems(dialect: Dialect) -> int:
    """How many G54-style work systems come before the G54.1 P ones (G54-G59: 6)."""
    return sum(1 for spec in dialect.gcodes.values() if spec.action == "wcs" and isinstance(spec.value, int))


def apply_setup(core: Seam, setup: SetupConfig) -> None:
    """Write ``setup`` into the run's offset stack and tool offset memory (module docstring)."""
    setup = setup.in_mm()
    st = core.state
    dialect = core.dialect

    def fail(key: str, problem: str) -> ConfigError:
        return ConfigError(f"{setup.source}: {setup.where}{key} {problem}")

    offsets = st.offsets
    extra = len(offsets.wcs) - offsets.n_standard_wcs
    for key, xyz in setup.work_offsets.items():
        if key == "EXT":
            if not dialect.external_work_offset:
                raise fail("work_offsets.EXT", f"cannot be set: the {dialect.title} has no external work "
                                               "offset")  # fmt: skip
            offsets.external = [float(c) for c in xyz]
            continue
        slot = work_offset_slot(dialect, key, extra)
        if slot is None or not 0 <= slot < len(offsets.wcs):
            raise fail(f"work_offsets.{key}", f"cannot be set: the {dialect.title} has no work coordinate "
                                              f"system {key}")  # fmt: skip
        offsets.wcs[slot] = [float(c) for c in xyz]
    offsets.update()
    core.resync_program_position()
    memory = st.comp.offsets
    for number, tool in setup.tools.items():
        for field, letter, wear in _TOOL_FIELDS:
            value = float(getattr(tool, field))
            if not value:
                continue
            if letter == "D" and memory.d_is_diameter:
                value *= 2.0  # the memory holds diameters (GSK 2601#7 ODI): the setup gives radii

            def config_error(message: str, code: str, key: str = f"tools.{number}.{field}") -> ConfigError:
                return fail(key, f"cannot be set in the {dialect.title}: {message}")

            memory.set(letter, number, value, wear=wear, error=config_error)  # type: ignore[arg-type]
