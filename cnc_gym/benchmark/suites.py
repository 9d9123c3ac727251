"""Benchmark suites: named, versioned sets of G-code programs with fixed train / val / test splits.

A suite ships as package data, ``cnc_gym/benchmark/suites/<name>/``: one plain GSK 25i program per file
(``<split>/<program>.nc``) and ``manifest.json`` (per program: split, family, tier, the path properties
the tier is measured from, the generator's attempt number and the text's SHA-256; and the SHA-256 of the
whole suite). The texts are written by a seeded generator (:mod:`cnc_gym.benchmark.families`), once:

    python -m cnc_gym.benchmark.suites build cnc-bench-v1      # write the files and the manifest
    python -m cnc_gym.benchmark.suites check cnc-bench-v1      # regenerate in memory, compare hashes

A program's random stream is seeded from (suite seed, split, family, index, attempt), so any program can
be regenerated alone. The build keeps a program only if it is *feasible*: some constant override
(20 % or 5 %, without the env's step budget) finishes it on the suite's machine with no contour
error above tolerance, so every violation can be avoided by slowing down; otherwise it draws the next
attempt. The shipped texts are the suite: tests check them against the manifest's hashes
and against the generator, bit for bit.

Use as a program source (evaluation, or training on the train split)::

    from cnc_gym.benchmark import load_suite
    suite = load_suite()                        # the default suite
    paths = suite.paths("train")                # files for FeedrateEnv(programs=...)
    few = suite.draw("train", 16, seed=0)       # a reproducible sample of entries
"""

from __future__ import annotations

import argparse
import hashlib
import json
import math
import sys
import zlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from cnc_gym.benchmark.families import FAMILIES, TIERS, builtin_text, program_text
from cnc_gym.errors import ConfigError

SUITES_DIR = Path(__file__).resolve().parent / "suites"
SPLITS = ("train", "val", "test")
DEFAULT_SUITE = "cnc-bench-v1"
MAX_ATTEMPTS = 40
#: Constant overrides tried, in order, to show that a program is feasible: slowing down enough removes
#: every violation (no error the feed cannot avoid). The env's step budget is lifted for this check only.
FEASIBILITY_OVERRIDES = (0.2, 0.05)


@dataclass(frozen=True)
class SuiteSpec:
    """How a suite is generated: programs per split and family, seed, machine and dialect."""

    name: str
    version: int
    seed: int
    machine: str
    dialect: str
    composition: dict[str, dict[str, int]]  # split → family → number of programs
    builtins: dict[str, tuple[str, ...]] = field(default_factory=dict)  # split → built-in programs
    description: str = ""


#: The families of cnc-bench-v1 (frozen: a family added later goes into a suite of its own).
V1_FAMILIES = ("contour", "pocket", "freeform", "arcs", "holes", "raster", "engraving")

SPECS: dict[str, SuiteSpec] = {
    "cnc-bench-v1": SuiteSpec(
        name="cnc-bench-v1",
        version=1,
        seed=20260601,
        machine="vmc-small",
        dialect="gsk25i",
        composition={
            # `engraving` is held out of train; the test split's freeform programs also include chords of
            # 0.02-0.05 mm, below the train split's range.
            "train": {"contour": 40, "pocket": 40, "freeform": 40, "arcs": 40, "holes": 36, "raster": 40},
            "val": {family: 10 for family in V1_FAMILIES},
            "test": {family: 10 for family in V1_FAMILIES},
        },
        builtins={"train": ("circle", "star", "freeform", "pocket")},
        description="Seven families of 2-D and 3-D milling programs plus the four built-ins, on vmc-small.",
    ),
    "kirl-planar-v1": SuiteSpec(
        name="kirl-planar-v1",
        version=1,
        seed=20261124,
        machine="kirl-planar",
        dialect="gsk25i",
        composition={"train": {"kirl": 16}, "val": {"kirl": 4}, "test": {"kirl": 4}},
        description="KIRL-style closed outlines of about 250 one-millimetre chords on KIRL's limits "
                    "(kirl-planar: 10 mm/s, 100 mm/s², 10 000 mm/s³ as norms, 0.5 mm deviation).",
    ),
}


@dataclass(frozen=True)
class ProgramEntry:
    """One program of a suite."""

    name: str
    split: str
    family: str
    tier: str
    path: Path
    sha256: str
    attempt: int
    description: str
    properties: dict[str, float]

    def text(self) -> str:
        return self.path.read_text()


