"""The planner-fallback shield: a residual policy falls back to the planner where a raise is risky.

A ``residual`` policy scales the deployable planner's override by ``ρ^a`` (docs/env.md, action modes).
The planner alone finishes every program of the benchmark's splits within tolerance; a learned policy
that only imitates a teacher now and then raises the knob (``a > 0``) where it must not, and one such
mistake costs a whole program. Two situations cause nearly all of them:

- **a sharp corner close ahead**: the controller's jerk-limited response to the knob cannot take the
  speed back down in time, the corner is entered too fast and its transient cuts over tolerance;
- **a contour error already large**: on a long run of fine CAM chords the error builds up over many
  steps while the raise goes on, and the lag of the servo carries it over tolerance.

:class:`PlannerShield` holds the action at ``min(a, 0)`` (the planner's override, or slower) while the
observation's preview shows a junction turning at least ``turn`` (``θ / π``) in its first ``bins`` bins
(each bin is ``lookahead_mm / lookahead_points`` long: 3 mm in Feedrate-v2 … v5), and for ``hold`` more
control periods after such a junction leaves the preview (the tool is then at the corner, and the
servo's transient through it lasts about four of its time constants ``1/Kv``), or while the largest
contour error of the last step is at least ``error`` × tolerance. Everywhere else the policy acts freely,
and below the planner it always does.

A shield may also carry the policy's **envelope**: the range of each of the observation's machine
entries (the axes' gains, their mismatch, the feed-forward, the acceleration) over the states it was
trained on. On a machine outside it the shield hands the knob to the planner (``a = 0``) for as long as
the observation says so, which on a machine that does not change is the whole episode. A learned
policy's action off the machines it was trained on is an extrapolation, not a learned response: on
``p-loop-30`` (no feed-forward) three distilled students trained with feed-forward in [0.5, 0.9] were
slower than the planner on every val program they ran (docs/training.md, the envelope).

It reads nothing but the observation, so a shielded policy stays deployable; it is a shield in the sense
of safe RL (Alshiekh et al., AAAI 2018): a fixed rule between the learned policy and the machine, with a
fallback known to be safe, the planner.

A trained model records its shield in its zip (``cnc_gym_shield``, plain JSON: :meth:`record`);
:class:`cnc_gym.policies.model.ModelPolicy` applies it, and the distillation learner trains with it in
the loop (its DAgger rollouts are shielded as the deployed policy is).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from cnc_gym.errors import CncGymError

#: The observation entries the shield reads (docs/env.md, observation table).
TURN_ENTRY = "turn_angle"
ERROR_ENTRY = "contour_error_step"
#: The record's keys (``cnc_gym_shield`` in a model zip); ``envelope`` and ``hold`` may be absent (none, 0).
RECORD_KEYS = frozenset({"kind", "bins", "turn", "error"})
OPTIONAL_RECORD_KEYS = frozenset({"envelope", "hold"})
#: How far beyond the recorded envelope an entry may lie and still count as inside (in the entry's units:
#: the envelope's ends are float32 observations, and the same machine observed on another CPU may differ
#: in the last bits).
ENVELOPE_SLACK = 1e-4


def _number(value: Any) -> bool:
    return not isinstance(value, bool) and isinstance(value, int | float)


def _envelope(envelope: Any) -> bool:
    """``envelope`` is a tuple of ``(name, low, high)`` with distinct names and finite ``low <= high``."""
    if not isinstance(envelope, tuple):
        return False
    names = set()
    for item in envelope:
        if not (isinstance(item, tuple) and len(item) == 3 and isinstance(item[0], str)):
            return False
        name, low, high = item
        if name in names or not (_number(low) and _number(high) and math.isfinite(low) and math.isfinite(high)
                                 and low <= high):  # fmt: skip
            return False
        names.add(name)
    return True


@dataclass(frozen=True)
class PlannerShield:
    """Hold a residual action at ≤ 0 while a junction turning at least ``turn`` (θ/π, in (0, 1]) lies in
    the first ``bins`` bins of the observation's preview and for ``hold`` control periods after, or while
    the last step's largest contour error is at least ``error`` × tolerance (None: no error rule); and at
    the planner (``a = 0``) while an observation entry named in ``envelope`` (``(name, low, high)`` each)
    lies outside its range; module docstring."""

    bins: int
    turn: float
    error: float | None = None
    envelope: tuple[tuple[str, float, float], ...] = ()
    hold: int = 0

    def __post_init__(self) -> None:
        if isinstance(self.bins, bool) or not isinstance(self.bins, int) or self.bins < 1:
            raise CncGymError(f"shield: bins must be an integer >= 1, got {self.bins!r}")
        if not _number(self.turn) or not 0.0 < float(self.turn) <= 1.0:
            raise CncGymError(f"shield: turn must be in (0, 1] (θ/π), got {self.turn!r}")
        if self.error is not None and (not _number(self.error) or not 0.0 < float(self.error) <= 5.0):
            raise CncGymError(f"shield: error must be in (0, 5] (× tolerance) or null, got {self.error!r}")
        if isinstance(self.hold, bool) or not isinstance(self.hold, int) or not 0 <= self.hold <= 1000:
            raise CncGymError(f"shield: hold must be an integer in [0, 1000] (control periods), got "
                              f"{self.hold!r}")  # fmt: skip
        if not _envelope(self.envelope):
            raise CncGymError("shield: envelope must map distinct observation entries to finite ranges "
                              f"[low, high], got {self.envelope!r}")  # fmt: skip

    def record(self) -> dict[str, Any]:
        """The shield as the plain JSON a model zip records (``cnc_gym_shield``)."""
        error = None if self.error is None else float(self.error)
        record: dict[str, Any] = {"kind": "planner-fallback", "bins": int(self.bins),
                                  "turn": float(self.turn), "error": error}  # fmt: skip
        if self.envelope:
            record["envelope"] = {name: [float(low), float(high)] for name, low, high in self.envelope}
        if self.hold:
            record["hold"] = int(self.hold)
        return record

    @classmethod
    def from_record(cls, record: Any) -> PlannerShield:
        """The shield a model zip records; a malformed record is one :class:`CncGymError` line."""
        allowed = RECORD_KEYS | OPTIONAL_RECORD_KEYS
        if not isinstance(record, dict) or not RECORD_KEYS <= set(record) <= allowed or (
                record["kind"] != "planner-fallback"):  # fmt: skip
            raise CncGymError("its cnc_gym_shield record is not a planner-fallback shield "
                              "{kind: planner-fallback, bins, turn, error[, envelope][, hold]}")  # fmt: skip
        envelope = record.get("envelope", {})
        if not isinstance(envelope, dict) or not all(
                isinstance(ends, list) and len(ends) == 2 for ends in envelope.values()):  # fmt: skip
            raise CncGymError("its cnc_gym_shield envelope is not {entry: [low, high], ...}")
        return cls(bins=record["bins"], turn=record["turn"], error=record["error"],
                   envelope=tuple((name, low, high) for name, (low, high) in envelope.items()),
                   hold=record.get("hold", 0))  # fmt: skip

    def bind(self, env: Any) -> BoundShield:
        """The shield on ``env``'s observation layout (``observation_structure``), for a ``residual``-mode
        env; anything else is one :class:`CncGymError` line."""
        base = env.unwrapped
        mode = getattr(base, "action_mode", None)
        if mode != "residual":
            raise CncGymError(f"the shield holds a residual action at the planner's override; the env is "
                              f"in {mode!r} action mode")  # fmt: skip
        structure = getattr(base, "observation_structure", {})
        turn = list(structure.get(TURN_ENTRY, []))
        error = list(structure.get(ERROR_ENTRY, []))
        if len(turn) < self.bins:
            raise CncGymError(f"the shield reads {self.bins} bin(s) of the observation's {TURN_ENTRY}; "
                              f"the env has {len(turn)}")  # fmt: skip
        if self.error is not None and len(error) != 1:
            raise CncGymError(f"the shield's error rule reads the observation's {ERROR_ENTRY}; the env "
                              "has none")  # fmt: skip
        for name, _, _ in self.envelope:
            if len(structure.get(name, [])) != 1:
                raise CncGymError(f"the shield's envelope reads the observation's {name}; the env has no "
                                  "such single entry")  # fmt: skip
        indices = np.array([structure[name][0] for name, _, _ in self.envelope], dtype=np.intp)
        low = np.array([low for _, low, _ in self.envelope]) - ENVELOPE_SLACK
        high = np.array([high for _, _, high in self.envelope]) + ENVELOPE_SLACK
        return BoundShield(self, int(turn[0]), int(turn[0]) + self.bins, int(error[0]) if error else -1,
                           indices, low, high)  # fmt: skip


@dataclass
class BoundShield:
    """A :class:`PlannerShield` on one observation layout: the slice of the preview it reads, the index
    of the contour error entry, and the envelope's entries with their ranges (the slack included); one
    episode's (bind again for the next: :meth:`apply` counts the control periods of ``hold``)."""

    shield: PlannerShield
    first: int
    stop: int
    error_index: int
    envelope_index: np.ndarray
    envelope_low: np.ndarray
    envelope_high: np.ndarray
    #: Control periods the corner rule still holds after its junction left the preview.
    hold_left: int = 0

    def outside(self, observation: np.ndarray) -> bool:
        """An envelope entry of the observation lies outside its range: a machine the policy was not
        trained on."""
        if not self.envelope_index.size:  # no envelope: nothing to read on every step
            return False
        values = observation[self.envelope_index]
        return bool(np.any(values < self.envelope_low) or np.any(values > self.envelope_high))

    def outside_entries(self, observation: np.ndarray) -> str:
        """The envelope entries the observation lies outside of, as ``name value not in [low, high]``."""
        values = observation[self.envelope_index]
        return ", ".join(
            f"{name} {float(v):.3g} not in [{low:.3g}, {high:.3g}]"
            for (name, low, high), v, lo, hi in zip(self.shield.envelope, values, self.envelope_low,
                                                    self.envelope_high, strict=True)
            if v < lo or v > hi)  # fmt: skip

    def turn_in_reach(self, observation: np.ndarray) -> bool:
        """A junction turning at least ``turn`` lies in the shield's reach."""
        return float(np.max(observation[self.first : self.stop])) >= self.shield.turn

    def error_at_bound(self, observation: np.ndarray) -> bool:
        """The last step's largest contour error is at least ``error`` × tolerance (False: no error rule)."""
        bound = self.shield.error
        return bound is not None and float(observation[self.error_index]) >= bound

    def engaged(self, observation: np.ndarray) -> bool:
        """A junction turning at least ``turn`` lies in the shield's reach, or the error is at its bound
        (this observation alone: :meth:`apply` adds the ``hold`` after a junction)."""
        return self.turn_in_reach(observation) or self.error_at_bound(observation)

    def apply(self, observation: np.ndarray, action: np.ndarray) -> np.ndarray:
        """``action`` at 0 (the planner) where :meth:`outside`, held at ≤ 0 where :meth:`engaged` or
        within ``hold`` control periods after a junction left the reach, else unchanged (float32). Call
        it once per control step."""
        action = np.asarray(action, dtype=np.float32)
        if self.outside(observation):
            return np.zeros_like(action)
        if self.turn_in_reach(observation):
            self.hold_left = self.shield.hold
            held = True
        elif self.hold_left > 0:
            self.hold_left -= 1
            held = True
        else:
            held = self.error_at_bound(observation)
        return np.minimum(action, np.float32(0.0)) if held else action
