"""The compiled nearest-point searches (helix, NURBS) against brute force and the NURBS curve's own search."""

from __future__ import annotations

import math

import numpy as np
import pytest

from cnc_gym.toolpath.nearest import (
    _GROUP_MARGIN,
    NURBS_GROUP,
    _group_spheres,
    _helix_root,
    _interval_spheres,
    helix_nearest,
    nurbs_distance2,
    nurbs_table,
)
from cnc_gym.toolpath.nurbs import NurbsCurve


def helix_brute_d2(p, cu, cv, w0, rise, radius, theta0, sweep) -> float:
    """Least squared distance over 400 001 samples of the sweep, refined around the best one."""
    f = np.linspace(0.0, 1.0, 400_001)

    def d2(f):
        ang = theta0 + sweep * f
        return (cu + radius * np.cos(ang) - p[0]) ** 2 + (cv + radius * np.sin(ang) - p[1]) ** 2 + (
            w0 + rise * f - p[2]) ** 2  # fmt: skip

    values = d2(f)
    i = int(np.argmin(values))
    fine = np.linspace(f[max(i - 1, 0)], f[min(i + 1, len(f) - 1)], 4001)
    return float(min(values.min(), d2(fine).min()))


HELIX_CASES = ["near", "axis", "far", "steep", "flat", "beyond"]


@pytest.mark.parametrize("case", HELIX_CASES)
def test_helix_nearest_is_the_global_minimum(case):
    # Random helices and points of six kinds: near the helix (contour error), on and near the axis (many
    # equal minima), far away, steep helices (rise ≫ radius·sweep: the distance is convex), flat arcs, and
    # near the helix's continuation past either end (the ends are the nearest points, or compete with a
    # root). The compiled search must never be worse than brute force, nor better than its resolution.
    rng = np.random.default_rng(HELIX_CASES.index(case))
    for _ in range(150):
        cu, cv, w0 = rng.normal(size=3) * 5
        radius = float(rng.uniform(0.2, 10.0))
        theta0 = float(rng.uniform(-4.0, 4.0))
        sweep = float(rng.uniform(-20.0, 20.0))
        rise = {"steep": 200.0, "flat": 0.0}.get(case, float(rng.normal() * 5))
        f = rng.uniform(0.0, 1.0) if case != "beyond" else rng.choice([-1.0, 1.0]) * rng.uniform(0.0, 0.3) + (
            rng.random() < 0.5)  # fmt: skip
        on = np.array([cu + radius * math.cos(theta0 + sweep * f), cv + radius * math.sin(theta0 + sweep * f),
                       w0 + rise * f])  # fmt: skip
        p = {
            "near": on + rng.normal(size=3) * 0.01,
            "axis": np.array([cu, cv, w0 + rise * rng.uniform(-0.2, 1.2)]) + rng.normal(size=3) * 1e-4,
            "far": on + rng.normal(size=3) * 20.0,
        }.get(case, on + rng.normal(size=3) * 0.5)
        d2, frac = helix_nearest(p[0], p[1], p[2], cu, cv, w0, rise, radius, theta0, sweep)
        brute = helix_brute_d2(p, cu, cv, w0, rise, radius, theta0, sweep)
        assert math.sqrt(d2) <= math.sqrt(brute) + 1e-12
        assert math.sqrt(d2) >= math.sqrt(brute) - 1e-6
        assert 0.0 <= frac <= 1.0


def test_helix_root_converges_in_a_few_newton_steps():
    # Near the helix (a contour error of up to 0.1 mm) Newton from the planar nearest angle converges in
    # two or three slope evaluations. A converged step rounds to nothing, so the search must stop on the
    # step's size before it tests the bracket: testing the bracket first bisected it down from the far end
    # again (20 to 50 evaluations on a third of such points).
    rng = np.random.default_rng(7)
    cu, cv, w0, radius, pitch = 1.5, -2.0, 0.3, 8.0, 0.5
    counts = []
    for _ in range(2000):
        theta0 = float(rng.uniform(-4.0, 4.0))
        sweep = float(rng.choice([-1.0, 1.0]) * math.pi)
        rise = -pitch * abs(sweep) / (2 * math.pi)
        f_on = float(rng.uniform(0.2, 0.8))
        ang = theta0 + sweep * f_on
        p = np.array([cu + radius * math.cos(ang), cv + radius * math.sin(ang), w0 + rise * f_on])
        p += rng.normal(size=3) * rng.choice([1e-6, 1e-3, 0.1])
        # A stretch around the point's own angle where the distance is convex; Newton starts at the planar
        # nearest angle.
        lo, hi = f_on - 0.2, f_on + 0.2
        start = (math.atan2(p[1] - cv, p[0] - cu) - theta0) / sweep
        start = start + round(f_on - start)  # the planar angle's fraction next to f_on (sweep = ±π)
        start = min(max(start, lo), hi)
        found, _, d2, evaluations = _helix_root(*p, cu, cv, w0, rise, radius, theta0, sweep, lo, hi, start)
        assert found
        assert math.sqrt(d2) == pytest.approx(math.sqrt(helix_brute_d2(p, cu, cv, w0, rise, radius, theta0,
                                                                        sweep)), abs=1e-9)  # fmt: skip
        counts.append(evaluations)
    assert max(counts) <= 5
    assert np.mean(counts) <= 3.0


