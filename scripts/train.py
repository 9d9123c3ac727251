"""Train a feed-override agent with Stable-Baselines3 PPO (or PPO-Lagrangian).

    .venv/bin/python scripts/train.py --config configs/train/ppo.yaml [--timesteps N] [--out DIR]
        [--seed N] [--run-name NAME] [--set KEY=VALUE ...] [--workers N] [--ray [ADDRESS]]

The config (YAML, read with the bounded safe loader; every key has a type and range, see docs/configs.md)
names the env (programs, machine, dialect, action mode, control period, reward weights), the number of
in-process envs (stepped by one batched engine: ``cnc_gym.envs.sb3``) and the PPO settings. The run writes,
under ``<output_dir>/<run_name>/``: ``model.zip`` (``cnc-gym run --policy`` and ``scripts/evaluate.py`` load
it without unpickling, see docs/security.md), ``config.yaml`` (the config as used), and TensorBoard logs under
``<output_dir>/tensorboard``. ``--timesteps``, ``--out``, ``--seed`` and ``--run-name`` override
``total_timesteps``, ``output_dir``, ``seed`` and ``run_name``, and ``--set KEY=VALUE`` any key (dotted:
``--set distill.rounds=1``), under the same rules; a bad config or option is one line on stderr and exit
status 2. ``algorithm: distill`` (distillation of the oracle, docs/training.md)
labels its episodes on a process pool with ``--workers N``, or on Ray with ``--ray [ADDRESS]``, as
``cnc-gym bench`` runs its episodes.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from cnc_gym.errors import CncGymError
from cnc_gym_agents.training import load_config, train, with_overrides


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--config", default="configs/train/ppo.yaml", help="training config (YAML)")
    parser.add_argument("--timesteps", type=int, default=None, help="override total_timesteps")
    parser.add_argument("--out", default=None, help="override output_dir")
    parser.add_argument("--seed", type=int, default=None, help="override seed")
    parser.add_argument("--run-name", default=None, help="override run_name")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="override any config key, dotted (e.g. distill.rounds=1; VALUE is YAML), "
        "checked by the same rules; repeatable",
    )
    parser.add_argument(
        "--workers",
        type=int,
        default=1,
        help="algorithm distill: label episodes on a local process pool of N workers",
    )
    parser.add_argument(
        "--ray",
        nargs="?",
        const="",
        default=None,
        metavar="ADDRESS",
        help="algorithm distill: label episodes on Ray (a local instance, or the cluster at ADDRESS)",
    )
    args = parser.parse_args(argv)
    try:
        config = load_config(args.config, overrides=args.set)
        config = with_overrides(config, seed=args.seed, run_name=args.run_name)
        progress = False if args.no_progress else None
        if config.algorithm == "distill":
            from cnc_gym_agents.distillation import train_distilled

            train_distilled(
                config,
                timesteps=args.timesteps,
                out=args.out,
                progress_bar=progress,
                workers=args.workers,
                use_ray=args.ray is not None,
                ray_address=args.ray or None,
            )
        else:
            if args.workers != 1 or args.ray is not None:
                raise CncGymError(
                    f"--workers and --ray are for algorithm distill (teacher labelling); "
                    f"{config.algorithm} trains in one process"
                )
            train(config, timesteps=args.timesteps, out=args.out, progress_bar=progress)
    except CncGymError as exc:
        print(f"train: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