@dataclass(frozen=True)
class Suite:
    """A loaded suite: its entries, in manifest order, and the suite hash."""

    name: str
    version: int
    machine: str
    dialect: str
    sha256: str
    entries: tuple[ProgramEntry, ...]

    def programs(self, split: str | None = None, family: str | None = None) -> list[ProgramEntry]:
        """Entries of one split (all splits with None), optionally of one family."""
        if split is not None and split not in SPLITS:
            raise ConfigError(f"unknown split {split!r}; splits: {', '.join(SPLITS)}")
        return [e for e in self.entries if (split is None or e.split == split)
                and (family is None or e.family == family)]  # fmt: skip

    def paths(self, split: str) -> list[Path]:
        """Program files of a split (what ``FeedrateEnv(programs=...)`` takes)."""
        return [e.path for e in self.programs(split)]

    def draw(self, split: str, n: int, seed: int = 0) -> list[ProgramEntry]:
        """``n`` entries of ``split`` drawn without replacement (all of them, shuffled, if n ≥ size)."""
        entries = self.programs(split)
        order = np.random.default_rng(seed).permutation(len(entries))[: max(0, int(n))]
        return [entries[i] for i in order]

    def entry(self, name: str) -> ProgramEntry:
        for e in self.entries:
            if e.name == name:
                return e
        raise ConfigError(f"suite {self.name}: no program named {name!r}")


def suite_names() -> list[str]:
    return sorted(SPECS)


def load_suite(name: str = DEFAULT_SUITE, verify: bool = True) -> Suite:
    """Load a shipped suite by name; with ``verify`` every file is checked against its manifest hash."""
    if name not in SPECS:
        raise ConfigError(f"unknown suite {name!r}; suites: {', '.join(suite_names())}")
    folder = SUITES_DIR / name
    manifest_path = folder / "manifest.json"
    try:
        manifest = json.loads(manifest_path.read_text())
    except (OSError, ValueError) as exc:
        raise ConfigError(f"{manifest_path}: cannot read the suite manifest ({exc})") from None
    entries = []
    for item in manifest["programs"]:
        path = folder / item["file"]
        entry = ProgramEntry(name=item["name"], split=item["split"], family=item["family"],
                             tier=item["tier"], path=path, sha256=item["sha256"],
                             attempt=int(item["attempt"]), description=item["description"],
                             properties=dict(item["properties"]))  # fmt: skip
        if verify and _sha256(path.read_bytes()) != entry.sha256:
            raise ConfigError(f"{path}: does not match the suite manifest (modified or corrupted)")
        entries.append(entry)
    return Suite(name=manifest["suite"], version=int(manifest["version"]), machine=manifest["machine"],
                 dialect=manifest["dialect"], sha256=manifest["sha256"], entries=tuple(entries))  # fmt: skip


def _sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def suite_digest(programs: list[dict[str, Any]]) -> str:
    """The suite hash: SHA-256 over ``name:split:family:sha256`` of every program, in order."""
    text = "\n".join(f"{p['name']}:{p['split']}:{p['family']}:{p['sha256']}" for p in programs)
    return _sha256(text.encode())


# ---------------------------------------------------------------------------------------- generation
def _stable_id(text: str) -> int:
    return zlib.crc32(text.encode())


def program_rng(spec: SuiteSpec, split: str, family: str, index: int, attempt: int) -> np.random.Generator:
    """The random stream of one program (independent of every other program)."""
    seq = np.random.SeedSequence([spec.seed, _stable_id(split), _stable_id(family), index, attempt])
    return np.random.default_rng(seq)


def program_name(family: str, split: str, index: int) -> str:
    return f"{family}-{split}-{index:03d}"


def generate_text(spec: SuiteSpec, split: str, family: str, index: int, attempt: int) -> tuple[str, str]:
    """``(description, text)`` of one generated program."""
    rng = program_rng(spec, split, family, index, attempt)
    tier = TIERS[index % len(TIERS)]  # requested tier; the filed tier is measured
    description, body = FAMILIES[family](rng, tier, split)
    name = program_name(family, split, index)
    return description, program_text(name, family, description, body)


