"""``cnc-gym bench`` under Ctrl-C: a real SIGINT to a running ``--workers 2`` bench, judged by the work it
kept and left undone (never by the clock): every finished record is in the file, valid JSON Lines, the
pending work is cancelled, no worker process is left, and the exit status is 130."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]

pytestmark = pytest.mark.skipif(sys.platform != "linux", reason="reads /proc for the worker processes")


def _load_script():
    """scripts/bench_interrupt.py, whose /proc helpers the test shares (the script measures, the test
    judges)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("bench_interrupt", REPO / "scripts" / "bench_interrupt.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


_SCRIPT = _load_script()
_children, _running = _SCRIPT._children, _SCRIPT._running


def _default_sigint() -> None:
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _records(path: Path) -> list[dict]:
    try:
        text = path.read_text()
    except FileNotFoundError:
        return []
    assert text == "" or text.endswith("\n"), "a partly written record"
    return [json.loads(line) for line in text.splitlines()]  # valid JSON Lines at every moment


@pytest.mark.parametrize("to", ["the command", "its process group"])
def test_ctrl_c_keeps_every_finished_record_cancels_the_rest_and_leaves_no_worker(tmp_path, to):
    out = tmp_path / "records.jsonl"
    # 7 programs (one per family) × 3 policies = 21 tasks of 3 seeds each, 63 records: far more work than
    # can finish between the first record and the signal even on a starved machine; the bounds are cached
    # in a fresh folder.
    command = [sys.executable, "-m", "cnc_gym.cli", "bench", "--per-family", "1", "--workers", "2",
               "--seeds", "0,1,2", "--policy", "constant:1.0", "--policy", "classical", "--policy", "oracle",
               "--json", str(out), "--no-progress"]  # fmt: skip
    env = {**os.environ, "CNC_GYM_CACHE_DIR": str(tmp_path / "cache")}
    # The command gets Ctrl-C's default disposition whatever the suite's own is: a suite started in the
    # background of a non-interactive shell (`make test &`) runs with SIGINT ignored, and a child inherits
    # an ignored signal, as Unix has every command started that way do.
    process = subprocess.Popen(command, cwd=REPO, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               text=True, start_new_session=True, preexec_fn=_default_sigint)  # fmt: skip
    try:
        seen: list[dict] = []
        while not seen and process.poll() is None:  # streamed: a record appears long before the end
            time.sleep(0.05)
            seen = _records(out)
        assert process.poll() is None, process.communicate()
        workers = _children(process.pid)
        assert len(workers) >= 2
        if to == "the command":  # the workers ignore SIGINT: the command must end them itself
            os.kill(process.pid, signal.SIGINT)
        else:  # what a terminal's Ctrl-C does
            os.killpg(process.pid, signal.SIGINT)
        stdout, stderr = process.communicate(timeout=600)
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait()
    kept = _records(out)
    assert process.returncode == 130, stderr
    assert stdout == "" and "Traceback" not in stderr, stderr
    # (a cold numba cache adds the "compiling the simulator" line before the work: not the interrupt's)
    lines = [line for line in stderr.strip().splitlines() if not line.startswith("cnc-gym: compiling")]
    assert lines[-1].endswith(f"kept {len(kept)} finished episode record(s) in {out}")
    assert len(lines) == 1, stderr
    # Every record seen before the interrupt is kept, whole; the pending work was cancelled, not finished.
    assert [r for r in kept if r in seen] == seen
    assert len(seen) <= len(kept) < 63
    assert all(r["finished"] in (True, False) and "score" in r for r in kept)
    deadline = time.monotonic() + 30  # (a bound on the test, not a measurement)
    while any(_running(pid) for pid in workers) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not [pid for pid in workers if _running(pid)], "a worker process outlived the command"
