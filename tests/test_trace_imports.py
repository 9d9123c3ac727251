"""``cnc-gym trace`` starts fast: the interpreter path loads neither numba, scipy nor Gymnasium, and the
env still registers when Gymnasium is imported after cnc_gym (or before)."""

from __future__ import annotations

import subprocess
import sys


def run(code: str) -> str:
    return subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True).stdout


def test_trace_loads_no_heavy_module(tmp_path):
    program = tmp_path / "p.nc"
    program.write_text("G90 G21\nG01 X5 F1200\nG02 X10 Y5 R5\nM30\n")
    out = run(f"import sys; from cnc_gym.cli import main; main(['trace', {str(program)!r}]); "
              "print(sorted(m for m in ('numba', 'scipy', 'gymnasium') if m in sys.modules))")
    assert out.strip().splitlines()[-1] == "[]"
    assert '"kind": "arc"' in out


def test_env_registers_whichever_is_imported_first():
    for order in ("import cnc_gym, gymnasium as gym", "import gymnasium as gym, cnc_gym"):
        out = run(f"{order}; print('cnc_gym/Feedrate-v0' in gym.registry)")
        assert out.strip() == "True", order
