#!/usr/bin/env python3
"""How much of an env's return the time a better policy saves is worth: the learning signal of a reward.

For each program (a suite split, ``--per-family`` of each family) and each env id, the ``classical``
planner and the ``oracle`` (it knows the plant: an upper reference, not a deployable policy) each run one
episode; the script sums every step's reward undiscounted and discounted with ``--gamma`` (PPO's γ), and
reports, per env id, the medians over programs of:

- the oracle's return minus the planner's (the signal a learner has to find), undiscounted and discounted;
- the finish bonus the planner's episode was paid (``info["reward_finish"]``), undiscounted and discounted
  from the episode's start;
- the planner's return;

and the spread (standard deviation over programs) of the planner's discounted return, about what reward
normalisation (SB3's ``VecNormalize``) scales the reward by: the discounted gap over it is the share of
the return's scale that the time a better policy saves is worth. For an env of the ``relative`` rule
(Feedrate-v6: time per the planner's scheduled time) a second row re-weights the same episodes as if the
time were counted per the planner's simulated cycle time of the program (what the schedule estimates).

Usage::

    .venv/bin/python scripts/reward_signal.py --split val --per-family 2 \\
        --ids cnc_gym/Feedrate-v5 cnc_gym/Feedrate-v6 [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
from dataclasses import dataclass
from typing import Any

#: The two policies compared: the deployable planner and the oracle (labelled as such in the output).
POLICIES = ("classical", "oracle")


@dataclass
class EpisodeReturn:
    """One episode's return, undiscounted and discounted, and its finish bonus (also both ways)."""

    total: float
    discounted: float
    bonus: float
    bonus_discounted: float
    feasible: bool
    cycle_time_s: float
    time_s: float  # the time the env's time term counts in (T_nominal or T_plan)
    relative: bool  # the env's reward rule is `relative`
    steps: list[tuple[float, float]]  # per step: the time term, and the rest of the reward

    def rescaled(self, time_s: float, gamma: float) -> float:
        """The discounted return had the time term counted per ``time_s`` instead of :attr:`time_s`."""
        scale, total, weight = self.time_s / time_s, 0.0, 1.0
        for time_term, rest in self.steps:
            total += weight * (rest + scale * time_term)
            weight *= gamma
        return total


