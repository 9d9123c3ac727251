"""cnc-gym: Gymnasium environments for CNC feed-rate control on real G-code.

Importing the package registers ``cnc_gym/Feedrate-v0`` (the env module itself is imported lazily by
``gymnasium.make``, so ``import cnc_gym`` stays cheap for interpreter-only users).
"""

from gymnasium.envs.registration import register, registry

__version__ = "0.1.0"

if "cnc_gym/Feedrate-v0" not in registry:
    register(id="cnc_gym/Feedrate-v0", entry_point="cnc_gym.envs.feedrate:FeedrateEnv")
