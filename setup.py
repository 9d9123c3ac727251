"""The package list of cnc-gym's wheel (everything else is in pyproject.toml).

Two folders of the repository install under a name of the project's own, so that no generic top-level
name lands in site-packages: ``agents/`` (the learning code) as ``cnc_gym_agents``, and ``configs/`` (the
machine presets, task and training configs: YAML that the repository keeps in plain sight at its top)
as ``cnc_gym/configs``, package data that :func:`cnc_gym.config.configs_dir` finds in either place.
Folders of data files (the suites, the configs) are listed as namespace packages, so that setuptools
ships their files. ``tests/test_install.py`` builds the wheel, installs it into a fresh venv and checks
what lands in site-packages.
"""

from setuptools import find_namespace_packages, setup

NOT_CODE = ["*.__pycache__", "*.__pycache__.*"]
PACKAGE_DIR = {"cnc_gym_agents": "agents", "cnc_gym.configs": "configs"}

setup(
    packages=[
        *find_namespace_packages(include=["cnc_gym", "cnc_gym.*"], exclude=NOT_CODE),
        "cnc_gym_agents",
        "cnc_gym.configs",
        *(f"cnc_gym.configs.{name}" for name in find_namespace_packages(where="configs", exclude=NOT_CODE)),
    ],
    package_dir=PACKAGE_DIR,
)
