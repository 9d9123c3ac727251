"""Stage 4 of the pipeline: the servo axes (reference → actual position) and contour error."""
