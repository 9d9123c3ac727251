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
    if spec == "nominal-oracle":
        return OraclePlanner(progress=progress, plans_on_nominal=True)
    path = Path(spec)
    if path.suffix == ".zip" or path.exists():
        from cnc_gym.policies.model import ModelPolicy

        return ModelPolicy(path)
    if _MODULE_CALLABLE.fullmatch(spec):
        return _user_policy(spec)
    raise CncGymError(
        f"unknown policy {spec!r}: use constant:<override> (e.g. constant:1.0), classical, oracle, "
        "nominal-oracle, the path of a trained model (.zip), or module:callable"
    )


class _FunctionPolicy:
    """A plain ``act(observation, info) -> action`` function as a policy; what it raises is one line."""

    def __init__(self, name: str, function: Any) -> None:
        self.name = name
        self._function = function

    def reset(self, env: Any) -> None:
        return None

    def act(self, observation: Any, info: dict[str, Any]) -> Any:
        try:
            return self._function(observation, info)
        except Exception as exc:  # the user's code: report it in one line
            raise CncGymError(f"policy {self.name!r}: act(observation, info) failed: "
                              f"{type(exc).__name__}: {exc}") from None  # fmt: skip


_KINDS = "a policy object, a policy class, a factory function f() or a function act(observation, info)"


def _user_policy(spec: str) -> Policy:
    """``module:callable``: a policy object, a class or a Python function with no arguments that makes
    one, or a Python function ``act(observation, info)``. Anything else is refused without calling it: a
    built-in function (``os:system``, ``builtins:exit``, ``os:abort``), a function of the wrong arity
    (``json:dumps``), a value; a factory that fails, exits or returns something else is one line too."""
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
    elif isinstance(target, type) or (_is_python_function(target) and _binds(target, 0)):
        try:
            policy = target()
        except (Exception, SystemExit) as exc:  # the user's code: report it in one line
            raise CncGymError(f"policy {spec!r}: calling {attr}() failed: "
                              f"{type(exc).__name__}: {exc}") from None
        if not _is_policy(policy):
            raise CncGymError(f"policy {spec!r}: {attr}() returned {type(policy).__name__}, which has no "
                              "reset(env) and act(observation, info)")  # fmt: skip
    elif _is_python_function(target) and _binds(target, 2):
        policy = _FunctionPolicy(spec, target)
    else:
        raise CncGymError(f"policy {spec!r}: {attr} is {_describe(target)}, not a policy; give {_KINDS}")
    if not getattr(policy, "name", None):
        with contextlib.suppress(AttributeError):
            policy.name = spec
    return policy


def _is_policy(obj: Any) -> bool:
    methods = (getattr(obj, "act", None), getattr(obj, "reset", None))
    return not isinstance(obj, type) and all(callable(m) for m in methods)


def _is_python_function(obj: Any) -> bool:
    """A function or method written in Python (or a ``functools.partial`` of one): something whose
    signature can be read and which is the user's code, not a built-in such as ``os.system``."""
    import functools
    import inspect

    if isinstance(obj, functools.partial):
        return _is_python_function(obj.func)
    return inspect.isfunction(obj) or (inspect.ismethod(obj) and inspect.isfunction(obj.__func__))


def _binds(function: Any, n_positional: int) -> bool:
    """Whether ``function`` can be called with ``n_positional`` positional arguments and nothing else."""
    import inspect

    try:
        inspect.signature(function).bind(*([None] * n_positional))
    except (TypeError, ValueError):
        return False
    return True


def _describe(obj: Any) -> str:
    import inspect

    if _is_python_function(obj):
        return "a function whose arguments fit neither f() nor act(observation, info)"
    if inspect.isbuiltin(obj):
        return "a built-in callable"
    if callable(obj):
        return f"a callable {type(obj).__name__}"
    return f"a {type(obj).__name__} value"
