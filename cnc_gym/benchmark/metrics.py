"""Per-episode metrics, the primary suite score, and the summary tables of ``cnc-gym bench``.

**The score.** An episode is *feasible* when it finished (the program ran to its end, not cut off by the
step budget) and cut no path length with contour error above tolerance (``violation_length_mm == 0``).
Its score is

    score = bound_s / cycle_time_s = 1 / time_ratio   if feasible,   0 otherwise,

and a suite score is 100 × the mean episode score over the programs (one value per seed; the table gives
its mean ± the 95 % confidence half-width over seeds). A feasible episode scores in (0, 1] (the bound is a
lower bound on the cycle time), so a truncated or violating episode can never outrank a finished,
violation-free one on the same program, and among feasible episodes the faster one ranks higher. The
rule is the one of "success weighted by path length" (SPL) in embodied navigation (Anderson et al., "On
Evaluation of Embodied Navigation Agents", 2018), with time in place of path length.

Every other figure is a column: feasible share, mean time ratio (over finished episodes), violation
length and time, contour error max and RMS.
"""

from __future__ import annotations

import math
from collections import defaultdict
from collections.abc import Iterable, Sequence
from typing import Any

#: Version of what a record's metrics mean; records of different versions never share a leaderboard.
#: 1 (records without the key): contour error on cutting moves only. 2: the programmed-path contour meter
#: (``contour_rule`` "path": rapids the reference has left are part of the path) and bound version 2.
#: 3: the deployable planner's version 2 behind ``classical`` (it holds tolerance), and the benchmark
#: track (``track``, ``plant_parameters``) in every record. 4: the deployable planner's version 3 behind
#: ``classical`` (faster, every split feasible). 5: the simulated controller's revision 2
#: (:data:`cnc_gym.motion.kernel.CONTROLLER_REVISION`: no overshoot where the override is lowered during
#: an acceleration) in every episode.
RECORD_VERSION = 5

#: Record keys every ``cnc-gym bench`` JSON Lines record carries (more may follow).
RECORD_KEYS = (
    "record_version", "contour_rule", "track", "plant_parameters",
    "suite", "suite_version", "suite_sha256", "split", "program", "program_sha256", "family", "tier",
    "machine", "machine_sha256", "plant", "dialect", "units", "policy", "seed", "commit", "cnc_gym_version",
    "bound_s", "bound_version", "cycle_time_s", "time_ratio", "violation_length_mm", "violation_time_s",
    "contour_error_max_mm", "contour_error_rms_mm", "tolerance_mm", "violations", "steps", "finished",
    "stopped_by", "feasible", "score", "total_return", "reference",
)  # fmt: skip


def is_feasible(finished: bool, violation_length_mm: float | None) -> bool:
    """Finished, with no path length cut over tolerance."""
    return bool(finished) and violation_length_mm is not None and violation_length_mm <= 0.0


def episode_score(finished: bool, violation_length_mm: float | None, time_ratio: float) -> float:
    """``1 / time_ratio`` for a feasible episode, 0 otherwise (module docstring)."""
    if not is_feasible(finished, violation_length_mm) or not (time_ratio > 0 and math.isfinite(time_ratio)):
        return 0.0
    return 1.0 / time_ratio


def t_quantile_975(dof: int) -> float:
    """Two-sided 95 % Student-t quantile for ``dof`` degrees of freedom."""
    from scipy.stats import t

    return float(t.ppf(0.975, dof))


def mean_ci(values: Sequence[float]) -> tuple[float, float | None]:
    """Mean and 95 % confidence half-width (Student t; None for a single value)."""
    n = len(values)
    if n == 0:
        return math.nan, None
    mean = sum(values) / n
    if n == 1:
        return mean, None
    sd = math.sqrt(sum((v - mean) ** 2 for v in values) / (n - 1))
    return mean, t_quantile_975(n - 1) * sd / math.sqrt(n)


def summarize(records: Iterable[dict[str, Any]], by_family: bool = True) -> list[dict[str, Any]]:
    """Rows of the bench table: per (family, policy) when ``by_family``, and per policy over all programs
    (family ``"all"``). Policies keep the order of their first record; families are sorted."""
    records = list(records)
    groups: dict[tuple[str, str], list[dict[str, Any]]] = defaultdict(list)
    policies: list[str] = []
    for r in records:
        if r["policy"] not in policies:
            policies.append(r["policy"])
        groups[("all", r["policy"])].append(r)
        if by_family:
            groups[(r["family"], r["policy"])].append(r)
    families = [*sorted({f for f, _ in groups if f != "all"}), "all"]
    rows = []
    for family in families:
        for policy in policies:
            group = groups.get((family, policy))
            if group:
                rows.append({"family": family, "policy": policy, **_aggregate(group)})
    return rows


def _aggregate(group: list[dict[str, Any]]) -> dict[str, Any]:
    per_seed: dict[int, list[float]] = defaultdict(list)
    for r in group:
        per_seed[int(r["seed"])].append(float(r["score"]))
    seed_scores = [100.0 * sum(v) / len(v) for _, v in sorted(per_seed.items())]
    score, ci = mean_ci(seed_scores)
    reference = all(r.get("reference") for r in group)
    finished = [r for r in group if r["finished"]]
    ratios = [float(r["time_ratio"]) for r in finished]
    lengths = [float(r["violation_length_mm"]) for r in group if r["violation_length_mm"] is not None]
    cut = [float(r.get("cut_length_mm") or 0.0) for r in group if r["violation_length_mm"] is not None]
    return {
        "episodes": len(group),
        "programs": len({r["program"] for r in group}),
        "seeds": len(per_seed),
        "score": score,
        "score_ci95": ci,
        "feasible_share": sum(bool(r["feasible"]) for r in group) / len(group),
        "finished_share": len(finished) / len(group),
        "time_ratio": sum(ratios) / len(ratios) if ratios else math.nan,
        "violation_length_mm": sum(lengths) / len(lengths) if lengths else None,
        "violation_rate": (sum(lengths) / sum(cut)) if lengths and sum(cut) > 0 else None,
        "reference": reference,
    }


def format_table(rows: list[dict[str, Any]]) -> str:
    """The summary table as plain text (one line per family × policy, then the suite rows)."""
    header = ("family", "policy", "score", "± 95% CI", "feasible", "time ratio", "viol. mm", "episodes")
    lines = [header]
    for r in rows:
        ci = "—" if r["score_ci95"] is None else f"{r['score_ci95']:.1f}"
        viol = "—" if r["violation_length_mm"] is None else f"{r['violation_length_mm']:.3f}"
        feasible = "—" if r["reference"] else f"{100 * r['feasible_share']:.0f} %"
        lines.append((r["family"], r["policy"], f"{r['score']:.1f}", ci, feasible, f"{r['time_ratio']:.2f}",
                      viol, str(r["episodes"])))  # fmt: skip
    widths = [max(len(row[i]) for row in lines) for i in range(len(header))]
    out = []
    for k, row in enumerate(lines):
        if k > 1 and row[0] == "all" and lines[k - 1][0] != "all":
            out.append("  ".join("-" * w for w in widths))
        out.append("  ".join(c.ljust(w) if i < 2 else c.rjust(w) for i, (c, w) in enumerate(zip(row, widths,
                                                                                                   strict=True))))
        if k == 0:
            out.append("  ".join("-" * w for w in widths))
    return "\n".join(out)
