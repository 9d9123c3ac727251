"""numba's disk cache: :func:`needs_compiling` tells a cold cache from a warm one without compiling."""

from __future__ import annotations

import os
import subprocess
import sys

KERNEL = "from numba import njit\n\n\n@njit(cache=True)\ndef twice(x):\n    return {body}\n"
PROBE = ("import sys; sys.path.insert(0, {folder!r}); import tiny_kernel as m; "
         "from cnc_gym.numba_cache import needs_compiling; before = needs_compiling([m.twice]); "
         "m.twice(1.5); print(before, needs_compiling([m.twice]))")  # fmt: skip


def probe(tmp_path) -> str:
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache")}
    code = PROBE.format(folder=str(tmp_path))
    return subprocess.run([sys.executable, "-c", code], env=env, check=True, capture_output=True,
                          text=True).stdout.strip()  # fmt: skip


def test_a_cold_cache_compiles_a_warm_one_does_not_and_an_edit_cools_it(tmp_path):
    source = tmp_path / "tiny_kernel.py"
    source.write_text(KERNEL.format(body="2.0 * x"))
    assert probe(tmp_path) == "True False"  # nothing cached; compiled in the process, then nothing to do
    assert probe(tmp_path) == "False False"  # the next process loads it
    source.write_text(KERNEL.format(body="2.0 * x + 1.0"))  # another size: numba's stamp changes
    assert probe(tmp_path) == "True False"
