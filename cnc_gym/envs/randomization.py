"""Domain randomisation of ``cnc_gym/Feedrate-v1``: the machine and the feed scale drawn for every episode.

:class:`DomainRandomization` declares the ranges (config keys with their specs, checked by the config
loader; docs/configs.md's table is written from them). Off by default, and off in the benchmark; the
training configs (``configs/train/``) switch it on. Each env draws ``machines`` machines from the ranges
with its own generator (the k-th the first time an episode picks it), and every episode runs one of them,
picked at random, with a feed scale of its own. A machine is:

- **Kv**: one level for the machine, ``kv_scale`` × the preset's Kv of every axis;
- **axis mismatch**: each axis's Kv further × ``1 + m·u``, u uniform in [-1, 1], m drawn in ``kv_mismatch``
  (unequal gains push the tool off straight lines, the dominant contour error of a real machine);
- **velocity feed-forward**: one fraction for all axes, in ``feedforward`` (absolute, 0 … 1);
- **acceleration limits**: acceleration and jerk of every axis × ``accel_scale`` (cutting and rapid);

and every episode's program has **feed scaling**: every programmed feed × ``feed_scale`` (the controller's
clamps still apply). A pool rather than a new machine every episode because a machine costs about 0.1 s
to set up (its servo models and the planner's error tables) and an episode about as much to run; with
8 envs of 8 machines a training run sees 64 machines, and the feed scale is fresh every episode.

A draw is uniform in each range; a range whose ends are equal holds the value fixed. The servo loop
must stay stable with every draw: :meth:`DomainRandomization.stability_problem` names a Kv range that
could reach the velocity loop's stability limit on the machine (checked when the env is built).

The ranges of ``configs/train/*.yaml`` are those of small and mid-size machining centres: position gains
from about 25 to 60 1/s, a few per cent of gain mismatch between axes, feed-forward from 50 to 90 %,
acceleration from 2 to 4 m/s², and feeds within ±30 % of what the CAM wrote.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from cnc_gym.config import Invalid, Number, Spec, declared, flag, number, shown
from cnc_gym.machine import MachineConfig


@dataclass(frozen=True)
class Range(Spec):
    """A closed range ``[low, high]`` of a randomised parameter, both ends within ``bounds``."""

    bounds: Number = Number()  # noqa: RUF009  (a frozen spec: shared safely)

    def _parse(self, raw: Any) -> Any:
        if not isinstance(raw, list | tuple) or len(raw) != 2:
            raise Invalid(f"must be a range [low, high], got {shown(raw)}")
        try:
            low, high = (self.bounds.parse(v) for v in raw)
        except Invalid as exc:
            raise Invalid(f"ends {exc}") from None
        if low > high:
            raise Invalid(f"must be [low, high] with low <= high, got {shown(list(raw))}")
        return (float(low), float(high))

    def _allowed(self) -> str:
        return f"[low, high] each {self.bounds.allowed()}"


def _range(default: tuple[float, float], lowest: float, highest: float, *, unit: str = "", doc: str = "",
           why: str = "") -> Any:  # fmt: skip
    return declared(Range(doc=doc, why=why, bounds=Number(low=lowest, high=highest, unit=unit)), default)


@dataclass(frozen=True)
class DomainRandomization:
    """What ``cnc_gym/Feedrate-v1`` draws every episode (module docstring); all ranges are [low, high]."""

    enabled: bool = flag(False, doc="draw a machine and a feed scale for every episode")
    machines: int = number(8, 1, 1000, integer=True, doc="machines each env draws (an episode picks one)",
                           why="each keeps its servo models (a few hundred kB).")  # fmt: skip
    kv_scale: tuple[float, float] = _range(
        (0.65, 1.5), 0.1, 10, doc="Kv of every axis × this (one draw per episode)",
        why="a tenth to ten times the preset; real position gains are 10-500 1/s.")  # fmt: skip
    kv_mismatch: tuple[float, float] = _range(
        (0.0, 0.08), 0, 0.5, doc="largest relative Kv difference of one axis from the level",
        why="up to ±50 %: a badly tuned axis; well-tuned machines match within a few per cent.")  # fmt: skip
    feedforward: tuple[float, float] = _range(
        (0.5, 0.9), 0, 1, doc="velocity feed-forward fraction of every axis",
        why="a fraction: 0 (none) to 1 (full).")  # fmt: skip
    accel_scale: tuple[float, float] = _range(
        (0.7, 1.3), 0.1, 10, doc="acceleration and jerk of every axis × this",
        why="a tenth to ten times the preset.")  # fmt: skip
    feed_scale: tuple[float, float] = _range(
        (0.7, 1.3), 0.1, 10, doc="every programmed feed × this",
        why="a tenth to ten times what the program says (the controller's clamps still apply).")  # fmt: skip

    def stability_problem(self, machine: MachineConfig) -> str | None:
        """Why the highest Kv these ranges can draw makes a servo loop of ``machine`` unstable, or None."""
        top = self.kv_scale[1] * (1.0 + self.kv_mismatch[1])
        for name, axis in zip("xyz", machine.axes, strict=True):
            if axis.velocity_loop_hz > 0:
                limit = 2.0 * axis.velocity_loop_damping * 2.0 * math.pi * axis.velocity_loop_hz
                if axis.kv_1_s * top >= limit:
                    return (f"kv_scale × (1 + kv_mismatch) can reach Kv {axis.kv_1_s * top:.4g} 1/s on axis "
                            f"{name}, at or above its velocity loop's stability limit {limit:.4g} 1/s")
        return None


@dataclass(frozen=True)
class MachineDraw:
    """A machine drawn from the ranges, and what was drawn."""

    machine: MachineConfig
    kv_scale: tuple[float, float, float]
    feedforward: float
    accel_scale: float


def draw_machine(base: MachineConfig, ranges: DomainRandomization,
                 rng: np.random.Generator) -> MachineDraw:  # fmt: skip
    """A machine drawn from ``ranges`` around ``base`` (module docstring) with ``rng``."""
    level = rng.uniform(*ranges.kv_scale)
    mismatch = rng.uniform(*ranges.kv_mismatch)
    kv = tuple(float(level * (1.0 + mismatch * rng.uniform(-1.0, 1.0))) for _ in range(3))
    feedforward = float(rng.uniform(*ranges.feedforward))
    accel = float(rng.uniform(*ranges.accel_scale))
    axes = tuple(
        dataclasses.replace(
            axis, kv_1_s=axis.kv_1_s * scale, feedforward=feedforward,
            max_accel_mm_s2=axis.max_accel_mm_s2 * accel, max_jerk_mm_s3=axis.max_jerk_mm_s3 * accel,
            rapid_accel_mm_s2=axis.rapid_accel_mm_s2 * accel, rapid_jerk_mm_s3=axis.rapid_jerk_mm_s3 * accel)
        for axis, scale in zip(base.axes, kv, strict=True)
    )  # fmt: skip
    machine = dataclasses.replace(base, axes=axes, name=f"{base.name}~random")
    return MachineDraw(machine, kv, feedforward, accel)  # type: ignore[arg-type]
