"""``make_policy(spec)``: a policy from a command-line spec (the table of :mod:`cnc_gym.policies`)."""

from __future__ import annotations

import contextlib
import importlib
import re
from pathlib import Path
from typing import Any

from cnc_gym.errors import CncGymError
from cnc_gym.policies.base import Policy
from cnc_gym.policies.classical import ClassicalPlanner
from cnc_gym.policies.constant import ConstantOverride
from cnc_gym.policies.oracle import OraclePlanner

_MODULE_CALLABLE = re.compile(r"[A-Za-z_][\w.]*:[A-Za-z_][\w.]*")


def make_policy(spec: str, *, progress: bool | None = None) -> Policy:
    """Build a policy from a spec (the table of :mod:`cnc_gym.policies`). ``progress`` is passed to
    planners that show a planning bar (None: on a terminal only)."""
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
    if spec == "oracle":
        return OraclePlanner(progress=progress)
    path = Path(spec)
    if path.suffix == ".zip" or path.exists():
        from cnc_gym.policies.model import ModelPolicy

        return ModelPolicy(path)
    if _MODULE_CALLABLE.fullmatch(spec):
        return _user_policy(spec)
    raise CncGymError(
        f"unknown policy {spec!r}: use constant:<override> (e.g. constant:1.0), classical, oracle, "
        "the path of a trained model (.zip), or module:callable"
    )


class _FunctionPolicy:
    """A plain ``act(observation, info) -> action`` function as a policy."""

    def __init__(self, name: str, function: Any) -> None:
        self.name = name
        self._function = function

    def reset(self, env: Any) -> None:
        return None

    def act(self, observation: Any, info: dict[str, Any]) -> Any:
        return self._function(observation, info)


def _user_policy(spec: str) -> Policy:
    module_name, attr = spec.split(":", 1)
    try:
        target: Any = importlib.import_module(module_name)
    except ImportError as exc:
        raise CncGymError(f"policy {spec!r}: cannot import module {module_name!r} ({exc})") from None
    for part in attr.split("."):
        if not hasattr(target, part):
            raise CncGymError(f"policy {spec!r}: module {module_name!r} has no {attr!r}")
        target = getattr(target, part)
    if _is_policy(target):
        policy = target
    elif isinstance(target, type) or _takes_no_arguments(target):
        try:
            policy = target()
        except Exception as exc:  # the user's code: report it in one line
            raise CncGymError(f"policy {spec!r}: calling {attr}() failed: "
                              f"{type(exc).__name__}: {exc}") from None
        if not _is_policy(policy):
            raise CncGymError(f"policy {spec!r}: {attr}() returned {type(policy).__name__}, which has no "
                              "reset(env) and act(observation, info)")  # fmt: skip
    elif callable(target):
        policy = _FunctionPolicy(spec, target)
    else:
        raise CncGymError(f"policy {spec!r}: {attr} is neither a policy nor callable")
    if not getattr(policy, "name", None):
        with contextlib.suppress(AttributeError):
            policy.name = spec
    return policy


def _is_policy(obj: Any) -> bool:
    methods = (getattr(obj, "act", None), getattr(obj, "reset", None))
    return not isinstance(obj, type) and all(callable(m) for m in methods)


def _takes_no_arguments(function: Any) -> bool:
    import inspect

    try:
        signature = inspect.signature(function)
    except (TypeError, ValueError):
        return False
    return all(p.default is not p.empty or p.kind in (p.VAR_POSITIONAL, p.VAR_KEYWORD)
               for p in signature.parameters.values())  # fmt: skip
