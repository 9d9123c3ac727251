"""The declared observation and reward (:mod:`cnc_gym.envs.engine.specs`) and the rows the step reads."""

from __future__ import annotations

import numpy as np
import pytest

from cnc_gym.envs.engine.layout import (
    BLOCK_COLS,
    LOOKAHEAD_ROWS,
    OBS_COLS,
    REWARD_COLS,
    SIG_KNOB,
    SIG_SPEED,
    SIG_VIOLATED,
    T_CAPPED_SQUARE,
    T_NONE,
    T_SATURATE,
)
from cnc_gym.envs.engine.specs import ObservationSpec, RewardSpec

SPEC = ObservationSpec(
    signals=(("speed", 0.5, -1.0, 1.0), ("knob", 1.0, -1.0, 1.0)),
    lookahead=(("curvature", "saturate", 10.0, 1.0, 0.0, 1.0), ("speed_limit", "none", 0.0, 0.1, 0.0, 2.0)),
    points=3,
    tail=(("violated", 1.0, 0.0, 1.0),),
)


def test_observation_spec_rows_size_and_bounds():
    signals, blocks, tail = SPEC.tables()
    assert signals.shape == (2, OBS_COLS) and blocks.shape == (2, BLOCK_COLS) and tail.shape == (1, OBS_COLS)
    np.testing.assert_array_equal(signals[:, 0], [SIG_SPEED, SIG_KNOB])
    np.testing.assert_array_equal(tail[0], [SIG_VIOLATED, 1.0, 0.0, 1.0])
    np.testing.assert_array_equal(blocks[:, :2], [[LOOKAHEAD_ROWS.index("curvature"), T_SATURATE],
                                                  [LOOKAHEAD_ROWS.index("speed_limit"), T_NONE]])  # fmt: skip
    # signals, then each block's points, then the tail: 2 + 2·3 + 1 entries, bounds in that order
    assert SPEC.size == 9
    np.testing.assert_array_equal(SPEC.low, [-1, -1, 0, 0, 0, 0, 0, 0, 0])
    np.testing.assert_array_equal(SPEC.high, [1, 1, 1, 1, 1, 2, 2, 2, 1])
    assert SPEC.low.dtype == np.float32


def test_an_empty_spec_has_rows_of_the_right_width():
    signals, blocks, tail = ObservationSpec(signals=(), lookahead=(), points=4).tables()
    assert signals.shape == (0, OBS_COLS) and blocks.shape == (0, BLOCK_COLS) and tail.shape == (0, OBS_COLS)


def test_reward_spec_rows_and_term_keys():
    spec = RewardSpec(terms=(("violated", "linear", 0.0, -2.0), ("speed", "capped_square", 3.0, 0.5)),
                      term_keys=("r_violation", "r_speed"))  # fmt: skip
    np.testing.assert_array_equal(spec.table(), [[SIG_VIOLATED, T_NONE, 0.0, -2.0],
                                                 [SIG_SPEED, T_CAPPED_SQUARE, 3.0, 0.5]])  # fmt: skip
    assert spec.table().shape[1] == REWARD_COLS
    with pytest.raises(ValueError, match="one term key per term"):
        RewardSpec(terms=spec.terms, term_keys=("only_one",))


def test_unknown_names_are_refused():
    with pytest.raises(ValueError):
        ObservationSpec(signals=(("no_such_signal", 1.0, 0.0, 1.0),), lookahead=(), points=1).tables()
    with pytest.raises(KeyError):
        RewardSpec(terms=(("speed", "cubic", 0.0, 1.0),)).table()
