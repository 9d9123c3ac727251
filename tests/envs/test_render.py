"""Plotting support: the bounded series (exact per bin, constant memory) and the choice of side views."""

from __future__ import annotations

from itertools import pairwise

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cnc_gym.envs.render import BinnedSeries, wants_z_views
from cnc_gym.errors import ConfigError


def bins_by_brute_force(x: np.ndarray, counts: np.ndarray) -> dict[str, np.ndarray]:
    edges = np.concatenate(([0], np.cumsum(counts)))
    parts = [x[a:b] for a, b in pairwise(edges)]
    return {
        "max": np.array([p.max() for p in parts]),
        "min": np.array([p.min() for p in parts]),
        "mean": np.array([p.mean() for p in parts]),
        "last": np.array([p[-1] for p in parts]),
    }


@pytest.mark.parametrize("n", [1, 7, 64, 65, 1000, 4099])
def test_each_bin_holds_the_exact_reductions_of_its_samples(n):
    x = np.random.default_rng(n).normal(size=n)
    series = BinnedSeries({"hi": "max", "lo": "min", "avg": "mean", "end": "last"}, max_bins=64)
    for value in x:
        series.add(value, value, value, value)
    data = series.arrays()
    counts = data["samples"]
    assert counts.sum() == n == series.count
    assert len(counts) <= 64 + 1  # the closed bins plus the one being filled
    assert np.all(counts[:-1] == series.width)  # equal bins; only the last may be partial
    expected = bins_by_brute_force(x, counts)
    np.testing.assert_array_equal(data["hi"], expected["max"])
    np.testing.assert_array_equal(data["lo"], expected["min"])
    np.testing.assert_array_equal(data["end"], expected["last"])
    np.testing.assert_allclose(data["avg"], expected["mean"], rtol=1e-12, atol=1e-12)
    # The envelope keeps the extremes of the whole series exactly.
    assert data["hi"].max() == x.max() and data["lo"].min() == x.min()


def test_memory_does_not_grow_with_the_number_of_samples():
    series = BinnedSeries({"t": "last", "e": "max"}, max_bins=16)
    arrays_before = (series._bins.nbytes, series._weights.nbytes, len(series._acc))
    for k in range(100_000):
        series.add(float(k), float(k % 7))
    assert (series._bins.nbytes, series._weights.nbytes, len(series._acc)) == arrays_before
    data = series.arrays()
    assert len(data["t"]) <= 17 and data["t"][-1] == 99_999.0 and data["e"].max() == 6.0


def test_clear_starts_over():
    series = BinnedSeries({"v": "mean"}, max_bins=4)
    series.extend([[1.0]] * 10)
    series.clear()
    series.add(5.0)
    data = series.arrays()
    assert series.width == 1 and list(data["v"]) == [5.0] and list(data["samples"]) == [1]


@pytest.mark.parametrize(("columns", "max_bins"), [({}, 8), ({"v": "median"}, 8), ({"v": "max"}, 7),
                                                   ({"v": "max"}, 0), ({"v": "max"}, True)])  # fmt: skip
def test_bad_arguments_are_config_errors(columns, max_bins):
    with pytest.raises(ConfigError):
        BinnedSeries(columns, max_bins)


def path(*points: tuple[float, float, float]) -> np.ndarray:
    return np.array(points, dtype=float)


def test_side_views_for_depth_changes_and_drilling_not_for_a_plunge():
    # A plunge to one depth, then an XY contour: the XY view says it all.
    plunge_then_contour = path((0, 0, 5), (0, 0, -1), (10, 0, -1), (10, 10, -1))
    assert not wants_z_views(plunge_then_contour, np.array([True, True, True, True]))
    # Two depths of XY cutting (a step-down): side views.
    two_depths = path((0, 0, -1), (10, 0, -1), (10, 0, -2), (0, 0, -2))
    assert wants_z_views(two_depths, np.array([True, True, True, True]))
    # A ramp (X and Z together): side views.
    assert wants_z_views(path((0, 0, 0), (10, 0, -1)), np.array([True, True]))
    # Drilling: Z-only cutting moves with rapids between holes.
    drill = path((0, 0, 2), (0, 0, -10), (0, 0, 2), (20, 0, 2), (20, 0, -10), (20, 0, 2))
    cutting = np.array([True, False, False, True, False, False])
    assert wants_z_views(drill, cutting)
    assert not wants_z_views(np.zeros((0, 3)), np.zeros(0, dtype=bool))


def test_the_path_envelope_keeps_every_maximum_in_at_most_max_bins():
    from cnc_gym.envs.render import path_envelope

    rng = np.random.default_rng(3)
    lengths = np.where(rng.random(5000) < 0.01, 0.0, rng.exponential(0.2, 5000))  # some dwells (length 0)
    edges = np.concatenate(([0.0], np.cumsum(lengths)))
    error = rng.random(5000)
    error[4000:] = np.nan  # not reached (a truncated run)
    x, y = path_envelope(edges, error, max_bins=300)
    assert len(x) == 301 and len(y) == 300 and x[0] == edges[0] and x[-1] == pytest.approx(edges[-1])
    assert np.nanmax(y) == np.nanmax(error[lengths > 0])
    # Each stretch's value is at most the envelope of every bin it overlaps (an upper envelope) ...
    for k in rng.choice(np.flatnonzero((lengths > 0) & np.isfinite(error)), 200):
        inside = (x[1:] > edges[k]) & (x[:-1] < edges[k + 1])
        assert np.all(y[inside] >= error[k])
    # ... and nothing past the last stretch reached is drawn.
    assert np.all(np.isnan(y[x[:-1] > edges[4001]]))
    # Few stretches: drawn as they are.
    x_few, y_few = path_envelope(edges[:51], error[:50], max_bins=300)
    assert np.array_equal(x_few, edges[:51]) and np.array_equal(y_few, error[:50], equal_nan=True)


@settings(max_examples=60, deadline=None)
@given(n=st.integers(0, 300), max_bins=st.sampled_from([2, 4, 16]), seed=st.integers(0, 2**32 - 1),
       holes=st.booleans())
def test_rows_added_at_once_are_the_samples_added_one_by_one(n, max_bins, seed, holes):
    # extend_rows (cnc-gym run's compiled episodes) keeps the bins of add() bit for bit: NaN and -0.0
    # included, whatever the blocks the rows come in.
    rng = np.random.default_rng(seed)
    rows = rng.normal(size=(n, 4))
    if holes:
        rows[rng.random(rows.shape) < 0.1] = np.nan
        rows[rng.random(rows.shape) < 0.1] = -0.0
    columns = {"hi": "max", "lo": "min", "avg": "mean", "end": "last"}
    one, many = BinnedSeries(columns, max_bins), BinnedSeries(columns, max_bins)
    for row in rows.tolist():
        one.add(*row)
    at = 0
    while at < n:
        k = int(rng.integers(1, 40))
        many.extend_rows(rows[at : at + k])
        at += k
    a, b = one.arrays(), many.arrays()
    assert (one.count, one.width) == (many.count, many.width)
    for key in a:
        assert a[key].tobytes() == b[key].tobytes(), key
