"""Evaluate a trained model against the baselines on the same programs, ranked as the benchmark ranks.

    .venv/bin/python scripts/evaluate.py --model runs/ppo/model.zip [--programs star pocket]
        [--overrides 0.5,1.0,1.5,2.0] [--no-classical] [--oracle] [--json]

Every policy runs one deterministic episode per program through the env configured as in training (read
from the ``config.yaml`` saved beside the model, or ``--config``; randomisation off), a trained model in
the env version and action mode it was trained with, the baselines turning the override knob. The table
shows return, cycle time, max/RMS contour error and violations; the summary ranks policies by the
benchmark's primary score (docs/benchmark.md: the time-optimal bound ÷ cycle time for an episode that
finished with no path cut over tolerance, 0 otherwise), so a truncated or violating run can never be the
"best constant". For a whole suite split use ``cnc-gym bench``.
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


def evaluate(policies: list[Any], env_kwargs: dict[str, Any], programs: list[str],
             env_id: str = "cnc_gym/Feedrate-v0") -> list[dict[str, Any]]:  # fmt: skip
    """One episode per (policy, program); rows carry the ``cnc-gym run --json`` keys plus the benchmark's
    metrics (``bound_s``, ``time_ratio``, ``violation_length_mm``, ``feasible``, ``score``).

    Every policy runs in the env it names (a trained model: the id and settings it was trained with),
    else in ``env_id`` with ``env_kwargs``; the baselines turn the override knob, so a ``residual``
    action mode is theirs in ``override`` mode. Randomisation is off: one deterministic episode each."""
    import gymnasium

    import cnc_gym  # noqa: F401
    from cnc_gym.benchmark.metrics import episode_score, is_feasible
    from cnc_gym.motion.bound import time_optimal_bound
    from cnc_gym.rollout import run_episode

    common = {k: v for k, v in env_kwargs.items() if k not in ("randomize", "programs")}
    rows = []
    for program in programs:
        bound = None
        for policy in policies:
            policy_id = getattr(policy, "env_id", None)
            kwargs = {**common, "programs": [program]}
            if policy_id is None:  # a baseline: the knob, in the configured env
                policy_id = env_id
                if kwargs.get("action_mode") == "residual":
                    kwargs["action_mode"] = "override"
            else:
                kwargs.update(getattr(policy, "env_kwargs", {}))
            if policy_id == "cnc_gym/Feedrate-v0":
                kwargs = {k: v for k, v in kwargs.items() if k not in ("residual_range",)}
            env = gymnasium.make(policy_id, **kwargs)
            try:
                base = env.unwrapped
                if bound is None:
                    mode = "feed" if base.action_mode == "feed" else "override"
                    bound = time_optimal_bound(base.toolpath, base.machine, action_mode=mode).total_s
                episode = run_episode(env, policy, 0)
            finally:
                env.close()
            info, finished = episode.info, episode.finished
            row = {key: info[key] for key in ("program", "cycle_time_s", "contour_error_max_mm",
                                              "contour_error_rms_mm", "tolerance_mm", "violations")}
            length, ratio = float(info["violation_length_mm"]), info["cycle_time_s"] / bound
            row.update(machine=base.machine.name, policy=str(getattr(policy, "name", policy)),
                       steps=episode.steps, total_return=episode.total_return, finished=finished,
                       bound_s=bound, time_ratio=ratio, violation_length_mm=length,
                       feasible=is_feasible(finished, length),
                       score=episode_score(finished, length, ratio))  # fmt: skip
            rows.append(row)
    return rows


def totals(rows: list[dict[str, Any]]) -> dict[str, dict[str, float]]:
    """Per policy: total return, cycle time, violations, and the benchmark score (100 × mean over programs
    of bound ÷ cycle for feasible episodes, 0 for the others)."""
    out: dict[str, dict[str, float]] = {}
    for r in rows:
        t = out.setdefault(r["policy"], {"return": 0.0, "cycle_time_s": 0.0, "violations": 0, "score": 0.0,
                                         "programs": 0, "feasible": 0})  # fmt: skip
        t["return"] += r["total_return"]
        t["cycle_time_s"] += r["cycle_time_s"]
        t["violations"] += r["violations"]
        t["score"] += r["score"]
        t["programs"] += 1
        t["feasible"] += int(r["feasible"])
    for t in out.values():
        t["score"] = 100.0 * t["score"] / t["programs"]
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
    parser.add_argument("--oracle", action="store_true",
                        help="add the oracle planner (simulates the exact env; slow on long programs)")
    parser.add_argument("--json", action="store_true", help="print rows and totals as one JSON object")
    args = parser.parse_args(argv)
    try:
        from cnc_gym.policies import ClassicalPlanner, ConstantOverride, OraclePlanner
        from cnc_gym.policies.model import ModelPolicy
        from cnc_gym_agents.training import load_config

        config_path = args.config
        if config_path is None and args.model is not None:
            beside = Path(args.model).parent / "config.yaml"
            config_path = str(beside) if beside.exists() else None
        config = load_config(config_path) if config_path else None
        env_kwargs = config.env.make_kwargs() if config else {"programs": ["star", "pocket", "freeform"]}
        env_id = config.env.id if config else "cnc_gym/Feedrate-v0"
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
        if args.oracle:
            policies.append(OraclePlanner(progress=False))
        if args.model:
            policies.append(ModelPolicy(args.model))
        rows = evaluate(policies, env_kwargs, programs, env_id)
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
    # Ranked by the benchmark score: a truncated or violating run scores 0, so it cannot be the best.
    best_name = max(constants, key=lambda k: constants[k]["score"]) if constants else None
    for name, t in sorted(summary.items(), key=lambda kv: -kv[1]["score"]):
        mark = "  <- best constant" if name == best_name else ""
        print(f"{name:>24}: score {t['score']:6.1f}  feasible {int(t['feasible'])}/{int(t['programs'])}  "
              f"cycle {t['cycle_time_s']:8.3f} s  violations {int(t['violations'])}  "
              f"return {t['return']:9.2f}{mark}")  # fmt: skip
    if args.model and best_name:
        model_name = Path(args.model).name
        gap = summary[model_name]["score"] - constants[best_name]["score"]
        print(f"\nmodel − best constant ({best_name}): {gap:+.1f} score")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
