"""cnc-gym: Gymnasium environments for CNC feed-rate control on real G-code.

Importing the package registers ``cnc_gym/Feedrate-v0`` to ``-v6`` (:data:`ENV_IDS`) with Gymnasium, each
with a vector entry point (``gymnasium.make_vec(id, n, vectorization_mode="vector_entry_point")``): at once
when Gymnasium is already imported, otherwise the moment it is (a post-import hook on
``gymnasium.envs.registration``). So ``import cnc_gym`` stays cheap for interpreter-only users:
``cnc-gym trace`` never loads Gymnasium, numba or scipy. The env module itself is imported by
``gymnasium.make``.
"""

from __future__ import annotations

import importlib.machinery
import sys
from collections.abc import Sequence
from types import ModuleType

__version__ = "0.1.0"

_REGISTRATION = "gymnasium.envs.registration"
#: The env ids this package registers (each with a vector entry point).
ENV_IDS = ("cnc_gym/Feedrate-v0", "cnc_gym/Feedrate-v1", "cnc_gym/Feedrate-v2", "cnc_gym/Feedrate-v3",
           "cnc_gym/Feedrate-v4", "cnc_gym/Feedrate-v5", "cnc_gym/Feedrate-v6")


def _register() -> None:
    from gymnasium.envs.registration import register, registry

    # v0 and v1 keep the contour meter they were published with (cutting moves only), so their numbers
    # reproduce; v2 is v1 with the programmed-path meter (docs/plant.md, "Contour error at a rapid → cut
    # junction").
    if "cnc_gym/Feedrate-v0" not in registry:
        register(id="cnc_gym/Feedrate-v0", entry_point="cnc_gym.envs.feedrate:FeedrateEnv",
                 vector_entry_point="cnc_gym.envs.vector:FeedrateVectorEnv",
                 kwargs={"contour_rule": "cuts"})  # fmt: skip
    if "cnc_gym/Feedrate-v1" not in registry:
        register(id="cnc_gym/Feedrate-v1", entry_point="cnc_gym.envs.feedrate_v1:FeedrateEnvV1",
                 vector_entry_point="cnc_gym.envs.vector:make_vector_env_v1",
                 kwargs={"contour_rule": "cuts"})  # fmt: skip
    if "cnc_gym/Feedrate-v2" not in registry:
        register(id="cnc_gym/Feedrate-v2", entry_point="cnc_gym.envs.feedrate_v1:FeedrateEnvV1",
                 vector_entry_point="cnc_gym.envs.vector:make_vector_env_v1",
                 kwargs={"contour_rule": "path"})  # fmt: skip
    # v3 and v4 are v2 with a later deployable planner (versions 2 and 3, the live one) behind the planner
    # entry and residual mode; v1 and v2 keep the frozen planner version 1, v3 the frozen version 2.
    # v5 is v4 on the controller's revision 2 (cnc_gym.motion.kernel.CONTROLLER_REVISION: no overshoot
    # where the override is lowered during an acceleration); v0 to v4 keep revision 1, the env classes'
    # default. v6 is v5 with the reward's `relative` rule (time per the deployable planner's scheduled time,
    # no finish bonus: docs/env.md, "The relative reward (v6)"); v1 to v5 keep the `ranking` rule.
    for env_id, planner, revision, rule in (("cnc_gym/Feedrate-v3", 2, 1, "ranking"),
                                            ("cnc_gym/Feedrate-v4", 3, 1, "ranking"),
                                            ("cnc_gym/Feedrate-v5", 3, 2, "ranking"),
                                            ("cnc_gym/Feedrate-v6", 3, 2, "relative")):  # fmt: skip
        if env_id not in registry:
            register(id=env_id, entry_point="cnc_gym.envs.feedrate_v1:FeedrateEnvV1",
                     vector_entry_point="cnc_gym.envs.vector:make_vector_env_v1",
                     kwargs={"contour_rule": "path", "planner_version": planner,
                             "controller_revision": revision, "reward_rule": rule})  # fmt: skip
    import warnings

    # v0 to v5 stay supported beside v6 (the published models act in v1 and v5): no "out of date" warning.
    warnings.filterwarnings("ignore", message=r".*cnc_gym/Feedrate-v[012345] is out of date",
                            category=DeprecationWarning)  # fmt: skip


class _RegisterOnImport:
    """Finds ``gymnasium.envs.registration`` with the usual finders, loads it, then registers the envs.

    A meta path finder and loader by protocol (``find_spec``; ``create_module``, ``exec_module``), not by
    subclassing ``importlib.abc``: that module imports ``importlib.resources`` and with it ``tempfile``,
    ``shutil``, ``random`` and the compression modules, a tenth of ``cnc-gym trace``'s start-up."""

    def find_spec(self, fullname: str, path: Sequence[str] | None,
                  target: ModuleType | None = None) -> importlib.machinery.ModuleSpec | None:  # fmt: skip
        if fullname != _REGISTRATION:
            return None
        spec = importlib.machinery.PathFinder.find_spec(fullname, path)
        if spec is None or spec.loader is None:
            return None
        self._loader = spec.loader
        spec.loader = self  # type: ignore[assignment]  # a Loader by protocol
        return spec

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> ModuleType | None:
        return self._loader.create_module(spec)

    def exec_module(self, module: ModuleType) -> None:
        self._loader.exec_module(module)
        if self in sys.meta_path:
            sys.meta_path.remove(self)
        _register()


if _REGISTRATION in sys.modules:
    _register()
elif not any(isinstance(finder, _RegisterOnImport) for finder in sys.meta_path):
    sys.meta_path.insert(0, _RegisterOnImport())
