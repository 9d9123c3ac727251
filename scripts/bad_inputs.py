"""Run every bad-input reproducer in a fresh process: one clean line each, and at what cost.

    .venv/bin/python scripts/bad_inputs.py [--only WORD] [--markdown]

Each case is a crafted config, model file or env call given to a real entry point (``cnc-gym run``,
``scripts/train.py``, or the env from Python) in its own process. The table shows whether it ended the
way the project promises (one line on stderr, no traceback; a crafted model's payload never runs), the
lines it printed on stderr, the wall time and the process's peak memory (max RSS, from ``wait4``), and
the line itself. The exit status is 1 if any case broke the promise. docs/security.md quotes a run.
"""

from __future__ import annotations

import argparse
import base64
import json
import os
import pickle
import subprocess
import sys
import tempfile
import time
import zipfile
from dataclasses import dataclass
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
PY = sys.executable


@dataclass
class Case:
    name: str
    argv: list[str]
    #: "error": must end with exit status != 0 and one stderr line; "ok": must succeed quietly.
    expect: str = "error"
    marker: Path | None = None


class _Touch:
    """Unpickling this creates a marker file (the payload of the crafted models; it pickles as a call of
    ``open``, so loading it needs nothing from this script)."""

    def __init__(self, marker: str) -> None:
        self.marker = marker

    def __reduce__(self):
        return (open, (self.marker, "w"))


def _env_call(code: str) -> list[str]:
    """A Python snippet with ``env`` = FeedrateEnv(programs=["circle"]) available; a CncGymError prints one
    line and exits 2, as the command line does."""
    prelude = ("import sys, numpy as np\nfrom cnc_gym.errors import CncGymError\n"
               "from cnc_gym.envs.feedrate import FeedrateEnv\ntry:\n")  # fmt: skip
    body = "".join(f"    {line}\n" for line in code.splitlines())
    tail = "except CncGymError as exc:\n    print(exc, file=sys.stderr)\n    sys.exit(2)\n"
    return [PY, "-c", prelude + body + tail]


def _model(folder: Path, pth_marker: Path) -> tuple[Path, Path]:
    """An untrained PPO model of Feedrate-v0 saved by SB3 (what scripts/train.py writes), and a torch file
    whose unpickling creates ``pth_marker``. Made in a child process, so that this one stays small (a
    child's peak memory counts its parent's before the child's exec)."""
    path, pth = folder / "model.zip", folder / "payload.pth"
    code = f"""
import torch
from stable_baselines3 import PPO
from cnc_gym.envs.feedrate import FeedrateEnv
class Touch:
    def __reduce__(self):
        return (open, ({str(pth_marker)!r}, "w"))
PPO("MlpPolicy", FeedrateEnv(programs=["circle"]), n_steps=64, batch_size=32, device="cpu",
    policy_kwargs={{"net_arch": [16, 16]}}).save({str(path)!r})
torch.save({{"log_std": Touch()}}, {str(pth)!r})
"""
    subprocess.run([PY, "-c", code], check=True, cwd=REPO)
    return path, pth


def _crafted(model: Path, target: Path, marker: Path, key: str = "",
             member: tuple[str, Path] | None = None) -> Path:  # fmt: skip
    """A copy of ``model`` with a payload in the ``data`` entry ``key``, or ``member = (name, file)``."""
    with zipfile.ZipFile(model) as zin, zipfile.ZipFile(target, "w", zipfile.ZIP_DEFLATED) as zout:
        for name in zin.namelist():
            content = zin.read(name)
            if name == "data" and key:
                data = json.loads(content)
                entry = data.get(key) if isinstance(data.get(key), dict) else {":type:": "<class 'dict'>"}
                entry[":serialized:"] = base64.b64encode(pickle.dumps(_Touch(str(marker)))).decode()
                data[key] = entry
                content = json.dumps(data).encode()
            if member is not None and name == member[0]:
                content = member[1].read_bytes()
            zout.writestr(name, content)
    return target


_BOMB = "\n".join(["a0: &a0 [x, x, x, x, x, x, x, x, x]"]
                  + [f"a{i}: &a{i} [{', '.join([f'*a{i - 1}'] * 9)}]" for i in range(1, 9)]
                  + ["description: *a8", ""])  # fmt: skip
