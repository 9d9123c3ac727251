"""The benchmark: program suites with fixed splits, the time-optimal bound as reference, honest metrics,
one primary score, and the ``cnc-gym bench`` runner (docs/benchmark.md).

==========================  ==========================================================================
:mod:`.suites`              named, versioned suites (package data) and their seeded generator
:mod:`.families`            the program families (contours, pockets, freeform, arcs, holes, ...)
:mod:`.metrics`             per-episode metrics, the primary score and its rule, summary tables
:mod:`.runner`              every program × policy × seed: serial, process pool or Ray
:mod:`.plots`               Pareto plot and per-family bars
:mod:`.leaderboard`         the leaderboard table of docs/benchmark.md, from bench records
:mod:`.cli`                 the ``cnc-gym bench`` subcommand
==========================  ==========================================================================

Imports are lazy (``cnc-gym trace`` loads this package's CLI module only).
"""

from __future__ import annotations

from typing import Any

__all__ = ["DEFAULT_SUITE", "ProgramEntry", "Suite", "load_suite"]


def __getattr__(name: str) -> Any:
    if name in __all__:
        from cnc_gym.benchmark import suites

        return getattr(suites, name)
    raise AttributeError(f"module 'cnc_gym.benchmark' has no attribute {name!r}")
