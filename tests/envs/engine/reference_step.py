"""The reference path the compiled step is held to, and the runs that compare the two.

The reference path is the modular step: the same state arrays driven through the Controller objects,
the plant object's ``step``/``settled`` and the ContourErrorMeter, one env at a time (the path a plant
backend without compiled kernels takes). For Feedrate-v1 and v2 the reference also computes in Python
what the compiled step computes for them: the machine, episode and planner entries of the observation,
the planner's override (with the planner's ``override_at``), the reward terms, the finish
bonus, the cost and the info keys. Every observation, reward, termination, truncation and info
value must be equal — exactly, not to a tolerance.
"""

from __future__ import annotations

import numpy as np

from cnc_gym.envs.engine import INFO_KEYS
from cnc_gym.envs.engine.layout import (
    F_SIGNAL,
    SIG_PROGRESS_DELTA,
    SIG_TIME_FRACTION,
    SIG_VIOLATION_LENGTH,
)
from cnc_gym.envs.feedrate import FeedrateEnv
from cnc_gym.envs.feedrate_v1 import FeedrateEnvV1
from cnc_gym.envs.observation import machine_quantities
from cnc_gym.plant import ServoPlant


class ReferencePlant(ServoPlant):
    """The LTI plant, stepped through its object interface (not inside the compiled step)."""

    compiled_step = False


class ReferenceEnv(FeedrateEnv):
    """Feedrate-v0 on the modular (reference) step."""

    def make_batch(self, n_envs, parallel=None, plant=None):
        return super().make_batch(n_envs, parallel, ReferencePlant(self.machine, n_envs))


def knob_schedule(rng: np.random.Generator, n: int) -> np.ndarray:
    """A random walk of the knob with jumps: long stretches at high and low override, sudden changes."""
    knob = np.empty(n, dtype=np.float32)
    x = 0.0
    for i in range(n):
        jump = rng.random() >= 0.9
        x = float(rng.uniform(-1, 1)) if jump else float(np.clip(x + rng.normal() * 0.3, -1, 1))
        knob[i] = max(x, 0.2) if i % 200 < 60 else x
    return knob


def assert_same_run(compiled: FeedrateEnv, reference: FeedrateEnv, knobs: np.ndarray,
                    seed: int = 0) -> int:  # fmt: skip
    """Step both envs with ``knobs`` (resetting at episode ends); returns the number of episode ends."""
    out_f, out_r = compiled.reset(seed=seed), reference.reset(seed=seed)
    np.testing.assert_array_equal(out_f[0], out_r[0])
    assert out_f[1] == out_r[1]
    ends = 0
    for t, knob in enumerate(knobs):
        out_f = compiled.step(np.array([knob]))
        out_r = reference.step(np.array([knob]))
        np.testing.assert_array_equal(out_f[0], out_r[0], err_msg=f"step {t}")
        assert out_f[1:] == out_r[1:], f"step {t}"
        if out_f[2] or out_f[3]:
            ends += 1
            reset_f, reset_r = compiled.reset(), reference.reset()
            np.testing.assert_array_equal(reset_f[0], reset_r[0])
            assert reset_f[1] == reset_r[1]
    return ends


class ReferenceEnvV1(FeedrateEnvV1):
    """Feedrate-v1 on the modular step, with its own entries, reward and info computed in Python from the
    step's v0 outputs (the planner's override with cnc_gym.motion.planner.override_at)."""

    def make_batch(self, n_envs, parallel=None, plant=None):
        return super().make_batch(n_envs, parallel, ReferencePlant(self.machine, n_envs))

    def _residual_knob(self, a):  # (the residual mode's knob, from the reference's own planner override)
        override = min(max(self.reference_override * self.residual_range**a, 0.0), self.max_override)
        return self._planner.knob(override)

    def reset(self, *, seed=None, options=None):
        obs, info = super().reset(seed=seed, options=options)
        return self._v1(obs, info, None)

    def step(self, action):
        obs, _, terminated, truncated, info = super().step(action)
        obs, info = self._v1(obs, info, terminated)
        return obs, self._reward, terminated, truncated, info

    def _v1(self, obs, info, terminated):
        """The v1 entries of ``obs`` and the v1 info (``terminated`` None: a reset), and the reward."""
        from cnc_gym.motion.planner import override_at

        program = self._batch.program(0)
        schedule = self._planner.schedule(program.toolpath, self.machine, program.limits)
        self.reference_override = override_at(schedule, info["path_s"], info["feed_mm_min"],
                                              self._planner.lead_s, self._planner.reach_mm)  # fmt: skip
        quantities = machine_quantities(self.machine)
        violation_free = info["violation_length_mm"] <= 0.0
        at = self.layout.kernel_spec.size - len(self.layout.kernel_spec.tail)
        for e in self.layout.entries:
            if e.source in ("machine", "episode", "planner"):
                value = {"machine": quantities.get(e.quantity), "episode": float(violation_free),
                         "planner": self.reference_override}[e.source]  # fmt: skip
                obs[at] = min(max(value * self.layout.scale(e), e.low), e.high)
                at += 1
        out = {key: info[key] for key in INFO_KEYS}
        signals = self._batch.state_f[0, F_SIGNAL:]
        w = self.reward_weights
        terms, finish, cost, self._reward = (0.0, 0.0, 0.0), 0.0, 0.0, 0.0
        if terminated is not None:
            terms = (float(-w.time * signals[SIG_TIME_FRACTION]),
                     float(w.progress * signals[SIG_PROGRESS_DELTA]),
                     float(-w.violation * signals[SIG_VIOLATION_LENGTH]))  # fmt: skip
            if len(program.toolpath):
                self._reward = 0.0
                for term in terms:
                    self._reward += term
            budget, t_nominal = program.max_episode_steps, max(self.nominal_time_s, 1e-12)
            finish = w.time * budget * self.control_period_s / t_nominal + w.finish if (
                terminated and violation_free) else 0.0  # fmt: skip
            self._reward += finish
            cost = float(signals[SIG_VIOLATION_LENGTH])
        out["cost"] = cost
        out.update(zip(("reward_time", "reward_progress", "reward_violation"), terms, strict=True))
        out["reward_finish"] = finish
        out["planner_override"] = self.reference_override
        return obs, out


def assert_same_run_v1(fast: FeedrateEnvV1, reference: ReferenceEnvV1, actions: np.ndarray,
                       seed: int = 0) -> int:  # fmt: skip
    """Step both envs with ``actions`` (resetting at episode ends): the same observations (bytes), rewards
    (sign of zero included), flags and infos (keys in order, values with their types); the episode ends."""
    def same(out_f, out_r, where):
        np.testing.assert_array_equal(out_f[0], out_r[0], err_msg=where)
        assert out_f[0].tobytes() == out_r[0].tobytes(), where
        assert repr(out_f[1:]) == repr(out_r[1:]), where
        # (the fast env's info is a dict made when first used, engine.batch.StepInfo: its entries' types)
        def types(out):
            return [(dict, [type(v) for v in x.values()]) if isinstance(x, dict) else type(x) for x in out]
        assert types(out_f[1:]) == types(out_r[1:]), where

    same(fast.reset(seed=seed), reference.reset(seed=seed), "reset")
    ends = 0
    for t, a in enumerate(actions):
        out_f, out_r = fast.step(np.array([a])), reference.step(np.array([a]))
        same(out_f, out_r, f"step {t}")
        if out_f[2] or out_f[3]:
            ends += 1
            same(fast.reset(), reference.reset(), f"reset after step {t}")
    return ends
