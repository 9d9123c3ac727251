"""The shipped suites: fixed splits, reproducible texts (hashes, bit for bit), tiers, valid G-code."""

from __future__ import annotations

import hashlib

import numpy as np
import pytest

from cnc_gym.benchmark.suites import (
    DEFAULT_SUITE,
    SPECS,
    TIER_THRESHOLDS,
    check_suite,
    load_suite,
    path_properties,
    suite_digest,
    tier_of,
)
from cnc_gym.gcode import interpret_file
from cnc_gym.machine import load_machine


@pytest.fixture(scope="module")
def suite():
    return load_suite(DEFAULT_SUITE)


def test_split_sizes_and_held_out_family(suite):
    sizes = {split: len(suite.programs(split)) for split in ("train", "val", "test")}
    assert sizes["train"] >= 200 and sizes["val"] >= 50 and sizes["test"] >= 50
    train_families = {e.family for e in suite.programs("train")}
    test_families = {e.family for e in suite.programs("test")}
    assert test_families - train_families  # engraving is held out of train
    # ... and a parameter range: freeform chords below the train split's shortest median
    train_chord = min(e.properties["median_segment_mm"] for e in suite.programs("train", "freeform"))
    test_chord = min(e.properties["median_segment_mm"] for e in suite.programs("test", "freeform"))
    assert test_chord < train_chord
    names = [e.name for e in suite.entries]
    assert len(names) == len(set(names))


def test_every_file_matches_the_manifest_and_the_suite_hash(suite):
    for e in suite.entries:
        assert hashlib.sha256(e.path.read_bytes()).hexdigest() == e.sha256, e.name
    programs = [{"name": e.name, "split": e.split, "family": e.family, "sha256": e.sha256}
                for e in suite.entries]
    assert suite_digest(programs) == suite.sha256


def test_the_generator_reproduces_every_text_bit_for_bit():
    assert check_suite(DEFAULT_SUITE) == []


def test_tiers_come_from_the_measured_properties(suite):
    for e in suite.entries:
        assert e.tier == tier_of(e.properties), e.name
    tiers = {e.tier for e in suite.programs("test")}
    assert tiers == {"easy", "medium", "hard"}
    # The rule itself: points per property at the documented thresholds.
    easy = {"max_turn_deg": 10.0, "median_segment_mm": 5.0, "max_curvature_1_mm": 0.01,
            "max_feed_mm_min": 1000}
    hard = {"max_turn_deg": 150.0, "median_segment_mm": 0.1, "max_curvature_1_mm": 2.0,
            "max_feed_mm_min": 5000}
    assert tier_of(easy) == "easy" and tier_of(hard) == "hard"
    assert set(TIER_THRESHOLDS) == set(easy)


@pytest.mark.parametrize("split", ["train", "val", "test"])
def test_a_sample_interprets_as_gsk25i_with_the_recorded_properties(suite, split):
    machine = load_machine(SPECS[DEFAULT_SUITE].machine)
    for e in suite.draw(split, 6, seed=1):
        toolpath = interpret_file(str(e.path), dialect="gsk25i", machine=machine)
        assert path_properties(toolpath, machine) == pytest.approx(e.properties, rel=1e-6, abs=1e-6)


def test_draw_is_reproducible_and_without_repeats(suite):
    a, b = suite.draw("train", 32, seed=7), suite.draw("train", 32, seed=7)
    assert [e.name for e in a] == [e.name for e in b]
    assert len({e.name for e in a}) == 32
    assert all(e.split == "train" for e in a)
    assert len(suite.draw("val", 10_000)) == len(suite.programs("val"))


def test_paths_feed_the_env(suite):
    import gymnasium

    import cnc_gym  # noqa: F401

    env = gymnasium.make("cnc_gym/Feedrate-v0", programs=suite.paths("test")[:2])
    _, info = env.reset(seed=0)
    assert info["program"] in {p.stem for p in suite.paths("test")[:2]}
    env.close()


def test_unknown_suite_or_split_is_one_clear_error(suite):
    from cnc_gym.errors import ConfigError

    with pytest.raises(ConfigError, match="unknown suite"):
        load_suite("no-such-suite")
    with pytest.raises(ConfigError, match="unknown split"):
        suite.programs("holdout")
    assert np.isfinite(len(suite.entries))
