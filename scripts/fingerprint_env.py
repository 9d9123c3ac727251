#!/usr/bin/env python3
"""Fingerprints of whole episodes of the registered Feedrate envs: did a change leave them as they were?

Each case runs one env through ``gymnasium.make`` with seeded random actions for ``--steps`` steps,
resetting at episode ends, and hashes everything the env returns, bit for bit: the observations' bytes,
the rewards (``float.hex``), the terminated and truncated flags, and every info dict's ``repr`` (keys in
order, values with their types). The cases cover v0 to v6 on the built-ins, the benchmark's helix and
NURBS programs, other presets, every action mode, another control period and look-ahead size, domain
randomisation, short step budgets (truncations) and a program without motion.

Usage (run it before and after a change and compare the lines)::

    .venv/bin/python scripts/fingerprint_env.py
    .venv/bin/python scripts/fingerprint_env.py --steps 500 --cases v1-flat v2-flat
"""

from __future__ import annotations

import argparse
import hashlib
import sys
from typing import Any

import gymnasium as gym
import numpy as np

import cnc_gym  # noqa: F401  (registers the ids)

sys.path.insert(0, __file__.rsplit("/", 1)[0])
from bench_env import helix_program, nurbs_program

NO_MOTION = "G90 G21 G17\nM03 S1000\nM30\n"
RANDOMIZE = {"enabled": True, "machines": 3}

#: name: (env id, keyword arguments)
CASES: dict[str, tuple[str, dict[str, Any]]] = {
    "v0-flat": ("cnc_gym/Feedrate-v0", {}),
    "v1-flat": ("cnc_gym/Feedrate-v1", {}),
    "v2-flat": ("cnc_gym/Feedrate-v2", {}),
    "v1-residual": ("cnc_gym/Feedrate-v1", {"programs": ["star", "circle"], "action_mode": "residual"}),
    "v2-residual-short": ("cnc_gym/Feedrate-v2", {"programs": ["pocket"], "action_mode": "residual",
                                                  "max_episode_steps": 150, "residual_range": 3.0}),
    "v2-feed": ("cnc_gym/Feedrate-v2", {"programs": ["freeform", "star"], "action_mode": "feed"}),
    "v1-helix-nurbs-gsk25i": ("cnc_gym/Feedrate-v1", {"programs": [helix_program(), nurbs_program()],
                                                      "machine": "gsk25i"}),
    "v2-period-points-h4cm": ("cnc_gym/Feedrate-v2", {"programs": ["circle", "star"], "machine": "h4cm",
                                                      "control_period_s": 0.02, "lookahead_points": 5,
                                                      "lookahead_mm": 12.0}),
    "v2-randomized": ("cnc_gym/Feedrate-v2", {"programs": ["circle", "freeform"], "randomize": RANDOMIZE}),
    "v1-randomized-residual": ("cnc_gym/Feedrate-v1", {"programs": ["star"], "randomize": RANDOMIZE,
                                                       "action_mode": "residual", "max_episode_steps": 300}),
    "v1-reward-no-motion": ("cnc_gym/Feedrate-v1", {"programs": [NO_MOTION, "circle"],
                                                    "reward": {"time": 2.0, "violation": 3.0,
                                                               "finish": 0.5, "progress": 0.0}}),
    "v2-mujoco": ("cnc_gym/Feedrate-v2", {"programs": ["circle"], "machine": "vmc-small-mujoco",
                                          "plant": "mujoco", "max_episode_steps": 200}),
    "v3-flat": ("cnc_gym/Feedrate-v3", {}),
    "v3-residual": ("cnc_gym/Feedrate-v3", {"programs": ["star", "pocket", "freeform"],
                                            "action_mode": "residual"}),
    "v4-flat": ("cnc_gym/Feedrate-v4", {}),
    "v4-residual": ("cnc_gym/Feedrate-v4", {"programs": ["star", "pocket", "freeform"],
                                            "action_mode": "residual"}),
    "v5-flat": ("cnc_gym/Feedrate-v5", {}),
    "v5-residual": ("cnc_gym/Feedrate-v5", {"programs": ["star", "pocket", "freeform"],
                                            "action_mode": "residual"}),
    "v6-flat": ("cnc_gym/Feedrate-v6", {}),
    "v6-randomized-residual": ("cnc_gym/Feedrate-v6", {"programs": ["star", "pocket", "freeform"],
                                                       "action_mode": "residual", "randomize": RANDOMIZE,
                                                       "reward": {"time": 2.0, "violation": 3.0}}),
}  # fmt: skip


def fingerprint(env_id: str, kwargs: dict[str, Any], steps: int, seed: int = 0) -> tuple[str, int, int]:
    """(hash, steps run, episodes ended) of ``steps`` random steps of ``env_id``."""
    env = gym.make(env_id, **kwargs)
    digest = hashlib.sha256()

    def add(obs: np.ndarray, info: dict[str, Any], *rest: Any) -> None:
        digest.update(obs.dtype.str.encode() + repr(obs.shape).encode() + obs.tobytes())
        digest.update(repr([float.hex(r) if type(r) is float else repr(r) for r in rest]).encode())
        digest.update(repr(info).encode())

    add(*env.reset(seed=seed))
    env.action_space.seed(seed)
    ends = 0
    for _ in range(steps):
        obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
        add(obs, info, reward, terminated, truncated)
        if terminated or truncated:
            ends += 1
            add(*env.reset())
    env.close()
    return digest.hexdigest()[:16], steps, ends


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=3000, help="steps per case (default 3000)")
    parser.add_argument("--cases", nargs="+", default=list(CASES), choices=list(CASES))
    args = parser.parse_args(argv)
    for name in args.cases:
        env_id, kwargs = CASES[name]
        digest, steps, ends = fingerprint(env_id, kwargs, args.steps)
        print(f"{name:26s} {digest}  ({steps} steps, {ends} episode ends)", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
