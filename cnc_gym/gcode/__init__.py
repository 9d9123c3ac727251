"""Stage 1 of the pipeline: the G-code interpreter (program text → canonical tool path)."""
