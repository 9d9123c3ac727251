"""Stage 5 of the pipeline: the Gymnasium environments.

``FeedrateEnv`` is registered as ``cnc_gym/Feedrate-v0`` by ``import cnc_gym``; ``FeedrateVectorEnv`` is
its native vector env (N copies stepped in one call, infos gathered as arrays).
"""

from cnc_gym.envs.feedrate import FeedrateEnv
from cnc_gym.envs.vector import FeedrateVectorEnv

__all__ = ["FeedrateEnv", "FeedrateVectorEnv"]