def path_properties(toolpath, machine) -> dict[str, float]:
    """Measurable properties of a program's cutting moves (what its tier is computed from).

    ``max_turn_deg``: largest change of direction between consecutive cutting moves (vertical plunges
    and lifts left out); ``median_segment_mm``:
    median cutting-move length; ``max_curvature_1_mm``: largest curvature of an arc, or of a polyline
    chain (turn ÷ mean neighbouring length, at junctions turning less than 30°); ``max_feed_mm_min``;
    ``cut_length_mm``; ``segments`` (cutting moves); ``nominal_time_s`` (at 100 %, infinite acceleration).
    """
    from cnc_gym.envs.feedrate import nominal_time_s
    from cnc_gym.toolpath import SegmentKind

    kind = toolpath.kind
    cut = (kind == SegmentKind.LINE) | (kind == SegmentKind.ARC) | (kind == SegmentKind.NURBS)
    rows = np.flatnonzero(cut & (toolpath.length > 1e-6))
    lengths = toolpath.length[rows]
    props = {"segments": float(len(rows)), "cut_length_mm": float(np.sum(lengths)),
             "nominal_time_s": float(nominal_time_s(toolpath, machine))}  # fmt: skip
    if len(rows) == 0:
        return {**props, "max_turn_deg": 0.0, "median_segment_mm": 0.0, "max_curvature_1_mm": 0.0,
                "max_feed_mm_min": 0.0}  # fmt: skip
    s_end = toolpath.s_start[rows] + lengths
    _, t_end, _ = toolpath.evaluate(s_end - np.minimum(1e-6, lengths / 2))
    _, t_start, k_mid = toolpath.evaluate(toolpath.s_start[rows] + np.minimum(1e-6, lengths / 2))
    # Junctions between consecutive cutting moves; a vertical plunge or lift (Z only) is an entry, not
    # part of the contour, so its corner does not count.
    vertical = np.abs(t_start[:, 2]) > 0.999
    consecutive = (rows[1:] == rows[:-1] + 1) & ~vertical[:-1] & ~vertical[1:]
    cos_turn = np.clip(np.sum(t_end[:-1] * t_start[1:], axis=1), -1.0, 1.0)
    turn = np.where(consecutive, np.arccos(cos_turn), 0.0)
    arc_kappa = np.where(kind[rows] != SegmentKind.LINE, k_mid, 0.0)
    mean_len = (lengths[:-1] + lengths[1:]) / 2
    chain_kappa = np.where(consecutive & (turn < math.radians(30.0)), turn / np.maximum(mean_len, 1e-9), 0.0)
    props.update(
        max_turn_deg=float(np.degrees(np.max(turn, initial=0.0))),
        median_segment_mm=float(np.median(lengths)),
        max_curvature_1_mm=float(max(np.max(arc_kappa, initial=0.0), np.max(chain_kappa, initial=0.0))),
        max_feed_mm_min=float(np.nanmax(toolpath.feed[rows])),
    )
    return {k: round(v, 6) for k, v in props.items()}


#: Tier rule: points per property (0, 1 or 2) at these thresholds; total ≤ 2 easy, ≤ 4 medium, else hard.
TIER_THRESHOLDS = {
    "max_turn_deg": (45.0, 120.0),  # sharper corners score higher
    "median_segment_mm": (2.0, 0.3),  # shorter segments score higher (thresholds descending)
    "max_curvature_1_mm": (0.1, 1.0),  # radius 10 mm, 1 mm
    "max_feed_mm_min": (2000.0, 3500.0),
}


def tier_of(properties: dict[str, float]) -> str:
    """easy / medium / hard from measured path properties (the rule: :data:`TIER_THRESHOLDS`)."""
    points = 0
    for key, (first, second) in TIER_THRESHOLDS.items():
        value = properties[key]
        if first > second:  # descending: smaller is harder
            points += (value < first) + (value < second)
        else:
            points += (value >= first) + (value >= second)
    return "easy" if points <= 2 else "medium" if points <= 4 else "hard"


def is_feasible(text: str, machine, dialect: str) -> bool:
    """True when some override of :data:`FEASIBILITY_OVERRIDES` finishes the program with no contour
    error above tolerance (zero violation length), with no step budget to speak of."""
    from cnc_gym.envs.feedrate import FeedrateEnv
    from cnc_gym.policies import ConstantOverride
    from cnc_gym.rollout import run_episode

    env = FeedrateEnv(programs=[text], dialect=dialect, machine=machine, max_episode_steps=10_000_000)
    for override in FEASIBILITY_OVERRIDES:
        episode = run_episode(env, ConstantOverride(override), 0)
        if episode.finished and episode.info["violation_length_mm"] == 0.0:
            return True
    return False


def _entries(spec: SuiteSpec) -> list[tuple[str, str, int]]:
    """(split, family, index) of every generated program, in manifest order."""
    out = []
    for split in SPLITS:
        for family, count in spec.composition.get(split, {}).items():
            out += [(split, family, i) for i in range(count)]
    return out


