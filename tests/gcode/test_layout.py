"""The layout of ``cnc_gym/gcode`` is its architecture: no import cycles, and the core knows no feature.

Imports are read from the source, all of them (``tests/import_graph.py``, the reader of
``tests/test_package_layout.py``, which checks the whole package's stages).
"""

from __future__ import annotations

from pathlib import Path

from import_graph import cycles, graph, modules

import cnc_gym.gcode

ROOT = Path(cnc_gym.gcode.__file__).resolve().parent
PREFIX = "cnc_gym.gcode"
#: The core: the contract, the state, the output boundary and the block executor. They name no language
#: family and no dialect (those plug in through the Dialect record).
CORE = {"codes", "settings", "program", "offsets", "canonical", "state", "dialect", "interpreter"}


MODULES = modules({ROOT: PREFIX})
GRAPH = graph(MODULES)


def test_the_package_has_the_layout_of_the_architecture():
    assert f"{PREFIX}.lang.fanuc" in MODULES and f"{PREFIX}.dialects.gsk25i" in MODULES
    assert f"{PREFIX}.dialects.fanuc" in MODULES
    assert all(f"{PREFIX}.{core}" in MODULES for core in CORE)


def test_no_import_cycles_in_gcode_type_checking_imports_included():
    found = cycles(GRAPH)
    assert not found, f"import cycles: {[sorted(c) for c in found]}"


def test_the_core_imports_no_language_family_and_no_dialect():
    for core in CORE:
        plug_ins = (f"{PREFIX}.lang", f"{PREFIX}.dialects")
        bad = sorted(m for m in GRAPH[f"{PREFIX}.{core}"] if m.startswith(plug_ins))
        assert not bad, f"{core}.py imports {bad}"


def test_features_see_the_core_only_through_the_seam():
    # Language parts and dialects never import the interpreter module: they get the core as a Seam.
    for name, imports in GRAPH.items():
        if name.startswith((f"{PREFIX}.lang", f"{PREFIX}.dialects")):
            assert f"{PREFIX}.interpreter" not in imports, name


def test_dialect_folders_do_not_import_each_other():
    for name, imports in GRAPH.items():
        if name.startswith(f"{PREFIX}.dialects."):
            own = ".".join(name.split(".")[:4])
            other = sorted(m for m in imports
                           if m.startswith(f"{PREFIX}.dialects.") and not m.startswith(own))  # fmt: skip
            assert not other, f"{name} imports another dialect: {other}"


def test_the_cycle_check_finds_a_cycle():
    # The check itself can fail: a two-module cycle planted in a copy of the graph is found.
    edges = {k: set(v) for k, v in GRAPH.items()}
    edges[f"{PREFIX}.codes"].add(f"{PREFIX}.interpreter")
    assert cycles(edges)
