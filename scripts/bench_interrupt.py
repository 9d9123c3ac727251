"""Ctrl-C on a running ``cnc-gym bench --workers 2 --json OUT``: how long until the command exits, how many
finished records the file keeps, and whether a worker process is left.

    .venv/bin/python scripts/bench_interrupt.py [--after-records 3] [--group] [--repeats 3]
    .venv/bin/python scripts/bench_interrupt.py --after-seconds 45      # a checkout that writes at the end

The bench runs the default suite's test split with ``constant:1.0``, ``classical`` and ``oracle`` on two
workers, in a fresh process from the current folder (run it from another checkout's root, with this
checkout's venv, to measure that checkout: ``cd /tmp/base && python /path/to/scripts/bench_interrupt.py``).
Once ``--after-records`` records are in the file (or ``--after-seconds`` have passed, for a version that
writes nothing before the end), SIGINT goes to the command (``--group``: to its whole process group, as a
terminal's Ctrl-C does). Reported per run: the seconds from the signal to the command's exit, its exit
status, the records in the file at the signal and after the exit (all of them valid JSON), and the worker
processes still running afterwards. A measurement, not a test: the wall-clock times depend on the load.
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def _children(pid: int) -> list[int]:
    out = []
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                stat = Path(f"/proc/{entry}/stat").read_text()
            except OSError:
                continue
            if int(stat.rsplit(")", 1)[1].split()[1]) == pid:
                out.append(int(entry))
    return out


def _running(pid: int) -> bool:
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] not in ("Z", "X")
    except OSError:
        return False


def _records(path: Path) -> list[dict]:
    try:
        return [json.loads(line) for line in path.read_text().splitlines()]
    except FileNotFoundError:
        return []


def measure(out: Path, after_records: int, after_seconds: float | None, group: bool) -> dict:
    command = [sys.executable, "-m", "cnc_gym.cli", "bench", "--workers", "2", "--json", str(out),
               "--no-progress", "--policy", "constant:1.0", "--policy", "classical", "--policy", "oracle"]
    process = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                               start_new_session=True)  # fmt: skip
    started = time.monotonic()
    if after_seconds is not None:
        time.sleep(after_seconds)
    else:
        while len(_records(out)) < after_records and process.poll() is None:
            time.sleep(0.05)
    workers = _children(process.pid)
    at_signal = len(_records(out))
    sent = time.monotonic()
    if group:
        os.killpg(process.pid, signal.SIGINT)
    else:
        os.kill(process.pid, signal.SIGINT)
    try:
        _, stderr = process.communicate(timeout=900)
    except subprocess.TimeoutExpired:
        os.killpg(process.pid, signal.SIGKILL)
        _, stderr = process.communicate()
    exited = time.monotonic()
    time.sleep(0.5)
    return {"signal_after_s": round(sent - started, 1), "exit_after_s": round(exited - sent, 2),
            "status": process.returncode, "records_at_signal": at_signal, "records_kept": len(_records(out)),
            "workers_left": [pid for pid in workers if _running(pid)],
            "stderr_last_line": (stderr.strip().splitlines() or [""])[-1]}  # fmt: skip


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--after-records", type=int, default=3)
    parser.add_argument("--after-seconds", type=float, default=None)
    parser.add_argument("--group", action="store_true", help="SIGINT to the process group (a terminal's)")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        for k in range(args.repeats):
            out = Path(folder) / f"run{k}.jsonl"
            print(json.dumps(measure(out, args.after_records, args.after_seconds, args.group)), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
