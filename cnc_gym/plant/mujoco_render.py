"""Off-screen pictures of the MuJoCo plant's machine (env 0) with the programmed path and the tool's trace.

MuJoCo's own renderer (``mjr_render`` into an off-screen buffer) needs an OpenGL context without a
window: EGL (GPU machines, and Mesa's) or OSMesa (software). :func:`open_gl_context` tries the one
``MUJOCO_GL`` names (``egl``, ``osmesa`` or ``glfw``), else EGL where libEGL is installed, else OSMesa.
PyOpenGL binds one platform per process, so a failed EGL leaves no OSMesa to try in that process: set
``MUJOCO_GL=osmesa`` to pick it. Where no context can be made, :class:`MachineView` says why
(``reason``) and the env draws its matplotlib picture instead.
"""

from __future__ import annotations

import ctypes.util
import os
from typing import TYPE_CHECKING, Any

import mujoco
import numpy as np

from cnc_gym.plant.mjcf import TOOL_TIP_ABOVE_TABLE_M

if TYPE_CHECKING:
    from cnc_gym.plant.mujoco import MujocoPlant

_PATH_RGBA = (0.75, 0.75, 0.75, 1.0)
#: Most line pieces drawn for the path and for the trace each (longer ones are thinned evenly).
MAX_PIECES = 2000


def _describe(exc: BaseException) -> str:
    try:
        text = str(exc)
    except Exception:  # PyOpenGL's EGL errors can fail to print themselves
        text = ""
    text = " ".join(text.split())[:160]
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


def _backends() -> list[str]:
    chosen = os.environ.get("MUJOCO_GL", "").strip().lower()
    if chosen in ("egl", "osmesa", "glfw"):
        return [chosen]
    if chosen in ("disable", "disabled", "off", "false", "0"):
        return []
    found = [name for name, lib in (("egl", "EGL"), ("osmesa", "OSMesa")) if ctypes.util.find_library(lib)]
    return found or ["egl", "osmesa"]


def open_gl_context(width: int, height: int) -> tuple[Any | None, str]:
    """``(context, "")`` made current, or ``(None, why not)``."""
    reasons = []
    for name in _backends():
        try:
            if name == "egl":
                from mujoco.egl import GLContext
            elif name == "osmesa":
                from mujoco.osmesa import GLContext
            else:
                from mujoco.glfw import GLContext
            context = GLContext(width, height)
            context.make_current()
            return context, ""
        except Exception as exc:  # any failure to make a context means: no GL here
            reasons.append(f"{name}: {_describe(exc)}")
        if name == "egl":
            break  # PyOpenGL is now bound to EGL in this process (see the module docstring)
    return None, "; ".join(reasons) or "MUJOCO_GL disables OpenGL"


def _error_rgba(ratio: float) -> tuple[float, float, float, float]:
    """Green within tolerance (ratio 0) through yellow to red at twice the tolerance (ratio 1)."""
    r = min(max(ratio, 0.0), 1.0)
    return (min(1.0, 2 * r), min(1.0, 2 * (1 - r)), 0.1, 1.0)


def _thin(points: np.ndarray) -> np.ndarray:
    step = max(1, -(-len(points) // MAX_PIECES))
    return points if step == 1 else np.vstack((points[::step], points[-1:]))


class MachineView:
    """Draws ``plant``'s machine 0 as it stands, with the programmed path and the recorded trace.

    ``available`` is False (and ``reason`` says why) where no off-screen OpenGL context could be made.
    """

    def __init__(self, plant: MujocoPlant, width: int = 640, height: int = 480) -> None:
        self.plant = plant
        self.width, self.height = width, height
        model = plant.model
        model.vis.global_.offwidth = max(model.vis.global_.offwidth, width)
        model.vis.global_.offheight = max(model.vis.global_.offheight, height)
        self._gl, self.reason = open_gl_context(width, height)
        self.available = self._gl is not None
        if not self.available:
            return
        try:
            self._scene = mujoco.MjvScene(model, maxgeom=model.ngeom + 2 * MAX_PIECES + 16)
            self._context = mujoco.MjrContext(model, mujoco.mjtFontScale.mjFONTSCALE_100)
            mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN, self._context)
        except Exception as exc:
            self.available, self.reason = False, _describe(exc)
            self.close()
            return
        self._option = mujoco.MjvOption()
        self._camera = mujoco.MjvCamera()
        self._camera.azimuth, self._camera.elevation, self._camera.distance = 90.0, -40.0, 0.9
        self._viewport = mujoco.MjrRect(0, 0, width, height)
        self._rgb = np.zeros((height, width, 3), dtype=np.uint8)

    def _to_world(self, points_mm: np.ndarray) -> np.ndarray:
        """Machine coordinates (mm, the tool relative to the table) → world points on the moving table."""
        table = self.plant.data.body("e0_table").xpos
        return table + points_mm / 1000.0 + np.array([0.0, 0.0, TOOL_TIP_ABOVE_TABLE_M])

    def _add_lines(self, points_mm: np.ndarray, colours: list[tuple] | None, width: float) -> None:
        scene = self._scene
        world = self._to_world(_thin(points_mm))
        for i in range(len(world) - 1):
            if scene.ngeom >= scene.maxgeom:
                return
            geom = scene.geoms[scene.ngeom]
            rgba = np.array(colours[i] if colours else _PATH_RGBA, dtype=np.float32)
            mujoco.mjv_initGeom(geom, mujoco.mjtGeom.mjGEOM_LINE, np.zeros(3), np.zeros(3), np.zeros(9), rgba)
            mujoco.mjv_connector(geom, mujoco.mjtGeom.mjGEOM_LINE, width, world[i], world[i + 1])
            scene.ngeom += 1

    def draw(self, path_mm: np.ndarray, trace_mm: np.ndarray, trace_error_mm: np.ndarray,
             tolerance_mm: float) -> np.ndarray:  # fmt: skip
        """An (height, width, 3) uint8 picture; the camera looks at the tool."""
        if self._gl is None:
            raise RuntimeError(f"no off-screen OpenGL context: {self.reason}")
        model, data = self.plant.model, self.plant.data
        self._gl.make_current()
        mujoco.mj_kinematics(model, data)  # body poses only: the dynamics' state is left as it is
        path = np.asarray(path_mm, dtype=float)
        if len(path):  # frame the programmed path: look at its middle from 3.5 times its size
            low, high = path.min(axis=0), path.max(axis=0)
            self._camera.lookat[:] = self._to_world((low + high) / 2.0)
            self._camera.distance = float(np.clip(3.5 * np.max(high - low) / 1000.0, 0.15, 2.5))
        else:
            self._camera.lookat[:] = data.site("e0_tool").xpos
        mujoco.mjv_updateScene(model, data, self._option, None, self._camera, mujoco.mjtCatBit.mjCAT_ALL,
                               self._scene)  # fmt: skip
        self._add_lines(path, None, 3.0)
        trace = _thin(np.asarray(trace_mm, dtype=float))
        if len(trace) > 1:
            error = _thin(np.asarray(trace_error_mm, dtype=float))
            colours = [_error_rgba(e / (2.0 * tolerance_mm)) for e in error[1:]]
            self._add_lines(trace, colours, 4.0)
        mujoco.mjr_render(self._viewport, self._scene, self._context)
        mujoco.mjr_readPixels(self._rgb, None, self._viewport, self._context)
        return np.flipud(self._rgb).copy()

    def close(self) -> None:
        context = getattr(self, "_context", None)
        if context is not None:
            context.free()
            self._context = None
        if self._gl is not None:
            self._gl.free()
            self._gl = None
