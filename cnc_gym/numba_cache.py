"""numba's disk cache, kept fresh across modules.

numba keys a function's cached machine code on its own source file and bytecode, not on the compiled
functions it calls from other modules: after an edit of the controller's kernel, the env's fused step
would go on loading the old controller from the cache. :func:`refresh_on_change` drops a module's cached
functions when a module they call has changed since they were cached.
"""

from __future__ import annotations

import hashlib
import sys
from pathlib import Path
from types import ModuleType


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