def build_suite(name: str = DEFAULT_SUITE, out_dir: Path | None = None, progress: bool = True) -> dict:
    """Generate every program (feasible attempts only), write the files and ``manifest.json``."""
    from tqdm import tqdm

    from cnc_gym.gcode import interpret
    from cnc_gym.machine import load_machine

    spec = SPECS[name]
    machine = load_machine(spec.machine)
    folder = Path(out_dir or SUITES_DIR / name)
    programs: list[dict[str, Any]] = []
    jobs = _entries(spec)
    bar = tqdm(total=len(jobs) + sum(len(b) for b in spec.builtins.values()), desc=f"build {name}",
               disable=not progress, file=sys.stderr)  # fmt: skip
    for split, builtins in spec.builtins.items():
        for builtin in builtins:
            text = builtin_text(builtin)
            toolpath = interpret(text, dialect=spec.dialect, machine=machine)
            programs.append(_record(f"builtin-{builtin}", split, "builtin", 0,
                                    f"the built-in program {builtin}", text, toolpath, machine))
            bar.update()
    for split, family, index in jobs:
        for attempt in range(MAX_ATTEMPTS):
            description, text = generate_text(spec, split, family, index, attempt)
            if is_feasible(text, machine, spec.dialect):
                break
        else:
            raise RuntimeError(f"{program_name(family, split, index)}: no feasible attempt in {MAX_ATTEMPTS}")
        toolpath = interpret(text, dialect=spec.dialect, machine=machine)
        programs.append(_record(program_name(family, split, index), split, family, attempt, description, text,
                                toolpath, machine))  # fmt: skip
        bar.update()
    bar.close()
    order = {s: i for i, s in enumerate(SPLITS)}
    programs.sort(key=lambda p: (order[p["split"]], p["name"]))
    manifest = {"suite": spec.name, "version": spec.version, "seed": spec.seed, "machine": spec.machine,
                "dialect": spec.dialect, "description": spec.description,
                "tier_rule": {k: list(v) for k, v in TIER_THRESHOLDS.items()},
                "sha256": suite_digest(programs), "programs": programs}  # fmt: skip
    for split in SPLITS:
        (folder / split).mkdir(parents=True, exist_ok=True)
        for old in (folder / split).glob("*.nc"):
            old.unlink()
    for p in programs:
        (folder / p["file"]).write_text(p.pop("_text"))
    (folder / "manifest.json").write_text(json.dumps(manifest, indent=1) + "\n")
    return manifest


def _record(name, split, family, attempt, description, text, toolpath, machine) -> dict[str, Any]:
    props = path_properties(toolpath, machine)
    return {"name": name, "split": split, "family": family, "tier": tier_of(props), "attempt": attempt,
            "file": f"{split}/{name}.nc", "sha256": _sha256(text.encode()), "description": description,
            "properties": props, "_text": text}  # fmt: skip


def check_suite(name: str = DEFAULT_SUITE) -> list[str]:
    """Regenerate every program from the manifest's attempts; names of those whose text differs."""
    spec = SPECS[name]
    suite = load_suite(name)
    stale = []
    for e in suite.entries:
        if e.family == "builtin":
            text = builtin_text(e.name.removeprefix("builtin-"))
        else:
            index = int(e.name.rsplit("-", 1)[1])
            _, text = generate_text(spec, e.split, e.family, index, e.attempt)
        if _sha256(text.encode()) != e.sha256:
            stale.append(e.name)
    return stale


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m cnc_gym.benchmark.suites",
                                     description="build or check a benchmark suite")  # fmt: skip
    parser.add_argument("action", choices=("build", "check", "list"))
    parser.add_argument("suite", nargs="?", default=DEFAULT_SUITE, choices=suite_names())
    args = parser.parse_args(argv)
    if args.action == "build":
        manifest = build_suite(args.suite)
        print(f"{args.suite}: {len(manifest['programs'])} programs, sha256 {manifest['sha256']}")
        return 0
    if args.action == "list":
        for e in load_suite(args.suite).entries:
            print(f"{e.name:24s} {e.split:5s} {e.family:9s} {e.tier:6s} {e.description}")
        return 0
    stale = check_suite(args.suite)
    if stale:
        print(f"differ from the generator: {', '.join(stale)}", file=sys.stderr)
        return 1
    print(f"{args.suite}: every program matches the generator and the manifest")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