#: (case, machine preset text) given to ``cnc-gym run circle --machine FILE``.
MACHINES: list[tuple[str, str | bytes]] = [
    ("post_filter_s 1e6", "controller: {post_filter_s: 1.0e6}\n"),
    ("lookahead_blocks 2^31", "controller: {lookahead_blocks: 2147483648}\n"),
    ("lookahead_blocks 1e29", "controller: {lookahead_blocks: 1e29}\n"),
    ("velocity_loop_damping 1e300", "axis_defaults: {velocity_loop_damping: 1e300}\n"),
    ("rapid_mm_min 1e-300", "axis_defaults: {rapid_mm_min: 1e-300}\n"),
    ("interpolation_period_s 1e-7", "controller: {interpolation_period_s: 1e-7}\n"),
    ("max_jerk_mm_s3 1e300", "axis_defaults: {max_jerk_mm_s3: 1e300}\n"),
    ("axes: {x: 5}", "axes: {x: 5}\n"),
    ("not UTF-8", b"name: caf\xe9\n"),
    ("5000 nested [", "a: " + "[" * 5000 + "]" * 5000 + "\n"),
    ("alias bomb in description", _BOMB),
]
#: (case, machine preset text) of valid machines at the edges of the ranges, run through ``cnc-gym run``.
EDGES = [
    ("finest: 0.1 ms period, 0.5 s filter, 5000 blocks",
     "controller: {interpolation_period_s: 1.0e-4, post_filter_s: 0.5, lookahead_blocks: 5000}\n"),
    ("slowest: 100 mm/min feeds and rapids",
     "controller: {max_feed_mm_min: 100}\naxis_defaults: {rapid_mm_min: 100, max_feed_mm_min: 100}\n"),
]
#: (case, training config text or None for the shipped one, extra arguments) for ``scripts/train.py``.
TRAINING: list[tuple[str, str | None, list[str]]] = [
    ("learning_rate NaN", "ppo: {learning_rate: .nan}\n", []),
    ("clip_range NaN", "ppo: {clip_range: .nan}\n", []),
    ("seed -1", "seed: -1\n", []),
    ("batch_size 1", "ppo: {batch_size: 1}\n", []),
    ("n_envs 1e8", "n_envs: 100000000\n", []),
    ("net_arch [1e8]", "ppo: {net_arch: [100000000]}\n", []),
    ("torch_threads 1e8", "torch_threads: 100000000\n", []),
    ("run_name absolute", "run_name: /tmp/x\n", []),
    ("run_name ../x", "run_name: ../x\n", []),
    ("output_dir unwritable", "output_dir: {folder}/file/runs\n", []),
    ("--timesteps 0", None, ["--timesteps", "0"]),
    ("--timesteps -1", None, ["--timesteps", "-1"]),
]
#: (case, Python with ``FeedrateEnv`` and ``np`` imported, "error" or "ok").
ENV = [
    ("control_period_s 1e6", "FeedrateEnv(programs=['circle'], control_period_s=1e6)", "error"),
    ("control_period_s 1e308", "FeedrateEnv(programs=['circle'], control_period_s=1e308)", "error"),
    ("programs=5", "FeedrateEnv(programs=5)", "error"),
    ("machine=None", "FeedrateEnv(programs=['circle'], machine=None)", "error"),
    ("lookahead_points=np.int64(8)", "FeedrateEnv(programs=['circle'], lookahead_points=np.int64(8))", "ok"),
    ("step before reset", "FeedrateEnv(programs=['circle']).step(np.zeros(1))", "error"),
    ("step(10**400) clips", "e = FeedrateEnv(programs=['circle'])\ne.reset()\ne.step(10**400)", "ok"),
    ("action '0.5'", "e = FeedrateEnv(programs=['circle'])\ne.reset()\ne.step('0.5')", "error"),
    ("action complex", "e = FeedrateEnv(programs=['circle'])\ne.reset()\ne.step(np.array([0.5j]))", "error"),
    ("action datetime64", "e = FeedrateEnv(programs=['circle'])\ne.reset()\ne.step(np.datetime64(0, 's'))",
     "error"),
]


