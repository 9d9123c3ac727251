"""Stage 5 of the pipeline: the Gymnasium environments."""
