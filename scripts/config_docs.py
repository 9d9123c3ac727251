"""Write (or check) the docs' config key tables from the schemas, so the docs never drift from the code.

    .venv/bin/python scripts/config_docs.py           # rewrite the tables in place
    .venv/bin/python scripts/config_docs.py --check   # exit 1 and name the table if one differs

A table sits in a Markdown file between ``<!-- config-table NAME -->`` and ``<!-- end config-table -->``;
NAME is a key of :data:`TABLES`, which maps it to the dataclass whose declared keys
(:func:`cnc_gym.config.markdown_table`) fill it. ``tests/test_config.py`` runs the check.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from doc_blocks import block_renderer, update_docs

from cnc_gym.config import markdown_table
from cnc_gym.envs import observation
from cnc_gym.envs.feedrate_v1 import EnvArgumentsV1, RankingReward, RelativeReward
from cnc_gym.envs.options import EnvArguments, RewardWeights
from cnc_gym.envs.randomization import DomainRandomization
from cnc_gym.envs.task import TaskConfig
from cnc_gym.machine import (
    AxisConfig,
    AxisMechanicsConfig,
    ControllerConfig,
    MachineConfig,
    MachineFunctionsConfig,
    PlantAxes,
    PlantConfig,
    RotaryAxisConfig,
    SetupConfig,
    ToolSetup,
)
from cnc_gym_agents.training import DistillSettings, EnvSettings, LagrangianSettings, PPOSettings, TrainConfig

REPO = Path(__file__).resolve().parent.parent
#: Table name → (schema, key prefix shown in the table).
TABLES: dict[str, tuple[type, str]] = {
    "machine": (MachineConfig, ""),
    "machine.controller": (ControllerConfig, "controller."),
    "machine.axis": (AxisConfig, ""),
    "machine.rotary": (RotaryAxisConfig, ""),
    "machine.plant": (PlantConfig, "plant."),
    "machine.plant.axes": (PlantAxes, "plant.axes."),
    "machine.plant.axis": (AxisMechanicsConfig, ""),
    "machine.setup": (SetupConfig, "setup."),
    "machine.setup.tool": (ToolSetup, ""),
    "machine.machine_functions": (MachineFunctionsConfig, "machine_functions."),
    "task": (TaskConfig, ""),
    "reward": (RewardWeights, ""),
    "train": (TrainConfig, ""),
    "train.env": (EnvSettings, "env."),
    "train.ppo": (PPOSettings, "ppo."),
    "train.lagrangian": (LagrangianSettings, "lagrangian."),
    "train.distill": (DistillSettings, "distill."),
    "env.arguments": (EnvArguments, ""),
    "env.v1.arguments": (EnvArgumentsV1, ""),
    "reward.v1": (RankingReward, ""),
    "reward.v6": (RelativeReward, ""),
    "randomize": (DomainRandomization, ""),
}
#: Tables written by a function instead of from a schema: the observations of Feedrate-v1 and -v0, from
#: their declarations.
GENERATED = {"env.v1.observation": observation.markdown_table,
             "env.v0.observation": lambda: observation.markdown_table(observation.OBSERVATION_V0)}
#: Files that hold tables.
DOCS = ("docs/configs.md", "docs/env.md")
#: ``text`` with every table block rewritten, and the names of the blocks found.
render = block_renderer("config-table", {
    **{name: (lambda cls=cls, prefix=prefix: markdown_table(cls, prefix))
       for name, (cls, prefix) in TABLES.items()},
    **GENERATED}, "config_docs")  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="report differences instead of writing")
    args = parser.parse_args(argv)
    stale, found = update_docs(REPO, DOCS, render, args.check)
    missing = sorted((set(TABLES) | set(GENERATED)) - set(found))
    if missing:
        where = ", ".join(DOCS)
        print(f"config_docs: no block for table(s) {', '.join(missing)} in {where}", file=sys.stderr)
        return 1
    if stale and args.check:
        stale_docs = ", ".join(stale)
        print(f"config_docs: stale table(s) in {stale_docs}; run scripts/config_docs.py", file=sys.stderr)
        return 1
    for doc in stale:
        print(f"rewrote {doc}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
