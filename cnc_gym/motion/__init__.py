"""Stage 3 of the pipeline: the controller (look-ahead, S-curve, real-time override) and the planners."""
