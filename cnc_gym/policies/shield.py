"""The corner shield: a residual policy falls back to the planner where a sharp corner is close ahead.

A ``residual`` policy scales the deployable planner's override by ``ρ^a`` (docs/env.md, action modes).
Where the path turns sharply a few millimetres ahead, a raise above the planner (``a > 0``) is the one
mistake that costs a whole program: the controller's jerk-limited response to the knob cannot take the
speed back down in time, the corner is entered too fast and its transient cuts over tolerance. A learned
policy that only imitates a teacher makes that mistake now and then (its observation cannot always tell
a corner it may take faster than the planner from one it may not).

:class:`CornerShield` holds the action at ``min(a, 0)`` (the planner's override, or slower) while the
observation's preview shows a junction turning at least ``turn`` (``θ / π``) in its first ``bins`` bins
(each bin is ``lookahead_mm / lookahead_points`` long: 3 mm in Feedrate-v2 … v5). Everywhere else the
policy acts freely, and below the planner it always does. It reads nothing but the observation, so a
shielded policy stays deployable; it is a shield in the sense of safe RL (Alshiekh et al., AAAI 2018):
a fixed rule between the learned policy and the machine, with a fallback that is known to be safe.

A trained model records its shield in its zip (``cnc_gym_shield``, plain JSON: :meth:`record`);
:class:`cnc_gym.policies.model.ModelPolicy` applies it, and the distillation learner trains with it in
the loop (its DAgger rollouts are shielded as the deployed policy is).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from cnc_gym.errors import CncGymError

#: The observation entry the shield reads (docs/env.md, observation table).
TURN_ENTRY = "turn_angle"


@dataclass(frozen=True)
class CornerShield:
    """Hold a residual action at ≤ 0 while a junction turning at least ``turn`` (θ/π, in (0, 1]) lies in
    the first ``bins`` bins of the observation's preview (module docstring)."""

    bins: int
    turn: float

    def __post_init__(self) -> None:
        if isinstance(self.bins, bool) or not isinstance(self.bins, int) or self.bins < 1:
            raise CncGymError(f"corner shield: bins must be an integer >= 1, got {self.bins!r}")
        turn = self.turn
        if isinstance(turn, bool) or not isinstance(turn, int | float) or not 0.0 < float(turn) <= 1.0:
            raise CncGymError(f"corner shield: turn must be in (0, 1] (θ/π), got {turn!r}")

    def record(self) -> dict[str, Any]:
        """The shield as the plain JSON a model zip records (``cnc_gym_shield``)."""
        return {"kind": "corner", "bins": int(self.bins), "turn": float(self.turn)}

    @classmethod
    def from_record(cls, record: Any) -> CornerShield:
        """The shield a model zip records; a malformed record is one :class:`CncGymError` line."""
        keys = {"kind", "bins", "turn"}
        if not isinstance(record, dict) or set(record) != keys or record["kind"] != "corner":
            raise CncGymError("its cnc_gym_shield record is not a corner shield {kind: corner, bins, turn}")
        return cls(bins=record["bins"], turn=record["turn"])

    def bind(self, env: Any) -> BoundShield:
        """The shield on ``env``'s observation layout (``observation_structure``), for a ``residual``-mode
        env; anything else is one :class:`CncGymError` line."""
        base = env.unwrapped
        mode = getattr(base, "action_mode", None)
        if mode != "residual":
            raise CncGymError(f"the corner shield holds a residual action at the planner's override; the env "
                              f"is in {mode!r} action mode")  # fmt: skip
        indices = list(getattr(base, "observation_structure", {}).get(TURN_ENTRY, []))
        if len(indices) < self.bins:
            raise CncGymError(f"the corner shield reads {self.bins} bin(s) of the observation's "
                              f"{TURN_ENTRY}; the env has {len(indices)}")  # fmt: skip
        return BoundShield(self, int(indices[0]), int(indices[0]) + self.bins)


@dataclass(frozen=True)
class BoundShield:
    """A :class:`CornerShield` on one observation layout: the slice of the preview it reads."""

    shield: CornerShield
    first: int
    stop: int

    def engaged(self, observation: np.ndarray) -> bool:
        """A junction turning at least ``turn`` lies in the shield's reach."""
        return bool(np.max(observation[self.first : self.stop]) >= self.shield.turn)

    def apply(self, observation: np.ndarray, action: np.ndarray) -> np.ndarray:
        """``action`` held at ≤ 0 where :meth:`engaged`, else unchanged (float32)."""
        action = np.asarray(action, dtype=np.float32)
        return np.minimum(action, np.float32(0.0)) if self.engaged(observation) else action
