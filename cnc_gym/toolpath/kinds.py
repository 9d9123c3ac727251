"""The tool path's vocabulary: segment kinds, arc planes, block modes, and the rows a service reads.

A leaf of the toolpath package: :mod:`~cnc_gym.toolpath.segments` (the :class:`~cnc_gym.toolpath.Toolpath`)
and its services (:mod:`~cnc_gym.toolpath.nearest`, :mod:`~cnc_gym.toolpath.records`) import it, and it
imports neither, so the tool path can offer those services as methods without an import circle. The
services see a tool path as :class:`ToolpathRows`, the per-row arrays they read.
"""

from __future__ import annotations

from collections.abc import Mapping
from enum import IntEnum, IntFlag
from typing import Protocol

import numpy as np

from cnc_gym.toolpath.nurbs import NurbsCurve


class SegmentKind(IntEnum):
    RAPID = 0
    LINE = 1
    ARC = 2
    DWELL = 3
    NURBS = 4


class Plane(IntEnum):
    """Arc planes. The value indexes :data:`PLANE_AXES`."""

    XY = 0
    ZX = 1
    YZ = 2


#: (u, v, w) axis indices per plane, with u × v = w (w is the plane normal).
PLANE_AXES: dict[Plane, tuple[int, int, int]] = {
    Plane.XY: (0, 1, 2),
    Plane.ZX: (2, 0, 1),
    Plane.YZ: (1, 2, 0),
}
#: :data:`PLANE_AXES` as an (3, 3) int array indexed by a :class:`Plane` value (for vectorised lookups).
PLANE_AXES_TABLE = np.array([PLANE_AXES[p] for p in Plane], dtype=np.int64)


class SegmentMode(IntFlag):
    """Per-block modes the controller must honour."""

    NONE = 0
    EXACT_STOP = 1  # G09 one-shot or G61 modal: stop with in-position check at the block end
    OVERRIDE_LOCKED = 2  # feed override fixed at 100 % (G63, tapping cycles, G31, #3004 bit 1)
    AUTO_CORNER = 4  # G62 automatic corner override
    INCH_PROGRAM = 8  # programmed in G20 (values already converted to mm)
    TAPPING_MODE = 16  # G63 tapping mode: no deceleration at block end (with OVERRIDE_LOCKED)
    #: A DIN controller's G36 "rounding of linear blocks": the block may end a little short or long so the
    #: last interpolation cycle keeps the path speed. Recorded for the controller; the motion stage plans
    #: continuous-time profiles, so the last-cycle speed dip G36 avoids does not arise there.
    ROUND_BLOCK_END = 32
    #: A dwell that stands for a machine function (an M code the control hands to the machine and waits
    #: for at rest): ``Toolpath.machine_functions`` names its code.
    MACHINE_FUNCTION = 64


class ToolpathRows(Protocol):
    """What the tool path's services read of it: the per-row arrays of :class:`~cnc_gym.toolpath.Toolpath`
    (its docstring describes them), the derived ``length`` and ``s_start``, and the exact NURBS curves."""

    @property
    def kind(self) -> np.ndarray: ...
    @property
    def start(self) -> np.ndarray: ...
    @property
    def end(self) -> np.ndarray: ...
    @property
    def center(self) -> np.ndarray: ...
    @property
    def plane(self) -> np.ndarray: ...
    @property
    def radius(self) -> np.ndarray: ...
    @property
    def start_angle(self) -> np.ndarray: ...
    @property
    def sweep(self) -> np.ndarray: ...
    @property
    def feed(self) -> np.ndarray: ...
    @property
    def dwell_s(self) -> np.ndarray: ...
    @property
    def line(self) -> np.ndarray: ...
    @property
    def file_index(self) -> np.ndarray: ...
    @property
    def modes(self) -> np.ndarray: ...
    @property
    def files(self) -> tuple[str, ...]: ...
    @property
    def nurbs(self) -> Mapping[int, NurbsCurve]: ...
    @property
    def rotary_axes(self) -> str: ...
    @property
    def machine_functions(self) -> Mapping[int, str]: ...
    @property
    def rotary_start(self) -> np.ndarray | None: ...
    @property
    def rotary_end(self) -> np.ndarray | None: ...
    @property
    def smoothing_tolerance_mm(self) -> np.ndarray | None: ...
    @property
    def length(self) -> np.ndarray: ...
    @property
    def s_start(self) -> np.ndarray: ...
    def __len__(self) -> int: ...
