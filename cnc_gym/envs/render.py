"""Plotting support: a bounded time series, and ``render_mode="rgb_array"`` for the feed-rate env.

:class:`BinnedSeries` keeps a series of any length in at most ``max_bins`` time bins (max, min, mean or
last value per bin), so that recording an episode for a plot takes bounded memory however long the
program runs; ``cnc-gym run`` and the env's renderer both record through it.

The renderer records the actual positions and contour errors of the episode's servo samples (nothing is
recorded when the env has no render mode). The matplotlib figure is built on the first ``render()`` call
on an Agg canvas (no display needed) and reused.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import TYPE_CHECKING, Any, NamedTuple, Protocol

import numpy as np

from cnc_gym.errors import ConfigError
from cnc_gym.toolpath import Toolpath

if TYPE_CHECKING:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

_FIG_SIZE_IN = (8.0, 4.0)
_DPI = 80  # 640 × 320 pixels

#: Bins a recorded episode keeps at most (per series): enough for a plot's full width at any length.
DEFAULT_MAX_BINS = 4096

_REDUCTIONS = ("max", "min", "mean", "last")  # the op codes 0..3 of BinnedSeries


class RenderedEpisode(Protocol):
    """What a renderer reads of the env whose episode it draws (:class:`~cnc_gym.envs.feedrate.FeedrateEnv`
    has it): the program's tool path and name, and the servo sample period."""

    @property
    def toolpath(self) -> Toolpath: ...
    @property
    def program_name(self) -> str: ...
    @property
    def interpolation_period_s(self) -> float: ...