def episode_return(env_id: str, policy_spec: str, program: Any, machine: str, dialect: str,
                   gamma: float) -> EpisodeReturn:  # fmt: skip
    """Run ``policy_spec`` on ``program`` in ``env_id`` (registered meter and controller revision)."""
    from cnc_gym.policies.spec import make_policy
    from cnc_gym.rollout import policy_env, run_episode

    policy = make_policy(policy_spec, progress=False)
    env = policy_env(policy, programs=[program], env_id=env_id, contour_rule=None, controller_revision=None,
                     machine=machine, dialect=dialect)  # fmt: skip
    sums = {"discounted": 0.0, "bonus": 0.0, "bonus_discounted": 0.0, "weight": 1.0}
    terms: list[tuple[float, float]] = []

    def on_step(steps: int, reward: float, terminated: bool, truncated: bool, info: dict[str, Any]) -> None:
        sums["discounted"] += sums["weight"] * float(reward)
        terms.append((float(info["reward_time"]), float(reward) - float(info["reward_time"])))
        bonus = float(info.get("reward_finish", 0.0))
        sums["bonus"] += bonus
        sums["bonus_discounted"] += sums["weight"] * bonus
        sums["weight"] *= gamma

    try:
        episode = run_episode(env, policy, seed=0, on_step=on_step)
        base = env.unwrapped
        time_s = base.reward_time_s(base.resolve_program(0)[1], base.nominal_time_s)
    finally:
        env.close()
    feasible = bool(episode.terminated) and float(episode.info.get("violation_length_mm", 0.0)) <= 0.0
    return EpisodeReturn(episode.total_return, sums["discounted"], sums["bonus"], sums["bonus_discounted"],
                         feasible, float(episode.info["cycle_time_s"]), time_s,
                         getattr(base, "reward_rule", "") == "relative", terms)  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--suite", default="cnc-bench-v1")
    parser.add_argument("--split", default="val")
    parser.add_argument("--per-family", type=int, default=2, metavar="N")
    parser.add_argument("--ids", nargs="+", default=["cnc_gym/Feedrate-v5", "cnc_gym/Feedrate-v6"])
    parser.add_argument("--gamma", type=float, default=0.999, help="PPO's discount (configs/train: 0.999)")
    parser.add_argument("--limit", type=int, default=None, metavar="N", help="the first N programs only")
    parser.add_argument("--json", default=None, help="write the per-program rows and the medians here")
    args = parser.parse_args(argv)

    from cnc_gym.benchmark.suites import load_suite

    suite = load_suite(args.suite)
    counts: dict[str, int] = {}
    programs = []
    for entry in suite.programs(args.split):
        if counts.get(entry.family, 0) < args.per_family:
            counts[entry.family] = counts.get(entry.family, 0) + 1
            programs.append(entry)
    programs = programs[: args.limit] if args.limit else programs
    rows: list[dict[str, Any]] = []
    for n, entry in enumerate(programs, 1):
        path = str(entry.path)
        row: dict[str, Any] = {"program": entry.name}
        for env_id in args.ids:
            got = {spec: episode_return(env_id, spec, path, suite.machine, suite.dialect, args.gamma)
                   for spec in POLICIES}  # fmt: skip
            planner, oracle = got["classical"], got["oracle"]
            row[env_id] = {"gap": oracle.total - planner.total,
                           "gap_discounted": oracle.discounted - planner.discounted,
                           "bonus": planner.bonus, "bonus_discounted": planner.bonus_discounted,
                           "planner_return": planner.total, "planner_discounted": planner.discounted,
                           "planner_feasible": planner.feasible,
                           "oracle_feasible": oracle.feasible}  # fmt: skip
            if planner.relative:  # re-weighted: time per the planner's simulated cycle time
                simulated = planner.cycle_time_s
                row[f"{env_id} (simulated)"] = {
                    "gap": oracle.rescaled(simulated, 1.0) - planner.rescaled(simulated, 1.0),
                    "gap_discounted": oracle.rescaled(simulated, args.gamma) - planner.rescaled(simulated,
                                                                                                args.gamma),
                    "bonus": 0.0, "bonus_discounted": 0.0,
                    "planner_return": planner.rescaled(simulated, 1.0),
                    "planner_discounted": planner.rescaled(simulated, args.gamma),
                    "planner_feasible": planner.feasible, "oracle_feasible": oracle.feasible}  # fmt: skip
        rows.append(row)
        print(f"[{n}/{len(programs)}] {entry.name}", file=sys.stderr, flush=True)

    def median(env_id: str, key: str) -> float:
        return statistics.median(row[env_id][key] for row in rows)

    summary: dict[str, dict[str, float]] = {}
    for env_id in [key for key in rows[0] if key != "program"]:
        summary[env_id] = {key: median(env_id, key) for key in
                           ("gap", "gap_discounted", "bonus", "bonus_discounted", "planner_return")}
        # What reward normalisation divides by is about the spread of discounted returns: over programs.
        spread = statistics.pstdev(row[env_id]["planner_discounted"] for row in rows)
        summary[env_id]["spread_discounted"] = spread
        summary[env_id]["signal"] = summary[env_id]["gap_discounted"] / spread if spread > 0 else 0.0
    print(f"{len(rows)} programs of {args.suite}/{args.split}, γ = {args.gamma}; medians over programs "
          "(oracle: knows the plant; an upper reference, not deployable)")
    print("| env id | oracle − planner return | discounted | planner's finish bonus | discounted from the "
          "start | planner's discounted return: spread over programs | discounted gap ÷ spread |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    for env_id, s in summary.items():
        name = (f"`{env_id.removesuffix(' (simulated)')}`, time per the planner's simulated cycle time"
                if env_id.endswith(" (simulated)") else f"`{env_id}`")  # fmt: skip
        print(f"| {name} | {s['gap']:.3f} | {s['gap_discounted']:.3f} | {s['bonus']:.3f} | "
              f"{s['bonus_discounted']:.3f} | {s['spread_discounted']:.3f} | {s['signal']:.3f} |")
    if args.json:
        with open(args.json, "w", encoding="utf-8") as out:
            json.dump({"gamma": args.gamma, "split": args.split, "summary": summary, "rows": rows}, out,
                      indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
