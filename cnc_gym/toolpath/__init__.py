"""Stage 2 of the pipeline: the canonical tool path and its geometry services."""

from cnc_gym.toolpath.kinds import PLANE_AXES, Plane, SegmentKind, SegmentMode
from cnc_gym.toolpath.nurbs import NurbsCurve
from cnc_gym.toolpath.segments import Toolpath, ToolpathBuilder

__all__ = ["PLANE_AXES", "NurbsCurve", "Plane", "SegmentKind", "SegmentMode", "Toolpath", "ToolpathBuilder"]