class BinnedSeries:
    """A series of samples kept in at most ``max_bins`` bins of equal sample count.

    ``columns`` maps each column name to its reduction over a bin: ``"max"`` (an envelope), ``"min"``,
    ``"mean"`` or ``"last"``. Each bin holds ``width`` consecutive samples: 1 until ``max_bins`` are
    filled, then neighbouring bins are merged pairwise and ``width`` doubles. Memory is
    ``max_bins`` × columns whatever the number of samples; the reductions are exact over each bin.
    """

    def __init__(self, columns: Mapping[str, str], max_bins: int = DEFAULT_MAX_BINS) -> None:
        bad = [f"{name}={how!r}" for name, how in columns.items() if how not in _REDUCTIONS]
        if not columns or bad:
            raise ConfigError(f"columns need a reduction among {', '.join(_REDUCTIONS)}: {', '.join(bad)}")
        if isinstance(max_bins, bool) or not isinstance(max_bins, int) or max_bins < 2 or max_bins % 2:
            raise ConfigError(f"max_bins must be an even integer >= 2, got {max_bins!r}")
        self.names = tuple(columns)
        self._how = tuple(columns.values())
        self._ops = tuple((j, _REDUCTIONS.index(how)) for j, how in enumerate(self._how))
        self.max_bins = max_bins
        self._bins = np.zeros((max_bins, len(self.names)))
        self._weights = np.zeros(max_bins)  # samples per bin
        self._acc = [0.0] * len(self.names)  # the bin being filled: running max / min / sum / last
        self.clear()

    def clear(self) -> None:
        self._staged = 0  # samples in the bin being filled
        self._filled = 0  # closed bins
        self.width = 1  # samples per closed bin
        self.count = 0  # samples added

    def add(self, *values: float) -> None:
        """One sample: a value per column, in the order of ``columns``."""
        acc = self._acc
        if self._staged == 0:
            acc[:] = values
        else:
            for j, op in self._ops:
                v = values[j]
                if op == 0:
                    if v > acc[j]:
                        acc[j] = v
                elif op == 1:
                    if v < acc[j]:
                        acc[j] = v
                elif op == 2:
                    acc[j] += v
                else:
                    acc[j] = v
        self._staged += 1
        self.count += 1
        if self._staged == self.width:
            self._bins[self._filled] = self._open_bin()
            self._weights[self._filled] = self._staged
            self._filled += 1
            self._staged = 0
            if self._filled == self.max_bins:
                self._merge_pairs()

    def extend(self, rows: Iterable[Iterable[float]]) -> None:
        """Several samples, one row each."""
        for row in rows:
            self.add(*row)

    def extend_rows(self, rows: np.ndarray) -> None:
        """Several samples, one row each of an (n, columns) array: the same bins as :meth:`add` of each
        row, bit for bit (each whole bin reduced in the order :meth:`add` takes its samples, a numpy
        operation per sample place over every bin at once)."""
        rows = np.asarray(rows, dtype=float)
        at, n = 0, len(rows)
        while at < n:
            width = self.width
            if self._staged or n - at < width:  # the bin being filled, sample by sample
                take = min(width - self._staged, n - at)
                for row in rows[at : at + take].tolist():
                    self.add(*row)
                at += take
                continue
            m = min((n - at) // width, self.max_bins - self._filled)
            block = rows[at : at + m * width].reshape(m, width, -1)
            acc = block[:, 0, :].copy()
            for j, op in self._ops:
                column = acc[:, j]
                for t in range(1, width):
                    value = block[:, t, j]
                    if op == 0:
                        np.copyto(column, value, where=value > column)
                    elif op == 1:
                        np.copyto(column, value, where=value < column)
                    elif op == 2:
                        column += value
                    else:
                        column[:] = value
                if op == 2:
                    column /= width
            self._bins[self._filled : self._filled + m] = acc
            self._weights[self._filled : self._filled + m] = width
            self._filled += m
            self.count += m * width
            at += m * width
            if self._filled == self.max_bins:
                self._merge_pairs()

    def arrays(self) -> dict[str, np.ndarray]:
        """One array per column (bins in order, the partly filled last bin included) and ``"samples"``
        (the number of samples in each bin)."""
        n = self._filled
        bins, weights = self._bins[:n], self._weights[:n]
        if self._staged:
            bins = np.vstack((bins, self._open_bin()))
            weights = np.append(weights, self._staged)
        out = {name: bins[:, j].copy() for j, name in enumerate(self.names)}
        out["samples"] = weights.astype(np.int64)
        return out

    def _open_bin(self) -> list[float]:
        """The bin being filled, reduced (a mean is its running sum over the samples so far)."""
        k = self._staged
        return [a / k if op == 2 else a for a, (_, op) in zip(self._acc, self._ops, strict=True)]

    def _merge_pairs(self) -> None:
        """Halve the resolution: bins 2i and 2i+1 become bin i; ``width`` doubles."""
        a, b = self._bins[0::2], self._bins[1::2]
        wa, wb = self._weights[0::2], self._weights[1::2]
        merged = np.empty_like(a)
        for j, op in self._ops:
            if op == 0:
                merged[:, j] = np.maximum(a[:, j], b[:, j])
            elif op == 1:
                merged[:, j] = np.minimum(a[:, j], b[:, j])
            elif op == 2:
                merged[:, j] = (a[:, j] * wa + b[:, j] * wb) / (wa + wb)
            else:
                merged[:, j] = b[:, j]
        half = self.max_bins // 2
        self._bins[:half] = merged
        self._weights[:half] = wa + wb
        self._filled = half
        self.width *= 2


class EpisodeRenderer:
    """Records an episode's actual motion and draws it (left: XY path; right: contour error over time).

    Servo samples go through a :class:`BinnedSeries` (position: last of each bin; contour error: max), so
    a long episode draws at lower resolution instead of growing without bound.
    """

    def __init__(self, tolerance_mm: float, max_bins: int = DEFAULT_MAX_BINS) -> None:
        self.tolerance_mm = tolerance_mm
        self._samples = BinnedSeries({"x": "last", "y": "last", "z": "last", "error": "max"}, max_bins)
        self._path_xy: np.ndarray | None = None
        self._path_key: int | None = None
        self._figure: Figure | None = None
        self._canvas: FigureCanvasAgg | None = None

    def clear(self) -> None:
        self._samples.clear()

    def start(self, env: RenderedEpisode) -> None:
        self.clear()
        if self._path_key != id(env.toolpath):
            _, points = env.toolpath.sample(0.5)
            self._path_xy = points[:, :2]
            self._path_key = id(env.toolpath)

    def record(self, actual: np.ndarray, error: np.ndarray) -> None:
        self._samples.extend(np.column_stack((actual, error)).tolist())

    def draw(self, env: RenderedEpisode) -> np.ndarray:
        """The current episode as an (H, W, 3) uint8 image."""
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.collections import LineCollection
        from matplotlib.figure import Figure

        if self._figure is None or self._canvas is None:
            self._figure = Figure(figsize=_FIG_SIZE_IN, dpi=_DPI)
            self._canvas = FigureCanvasAgg(self._figure)
        if self._path_xy is None or self._path_key != id(env.toolpath):
            self.start(env)
        fig, canvas, path_xy = self._figure, self._canvas, self._path_xy
        assert path_xy is not None  # start() sets it
        fig.clf()
        ax_path, ax_err = fig.subplots(1, 2, gridspec_kw={"width_ratios": [1.1, 1.0]})
        tol = self.tolerance_mm
        ax_path.plot(path_xy[:, 0], path_xy[:, 1], color="0.75", lw=2.5, label="programmed")
        error_max = 0.0
        if self._samples.count:
            series = self._samples.arrays()
            error = series["error"]
            error_max = float(error.max())  # each bin holds its samples' max: the episode's max
            xy = np.column_stack((series["x"], series["y"]))
            if len(xy) > 1:
                # Colour each sample by its contour error: green within tolerance, red at 2× tolerance.
                segments = np.stack((xy[:-1], xy[1:]), axis=1)
                lines = LineCollection(segments, cmap="RdYlGn_r", norm=_norm(0.0, 2.0 * tol),  # type: ignore[arg-type]
                                       lw=1.2)  # (an (n, 2, 2) array is a valid sequence of segments)
                lines.set_array(error[1:])
                ax_path.add_collection(lines)
                fig.colorbar(lines, ax=ax_path, label="contour error (mm)", fraction=0.046, pad=0.04)
            ax_path.plot(xy[-1, 0], xy[-1, 1], "o", color="k", ms=4)
            t = np.cumsum(series["samples"]) * env.interpolation_period_s
            bin_s = self._samples.width * env.interpolation_period_s
            plot_error_envelope(ax_err, t, error, tol, bin_s=bin_s, fontsize=7)
        else:
            plot_error_envelope(ax_err, np.zeros(0), np.zeros(0), tol, fontsize=7)
        ax_path.set_aspect("equal", adjustable="datalim")
        ax_path.set_title(f"{env.program_name}: tool path", fontsize=9)
        ax_path.set_xlabel("X (mm)", fontsize=8)
        ax_path.set_ylabel("Y (mm)", fontsize=8)
        ax_err.set_title(f"contour error, max {error_max * 1000:.1f} µm", fontsize=9)
        ax_err.set_xlabel("time (s)", fontsize=8)
        ax_err.set_ylabel("µm", fontsize=8)
        for ax in (ax_path, ax_err):
            ax.tick_params(labelsize=7)
        fig.tight_layout()
        canvas.draw()
        return np.asarray(canvas.buffer_rgba())[:, :, :3].copy()

    def close(self) -> None:
        if self._figure is not None:
            self._figure.clf()
        self._figure = None
        self._canvas = None


class MachineRenderer(EpisodeRenderer):
    """``render_mode="rgb_array"`` on the MuJoCo plant: MuJoCo's off-screen picture of the machine as it
    stands, with the programmed path on the table and the tool's trace coloured by contour error
    (:class:`~cnc_gym.plant.mujoco_render.MachineView`). Where no OpenGL context can be made (no EGL, no
    OSMesa) it warns once, naming the reason, and draws :class:`EpisodeRenderer`'s matplotlib picture.
    """

    def __init__(self, tolerance_mm: float, plant: Any, max_bins: int = DEFAULT_MAX_BINS) -> None:
        super().__init__(tolerance_mm, max_bins)
        self._plant = plant
        self._view: Any = None
        self._path_xyz: np.ndarray | None = None

    def start(self, env: RenderedEpisode) -> None:
        if self._path_key != id(env.toolpath) or self._path_xyz is None:
            self._path_xyz = env.toolpath.sample(0.5)[1]
        super().start(env)

    def draw(self, env: RenderedEpisode) -> np.ndarray:
        if self._view is None:
            import gymnasium

            from cnc_gym.plant.mujoco_render import MachineView

            self._view = MachineView(self._plant)
            if not self._view.available:
                gymnasium.logger.warn(f"render: no off-screen OpenGL context for MuJoCo's renderer ("
                                      f"{self._view.reason}); drawing the matplotlib picture instead")
        if not self._view.available:
            return super().draw(env)
        if self._path_xyz is None or self._path_key != id(env.toolpath):
            self.start(env)
        series = self._samples.arrays()
        trace = np.column_stack((series["x"], series["y"], series["z"]))
        assert self._path_xyz is not None  # start() sets it
        return self._view.draw(self._path_xyz, trace, series["error"], self.tolerance_mm)

    def close(self) -> None:
        super().close()
        if self._view is not None:
            self._view.close()
            self._view = None


def _norm(vmin: float, vmax: float):
    from matplotlib.colors import Normalize

    return Normalize(vmin=vmin, vmax=vmax)


# ------------------------------------------------------------------------------ plot pieces (runner too)
#: Views of the path: (horizontal axis, vertical axis) indices into XYZ.
_VIEW_AXES = {"XY": (0, 1), "XZ": (0, 2), "YZ": (1, 2)}
#: Z-only cutting moves longer than this share of the cutting length call for side views (drilling).
_Z_ONLY_SHARE = 0.5
#: Depth span (mm) of the XY-moving cutting moves above which the part is cut at several depths or in 3-D.
_DEPTH_SPAN_MM = 0.01


def wants_z_views(xyz: np.ndarray, cutting: np.ndarray) -> bool:
    """Whether a path needs XZ/YZ views: it cuts at more than one depth (or in 3-D), or a good share of
    its cutting is straight down (drilling). A plunge to one depth before an XY contour needs neither.

    ``xyz`` are points along the path, ``cutting[k]`` whether the piece from point k to k+1 cuts.
    """
    if len(xyz) < 2:
        return False
    delta = np.diff(xyz, axis=0)
    cut = np.asarray(cutting[:-1], dtype=bool)
    planar = np.hypot(delta[:, 0], delta[:, 1])
    length = np.linalg.norm(delta, axis=1)
    moving_xy = cut & (planar > 1e-9)
    if np.any(moving_xy):
        z = np.concatenate((xyz[:-1][moving_xy, 2], xyz[1:][moving_xy, 2]))
        if np.ptp(z) > _DEPTH_SPAN_MM:
            return True
    total = float(np.sum(length[cut]))
    return total > 0 and float(np.sum(length[cut & (planar <= 1e-9)])) > _Z_ONLY_SHARE * total


def plot_path_views(fig, views: dict, xyz: np.ndarray, cutting: np.ndarray, feed_mm_min: np.ndarray,
                    feed_range: tuple[float, float] | None = None) -> None:  # fmt: skip
    """Draw the path in each view (``{"XY": ax, "XZ": ax, "YZ": ax}``): cutting pieces coloured by
    ``feed_mm_min`` (one colour scale for all views, ``feed_range`` or 0 … the largest feed), rapids thin
    grey, cutting pieces the run did not reach (feed NaN) dashed. ``cutting`` and ``feed_mm_min`` are per
    point; a piece takes the values of its first point."""
    from matplotlib.collections import LineCollection
    from matplotlib.colors import Normalize

    cut = np.asarray(cutting[:-1], dtype=bool) if len(xyz) >= 2 else np.zeros(0, dtype=bool)
    feed = np.full(len(cut), np.nan)
    if len(feed_mm_min) == len(xyz):
        feed = np.asarray(feed_mm_min[:-1], dtype=float)
    reached = cut & np.isfinite(feed)
    missed = cut & ~np.isfinite(feed)
    if feed_range is None:
        top = float(np.max(feed[reached])) if np.any(reached) else 1.0
        feed_range = (0.0, max(top, 1.0))
    norm = Normalize(*feed_range)
    coloured = None
    for label, ax in views.items():
        i, j = _VIEW_AXES[label]
        if len(xyz) >= 2:
            pts = xyz[:, (i, j)]
            segments = np.stack((pts[:-1], pts[1:]), axis=1)
            # Rapids in thin grey: their speed would swamp the colour scale of the cutting feed.
            if np.any(~cut):
                ax.add_collection(LineCollection(segments[~cut], colors="0.7", linewidths=0.8))
            if np.any(missed):  # one polyline per stretch, so the dashes run on across the pieces
                ax.plot(*_stretches(pts, missed).T, color="0.55", lw=1.0, ls="--")
            lines = LineCollection(segments[reached], cmap="viridis", norm=norm, linewidths=2)
            lines.set_array(feed[reached])
            ax.add_collection(lines)
            # Cuts straight into the view (drilling seen from above) are points: mark each place once, in
            # the colour of the largest feed cut there.
            end_on = reached & (np.hypot(*(pts[1:] - pts[:-1]).T) <= 1e-9)
            if np.any(end_on):
                spots, where = np.unique(np.round(pts[:-1][end_on], 6), axis=0, return_inverse=True)
                spot_feed = np.zeros(len(spots))
                np.maximum.at(spot_feed, where.ravel(), feed[end_on])
                ax.scatter(spots[:, 0], spots[:, 1], c=spot_feed, cmap="viridis", norm=norm, s=36, zorder=3,
                           edgecolors="k", linewidths=0.5)  # fmt: skip
            coloured = coloured or lines
            ax.autoscale()
        else:
            ax.text(0.5, 0.5, "no motion in this program", transform=ax.transAxes, ha="center")
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_xlabel(f"{label[0]} (mm)")
        ax.set_ylabel(f"{label[1]} (mm)")
        if label != "XY":
            ax.set_title(f"{label} view")
    if coloured is not None:
        fig.colorbar(coloured, ax=views["XY"], label="feed on cutting moves (mm/min)")


def _stretches(points: np.ndarray, pieces: np.ndarray) -> np.ndarray:
    """The points of the selected pieces (piece k joins point k to k+1) as one polyline, a NaN row
    between separate stretches."""
    idx = np.flatnonzero(pieces)
    gap = np.diff(idx) > 1
    starts, ends = idx[np.r_[True, gap]], idx[np.r_[gap, True]]
    nan_row = np.full((1, points.shape[1]), np.nan)
    return np.concatenate([part for a, b in zip(starts, ends, strict=True)
                           for part in (points[a : b + 2], nan_row)])  # fmt: skip


def plot_error_envelope(ax, t_end_s: np.ndarray, error_mm: np.ndarray, tolerance_mm: float,
                        bin_s: float = 0.0, fontsize: float | None = None) -> None:  # fmt: skip
    """Contour error over time as a max envelope: bin k (ending at ``t_end_s[k]``, the first starting at
    0) drawn at its largest error, filled below, with the tolerance line; the legend sits under the axes
    so it never hides the line."""
    tol_um = tolerance_mm * 1000.0
    if len(t_end_s):
        x = np.concatenate(([0.0], t_end_s))
        y = np.concatenate((error_mm[:1], error_mm)) * 1000.0
        what = f"max per {bin_s * 1000:.0f} ms" if bin_s > 0 else "max per bin"
        ax.fill_between(x, y, step="pre", color="C0", alpha=0.3, lw=0)
        ax.step(x, y, where="pre", color="C0", lw=0.8, label=f"contour error ({what})")
        top = max(tol_um, float(np.max(y)))
    else:
        top = tol_um
    ax.axhline(tol_um, color="C3", ls="--", lw=1.2, label=f"tolerance {tol_um:g} µm")
    ax.set_ylim(0.0, 1.12 * top)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("contour error (µm)")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=2, frameon=False, fontsize=fontsize)



