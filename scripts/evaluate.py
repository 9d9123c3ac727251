"""Evaluate a trained model against the baselines on the same programs.

    .venv/bin/python scripts/evaluate.py --model runs/ppo/model.zip [--programs star pocket]
        [--overrides 0.5,1.0,1.5,2.0] [--no-classical] [--json]

Every policy runs one deterministic episode per program through the env configured as in training (read
from the ``config.yaml`` saved beside the model, or ``--config``). The table shows return, cycle time,
max/RMS contour error and violations; the summary compares the model's total return with the best
constant override's and the classical planner's.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from cnc_gym.errors import CncGymError

DEFAULT_OVERRIDES = (0.25, 0.5, 0.75, 1.0, 1.25, 1.5, 1.75, 2.0)


def evaluate(policies: list[Any], env_kwargs: dict[str, Any], programs: list[str]) -> list[dict[str, Any]]:
    """One episode per (policy, program); rows are RunResult summaries."""
    import gymnasium

    import cnc_gym  # noqa: F401
    from cnc_gym.runner import run_episode

    rows = []
    for program in programs:
        kwargs = {**env_kwargs, "programs": [program]}
        env = gymnasium.make("cnc_gym/Feedrate-v0", **kwargs)
        try:
            for policy in policies:
                rows.append(run_episode(env, policy, seed=0, record=False).summary())
        finally:
            env.close()
    return rows


def totals(rows: list[dict[str, Any]]) -> dict[str, dict[str, float]]:
    """Per policy: total return, total cycle time and violations over all programs."""
    out: dict[str, dict[str, float]] = {}
    for r in rows:
        t = out.setdefault(r["policy"], {"return": 0.0, "cycle_time_s": 0.0, "violations": 0})
        t["return"] += r["total_return"]
        t["cycle_time_s"] += r["cycle_time_s"]
        t["violations"] += r["violations"]
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--model", default=None, help="trained SB3 model (.zip); omit to compare baselines only"
    )
    parser.add_argument(
        "--config", default=None, help="training config for the env (default: beside the model)"
    )
    parser.add_argument("--programs", nargs="+", default=None, help="programs (default: the training set)")
    parser.add_argument("--machine", default=None)
    parser.add_argument(
        "--overrides",
        default=",".join(map(str, DEFAULT_OVERRIDES)),
        help="constant overrides to compare, comma separated",
    )
    parser.add_argument("--no-classical", action="store_true", help="leave the classical planner out")
    parser.add_argument("--json", action="store_true", help="print rows and totals as one JSON object")
    args = parser.parse_args(argv)
    try:
        from agents import ClassicalPlanner, ConstantOverride
        from agents.model import ModelPolicy
        from agents.training import load_config

        config_path = args.config
        if config_path is None and args.model is not None:
            beside = Path(args.model).parent / "config.yaml"
            config_path = str(beside) if beside.exists() else None
        config = load_config(config_path) if config_path else None
        env_kwargs = config.env.make_kwargs() if config else {"programs": ["star", "pocket", "freeform"]}
        if args.machine:
            env_kwargs["machine"] = args.machine
        programs = args.programs or list(env_kwargs["programs"])
        try:
            overrides = [float(x) for x in args.overrides.split(",") if x.strip()]
        except ValueError:
            raise CncGymError(
                f"--overrides must be numbers separated by commas, got {args.overrides!r}"
            ) from None
        policies: list[Any] = [ConstantOverride(x) for x in overrides]
        if not args.no_classical:
            policies.append(ClassicalPlanner())
        if args.model:
            policies.append(ModelPolicy(args.model))
        rows = evaluate(policies, env_kwargs, programs)
    except CncGymError as exc:
        print(f"evaluate: {exc}", file=sys.stderr)
        return 2
    summary = totals(rows)
    if args.json:
        print(json.dumps({"rows": rows, "totals": summary}))
        return 0
    from cnc_gym.runner import format_table

    print(format_table(rows))
    print()
    constants = {k: v for k, v in summary.items() if k.startswith("constant:")}
    best_name = max(constants, key=lambda k: constants[k]["return"]) if constants else None
    for name, t in sorted(summary.items(), key=lambda kv: -kv[1]["return"]):
        mark = "  <- best constant" if name == best_name else ""
        print(f"{name:>24}: return {t['return']:9.2f}  cycle {t['cycle_time_s']:8.3f} s  "
              f"violations {int(t['violations'])}{mark}")  # fmt: skip
    if args.model and best_name:
        model_name = Path(args.model).name
        gap = summary[model_name]["return"] - constants[best_name]["return"]
        print(f"\nmodel − best constant ({best_name}): {gap:+.2f} return")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
