"""Exact NURBS curves for the tool path (``G06.2``, GSK 25i programming manual §3.2.5).

A curve of rank (order) k = degree + 1 with control points P_i, weights w_i and a clamped knot vector x:

    P(t) = Σ N_{i,k}(t) w_i P_i / Σ N_{i,k}(t) w_i,    x_0 ≤ t ≤ x_m

with the de Boor–Cox basis N_{i,k}. It is evaluated in homogeneous coordinates A(t) = Σ N w P, W(t) = Σ N w.
At construction the homogeneous B-spline is converted once (with scipy) to one polynomial per knot span,
stored as Taylor coefficients about the span's midpoint in a normalised variable u ∈ [-1, 1]; evaluation
is then a span look-up plus a small dense product, vectorised over parameters, and cheap enough for the
contour-error measurement at every control step.

Arc length is tabulated by adaptive 8-point Gauss–Legendre quadrature of the speed |P'(t)| (leaves split
until the two-halves estimate agrees with the whole-leaf one far below 1e-9 of the length, or stops
improving at the speed's round-off; a leaf shorter than its chord is always split; the leaves are
bounded in number; weights more than a factor :data:`MAX_WEIGHT_RATIO` apart are refused). Arc length →
parameter inverts that table (cubic Hermite first guess, then safeguarded Newton), so a NURBS row of the
tool path is evaluated by arc length like every other segment.

The nearest point (:meth:`NurbsCurve.nearest`) brackets every local minimum of the distance from a
precomputed sample table with one-sided derivatives, prunes far spans with their control-point bounding
spheres (convex-hull property), and refines the best brackets by safeguarded Newton on the slope.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

_GL_NODES, _GL_WEIGHTS = np.polynomial.legendre.leggauss(8)
_INITIAL_LEAVES_PER_SPAN = 8
_LENGTH_REL_TOL = 1e-13  # per unit parameter width, relative to the length: far below the 1e-9 target
_LENGTH_NOISE_REL = 1e-10  # a leaf whose estimate stalls below this (relative to its length) is done
_MAX_LEAVES = 16_384  # per curve (or 16 per initial leaf, if more): the work bound
#: Largest ratio of the largest to the smallest weight of a curve. Beyond it the homogeneous form cancels
#: so much that points are off by more than 1e-10 of the coordinates (weights 1e-6 beside 1e6 put the
#: first point 0.5 µm from the first control point), and the arc length needs thousands of leaves.
MAX_WEIGHT_RATIO = 1e6
_MAX_SAMPLES = 4096  # coarse table for the nearest point
_PRUNE_ABOVE_SAMPLES = 160  # smaller tables are scanned whole (cheaper than the span pruning)
_NEAREST_STARTS = 3  # Newton runs per query: the best-ranked brackets of a sampled minimum
_NEAREST_NEWTON_STEPS = 8
_NEAREST_STEP_TOLERANCE_MM = 1e-4  # last Newton step, along the curve
_INVERSE_NEWTON_STEPS = 12
_NEXT, _AFTER = np.array([1, 2, 0]), np.array([2, 0, 1])  # cyclic axis shifts for the cross product


def _as_readonly(arr: np.ndarray) -> np.ndarray:
    arr = np.array(arr)  # a private copy: the caller's array stays the caller's
    if arr.dtype.kind not in "iu":
        arr = arr.astype(np.float64)
    arr.flags.writeable = False
    return arr


@dataclass(frozen=True, eq=False)
class NurbsCurve:
    """A clamped, rational B-spline curve in 3-D (machine coordinates, mm), immutable.

    ``control_points`` (n, 3), ``weights`` (n,) > 0, ``knots`` (n + order,) non-decreasing with the first
    ``order`` and the last ``order`` knots equal (clamped), ``order`` = rank = degree + 1 ∈ {2, 3, 4}.
    Bad input raises :class:`ValueError` with a message meant for the program's author; the interpreter
    wraps it in a ``ProgramError`` naming file and line.

    Services: :meth:`evaluate` / :meth:`derivatives` / :meth:`tangent_curvature` by parameter,
    :attr:`length`, :meth:`length_at` / :meth:`parameter_at_length`, :meth:`at_length` (point, unit
    tangent, curvature by arc length), and :meth:`nearest` (exact nearest point, vectorised).
    """

    control_points: np.ndarray
    weights: np.ndarray
    knots: np.ndarray
    order: int = 4
    # Derived, filled in __post_init__.
    length: float = field(init=False, repr=False)
    _breaks: np.ndarray = field(init=False, repr=False)
    _poly: np.ndarray = field(init=False, repr=False)
    _half_width: np.ndarray = field(init=False, repr=False)
    _interior_breaks: np.ndarray = field(init=False, repr=False)
    _mid: np.ndarray = field(init=False, repr=False)
    _inv_half: np.ndarray = field(init=False, repr=False)
    _exponents: np.ndarray = field(init=False, repr=False)
    _leaf_t: np.ndarray = field(init=False, repr=False)
    _leaf_s: np.ndarray = field(init=False, repr=False)
    _leaf_dt_ds: np.ndarray = field(init=False, repr=False)
    _sample_t: np.ndarray = field(init=False, repr=False)
    _sample_points: np.ndarray = field(init=False, repr=False)
    _origin: np.ndarray = field(init=False, repr=False)
    _sample_rel_t: np.ndarray = field(init=False, repr=False)  # (3, n): sample points - origin
    _sample_rel_sq: np.ndarray = field(init=False, repr=False)  # (n,)
    _sample_d1_t: np.ndarray = field(init=False, repr=False)  # (2, 3, n): right and left derivatives
    _sample_rel_d1: np.ndarray = field(init=False, repr=False)  # (2, n): (point - origin) · derivative
    _span_center_t: np.ndarray = field(init=False, repr=False)  # (3, spans), relative to the origin
    _span_center_sq: np.ndarray = field(init=False, repr=False)
    _span_radius: np.ndarray = field(init=False, repr=False)
    _span_samples: np.ndarray = field(init=False, repr=False)
    _per_span: int = field(init=False, repr=False)
    _nearest_step_tolerance: float = field(init=False, repr=False)

    def __post_init__(self) -> None:
        points, weights, knots, order = _validated(self.control_points, self.weights, self.knots, self.order)
        object.__setattr__(self, "control_points", _as_readonly(points))
        object.__setattr__(self, "weights", _as_readonly(weights))
        object.__setattr__(self, "knots", _as_readonly(knots))
        object.__setattr__(self, "order", order)
        self._build_span_polynomials()
        self._build_length_table()
        self._build_sample_table()

    # ------------------------------------------------------------ construction
    def _build_span_polynomials(self) -> None:
        """Taylor coefficients of the homogeneous curve per knot span, and of its 1st and 2nd derivatives.

        ``_poly[j, r, 4 d + c]``: coefficient of u^r in the d-th t-derivative of homogeneous coordinate c
        on span j, with u = (t - mid_j) / half_j ∈ [-1, 1].
        """
        from scipy.interpolate import BSpline  # here, not at import: the interpreter alone never needs scipy

        k = self.order
        degree = k - 1
        homogeneous = np.column_stack((self.control_points * self.weights[:, None], self.weights))
        spline = BSpline(self.knots, homogeneous, degree, extrapolate=True)
        breaks = np.unique(self.knots)  # clamped and validated: the spans of positive width
        mid = 0.5 * (breaks[:-1] + breaks[1:])
        half = 0.5 * (breaks[1:] - breaks[:-1])
        taylor = np.zeros((len(mid), k, 4))
        for r in range(k):
            # r-th derivative / r!, scaled to the normalised variable: d^r/du^r = half^r d^r/dt^r.
            taylor[:, r, :] = spline(mid, nu=r) * (half**r / math.factorial(r))[:, None]
        # Coefficients of the t-derivatives in powers of u: d/dt = (1/half) d/du.
        poly = np.zeros((len(mid), k, 3, 4))
        poly[:, :, 0] = taylor
        for r in range(k - 1):
            poly[:, r, 1] = (r + 1) * taylor[:, r + 1] / half[:, None]
        for r in range(k - 2):
            poly[:, r, 2] = (r + 1) * (r + 2) * taylor[:, r + 2] / (half * half)[:, None]
        object.__setattr__(self, "_breaks", _as_readonly(breaks))
        object.__setattr__(self, "_interior_breaks", _as_readonly(breaks[1:-1]))
        object.__setattr__(self, "_poly", _as_readonly(poly.reshape(len(mid), k, 12)))
        object.__setattr__(self, "_half_width", _as_readonly(half))
        object.__setattr__(self, "_mid", _as_readonly(mid))
        object.__setattr__(self, "_inv_half", _as_readonly(1.0 / half))
        object.__setattr__(self, "_exponents", _as_readonly(np.arange(k)))

    def _build_length_table(self) -> None:
        """Adaptive Gauss–Legendre arc length. Leaves never straddle a knot, where P' may jump.

        A leaf is split until its two halves agree with it to :data:`_LENGTH_REL_TOL` of the length per
        unit parameter width, which smooth curves reach in a few levels (the accuracy contract: far below
        1e-9 of the length). The work stays bounded, whatever the weights:

        * a leaf whose disagreement is negligible in absolute terms (1e-14 of the length) is done;
        * round-off: where weights make the homogeneous polynomials cancel, the speed itself is noisy and
          no split can beat that. Halving a smooth leaf shrinks its 8-point estimate some 2^16 times; a leaf
          whose estimate stays above an eighth of its parent's, at below :data:`_LENGTH_NOISE_REL` of its
          own length (or of its share of the length), is at that floor and done;
        * the leaf budget :data:`_MAX_LEAVES` (accept what is left; never reached in the tests).

        The arc is at least its chord: a leaf shorter than its chord is split whatever its estimate says,
        so a narrow feature that every quadrature node misses (a small weight beside a large one moves the
        curve millimetres within 1e-7 of the parameter next to a knot) is found.
        """
        breaks = self._breaks
        frac = np.linspace(0.0, 1.0, _INITIAL_LEAVES_PER_SPAN + 1)
        edges = breaks[:-1, None] + (breaks[1:] - breaks[:-1])[:, None] * frac[None, :]
        a, b = edges[:, :-1].ravel(), edges[:, 1:].ravel()
        parent_error = np.full(a.size, np.inf)  # the estimate of the leaf each one was split from
        width = breaks[-1] - breaks[0]
        max_leaves = max(_MAX_LEAVES, 16 * a.size)
        size = float(np.max(np.abs(self.control_points)))  # coordinate scale, for the chord's round-off
        done_a, done_b, done_len = [], [], []
        n_done = 0
        scale = None
        while a.size:
            mid = 0.5 * (a + b)
            # Whole leaf and its two halves in one vectorised quadrature.
            parts = self._speed_integral(np.concatenate((a, a, mid)), np.concatenate((b, mid, b)))
            whole, left, right = parts.reshape(3, -1)
            halves = left + right
            ends = self.evaluate(np.concatenate((a, b))).reshape(2, -1, 3)
            chord = np.sqrt(np.sum((ends[1] - ends[0]) ** 2, axis=1))
            if scale is None:  # the length, as the first level of leaves sees it
                scale = max(float(np.sum(np.maximum(halves, chord))), 1e-300)
            error = np.abs(whole - halves)
            share = scale / width * (b - a)  # the leaf's share of the length by parameter width
            ok = (error <= _LENGTH_REL_TOL * share) | (error <= 1e-14 * scale)
            ok |= (error > 0.125 * parent_error) & (error <= _LENGTH_NOISE_REL * np.maximum(halves, share))
            ok &= chord <= halves * (1.0 + 1e-9) + 1e-12 * (scale + size)
            # A leaf at the resolution of a double cannot be split (its midpoint is one of its ends).
            ok |= (mid <= a) | (mid >= b)
            if n_done + a.size + int(np.count_nonzero(~ok)) > max_leaves:
                ok[:] = True  # bounded work: accept what is left
            n_done += int(np.count_nonzero(ok))
            done_a.append(a[ok])
            done_b.append(b[ok])
            done_len.append(halves[ok])
            keep = ~ok
            a, b = np.concatenate((a[keep], mid[keep])), np.concatenate((mid[keep], b[keep]))
            parent_error = np.concatenate((error[keep], error[keep]))
        leaf_a, leaf_b, leaf_len = (np.concatenate(x) for x in (done_a, done_b, done_len))
        order = np.argsort(leaf_a, kind="stable")
        leaf_t = np.concatenate((leaf_a[order], leaf_b[order][-1:]))
        leaf_s = np.concatenate(([0.0], np.cumsum(leaf_len[order])))
        # dt/ds at both ends of every leaf (one-sided, inside the leaf) for the inverse's first guess.
        leaf_span = self._interior_breaks.searchsorted(leaf_t[:-1], side="right")
        start_speed = self._speed(leaf_t[:-1], leaf_span)
        end_speed = self._speed(leaf_t[1:], leaf_span)
        leaf_dt_ds = np.stack((1.0 / np.maximum(start_speed, 1e-300), 1.0 / np.maximum(end_speed, 1e-300)))
        leaf_dt_ds[:, (start_speed <= 0) | (end_speed <= 0)] = np.nan  # a stall: linear guess there
        object.__setattr__(self, "_leaf_dt_ds", _as_readonly(leaf_dt_ds.T))
        object.__setattr__(self, "_leaf_t", _as_readonly(leaf_t))
        object.__setattr__(self, "_leaf_s", _as_readonly(leaf_s))
        object.__setattr__(self, "length", float(leaf_s[-1]))

    def _build_sample_table(self) -> None:
        """The coarse stage of :meth:`nearest`: points at equal parameter steps in every span (knots
        included) with the one-sided derivatives there (they differ at a knot where the curve has a kink)."""
        spans = len(self._breaks) - 1
        per_span = int(np.clip(_MAX_SAMPLES // spans, 4, 16))
        frac = np.linspace(0.0, 1.0, per_span + 1)[:-1]
        t = (self._breaks[:-1, None] + 2 * self._half_width[:, None] * frac[None, :]).ravel()
        t = np.append(t, self._breaks[-1])
        right_span = self._interior_breaks.searchsorted(t, side="right")
        left_span = np.maximum(self._interior_breaks.searchsorted(t, side="left"), 0)
        point, right_d1, _ = self._rational(self._homogeneous(t, 2, right_span))
        _, left_d1, _ = self._rational(self._homogeneous(t, 2, left_span))
        # Bounding sphere of every span: a NURBS point with positive weights is a convex combination of
        # its span's `order` control points, so the sphere around them holds the span (pruning bound).
        first_knot = np.searchsorted(self.knots, self._breaks[:-1], side="right") - 1
        hull = self.control_points[first_knot[:, None] - self.order + 1 + np.arange(self.order)]
        center = hull.mean(axis=1)
        radius = np.sqrt(np.max(np.sum((hull - center[:, None, :]) ** 2, axis=2), axis=1))
        object.__setattr__(self, "_span_radius", _as_readonly(radius))
        object.__setattr__(self, "_span_samples", _as_readonly(np.arange(per_span + 1)))
        object.__setattr__(self, "_per_span", per_span)
        # Coarse distances and slopes are matrix products (p·P, p·P'): coordinates relative to the
        # control points' mean keep the expanded |P - p|² free of cancellation at large machine coords.
        origin = self.control_points.mean(axis=0)
        rel = point - origin
        object.__setattr__(self, "_origin", _as_readonly(origin))
        center_rel = center - origin
        object.__setattr__(self, "_span_center_t", _as_readonly(center_rel.T))
        center_sq = np.einsum("ij,ij->i", center_rel, center_rel)
        object.__setattr__(self, "_span_center_sq", _as_readonly(center_sq))
        max_speed = float(np.max(np.linalg.norm(np.concatenate((right_d1, left_d1)), axis=1)))
        # Parameter step that moves at most _NEAREST_STEP_TOLERANCE_MM (speeds between samples may be a
        # little higher than at them: factor 2).
        step_tolerance = _NEAREST_STEP_TOLERANCE_MM / max(2.0 * max_speed, 1e-300)
        object.__setattr__(self, "_nearest_step_tolerance", step_tolerance)
        object.__setattr__(self, "_sample_t", _as_readonly(t))
        object.__setattr__(self, "_sample_points", _as_readonly(point))
        object.__setattr__(self, "_sample_rel_t", _as_readonly(rel.T))
        object.__setattr__(self, "_sample_rel_sq", _as_readonly(np.einsum("ij,ij->i", rel, rel)))
        object.__setattr__(self, "_sample_d1_t", _as_readonly(np.stack((right_d1.T, left_d1.T))))
        object.__setattr__(self, "_sample_rel_d1", _as_readonly(np.stack((
            np.einsum("ij,ij->i", rel, right_d1), np.einsum("ij,ij->i", rel, left_d1)))))  # fmt: skip

    # ------------------------------------------------------------- evaluation
    @property
    def degree(self) -> int:
        return self.order - 1

    @property
    def domain(self) -> tuple[float, float]:
        """Parameter range (x_0, x_m)."""
        return float(self.knots[0]), float(self.knots[-1])

    def _homogeneous(self, t: np.ndarray, n_derivatives: int, span: np.ndarray | None = None) -> np.ndarray:
        """Homogeneous coordinates and t-derivatives, (m, 4 (n_derivatives + 1)): blocks of (x, y, z, w).

        This is the hot path of the nearest point, hence the flat layout and no per-call checks. ``span``
        forces the knot span (for one-sided derivatives at a knot); by default the right-hand one.
        """
        if span is None:
            span = self._interior_breaks.searchsorted(t, side="right")
        u = (t - self._mid[span]) * self._inv_half[span]
        powers = u[:, None] ** self._exponents
        coef = self._poly[span, :, : 4 * (n_derivatives + 1)]  # (m, k, cols)
        return np.matmul(powers[:, None, :], coef)[:, 0, :]

    def derivatives(self, t: np.ndarray | float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """P(t), P'(t), P''(t), each (m, 3). At a knot the right-hand span is used (the left at x_m)."""
        t_arr = np.clip(np.atleast_1d(np.asarray(t, dtype=float)), self.knots[0], self.knots[-1])
        return self._rational(self._homogeneous(t_arr, 2))

    @staticmethod
    def _rational(h: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """P, P', P'' from homogeneous A, W and derivatives (quotient rule on P = A / W)."""
        inv_w = 1.0 / h[:, 3:4]
        point = h[:, 0:3] * inv_w
        d1 = (h[:, 4:7] - h[:, 7:8] * point) * inv_w
        d2 = (h[:, 8:11] - 2.0 * h[:, 7:8] * d1 - h[:, 11:12] * point) * inv_w
        return point, d1, d2

    def evaluate(self, t: np.ndarray | float) -> np.ndarray:
        """Points P(t), shape (m, 3)."""
        t_arr = np.clip(np.atleast_1d(np.asarray(t, dtype=float)), self.knots[0], self.knots[-1])
        h = self._homogeneous(t_arr, 0)
        return h[:, :3] / h[:, 3:]

    def _speed(self, t: np.ndarray, span: np.ndarray | None = None) -> np.ndarray:
        h = self._homogeneous(t, 1, span)
        inv_w = 1.0 / h[:, 3:4]
        d1 = (h[:, 4:7] - h[:, 7:8] * (h[:, 0:3] * inv_w)) * inv_w
        return np.sqrt(np.einsum("ij,ij->i", d1, d1))

    def _speed_integral(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """∫_a^b |P'(t)| dt per pair, 8-point Gauss–Legendre (exact enough inside one tabulated leaf)."""
        half = 0.5 * (b - a)
        nodes = (0.5 * (a + b))[:, None] + half[:, None] * _GL_NODES[None, :]
        speed = self._speed(nodes.ravel()).reshape(nodes.shape)
        return half * (speed @ _GL_WEIGHTS)

    def tangent_curvature(self, t: np.ndarray | float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Point, unit tangent and curvature |P' × P''| / |P'|³ at parameter(s) ``t``.

        Where the parametrisation stalls (|P'| = 0, e.g. a repeated end control point) the tangent and
        curvature are taken a hair (1e-7 of the domain) inside the curve: their limits where the curve is
        geometrically smooth.
        """
        t_arr = np.clip(np.atleast_1d(np.asarray(t, dtype=float)), self.knots[0], self.knots[-1])
        point, d1, d2 = self._rational(self._homogeneous(t_arr, 2))
        speed = np.sqrt(np.einsum("ij,ij->i", d1, d1))
        t0, t1 = self.domain
        stalled = speed <= 1e-12 * max(self.length / (t1 - t0), 1e-300)
        if np.any(stalled):
            nudge = 1e-7 * (t1 - t0)
            ts = t_arr[stalled]
            ts = np.where(ts + nudge <= t1, ts + nudge, ts - nudge)
            _, d1[stalled], d2[stalled] = self._rational(self._homogeneous(ts, 2))
            speed = np.sqrt(np.einsum("ij,ij->i", d1, d1))
        safe = np.where(speed > 0, speed, 1.0)
        tangent = d1 / safe[:, None]
        cross = d1[:, _NEXT] * d2[:, _AFTER] - d1[:, _AFTER] * d2[:, _NEXT]  # P' × P'' (np.cross is slow)
        curvature = np.where(speed > 0, np.sqrt(np.einsum("ij,ij->i", cross, cross)) / safe**3, 0.0)
        return point, tangent, curvature

    # ------------------------------------------------------------ arc length
    def length_at(self, t: np.ndarray | float) -> np.ndarray:
        """Arc length from the start of the curve to parameter(s) ``t``."""
        t_arr = np.atleast_1d(np.asarray(t, dtype=float))
        t_arr = np.minimum(np.maximum(t_arr, self.knots[0]), self.knots[-1])
        leaf = self._leaf_t[1:-1].searchsorted(t_arr, side="right")
        return self._leaf_s[leaf] + self._speed_integral(self._leaf_t[leaf], t_arr)

    def parameter_at_length(self, s: np.ndarray | float) -> np.ndarray:
        """Parameter(s) t with ``length_at(t) == s`` (s clamped to [0, length])."""
        s_arr = np.clip(np.atleast_1d(np.asarray(s, dtype=float)), 0.0, self.length)
        if self.length == 0.0:
            return np.full(s_arr.shape, self.knots[0])
        leaf = np.clip(np.searchsorted(self._leaf_s, s_arr, side="right") - 1, 0, len(self._leaf_s) - 2)
        lo, hi = self._leaf_t[leaf].copy(), self._leaf_t[leaf + 1].copy()
        s_lo, s_hi = self._leaf_s[leaf], self._leaf_s[leaf + 1]
        ds = s_hi - s_lo
        x = np.divide(s_arr - s_lo, ds, out=np.zeros_like(s_arr), where=ds > 0)
        # First guess: cubic Hermite of t(s) with the exact end slopes dt/ds = 1/|P'| (error O(ds⁴)).
        slope_a, slope_b = self._leaf_dt_ds[leaf, 0], self._leaf_dt_ds[leaf, 1]
        x2, x3 = x * x, x * x * x
        hermite = ((2 * x3 - 3 * x2 + 1) * lo + (x3 - 2 * x2 + x) * ds * slope_a
                   + (3 * x2 - 2 * x3) * hi + (x3 - x2) * ds * slope_b)  # fmt: skip
        linear = lo + (hi - lo) * x
        t = np.where(np.isfinite(hermite), np.clip(hermite, lo, hi), linear)
        leaf_start = lo.copy()
        m = len(s_arr)
        # Newton converges quadratically: after a Newton step below 1e-7 of the domain the remaining
        # error is ~1e-14 of it (times the speed's relative variation), so the loop stops there.
        scale = 1e-7 * (self.knots[-1] - self.knots[0])
        for _ in range(_INVERSE_NEWTON_STEPS):
            # One speed evaluation serves both the partial integral (8 nodes) and Newton's slope.
            half = 0.5 * (t - leaf_start)
            nodes = (leaf_start + half)[:, None] + half[:, None] * _GL_NODES[None, :]
            speed = self._speed(np.concatenate((nodes.ravel(), t)))
            residual = s_lo + half * (speed[: 8 * m].reshape(m, 8) @ _GL_WEIGHTS) - s_arr
            slope = speed[8 * m :]
            # Keep a bracket so a stall (zero speed) or a wild step falls back to bisection.
            hi = np.where(residual > 0, t, hi)
            lo = np.where(residual <= 0, t, lo)
            # (an exact hit stays put even where the speed is 0; elsewhere a stall means bisection)
            stall = np.where(residual == 0, 0.0, np.inf)
            newton = t - np.divide(residual, slope, out=stall, where=slope > 0)
            inside = (newton >= lo) & (newton <= hi)
            t_new = np.where(inside, newton, 0.5 * (lo + hi))
            step = np.max(np.abs(t_new - t))
            t = t_new
            if step <= scale and np.all(inside):
                break
        return t

    def at_length(self, s: np.ndarray | float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Point, unit tangent and curvature (1/mm) at arc length(s) ``s`` from the curve's start."""
        return self.tangent_curvature(self.parameter_at_length(s))

    # ---------------------------------------------------------- nearest point
    def nearest(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Distance, parameter and arc length of the nearest curve point to each of ``points`` (m, 3).

        Coarse stage: the table (4–16 points per span, knots included) with one-sided slopes of d²/2
        gives every bracket that must hold a local minimum: an interval where the slope turns from - to
        +, or a sample where it does (an end of the curve, or a kink at a knot). The best few brackets
        (by sampled distance) plus the best sample itself are refined by safeguarded Newton on the slope,
        and the closest converged point wins. The ends are candidates, so the result is clamped to the
        curve. On long curves, spans whose bounding sphere is farther than some span's start point are
        skipped first. Distances are exact to ~1e-12 mm; the foot point's parameter to a few nm of arc.
        """
        p = np.atleast_2d(np.asarray(points, dtype=float))
        m = len(p)
        rel = p - self._origin
        rel_sq_p = np.einsum("ij,ij->i", rel, rel)[:, None]
        rel_t, rel_sq, d1_t, rel_d1 = (self._sample_rel_t, self._sample_rel_sq, self._sample_d1_t,
                                       self._sample_rel_d1)  # fmt: skip
        if len(self._sample_t) > _PRUNE_ABOVE_SAMPLES:
            # Prune spans: keep those whose bounding sphere comes closer than some span's start point
            # (slack for rounding: a span's start point lies on or inside its sphere).
            starts = slice(None, None, self._per_span)
            upper2 = np.min(rel_sq[starts] - 2.0 * (rel @ rel_t[:, starts]), axis=1)[:, None] + rel_sq_p
            center2 = self._span_center_sq - 2.0 * (rel @ self._span_center_t) + rel_sq_p
            lower = np.sqrt(np.maximum(center2, 0.0)) - self._span_radius
            upper = np.sqrt(np.maximum(upper2, 0.0))
            kept = np.flatnonzero(np.any(lower <= upper * (1 + 1e-9) + 1e-9, axis=0))
            index = np.unique((kept[:, None] * self._per_span + self._span_samples).ravel())
            consecutive = np.diff(index) == 1
            sample_t = self._sample_t[index]
            rel_t, rel_sq, rel_d1 = rel_t[:, index], rel_sq[index], rel_d1[:, index]
            d1_t = d1_t[:, :, index]
        else:
            consecutive = True
            sample_t = self._sample_t
        n = len(sample_t)
        # |P - p|²/2 and the one-sided slopes (P - p)·P' of it at the samples, as matrix products.
        half_d2 = 0.5 * (rel_sq - 2.0 * (rel @ rel_t) + rel_sq_p)
        slope_right = rel_d1[0] - rel @ d1_t[0]
        slope_left = rel_d1[1] - rel @ d1_t[1]
        # A minimum sits where the slope turns from - to +.
        # Slots 0..n-1: a minimum exactly at sample i (an end, or a kink at a knot).
        at_sample = np.ones((m, n), dtype=bool)
        at_sample[:, 1:] = slope_left[:, 1:] <= 0
        at_sample[:, :-1] &= slope_right[:, :-1] >= 0
        # Slots n..2n-2: a minimum inside the interval (t_i, t_i+1).
        inside = (slope_right[:, :-1] < 0) & (slope_left[:, 1:] > 0) & consecutive
        rank = np.concatenate((np.where(at_sample, half_d2, np.inf),
                               np.where(inside, np.minimum(half_d2[:, :-1], half_d2[:, 1:]), np.inf)),
                              axis=1)  # fmt: skip
        k = min(_NEAREST_STARTS, rank.shape[1])
        slot = np.argpartition(rank, k - 1, axis=1)[:, :k]  # (m, k)
        rows = np.arange(m)[:, None]
        valid = np.isfinite(rank[rows, slot])
        first = np.where(slot < n, slot, slot - n)
        last = np.where((slot < n) | ~valid, first, slot - n + 1)  # empty slots: frozen, never chosen
        g_lo, g_hi = slope_right[rows, first], slope_left[rows, last]
        # One more, frozen start at the best sample: the result is never worse than the sampling.
        best_sample = np.argmin(half_d2, axis=1)[:, None]
        first = np.concatenate((first, best_sample), axis=1).ravel()
        last = np.concatenate((last, best_sample), axis=1).ravel()
        zero = np.zeros((m, 1))
        g_lo = np.concatenate((g_lo, zero), axis=1).ravel()
        g_hi = np.concatenate((g_hi, zero), axis=1).ravel()
        valid = np.concatenate((valid, np.ones((m, 1), dtype=bool)), axis=1).ravel()
        k += 1
        lo, hi = sample_t[first], sample_t[last]
        # Start where the slope's chord crosses zero (secant), inside the bracket.
        denom = g_hi - g_lo
        t = lo + (hi - lo) * np.divide(-g_lo, denom, out=np.full(len(lo), 0.5), where=denom > 0)
        q = np.repeat(p, k, axis=0)[:, None, :]
        for _ in range(_NEAREST_NEWTON_STEPS):
            t_at = t
            # Homogeneous form, no division: with E = A - W q (and E', E''), the slope of d²/2 is
            # g / W³ with g = (E·E') W - (E·E) W', so g has its sign and its root; Newton runs on g.
            h = self._homogeneous(t, 2).reshape(-1, 3, 4)
            weight = h[:, :, 3]  # W, W', W''
            e = h[:, :, :3] - weight[:, :, None] * q  # E, E', E''
            gram = np.matmul(e, e.transpose(0, 2, 1))
            ee, ee1, e1e1, ee2 = gram[:, 0, 0], gram[:, 0, 1], gram[:, 1, 1], gram[:, 0, 2]
            w, w1, w2 = weight[:, 0], weight[:, 1], weight[:, 2]
            g = ee1 * w - ee * w1
            g_prime = (e1e1 + ee2) * w - ee1 * w1 - ee * w2
            # Safeguarded Newton: the bracket shrinks on the slope's sign, and a step that leaves it
            # (or a concave model) is replaced by bisection.
            hi = np.where(g > 0, t, hi)
            lo = np.where(g < 0, t, lo)
            newton = t - g / np.where(g_prime > 0, g_prime, np.nan)
            accepted = (newton >= lo) & (newton <= hi)
            t = np.where(accepted, newton, 0.5 * (lo + hi))
            if np.max(np.abs(t - t_at)) <= self._nearest_step_tolerance:
                break
        # The distance is exact at t_at. Where the last step was Newton's (at most 0.1 µm of arc) the
        # foot point moves on to t, and d² drops by the quadratic model's f'²/f'' = g²/(g' W³); both
        # are then exact to O(step³) (~1e-12 mm), which saves evaluating the curve again.
        refined = accepted & (g_prime > 0) & (np.abs(t - t_at) <= self._nearest_step_tolerance)
        d2 = ee / (w * w)
        d2 = np.where(refined, d2 - g * g / np.where(refined, g_prime * w**3, 1.0), d2)
        t_at = np.where(refined, t, t_at)
        d2 = np.where(valid, np.maximum(d2, 0.0), np.inf).reshape(m, k)
        col = np.argmin(d2, axis=1)
        rows = np.arange(m)
        t_best = t_at.reshape(m, k)[rows, col]
        d2_best = d2[rows, col]
        return np.sqrt(d2_best), t_best, self.length_at(t_best)


def _validated(points, weights, knots, order) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """Check a NURBS definition against the GSK 25i rules; one clear ValueError for the first problem."""
    try:
        order_int = int(order)
    except (TypeError, ValueError):
        raise ValueError(f"NURBS rank must be 2, 3 or 4, got {order!r}") from None
    if order_int != order or order_int not in (2, 3, 4):
        raise ValueError(f"NURBS rank must be 2, 3 or 4, got {order!r}")
    points = np.asarray(points, dtype=float)
    if points.ndim != 2 or points.shape[1] != 3:
        raise ValueError(f"NURBS control points must be an (n, 3) array, got shape {points.shape}")
    n = len(points)
    if n < order_int:
        raise ValueError(f"a rank-{order_int} NURBS needs at least {order_int} control points, got {n}")
    if not np.all(np.isfinite(points)):
        raise ValueError("NURBS control points must be finite numbers")
    if np.all(points == points[0]):
        raise ValueError("NURBS control points all coincide: the curve would have no length")
    weights = np.asarray(weights, dtype=float)
    if weights.shape != (n,):
        raise ValueError(f"NURBS needs one weight per control point ({n}), got shape {weights.shape}")
    if not np.all(np.isfinite(weights)) or np.any(weights <= 0):
        bad = int(np.flatnonzero(~(np.isfinite(weights) & (weights > 0)))[0])
        raise ValueError(f"NURBS weights must be positive; weight {bad + 1} is {weights[bad]}")
    if weights.max() > MAX_WEIGHT_RATIO * weights.min():
        raise ValueError(f"NURBS weights {weights.min():g} and {weights.max():g} differ by more than a "
                         f"factor of {MAX_WEIGHT_RATIO:g}: the curve cannot be evaluated to the tool path's "
                         "accuracy")  # fmt: skip
    knots = np.asarray(knots, dtype=float)
    if knots.ndim != 1 or len(knots) != n + order_int:
        count = knots.size if knots.ndim == 1 else knots.shape
        raise ValueError(
            f"NURBS knot count must be control points + rank = {n} + {order_int} = {n + order_int}, "
            f"got {count}"
        )
    if not np.all(np.isfinite(knots)):
        raise ValueError("NURBS knots must be finite numbers")
    drops = np.flatnonzero(np.diff(knots) < 0)
    if drops.size:
        i = int(drops[0])
        raise ValueError(f"NURBS knots must be non-decreasing: knot {i + 2} ({knots[i + 1]}) < knot {i + 1} "
                         f"({knots[i]})")  # fmt: skip
    if np.any(knots[:order_int] != knots[0]):
        raise ValueError(f"NURBS knots must be clamped: the first {order_int} knots (the rank) must be equal")
    if np.any(knots[-order_int:] != knots[-1]):
        raise ValueError(f"NURBS knots must be clamped: the last {order_int} knots (the rank) must be equal")
    if knots[-1] <= knots[0]:
        raise ValueError("NURBS knots span no parameter range (first knot = last knot)")
    values, counts = np.unique(knots, return_counts=True)
    if counts[0] > order_int or counts[-1] > order_int:
        raise ValueError(f"NURBS end knots may repeat exactly {order_int} times (the rank), not more")
    interior = counts[1:-1] >= order_int
    if np.any(interior):
        value = values[1:-1][interior][0]
        raise ValueError(
            f"NURBS knot {value} repeats {int(counts[1:-1][interior][0])} times; inside the curve a knot may "
            f"repeat at most rank - 1 = {order_int - 1} times (more would break the curve apart)"
        )
    return points, weights, knots, order_int