#: Path-length bins the error-along-the-path panel draws at most: about one per pixel column of a
#: plot's width, so that a program of many short segments draws as an envelope, not a solid band.
ALONG_PATH_BINS = 400


class Violation(NamedTuple):
    """The worst stretch over tolerance: where along the path (mm), its program line and its error."""

    s_start_mm: float
    s_end_mm: float
    line: int
    error_mm: float


def worst_violation(run: Any, tolerance_mm: float) -> Violation | None:
    """The largest error over ``tolerance_mm`` of a run (``segment_error_mm`` per programmed segment,
    with ``segment_s_mm`` edges and ``segment_line``; ``path_error_mm`` per path-length bin with
    ``path_error_edges_mm``): its segment's program line, and where along the path within that segment
    the error was largest. None when nothing is over tolerance."""
    segment = np.asarray(run.segment_error_mm, dtype=float)
    if not len(segment) or not np.any(segment > tolerance_mm):
        return None
    k = int(np.nanargmax(segment))
    lo, hi = float(run.segment_s_mm[k]), float(run.segment_s_mm[k + 1])
    edges, grid = np.asarray(run.path_error_edges_mm), np.asarray(run.path_error_mm, dtype=float)
    inside = np.flatnonzero((edges[1:] >= lo) & (edges[:-1] <= hi) & np.isfinite(grid))
    if len(inside):
        b = int(inside[np.argmax(grid[inside])])
        lo, hi = max(lo, float(edges[b])), min(hi, float(edges[b + 1]))
    return Violation(lo, hi, int(run.segment_line[k]), float(segment[k]))


