"""The package installs: a wheel built from the repository, in a fresh venv, works from any folder.

The wheel is built from the tracked files (as a clean checkout has them) with ``pip wheel --no-deps
--no-build-isolation`` and installed with ``--no-deps`` into a new venv whose dependencies come from the
project's own environment (a ``.pth`` line naming its site-packages, so nothing is downloaded); then, from
a folder outside the repository, ``cnc-gym run``, ``cnc-gym bench`` and ``gymnasium.make`` run on the
installed copy alone: machine presets, task and training configs, suites and built-in programs are package
data. Nothing with a generic name (``agents``, ``configs``, ...) may land in site-packages.

The first command compiles the env's kernels for the installed copy (numba caches them there), so this
test takes a minute or two.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import sysconfig
import zipfile
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent
#: What the wheel is built from.
SOURCES = ("pyproject.toml", "setup.py", "README.md", "LICENSE", "cnc_gym", "agents", "configs")
#: Top-level names the wheel may install (besides its .dist-info folder).
TOP_LEVEL = {"cnc_gym", "cnc_gym_agents"}
#: A folder of tests runs this long at most (the first command compiles the env's kernels).
TIMEOUT_S = 900

PART = "G90 G21 G17\nG00 X0 Y0\nG01 X20 F1200\nG02 X30 Y10 R10\nG01 Y25\nM30\n"


def _tracked(root: Path) -> list[Path]:
    """The build's source files as a clean checkout has them (every file when git is not at hand)."""
    try:
        listed = subprocess.run(["git", "-C", str(root), "ls-files", "-z", "--", *SOURCES],
                                capture_output=True, check=True, timeout=60).stdout.decode()  # fmt: skip
    except (OSError, subprocess.SubprocessError):
        listed = ""
    files = [Path(name) for name in listed.split("\0") if name and (root / name).is_file()]
    if not files:
        files = [path.relative_to(root) for name in SOURCES for path in
                 ([root / name] if (root / name).is_file() else (root / name).rglob("*"))
                 if path.is_file() and "__pycache__" not in path.parts]  # fmt: skip
    return files


def _run(args: list[str], cwd: Path, env: dict[str, str]) -> subprocess.CompletedProcess:
    done = subprocess.run(args, cwd=cwd, env=env, capture_output=True, text=True, timeout=TIMEOUT_S)
    assert done.returncode == 0, f"{' '.join(args)} failed ({done.returncode}):\n{done.stdout}\n{done.stderr}"
    return done