def test_helix_root_reports_a_stretch_without_a_root():
    # The slope is positive across the whole bracket (the point lies before the stretch): no root, and the
    # caller compares the stretch's ends instead.
    cu, cv, w0, radius, theta0, sweep, rise = 0.0, 0.0, 0.0, 5.0, 0.0, math.pi, 2.0
    p = (radius * math.cos(-0.3), radius * math.sin(-0.3), -0.5)
    found, _, _, _ = _helix_root(*p, cu, cv, w0, rise, radius, theta0, sweep, 0.0, 0.4, 0.2)
    assert not found


def random_curve(rng: np.random.Generator, n_ctrl: int, order: int) -> NurbsCurve:
    ctrl = np.cumsum(rng.normal(size=(n_ctrl, 3)) * np.array([3.0, 3.0, 0.6]), axis=0)
    knots = np.concatenate((np.zeros(order), np.sort(rng.uniform(0, 1, n_ctrl - order)), np.ones(order)))
    return NurbsCurve(ctrl, rng.uniform(0.3, 3.0, n_ctrl), knots, order=order)


@pytest.mark.parametrize("n_ctrl", [4, 7, 40, 120])  # 120 control points: a table past the pruning size
def test_nurbs_distance_matches_the_curves_own_search(n_ctrl):
    rng = np.random.default_rng(n_ctrl)
    for order in (2, 3, 4):
        curve = random_curve(rng, n_ctrl, order)
        floats, header = nurbs_table(curve)
        offsets = rng.normal(size=(40, 3)) * rng.choice([1e-3, 0.1, 5.0])
        points = curve.evaluate(rng.uniform(0, 1, 40)) + offsets
        expected, _, _ = curve.nearest(points)
        got = np.array([math.sqrt(nurbs_distance2(floats, header, *p, math.inf)) for p in points])
        np.testing.assert_allclose(got, expected, rtol=0, atol=1e-9)
        # With a bound: the distance where it is below the bound, else anything at or above the bound
        # (the caller keeps the least distance, and the bound is its best so far).
        for p, d in zip(points[:10], expected[:10], strict=True):
            assert nurbs_distance2(floats, header, *p, (0.5 * d) ** 2) >= (0.5 * d) ** 2
            above = nurbs_distance2(floats, header, *p, (2 * d + 1e-6) ** 2)
            assert math.sqrt(above) == pytest.approx(d, abs=1e-9)


def test_nurbs_tables_of_two_curves_share_one_array():
    # The contour meter concatenates the tables of every NURBS row; the header's offset finds each one.
    rng = np.random.default_rng(9)
    a, b = random_curve(rng, 6, 4), random_curve(rng, 9, 3)
    fa, _ = nurbs_table(a)
    fb, hb = nurbs_table(b, offset=len(fa))
    both = np.concatenate((fa, fb))
    p = b.evaluate([0.3])[0] + 0.01
    assert nurbs_distance2(both, hb, *p, math.inf) == nurbs_distance2(fb, nurbs_table(b)[1], *p, math.inf)


@pytest.mark.parametrize("order", [2, 3, 4])
def test_interval_spheres_hold_the_curve_between_neighbouring_samples(order):
    # The pruning bound of the compiled search: every point of the curve between two neighbouring samples
    # of its table lies in that interval's sphere (Bernstein points of the rational curve, positive weights).
    rng = np.random.default_rng(order)
    curve = random_curve(rng, 12, order)
    centre, radius = _interval_spheres(curve)
    t = curve._sample_t
    assert np.all(np.isfinite(radius))
    assert np.all(radius <= np.linalg.norm(np.diff(curve.evaluate(t), axis=0), axis=1) * 10 + 1e-9)  # tight
    for i in range(len(t) - 1):
        inside = curve.evaluate(np.linspace(t[i], t[i + 1], 41))
        assert np.all(np.linalg.norm(inside - centre[i], axis=1) <= radius[i] * (1 + 1e-12) + 1e-12)


@pytest.mark.parametrize("n_ctrl", [5, 40])
def test_group_spheres_hold_their_intervals_spheres_with_slack(n_ctrl):
    # A group's sphere stands for its intervals' tests: each interval sphere lies inside it with the slack
    # that absorbs the rounding of the tests, so skipping a group skips no interval that could pass.
    rng = np.random.default_rng(n_ctrl)
    curve = random_curve(rng, n_ctrl, 4)
    centre, radius = _interval_spheres(curve)
    extent = float(np.abs(centre).max()) + 10.0
    group_centre, group_radius = _group_spheres(centre, radius, extent)
    assert len(group_radius) == -(-len(radius) // NURBS_GROUP)
    for i in range(len(radius)):
        g = i // NURBS_GROUP
        reach = np.linalg.norm(centre[i] - group_centre[g]) + radius[i]
        assert reach <= group_radius[g] - 0.99 * _GROUP_MARGIN * (1.0 + 0.1 * extent)
    # and the search, which skips groups out of reach, still finds the distance a point in every group has
    t = rng.uniform(0, 1, 60)
    points = curve.evaluate(t) + rng.normal(size=(60, 3)) * 1e-3
    floats, header = nurbs_table(curve)
    expected, _, _ = curve.nearest(points)
    got = np.array([math.sqrt(nurbs_distance2(floats, header, *p, math.inf)) for p in points])
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-9)
