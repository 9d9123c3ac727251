"""``cnc-gym bench --plot DIR``: the Pareto plot (time ratio against violation rate) and per-family bars."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from cnc_gym.benchmark.metrics import summarize
from cnc_gym.errors import CncGymError


def write_plots(records: list[dict[str, Any]], folder: str | Path, title: str = "") -> list[Path]:
    """``pareto.png`` and ``families.png`` in ``folder`` for the nominal track's records, and
    ``pareto-<track>.png``, ``families-<track>.png`` for each other track's (records of different tracks
    never share a plot); returns their paths."""
    from cnc_gym.benchmark.leaderboard import track_of

    paths = []
    for track in sorted({track_of(r) for r in records}, key=lambda t: (t != "nominal", t)):
        suffix = "" if track == "nominal" else f"-{track}"
        label = title if track == "nominal" else f"{title} ({track} track)".strip()
        paths += _write_track_plots([r for r in records if track_of(r) == track], Path(folder), label, suffix)
    return paths


def _write_track_plots(records: list[dict[str, Any]], folder: Path, title: str, suffix: str) -> list[Path]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    folder = Path(folder)
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise CncGymError(f"{folder}: cannot create the plot folder: {exc.strerror or exc}") from None
    rows = summarize(records)
    suite = [r for r in rows if r["family"] == "all"]
    paths = []

    # Pareto: each policy at (violation rate, mean time ratio); lower-left is better.
    fig, ax = plt.subplots(figsize=(8, 5), constrained_layout=True)
    largest = 0.0
    for r in suite:
        rate = r["violation_rate"]
        x = 0.0 if rate is None else 100.0 * rate
        largest = max(largest, x)
        marker = "*" if r["reference"] else "o"
        ax.scatter([x], [r["time_ratio"]], s=90 if r["reference"] else 50, marker=marker, zorder=3)
        ax.annotate(f"{r['policy']}  (score {r['score']:.1f})", (x, r["time_ratio"]),
                    textcoords="offset points", xytext=(6, 4), fontsize=8)  # fmt: skip
    ax.axhline(1.0, color="0.6", lw=0.8, ls="--")
    ax.set_xscale("symlog", linthresh=0.1)
    ax.set_xlim(0.0, max(1.0, 4.0 * largest))  # room for the labels on the right
    ax.set_xlabel("violation rate: path length cut over tolerance, % of the cut length")
    ax.set_ylabel("mean time ratio (cycle ÷ time-optimal bound), finished episodes")
    ax.set_title(title or "policies: time against contour violations")
    ax.grid(alpha=0.3)
    paths.append(_save(fig, folder / f"pareto{suffix}.png"))
    plt.close(fig)

    # Per-family bars of the primary score.
    families = sorted({r["family"] for r in rows if r["family"] != "all"})
    policies = [r["policy"] for r in suite]
    fig, ax = plt.subplots(figsize=(max(7, 1.2 * len(families) + 3), 4.5), constrained_layout=True)
    width = 0.8 / max(len(policies), 1)
    lookup = {(r["family"], r["policy"]): r["score"] for r in rows}
    for k, policy in enumerate(policies):
        xs = [i + (k - (len(policies) - 1) / 2) * width for i in range(len(families))]
        ax.bar(xs, [lookup.get((f, policy), 0.0) for f in families], width=width, label=policy)
    ax.set_xticks(range(len(families)), families)
    ax.set_ylabel("score (0–100)")
    ax.set_title((title + ": " if title else "") + "score per family")
    ax.legend(fontsize=8, ncols=min(len(policies), 4), loc="upper center", bbox_to_anchor=(0.5, -0.08))
    ax.grid(axis="y", alpha=0.3)
    paths.append(_save(fig, folder / f"families{suffix}.png"))
    plt.close(fig)
    return paths


def _save(fig: Any, path: Path) -> Path:
    try:
        fig.savefig(path, dpi=110)
    except OSError as exc:
        raise CncGymError(f"{path}: cannot write plot: {exc.strerror or exc}") from None
    return path
