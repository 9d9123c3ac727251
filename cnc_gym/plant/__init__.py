"""Stage 4 of the pipeline: the servo axes (reference → actual position) and contour error.

Two servo backends share one interface: :class:`ServoPlant` (the exact LTI model) and
:class:`~cnc_gym.plant.mujoco.MujocoPlant` (the same loops on the machine's mechanics in MuJoCo, imported
only when used). :func:`make_plant` builds the one a machine's ``plant.backend`` names.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from cnc_gym.config import escaped
from cnc_gym.errors import ConfigError
from cnc_gym.plant.contour import ContourErrorMeter
from cnc_gym.plant.servo import ServoPlant

if TYPE_CHECKING:
    from cnc_gym.machine import MachineConfig

__all__ = ["ContourErrorMeter", "ServoPlant", "make_plant"]


def make_plant(machine: MachineConfig, n_envs: int = 1, backend: str | None = None) -> Any:
    """The servo plant of ``n_envs`` copies of ``machine``: the backend ``backend`` names (``lti`` or
    ``mujoco``), by default the machine's ``plant.backend``."""
    from cnc_gym.machine import with_plant_backend

    machine = with_plant_backend(machine, backend)
    if machine.plant.backend == "mujoco":
        try:
            from cnc_gym.plant.mujoco import MujocoPlant
        except (ImportError, RuntimeError) as exc:  # not installed, or a bad MUJOCO_GL at its import
            why = escaped(str(exc))
            raise ConfigError(f"{machine.source}: the MuJoCo plant cannot be loaded: {why}") from None

        return MujocoPlant(machine, n_envs=n_envs)
    return ServoPlant(machine, n_envs=n_envs)