def path_envelope(edges_mm: np.ndarray, error_mm: np.ndarray,
                  max_bins: int = ALONG_PATH_BINS) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """The maxima ``error_mm`` of the stretches of path from ``edges_mm[i]`` to ``edges_mm[i + 1]`` as a step
    envelope: ``(x, y)`` with bin k from ``x[k]`` to ``x[k + 1]`` at ``y[k]``. At most ``max_bins`` bins: the
    stretches themselves when there are few enough, else equal path-length bins, each at the largest error
    of the stretches it overlaps (NaN where none was reached)."""
    edges = np.asarray(edges_mm, dtype=float)
    error = np.asarray(error_mm, dtype=float)
    keep = edges[1:] > edges[:-1]  # zero-length stretches (dwells) take no room on a length axis
    if len(error) <= max_bins or not np.any(keep):
        return edges, error
    lo, hi = float(edges[0]), float(edges[-1])
    width = (hi - lo) / max_bins
    x = lo + width * np.arange(max_bins + 1)
    first = np.clip(((edges[:-1][keep] - lo) / width).astype(np.int64), 0, max_bins - 1)
    last = np.clip(np.ceil((edges[1:][keep] - lo) / width).astype(np.int64) - 1, first, max_bins - 1)
    bins, owner = range_indices(first, last)
    y = np.full(max_bins, np.nan)
    np.fmax.at(y, bins, error[keep][owner])
    return x, y