def cases(folder: Path) -> list[Case]:
    run = [PY, "-m", "cnc_gym.cli", "run", "circle", "--no-progress"]
    (folder / "file").write_text("")
    out: list[Case] = [Case("reference: a good run (constant:1.0)", [*run, "--json"], "ok")]
    for i, (name, content) in enumerate(MACHINES):
        path = folder / f"machine{i}.yaml"
        path.write_bytes(content if isinstance(content, bytes) else content.encode())
        out.append(Case(f"machine {name}", [*run, "--machine", str(path)]))
    # Valid machines at the edges of the ranges: they must run, within bounded time and memory.
    for name, content in EDGES:
        path = folder / f"edge-{len(out)}.yaml"
        path.write_text(content)
        out.append(Case(f"edge: {name}", [*run, "--machine", str(path), "--json"], "ok"))
    for i, (name, train_text, extra) in enumerate(TRAINING):
        config = "configs/train/ppo.yaml"
        if train_text is not None:
            config = str(folder / f"train{i}.yaml")
            Path(config).write_text(train_text.replace("{folder}", str(folder)))
        argv = [PY, "scripts/train.py", "--no-progress", "--config", config, *extra]
        out.append(Case(f"train {name}", argv))
    out += [Case(f"env {name}", _env_call(code), expect) for name, code, expect in ENV]
    pth_marker = folder / "ran-pth"
    model, pth = _model(folder, pth_marker)
    out.append(Case("reference: a good run (clean model)", [*run, "--policy", str(model), "--json"], "ok"))
    for key in ("policy_class", "lr_schedule", "observation_space", "an_extra_key"):
        marker = folder / f"ran-{key}"
        crafted = _crafted(model, folder / f"{key}.zip", marker, key=key)
        out.append(Case(f"model payload in {key}", [*run, "--policy", str(crafted), "--json"], "ok", marker))
    crafted = _crafted(model, folder / "pth.zip", pth_marker, member=("policy.pth", pth))
    out.append(Case("model payload in policy.pth", [*run, "--policy", str(crafted)], "error", pth_marker))
    return out


def measure(case: Case) -> dict:
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        started = time.perf_counter()
        proc = subprocess.Popen(case.argv, cwd=REPO, stdout=out, stderr=err)
        _, status, usage = os.wait4(proc.pid, 0)
        wall = time.perf_counter() - started
        proc.returncode = os.waitstatus_to_exitcode(status)
        err.seek(0)
        lines = err.read().decode("utf-8", "replace").strip().splitlines()
    warnings = [line for line in lines if "Warning" in line]
    lines = [line for line in lines if line not in warnings]
    ran = case.marker is not None and case.marker.exists()
    if case.expect == "error":
        kept = proc.returncode != 0 and len(lines) == 1 and "Traceback" not in lines[0] and not ran
    else:
        kept = proc.returncode == 0 and not lines and not ran
    return {"case": case.name, "kept": kept, "status": proc.returncode, "lines": len(lines), "wall_s": wall,
            "max_rss_mb": usage.ru_maxrss / 1024, "message": lines[0] if lines else "",
            "payload_ran": ran}  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", default="", help="run the cases whose name contains this text")
    parser.add_argument("--markdown", action="store_true", help="print a Markdown table")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        rows = []
        for case in cases(folder):
            if args.only in case.name:
                row = measure(case)
                rows.append(row)
                message = row["message"].replace(tmp, "TMP")
                if args.markdown:
                    print(f"| {row['case']} | {'yes' if row['kept'] else '**NO**'} | {row['lines']} | "
                          f"{row['wall_s']:.1f} | {row['max_rss_mb']:.0f} | {message[:110]} |")  # fmt: skip
                else:
                    print(f"{'ok ' if row['kept'] else 'BAD'} {row['case']:<38} {row['lines']} line  "
                          f"{row['wall_s']:5.1f} s {row['max_rss_mb']:6.0f} MB  {message[:100]}")  # fmt: skip
    worst = max(rows, key=lambda r: r["max_rss_mb"]) if rows else None
    if worst:
        slowest = max(rows, key=lambda r: r["wall_s"])
        print(f"\n{sum(r['kept'] for r in rows)}/{len(rows)} kept the promise; most memory: "
              f"{worst['case']} ({worst['max_rss_mb']:.0f} MB); slowest: {slowest['case']} "
              f"({slowest['wall_s']:.1f} s)")  # fmt: skip
    return 0 if all(r["kept"] for r in rows) else 1


if __name__ == "__main__":
    raise SystemExit(main())
