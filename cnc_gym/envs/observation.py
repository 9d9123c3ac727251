"""The Feedrate envs' observations, declared once: each entry's name, source, formula, scale, bounds.

:data:`OBSERVATION_V1` (Feedrate-v1 and -v2) and :data:`OBSERVATION_V0` (Feedrate-v0) are the declarations.
From each come

- the Box bounds (:meth:`ObservationLayout.low`, :meth:`ObservationLayout.high`);
- the compiled step's :class:`~cnc_gym.envs.engine.specs.ObservationSpec`
  (:attr:`ObservationLayout.kernel_spec`), which scales and clips every entry inside the step: the
  per-step signals, the look-ahead blocks, and after them the entries of the episode's machine, of the
  episode and of the deployable planner (signals of the kernel too, :func:`kernel_signal`);
- the table of the env's docstring and of docs/env.md (:func:`markdown_table`; a test keeps docs/env.md
  equal to it);
- ``observation_structure``: entry name → the indices it occupies, as Gymnasium's MuJoCo envs expose it.

In v1 no entry identifies a position in a particular program (v0's ``progress = s / L`` is gone): every entry
is the machine's state, the path ahead within a fixed horizon, the controller's limits there, the
machine's own parameters, whether the episode is still violation-free (so a value function can tell
whether the finish bonus is still to be had), or what the deployable planner would command now. A policy
therefore sees the same kind of input on any program, which is what lets it run programs it was not
trained on.

Scales are written as the reference quantity an entry is divided by (``v_ref`` = the controller's max
feed in mm/s, ``a_ref`` = the largest axis acceleration of the preset, ``tol`` = the contour tolerance,
``H`` = the look-ahead horizon, ``Kv_ref`` = 40 1/s, ``ov_max`` = the override knob's top): the scale
stays the same when the episode's machine is randomised, so the entries carry the change.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from cnc_gym.envs.engine import (
    LOOKAHEAD_ROWS,
    MACHINE_QUANTITIES,
    SIGNALS,
    ObservationSpec,
    machine_quantities,
)

#: Where an entry's value comes from.
SOURCES = ("signal", "lookahead", "machine", "episode", "planner")
#: Fixed references (the others are the env's: v_ref, a_ref, tol, H, ov_max).
KV_REF_1_S = 40.0
CURVATURE_LENGTH_MM = 10.0  # curvature κ is observed as κL/(1 + κL): R 50 mm → 0.17, R 1 mm → 0.91
FOLLOWING_ERROR_REF_MM = 1.0
MISMATCH_REF = 0.1


@dataclass(frozen=True)
class Entry:
    """One observation entry (a look-ahead entry is a block of ``N = lookahead_points`` values).

    ``quantity`` is a kernel signal (:data:`~cnc_gym.envs.engine.layout.SIGNALS`), a look-ahead row
    (:data:`~cnc_gym.envs.engine.layout.LOOKAHEAD_ROWS`), a machine quantity (:data:`MACHINE_QUANTITIES`) or
    ``override`` of the planner; ``divide_by`` names the reference it is divided by (``1`` for none);
    ``saturate`` applies ``x·L / (1 + x·L)`` with L = ``saturate`` mm before scaling.
    """

    name: str
    source: str
    quantity: str
    formula: str
    meaning: str
    low: float
    high: float
    divide_by: str = "1"
    saturate: float = 0.0


#: Feedrate-v0's observation (unchanged since it was published: its ``progress`` is ``s / L``). The
#: bounds keep the types v0 was published with (int, and 0.0 below the look-ahead blocks) so that its
#: kernel spec is the same record, ``repr`` included.
OBSERVATION_V0: tuple[Entry, ...] = (
    Entry("speed", "signal", "speed", "v / v_ref", "path speed", 0, 2, "v_ref"),
    Entry("accel", "signal", "accel", "a / a_ref", "path acceleration", -2, 2, "a_ref"),
    Entry("override", "signal", "override", "override / max_override", "applied override", 0, 1, "ov_max"),
    Entry("knob", "signal", "knob", "a", "last action (knob)", -1, 1),
    Entry("following_error", "signal", "following_error", "‖reference − actual‖ / 1 mm", "following error",
          0, 5, "following_ref"),
    Entry("contour_error_step", "signal", "contour_error_step", "e_max / tol",
          "contour error, max over the last step", 0, 5, "tol"),
    Entry("contour_error_now", "signal", "contour_error_now", "e / tol", "contour error, last servo sample",
          0, 5, "tol"),
    Entry("progress", "signal", "path_fraction", "s / L", "progress (path length done)", 0, 1),
    Entry("distance_to_stop", "signal", "distance_to_stop", "min(d_stop / H, 1)",
          "distance to the next stop", 0, 1, "H"),
    Entry("speed_limit", "lookahead", "speed_limit", "v_lim / v_ref",
          "speed limit ahead: the controller's limit at N points over the next H mm", 0.0, 2,
          "v_ref"),
    Entry("curvature", "lookahead", "curvature", "κ L_k / (1 + κ L_k)", "curvature ahead (L_k = 10 mm)",
          0.0, 1, saturate=CURVATURE_LENGTH_MM),
    Entry("turn_angle", "lookahead", "turn_angle", "θ / π",
          "turning angle ahead, the largest junction turn in each bin", 0.0, 1,
          "pi"),
    Entry("programmed_feed", "lookahead", "programmed_feed", "F / 60 / v_ref", "programmed feed ahead",
          0.0, 2, "v_ref"),
)  # fmt: skip

OBSERVATION_V1: tuple[Entry, ...] = (
    Entry("speed", "signal", "speed", "v / v_ref", "path speed of the reference", 0, 2, "v_ref"),
    Entry("accel", "signal", "accel", "a / a_ref", "path acceleration of the reference", -2, 2, "a_ref"),
    Entry("override", "signal", "override", "override / ov_max", "override in force", 0, 1, "ov_max"),
    Entry("knob", "signal", "knob", "k", "the knob value the last step applied", -1, 1),
    Entry("following_error", "signal", "following_error", "‖r − x‖ / 1 mm",
          "following error at the last servo sample", 0, 5, "following_ref"),
    Entry("contour_error_step", "signal", "contour_error_step", "e_max / tol",
          "largest contour error over the last step's servo samples", 0, 5, "tol"),
    Entry("contour_error_now", "signal", "contour_error_now", "e / tol",
          "contour error at the last servo sample", 0, 5, "tol"),
    Entry("distance_to_stop", "signal", "distance_to_stop", "min(d_stop / H, 1)",
          "distance to the next mandatory stop", 0, 1, "H"),
    Entry("speed_limit", "lookahead", "speed_limit", "v_lim / v_ref",
          "the controller's speed limit (100 % override) in each bin of the next H mm", 0, 2, "v_ref"),
    Entry("curvature", "lookahead", "curvature", "κL / (1 + κL), L = 10 mm",
          "largest curvature in each bin", 0, 1, saturate=CURVATURE_LENGTH_MM),
    Entry("turn_angle", "lookahead", "turn_angle", "θ / π", "largest junction turn in each bin", 0, 1, "pi"),
    Entry("programmed_feed", "lookahead", "programmed_feed", "F / 60 / v_ref",
          "programmed feed at each bin's far end", 0, 2, "v_ref"),
    Entry("kv", "machine", "kv_min", "min Kv / 40 1/s", "the lowest position gain of the axes", 0, 5,
          "kv_ref"),
    Entry("kv_mismatch", "machine", "kv_mismatch", "(max Kv − min Kv) / mean Kv / 0.1",
          "gain mismatch between the axes", 0, 5, "mismatch_ref"),
    Entry("feedforward", "machine", "feedforward", "f", "mean velocity feed-forward of the axes", 0, 1),
    Entry("accel_limit", "machine", "accel_min", "min A / a_ref", "the lowest axis acceleration", 0, 5,
          "a_ref"),
    Entry("violation_free", "episode", "violation_free", "[L_viol = 0]",
          "1 while the episode has cut no path over tolerance (the finish bonus is still to be had)", 0, 1),
    Entry("planner_override", "planner", "override", "ov_plan / ov_max",
          "what the deployable planner (`classical`) would command now", 0, 1, "ov_max"),
)  # fmt: skip


__all__ = ["MACHINE_QUANTITIES", "OBSERVATION_V0", "OBSERVATION_V1", "Entry", "ObservationLayout",
           "kernel_signal", "machine_quantities", "markdown_table"]  # fmt: skip


def kernel_signal(entry: Entry) -> str:
    """The kernel signal (:data:`~cnc_gym.envs.engine.layout.SIGNALS`) an entry of a source other than the
    look-ahead reads: a signal itself, a machine quantity, ``violation_free``, or ``planner_override``."""
    return f"planner_{entry.quantity}" if entry.source == "planner" else entry.quantity


class ObservationLayout:
    """:data:`OBSERVATION_V1` (or another entry list) resolved for one env: ``points`` look-ahead points and
    the env's reference values (``v_ref``, ``a_ref``, ``tol``, ``H``, ``ov_max``)."""

    def __init__(self, entries: tuple[Entry, ...], points: int, references: dict[str, float]) -> None:
        self.entries = entries
        self.points = int(points)
        self.references = {"1": 1.0, "pi": math.pi, "kv_ref": KV_REF_1_S, "mismatch_ref": MISMATCH_REF,
                           "following_ref": FOLLOWING_ERROR_REF_MM, **references}  # fmt: skip
        order = [SOURCES.index(e.source) for e in entries]
        if order != sorted(order):
            raise ValueError(f"observation entries must be ordered by source: {', '.join(SOURCES)}")
        for e in entries:
            known = {"signal": SIGNALS, "lookahead": LOOKAHEAD_ROWS, "machine": MACHINE_QUANTITIES,
                     "episode": ("violation_free",), "planner": ("override",)}[e.source]  # fmt: skip
            if e.quantity not in known:
                raise ValueError(f"observation entry {e.name}: unknown {e.source} quantity {e.quantity!r}")
        self.kernel_spec = ObservationSpec(
            tuple((e.quantity, self.scale(e), e.low, e.high) for e in entries if e.source == "signal"),
            tuple((e.quantity, "saturate" if e.saturate else "none", e.saturate, self.scale(e), e.low, e.high)
                  for e in entries if e.source == "lookahead"),
            self.points,
            tuple((kernel_signal(e), self.scale(e), e.low, e.high) for e in entries
                  if e.source in ("machine", "episode", "planner")),
        )  # fmt: skip
        self.structure: dict[str, np.ndarray] = {}
        at = 0
        for e in entries:
            width = self.points if e.source == "lookahead" else 1
            self.structure[e.name] = np.arange(at, at + width)
            at += width
        self.size = at

    def scale(self, entry: Entry) -> float:
        return 1.0 / self.references[entry.divide_by]

    def _bounds(self, column: str) -> np.ndarray:
        return np.concatenate([np.full(len(self.structure[e.name]), getattr(e, column), dtype=np.float32)
                               for e in self.entries])  # fmt: skip

    @property
    def low(self) -> np.ndarray:
        return self._bounds("low")

    @property
    def high(self) -> np.ndarray:
        return self._bounds("high")


def markdown_table(entries: tuple[Entry, ...] = OBSERVATION_V1) -> str:
    """The observation table (index, name, formula, meaning, bounds), ``N`` look-ahead points symbolic."""
    def index(base: int, blocks: int) -> str:
        return f"{base}" if not blocks else f"{base}+{'' if blocks == 1 else blocks}N"

    rows = ["| index | name | formula | meaning | range |", "|---|---|---|---|---|"]
    at, blocks = 0, 0
    for e in entries:
        if e.source == "lookahead":
            where = f"{index(at, blocks)} … {index(at - 1, blocks + 1)}"
            blocks += 1
        else:
            where = index(at, blocks)
            at += 1
        rows.append(f"| {where} | `{e.name}` | `{e.formula}` | {e.meaning} | [{e.low:g}, {e.high:g}] |")
    return "\n".join(rows)