@pytest.fixture(scope="module")
def installed(tmp_path_factory) -> dict[str, Path]:
    """Build the wheel, make the venv, install: the paths of the wheel, the venv and a folder elsewhere."""
    tmp = tmp_path_factory.mktemp("install")
    source = tmp / "source"
    files = _tracked(REPO)
    for name in files:
        (source / name).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(REPO / name, source / name)
    dist = tmp / "dist"
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}
    _run([sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "--no-build-isolation", "-w", str(dist),
          str(source)], tmp, env)  # fmt: skip
    (wheel,) = dist.glob("cnc_gym-*.whl")
    venv = tmp / "venv"
    _run([sys.executable, "-m", "venv", "--without-pip", str(venv)], tmp, env)
    python = venv / "bin" / "python"
    site = Path(_run([str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"], tmp,
                     env).stdout.strip())  # fmt: skip
    before = set(os.listdir(site))
    # The dependencies: the project's own environment, named by a path line (its own .pth files, the
    # editable install's among them, are not read from there).
    ours = dict.fromkeys(sysconfig.get_paths()[key] for key in ("purelib", "platlib"))
    (site / "_cnc_gym_test_dependencies.pth").write_text("\n".join(ours) + "\n")
    _run([sys.executable, "-m", "pip", "--python", str(python), "install", "-q", "--no-deps", "--no-index",
          str(wheel)], tmp, env)  # fmt: skip
    elsewhere = tmp / "elsewhere"
    elsewhere.mkdir()
    env["CNC_GYM_CACHE_DIR"] = str(tmp / "cache")
    return {"wheel": wheel, "venv": venv, "site": site, "elsewhere": elsewhere, "files": files,
            "added": set(os.listdir(site)) - before - {"_cnc_gym_test_dependencies.pth"},
            "env": env}  # type: ignore[dict-item]  # fmt: skip


def test_the_wheel_holds_the_package_and_its_data_under_the_projects_own_names(installed):
    names = zipfile.ZipFile(installed["wheel"]).namelist()
    top = {name.split("/")[0] for name in names}
    dist_info = {name for name in top if name.endswith(".dist-info")}
    assert len(dist_info) == 1 and top - dist_info == TOP_LEVEL
    # Every tracked module and data file is in it, under its installed name.
    installed_as = {"agents": "cnc_gym_agents", "configs": "cnc_gym/configs"}
    wanted = set()
    for path in installed["files"]:
        head = path.parts[0]
        if head in ("cnc_gym", "agents", "configs") and path.suffix in (".py", ".yaml", ".nc", ".json"):
            wanted.add("/".join((installed_as.get(head, head), *path.parts[1:])))
    assert wanted - set(names) == set()
    assert {"cnc_gym/configs/machines/vmc-small.yaml", "cnc_gym/configs/tasks/default.yaml",
            "cnc_gym/configs/train/ppo.yaml", "cnc_gym/programs/circle.nc",
            "cnc_gym/benchmark/suites/cnc-bench-v1/manifest.json"} <= set(names)  # fmt: skip


def test_nothing_generic_lands_in_site_packages(installed):
    added = installed["added"]
    assert {name for name in added if not name.endswith(".dist-info")} == TOP_LEVEL, sorted(added)


def test_cnc_gym_run_works_from_another_folder(installed):
    out = _run([str(installed["venv"] / "bin" / "cnc-gym"), "run", "circle", "--json", "--no-progress"],
               installed["elsewhere"], installed["env"]).stdout  # fmt: skip
    summary = json.loads(out)
    assert summary["program"] == "circle" and summary["machine"] == "vmc-small" and summary["finished"]
    assert summary["cycle_time_s"] > 0


def test_cnc_gym_bench_works_from_another_folder(installed):
    folder = installed["elsewhere"]
    (folder / "part.nc").write_text(PART)
    policies = ["--policy", "constant:1.0", "--policy", "classical", "--policy", "bound"]
    _run([str(installed["venv"] / "bin" / "cnc-gym"), "bench", "--programs", "part.nc", *policies, "--json",
          "out.jsonl", "--no-progress"], folder, installed["env"])  # fmt: skip
    records = [json.loads(line) for line in (folder / "out.jsonl").read_text().splitlines()]
    assert [r["policy"] for r in records] == ["constant:1.0", "classical", "bound"]
    assert all(r["machine"] == "vmc-small" and r["program"] == "part" for r in records)
    assert records[1]["finished"] and records[1]["bound_s"] > 0


def test_gymnasium_make_and_the_package_data_work_from_another_folder(installed):
    check = """
import importlib.util
from pathlib import Path

import gymnasium as gym

import cnc_gym
from cnc_gym.benchmark import load_suite
from cnc_gym.machine import load_machine, machine_names
from cnc_gym_agents.training import load_config

site = Path(__import__("sys").argv[1]).resolve()
assert Path(cnc_gym.__file__).resolve().is_relative_to(site), cnc_gym.__file__
assert importlib.util.find_spec("agents") is None and importlib.util.find_spec("configs") is None
env = gym.make("cnc_gym/Feedrate-v2")
observation, info = env.reset(seed=0)
observation, reward, terminated, truncated, info = env.step(env.action_space.sample())
assert observation.shape == env.observation_space.shape and info["program"]
env.close()
assert "vmc-small" in machine_names() and load_machine("gsk25i").name == "gsk25i"
suite = load_suite("cnc-bench-v1")
assert suite.programs("test") and "G" in suite.programs("test")[0].text()
assert load_config("ppo").env.id.startswith("cnc_gym/Feedrate-")
print("ok")
"""
    out = _run([str(installed["venv"] / "bin" / "python"), "-c", check, str(installed["site"])],
               installed["elsewhere"], installed["env"]).stdout  # fmt: skip
    assert out.strip().endswith("ok")
