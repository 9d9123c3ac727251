"""The observation and the reward as declared records: what the compiled step assembles, not how.

An :class:`ObservationSpec` lists signal entries, look-ahead blocks and tail entries (each with a transform,
a scale and bounds); a :class:`RewardSpec` a weighted sum of transformed signals, optionally with a finish
bonus. Each turns into rows of floats (:meth:`ObservationSpec.tables`, :meth:`RewardSpec.table`) that the
program bank packs after the config and the compiled step reads (:mod:`cnc_gym.envs.engine.step`). An env
version defines its own specs; the signals they name are :data:`~cnc_gym.envs.engine.layout.SIGNALS`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cnc_gym.envs.engine.layout import (
    BLOCK_COLS,
    LOOKAHEAD_ROWS,
    OBS_COLS,
    REWARD_COLS,
    SIGNALS,
    T_CAPPED_SQUARE,
    T_NONE,
    T_SATURATE,
)


@dataclass(frozen=True)
class ObservationSpec:
    """The observation: ``signals`` entries, then ``lookahead`` blocks, then ``tail`` entries, in order.

    A signal entry ``(name, scale, low, high)`` is one of :data:`SIGNALS` (``tail`` entries are signal
    entries too, placed after the blocks); a look-ahead block ``(row, transform, parameter, scale, low,
    high)`` is ``points`` entries, a row of :data:`LOOKAHEAD_ROWS` at each point ahead, ``transform``
    ``"none"`` or ``"saturate"`` (x·p / (1 + x·p)). Each entry is ``clip(transform(x) · scale, low, high)``
    as float32, 0 where NaN.
    """

    signals: tuple[tuple[str, float, float, float], ...]
    lookahead: tuple[tuple[str, str, float, float, float, float], ...]
    points: int
    tail: tuple[tuple[str, float, float, float], ...] = ()

    def tables(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The signal rows (n, 4), the block rows (m, 6) and the tail rows (k, 4) of the kernel."""
        def signal_rows(entries: tuple[tuple[str, float, float, float], ...]) -> np.ndarray:
            rows = [(SIGNALS.index(name), scale, low, high) for name, scale, low, high in entries]
            return np.array(rows, dtype=np.float64).reshape(-1, OBS_COLS)

        codes = {"none": T_NONE, "saturate": T_SATURATE}
        blocks = [(LOOKAHEAD_ROWS.index(row), codes[transform], param, scale, low, high)
                  for row, transform, param, scale, low, high in self.lookahead]  # fmt: skip
        return (signal_rows(self.signals), np.array(blocks, dtype=np.float64).reshape(-1, BLOCK_COLS),
                signal_rows(self.tail))  # fmt: skip

    @property
    def size(self) -> int:
        return len(self.signals) + len(self.lookahead) * self.points + len(self.tail)

    def _bounds(self, column: int) -> np.ndarray:
        values = [entry[column] for entry in self.signals]
        for block in self.lookahead:
            values += [block[column + 2]] * self.points
        values += [entry[column] for entry in self.tail]
        return np.array(values, dtype=np.float32)

    @property
    def low(self) -> np.ndarray:
        return self._bounds(2)

    @property
    def high(self) -> np.ndarray:
        return self._bounds(3)


@dataclass(frozen=True)
class RewardSpec:
    """The reward: ``Σ weight · transform(signal)`` over ``terms`` of ``(signal name, transform,
    parameter, weight)`` (transforms ``"linear"``: x; ``"capped_square"``: min(x, p)²), summed in order.

    ``term_keys``: the info key of each term's value (empty: the terms are not in the info). ``finish_key``:
    when set, the step that ends the episode by termination with a violation length of 0 also pays the
    program's finish bonus (:meth:`~cnc_gym.envs.engine.batch.FeedrateBatch.add_program`), shown in the
    info under this key. ``cost``: the signal that is ``info["cost"]``.
    """

    terms: tuple[tuple[str, str, float, float], ...]
    term_keys: tuple[str, ...] = ()
    finish_key: str | None = None
    cost: str = "violated"

    def __post_init__(self) -> None:
        if self.term_keys and len(self.term_keys) != len(self.terms):
            raise ValueError("RewardSpec: one term key per term")

    def table(self) -> np.ndarray:
        codes = {"linear": T_NONE, "capped_square": T_CAPPED_SQUARE}
        rows = [(SIGNALS.index(name), codes[transform], param, weight) for name, transform, param, weight
                in self.terms]  # fmt: skip
        return np.array(rows, dtype=np.float64).reshape(-1, REWARD_COLS)
