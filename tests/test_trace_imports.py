"""``cnc-gym trace`` starts fast: the interpreter path loads none of the simulation's heavy libraries
(numba, scipy, matplotlib, MuJoCo, Gymnasium, torch), with or without a machine preset, and the env still
registers when Gymnasium is imported after cnc_gym (or before)."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest


def run(code: str) -> str:
    return subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True).stdout


#: What a simulation needs and a trace does not: each costs start-up time (numba alone ~0.3 s).
HEAVY = ("numba", "llvmlite", "scipy", "matplotlib", "mujoco", "gymnasium", "torch", "toppra")
#: What a trace without a config file does not need either: PyYAML (read with a machine preset or a setup
#: file), importlib.resources (with tempfile, shutil, random and the compression modules), and the machine
#: records with their config schema (the command line's unit choices come from cnc_gym.defaults).
CONFIG_ONLY = ("yaml", "importlib.resources", "tempfile", "random", "cnc_gym.machine", "cnc_gym.config")


@pytest.mark.parametrize("options", [[], ["--machine", "vmc-small", "--dialect", "fanuc"]])
def test_trace_loads_no_heavy_module(tmp_path, options):
    program = tmp_path / "p.nc"
    program.write_text("G90 G21\nG01 X5 F1200\nG02 X10 Y5 R5\nM30\n")
    out = run(f"import sys; from cnc_gym.cli import main; main(['trace', {str(program)!r}, *{options!r}]); "
              f"print(sorted(m for m in {HEAVY!r} if m in sys.modules))")
    assert out.strip().splitlines()[-1] == "[]"
    assert '"kind": "arc"' in out


def test_trace_without_a_config_loads_no_yaml(tmp_path):
    program = tmp_path / "p.nc"
    program.write_text("G90 G21\nG01 X5 F1200\nM30\n")
    out = run(f"import sys; from cnc_gym.cli import main; main(['trace', {str(program)!r}]); "
              f"print(sorted(m for m in {CONFIG_ONLY!r} if m in sys.modules))")
    assert out.strip().splitlines()[-1] == "[]"


def test_the_interpreter_without_a_machine_loads_no_machine_record():
    # The machine records and their config schema (dataclasses built at import) are for a preset; the
    # interpreter's unit constants come from cnc_gym.defaults.
    out = run("import sys; from cnc_gym.gcode import interpret; from cnc_gym.toolpath.records import "
              "toolpath_jsonl; toolpath_jsonl(interpret('G20 G91 G01 X1 F10\\nG02 X1 Y1 R1\\nM30\\n')); "
              "print(sorted(m for m in ('cnc_gym.machine', 'cnc_gym.config') if m in sys.modules))")
    assert out.strip() == "[]"


def test_env_registers_whichever_is_imported_first():
    for order in ("import cnc_gym, gymnasium as gym", "import gymnasium as gym, cnc_gym"):
        out = run(f"{order}; print('cnc_gym/Feedrate-v0' in gym.registry)")
        assert out.strip() == "True", order


def test_the_command_keeps_openblas_to_one_thread_unless_the_user_chose():
    # OpenBLAS reads the variable when numpy loads: the command sets it before its imports (its thread pool
    # spins at load, a third of trace's start-up CPU on two cores); a user's own value stays.
    code = "import os, cnc_gym.cli, numpy; print(os.environ['OPENBLAS_NUM_THREADS'])"
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"}
    assert subprocess.run([sys.executable, "-c", code], env=env, check=True, capture_output=True,
                          text=True).stdout.strip() == "1"  # fmt: skip
    env["OPENBLAS_NUM_THREADS"] = "3"
    assert subprocess.run([sys.executable, "-c", code], env=env, check=True, capture_output=True,
                          text=True).stdout.strip() == "3"  # fmt: skip
