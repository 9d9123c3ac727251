"""numba's disk cache, kept fresh across modules.

numba keys a function's cached machine code on its own source file and bytecode, not on the compiled
functions it calls from other modules: after an edit of the controller's kernel, the env's fused step
would go on loading the old controller from the cache. :func:`refresh_on_change` drops a module's cached
functions when a module they call has changed since they were cached. :func:`needs_compiling` tells,
cheaply, whether a first call will compile (so that a command can say so before a long silence).
"""

from __future__ import annotations

import hashlib
import sys
from pathlib import Path
from types import ModuleType
from typing import Any


def refresh_on_change(module_name: str, dependencies: list[ModuleType]) -> None:
    """Flush the disk cache of every numba function of ``module_name`` if the sources of ``dependencies``
    differ from those its cache was built with (a stamp file beside the cache records them)."""
    from numba.core.registry import CPUDispatcher

    module = sys.modules[module_name]
    dispatchers = [f for f in vars(module).values()
                   if isinstance(f, CPUDispatcher) and f.py_func.__module__ == module_name]  # fmt: skip
    caches = [cache for cache in (getattr(f, "_cache", None) for f in dispatchers)
              if hasattr(cache, "_cache_path")]  # (a function without a disk cache has a null one)
    if not caches:
        return
    digest = hashlib.sha256()
    for path in sorted({Path(m.__file__) for m in dependencies if m.__file__}):
        digest.update(path.read_bytes())
    stamp = Path(caches[0]._cache_path) / f"{module_name}.deps"
    try:
        if stamp.exists() and stamp.read_text() == digest.hexdigest():
            return
        for cache in caches:
            cache.flush()
        stamp.write_text(digest.hexdigest())
    except OSError:  # a read-only cache: numba compiles in memory then
        pass


def needs_compiling(dispatchers: list[Any]) -> bool:
    """Whether calling one of ``dispatchers`` (numba functions) will compile: it has no machine code in
    this process, nor in numba's disk cache for this source and this CPU. Reads the cache's index file
    (a few kB), compiles nothing. False where it cannot tell (a numba whose cache internals differ): a
    command then only misses its notice."""
    return any(not _has_machine_code(d) for d in dispatchers)


def _has_machine_code(dispatcher: Any) -> bool:
    if dispatcher.overloads:  # compiled or loaded in this process
        return True
    try:
        cache = dispatcher._cache
        if not hasattr(cache, "_cache_path"):  # no disk cache: every process compiles
            return False
        # numba's own validity test: an index written for this source stamp (else it reads as empty),
        # with an entry keyed on this CPU's code generator and this bytecode.
        index = cache._cache_file._load_index()
        codegen = dispatcher.targetctx.codegen()
        return any(cache._index_key(key[0], codegen) == key for key in index)
    except Exception:  # numba's private cache API: anything unexpected means "cannot tell"
        return True
