"""The planner as a service: a schedule per (tool path, machine), planned once by the version asked for.

Version 3 (:mod:`.schedule` with :data:`~.schedule.SETTINGS_V3`) is the live planner: the ``classical``
baseline, the benchmark and ``cnc_gym/Feedrate-v4`` and ``-v5`` use it. Version 2 (the same module with
:data:`~.schedule.SETTINGS_V2`) is kept bit for bit for ``cnc_gym/Feedrate-v3``, version 1 (:mod:`.v1`) for
``cnc_gym/Feedrate-v1`` and ``-v2``: their planner observation entry and ``residual`` action mode publish
them.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial

from cnc_gym.machine import MachineConfig
from cnc_gym.motion.limits import PathLimits
from cnc_gym.motion.planner.record import Schedule
from cnc_gym.motion.planner.rule import rule_reach_mm
from cnc_gym.motion.planner.schedule import MARGIN, SETTINGS_V2, SETTINGS_V3, plan_schedule
from cnc_gym.motion.planner.v1 import MARGIN_V1, plan_schedule_v1
from cnc_gym.toolpath import Toolpath

#: The live planner version (the ``classical`` baseline's).
PLANNER_VERSION = 3
#: Planner versions: (schedule function, default margin).
PLANNERS: dict[int, tuple[Callable[..., Schedule], float]] = {
    1: (plan_schedule_v1, MARGIN_V1),
    2: (partial(plan_schedule, settings=SETTINGS_V2), MARGIN),
    3: (partial(plan_schedule, settings=SETTINGS_V3), MARGIN),
}


def planner_version(version: int) -> int:
    """``version`` checked against :data:`PLANNERS` (a ValueError naming the known ones)."""
    if version not in PLANNERS:
        raise ValueError(f"unknown planner version {version!r} (known: {', '.join(map(str, PLANNERS))})")
    return int(version)


class SchedulePlanner:
    """The schedule of a (tool path, machine), planned once and recalled after.

    ``margin``: the fraction of the contour tolerance the schedules aim at (None: the version's own);
    ``cache_size``: schedules kept (a randomised machine makes a new one every episode); ``version``: the
    planner version (:data:`PLANNERS`). A tool path is recognised by identity (they are immutable): the
    cache holds it, so its id stays unique while its schedule is kept.
    """

    def __init__(self, margin: float | None = None, cache_size: int = 64,
                 version: int = PLANNER_VERSION) -> None:  # fmt: skip
        self.version = planner_version(version)
        self._plan, default = PLANNERS[self.version]
        self.margin = float(default if margin is None else margin)
        #: How far beyond the reaction lead the version's knob rule looks, mm.
        self.reach_mm = rule_reach_mm(self.version)
        self.cache_size = int(cache_size)
        self._cache: dict[tuple[int, MachineConfig], tuple[Toolpath, Schedule]] = {}

    def schedule(self, toolpath: Toolpath, machine: MachineConfig,
                 limits: PathLimits | None = None) -> Schedule:  # fmt: skip
        """The schedule of ``toolpath`` on ``machine`` (planned, or recalled). ``limits``: the controller's
        static tables when the caller has them (what a controller's look-ahead knows), else built."""
        key = (id(toolpath), machine)
        cached = self._cache.get(key)
        if cached is not None and cached[0] is toolpath:
            return cached[1]
        schedule = self._plan(toolpath, machine, limits=limits, margin=self.margin)
        if len(self._cache) >= self.cache_size:
            self._cache.pop(next(iter(self._cache)))
        self._cache[key] = (toolpath, schedule)
        return schedule