def range_indices(first: np.ndarray, last: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Every index of the ranges ``first[k]..last[k]`` (inclusive, ``last >= first``), and for each the
    range ``k`` it came from."""
    counts = np.asarray(last) - np.asarray(first) + 1
    owner = np.repeat(np.arange(len(counts)), counts)
    offset = np.arange(int(counts.sum())) - np.repeat(np.cumsum(counts) - counts, counts)
    return np.asarray(first)[owner] + offset, owner


def plot_error_along_path(ax, edges_mm: np.ndarray, error_mm: np.ndarray, tolerance_mm: float, *,
                          segment_edges_mm: np.ndarray | None = None, cutting: np.ndarray | None = None,
                          worst: Violation | None = None, max_bins: int = ALONG_PATH_BINS,
                          fontsize: float | None = None) -> None:  # fmt: skip
    """Contour error against path length: the envelope of :func:`path_envelope` filled below, the
    stretches over tolerance in red, rapids shaded grey (``cutting`` per segment of ``segment_edges_mm``;
    the programmed path's meter counts their error too), the tolerance line and the worst violation named
    by its program line. The legend sits under the axes so it never hides the line."""
    tol_um = tolerance_mm * 1000.0
    x, y = path_envelope(edges_mm, error_mm, max_bins)
    top = tol_um
    if len(y) and np.any(np.isfinite(y)):
        y_um = y * 1000.0
        xs = np.repeat(x, 2)[1:-1]  # each bin as a flat step: no slope between neighbours
        ys = np.repeat(y_um, 2)
        width = (x[-1] - x[0]) / max(len(y), 1)
        ax.fill_between(xs, ys, color="C0", alpha=0.3, lw=0)
        ax.plot(xs, ys, color="C0", lw=0.8, label=f"contour error (max per {width:.2g} mm of path)")
        over = ys > tol_um
        if np.any(over):
            ax.fill_between(xs, ys, tol_um, where=over, color="C3", alpha=0.6, lw=0, interpolate=False,
                            label="over tolerance")  # fmt: skip
            # ... and a tick under the axis at each such stretch: a narrow spike is found at a glance.
            over_bins = np.flatnonzero(y_um > tol_um)
            ax.plot(0.5 * (x[over_bins] + x[over_bins + 1]), np.zeros(len(over_bins)), "|", color="C3",
                    markersize=12, mew=1.5, clip_on=False, zorder=4)  # fmt: skip
        top = max(top, float(np.nanmax(y_um)))
    if cutting is not None and segment_edges_mm is not None and len(cutting) == len(segment_edges_mm) - 1:
        for a, b in _runs(~np.asarray(cutting, dtype=bool) & (np.diff(segment_edges_mm) > 0)):
            ax.axvspan(segment_edges_mm[a], segment_edges_mm[b + 1], color="0.88", lw=0, zorder=0)
    ax.axhline(tol_um, color="C3", ls="--", lw=1.2, label=f"tolerance {tol_um:g} µm")
    if worst is not None:
        ax.annotate(f"line {worst.line}: {worst.error_mm * 1000:.1f} µm",
                    xy=(0.5 * (worst.s_start_mm + worst.s_end_mm), worst.error_mm * 1000.0), xytext=(0, 8),
                    textcoords="offset points", ha="center", color="C3", fontsize=fontsize or 9)  # fmt: skip
    ax.set_ylim(0.0, 1.15 * top)
    if len(edges_mm) >= 2 and edges_mm[-1] > edges_mm[0]:
        ax.set_xlim(edges_mm[0], edges_mm[-1])
    ax.set_xlabel("path length (mm; rapids shaded)")
    ax.set_ylabel("contour error (µm)")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=2, frameon=False, fontsize=fontsize)


def mark_violations(views: dict, xyz: np.ndarray, sample_s: np.ndarray, edges_mm: np.ndarray,
                    error_mm: np.ndarray, tolerance_mm: float,
                    worst: Violation | None = None) -> None:  # fmt: skip
    """Mark in each view (``{"XY": ax, ...}``) the path points (at path positions ``sample_s``) whose
    stretch of path (``edges_mm``, ``error_mm``) is over tolerance, and the worst violation with its
    program line."""
    if worst is None or len(xyz) != len(sample_s) or not len(xyz) or len(edges_mm) < 2:
        return
    rows = np.clip(np.searchsorted(edges_mm, sample_s, side="right") - 1, 0, len(error_mm) - 1)
    over = np.asarray(error_mm)[rows] > tolerance_mm
    at_worst = (sample_s >= worst.s_start_mm) & (sample_s <= worst.s_end_mm)
    spot = xyz[np.flatnonzero(at_worst)[len(np.flatnonzero(at_worst)) // 2]] if np.any(at_worst) else None
    for label, ax in views.items():
        i, j = _VIEW_AXES[label]
        # A red halo under the feed colours (which stay readable), where the path was cut over tolerance.
        ax.plot(xyz[over, i], xyz[over, j], "o", ms=6, mew=0, color="C3", alpha=0.3, ls="none", zorder=1.5,
                label="over tolerance")  # fmt: skip
        if spot is not None:
            ax.annotate(f"worst: line {worst.line}, {worst.error_mm * 1000:.1f} µm", xy=(spot[i], spot[j]),
                        xytext=(18, 18), textcoords="offset points", color="C3", fontsize=9, zorder=5,
                        arrowprops={"arrowstyle": "->", "color": "C3"}, bbox=_LABEL_BOX)  # fmt: skip


_LABEL_BOX = {"boxstyle": "round,pad=0.2", "fc": "white", "ec": "C3", "alpha": 0.85}


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """``(first, last)`` index of each run of True in ``mask``."""
    idx = np.flatnonzero(mask)
    if not len(idx):
        return []
    gap = np.diff(idx) > 1
    return list(zip(idx[np.r_[True, gap]].tolist(), idx[np.r_[gap, True]].tolist(), strict=True))
