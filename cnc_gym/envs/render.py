"""``render_mode="rgb_array"`` for the feed-rate env: programmed path, actual motion and contour error.

The recorder keeps the actual positions and errors of every servo sample of the episode (appended per
step; nothing is recorded when the env has no render mode). The matplotlib figure is built on the first
``render()`` call on an Agg canvas (no display needed) and reused.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from cnc_gym.envs.feedrate import FeedrateEnv

_FIG_SIZE_IN = (8.0, 4.0)
_DPI = 80  # 640 × 320 pixels


class EpisodeRenderer:
    """Records an episode's actual motion and draws it (left: XY path; right: contour error over time)."""

    def __init__(self, tolerance_mm: float) -> None:
        self.tolerance_mm = tolerance_mm
        self._positions: list[np.ndarray] = []
        self._errors: list[np.ndarray] = []
        self._path_xy: np.ndarray | None = None
        self._path_key: int | None = None
        self._figure = None
        self._canvas = None

    def clear(self) -> None:
        self._positions.clear()
        self._errors.clear()

    def start(self, env: FeedrateEnv) -> None:
        self.clear()
        if self._path_key != id(env.toolpath):
            _, points = env.toolpath.sample(0.5)
            self._path_xy = points[:, :2]
            self._path_key = id(env.toolpath)

    def record(self, actual: np.ndarray, error: np.ndarray) -> None:
        self._positions.append(actual.copy())
        self._errors.append(error.copy())

    def draw(self, env: FeedrateEnv) -> np.ndarray:
        """The current episode as an (H, W, 3) uint8 image."""
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.collections import LineCollection
        from matplotlib.figure import Figure

        if self._figure is None:
            self._figure = Figure(figsize=_FIG_SIZE_IN, dpi=_DPI)
            self._canvas = FigureCanvasAgg(self._figure)
        if self._path_key != id(env.toolpath):
            self.start(env)
        fig = self._figure
        fig.clf()
        ax_path, ax_err = fig.subplots(1, 2, gridspec_kw={"width_ratios": [1.1, 1.0]})
        tol = self.tolerance_mm
        ax_path.plot(self._path_xy[:, 0], self._path_xy[:, 1], color="0.75", lw=2.5, label="programmed")
        if self._positions:
            actual = np.concatenate(self._positions)
            error = np.concatenate(self._errors)
            xy = actual[:, :2]
            if len(xy) > 1:
                # Colour each sample by its contour error: green within tolerance, red at 2× tolerance.
                segments = np.stack((xy[:-1], xy[1:]), axis=1)
                lines = LineCollection(segments, cmap="RdYlGn_r", norm=_norm(0.0, 2.0 * tol), lw=1.2)
                lines.set_array(error[1:])
                ax_path.add_collection(lines)
                fig.colorbar(lines, ax=ax_path, label="contour error (mm)", fraction=0.046, pad=0.04)
            ax_path.plot(xy[-1, 0], xy[-1, 1], "o", color="k", ms=4)
            t = (np.arange(len(error)) + 1) * env.interpolation_period_s
            ax_err.plot(t, error * 1000.0, color="C0", lw=1.0)
        ax_err.axhline(tol * 1000.0, color="C3", ls="--", lw=1.0, label=f"tolerance {tol * 1000:g} µm")
        ax_path.set_aspect("equal", adjustable="datalim")
        ax_path.set_title(f"{env.program_name}: tool path", fontsize=9)
        ax_path.set_xlabel("X (mm)", fontsize=8)
        ax_path.set_ylabel("Y (mm)", fontsize=8)
        error_max = max((float(e.max()) for e in self._errors if len(e)), default=0.0)
        ax_err.set_title(f"contour error, max {error_max * 1000:.1f} µm", fontsize=9)
        ax_err.set_xlabel("time (s)", fontsize=8)
        ax_err.set_ylabel("µm", fontsize=8)
        ax_err.legend(fontsize=7, loc="upper right")
        for ax in (ax_path, ax_err):
            ax.tick_params(labelsize=7)
        fig.tight_layout()
        self._canvas.draw()
        return np.asarray(self._canvas.buffer_rgba())[:, :, :3].copy()

    def close(self) -> None:
        if self._figure is not None:
            self._figure.clf()
        self._figure = None
        self._canvas = None


def _norm(vmin: float, vmax: float):
    from matplotlib.colors import Normalize

    return Normalize(vmin=vmin, vmax=vmax)
