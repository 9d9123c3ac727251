"""Policies that drive cnc-gym envs: baselines and trained models.

``make_policy(spec)`` turns a command-line spec into a policy:

=====================  ======================================================================
``constant:<x>``       :class:`~agents.constant.ConstantOverride` at override x (1.0 = 100 %)
``classical``          :class:`~agents.classical.ClassicalPlanner` (tolerance-aware look-ahead)
a path (``*.zip``)     :class:`~agents.model.ModelPolicy`, an SB3 model rebuilt without unpickling
=====================  ======================================================================
"""

from __future__ import annotations

from pathlib import Path

from agents.base import Policy, override_action
from agents.classical import ClassicalPlanner
from agents.constant import ConstantOverride
from cnc_gym.errors import CncGymError

__all__ = ["ClassicalPlanner", "ConstantOverride", "Policy", "make_policy", "override_action"]


def make_policy(spec: str) -> Policy:
    """Build a policy from ``constant:<override>``, ``classical`` or a path to a trained SB3 model."""
    spec = spec.strip()
    if spec.startswith("constant:"):
        value = spec.removeprefix("constant:")
        try:
            override = float(value)
        except ValueError:
            raise CncGymError(
                f"bad policy {spec!r}: constant:<override> needs a number, e.g. constant:1.0"
            ) from None
        return ConstantOverride(override)
    if spec == "constant":
        return ConstantOverride(1.0)
    if spec == "classical":
        return ClassicalPlanner()
    path = Path(spec)
    if path.suffix == ".zip" or path.exists():
        from agents.model import ModelPolicy

        return ModelPolicy(path)
    raise CncGymError(
        f"unknown policy {spec!r}: use constant:<override> (e.g. constant:1.0), classical, "
        "or the path of a trained model (.zip)"
    )
