"""Stage 3 of the pipeline: the controller (look-ahead, S-curve, real-time override) and the planners."""

from cnc_gym.motion.controller import ActionError, Controller, LookaheadFeatures, MotionChunk

__all__ = ["ActionError", "Controller", "LookaheadFeatures", "MotionChunk"]
