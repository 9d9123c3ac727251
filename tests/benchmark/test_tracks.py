"""Benchmark tracks: the plants they define, the runner's records, the leaderboard's tables, the CLI."""

from __future__ import annotations

import dataclasses
import math

import pytest

from cnc_gym.benchmark.leaderboard import leaderboard_rows, render_markdown
from cnc_gym.benchmark.metrics import RECORD_VERSION
from cnc_gym.benchmark.runner import BenchConfig, BenchProgram, run_bench
from cnc_gym.benchmark.tracks import (
    PERTURBATION,
    TRACKS,
    mujoco_machine,
    perturbed_machine,
    track_plant,
)
from cnc_gym.errors import CncGymError
from cnc_gym.machine import AXIS_NAMES, load_machine
from cnc_gym.motion.planner import PLANNER_VERSION

# A short L-shaped cut: one corner, so the plants differ in contour error, and each episode is short.
PROGRAM = "G90 G21 G17\nG00 X0 Y0\nG01 X12 F2400\nG01 Y6\nM30\n"


def test_nominal_track_is_the_machine_itself():
    nominal = load_machine("vmc-small")
    assert track_plant("nominal", nominal, "s", "p") == (nominal, None)


def test_mujoco_track_has_the_nominal_loops_and_the_companion_presets_mechanics():
    nominal, companion = load_machine("vmc-small"), load_machine("vmc-small-mujoco")
    machine, parameters = track_plant("mujoco", nominal, "s", "p")
    assert parameters is None
    assert machine.plant.backend == "mujoco"
    assert machine.controller == nominal.controller and machine.axes == nominal.axes
    assert machine.plant.axes == companion.plant.axes


def test_perturbed_plant_is_the_same_for_a_program_and_differs_between_programs():
    nominal = load_machine("vmc-small")
    a1, p1 = perturbed_machine(nominal, "cnc-bench-v1", "arcs-test-000")
    a2, p2 = perturbed_machine(nominal, "cnc-bench-v1", "arcs-test-000")
    b, q = perturbed_machine(nominal, "cnc-bench-v1", "arcs-test-001")
    assert a1 == a2 and p1 == p2
    assert p1 != q and a1 != b


@pytest.mark.parametrize("program", [f"prog-{k}" for k in range(20)])
def test_perturbed_parameters_lie_in_the_documented_ranges_and_are_what_the_plant_runs(program):
    nominal = load_machine("vmc-small")
    base = mujoco_machine(nominal)
    machine, p = perturbed_machine(nominal, "suite", program)
    d = PERTURBATION
    kv_nominal = nominal.axis_array("kv_1_s")
    lo = d.kv_scale[0] * (1 + d.kv_mismatch[0])
    hi = d.kv_scale[1] * (1 + d.kv_mismatch[1])
    for i, name in enumerate(AXIS_NAMES):
        assert lo - 1e-12 <= p["kv_1_s"][i] / kv_nominal[i] <= hi + 1e-12
        assert machine.axes[i].kv_1_s == p["kv_1_s"][i]
        ratio = p["velocity_loop_hz"][i] / nominal.axes[i].velocity_loop_hz
        assert d.velocity_loop_scale[0] - 1e-12 <= ratio <= d.velocity_loop_scale[1] + 1e-12
        assert abs(p["feedforward"][i] - nominal.axes[i].feedforward) <= d.feedforward_error[1] + 1e-12
        assert 0.0 <= p["feedforward"][i] <= 1.0
        mech = getattr(machine.plant.axes, name)
        friction = getattr(base.plant.axes, name).coulomb_friction_n
        assert mech.coulomb_friction_n == p["coulomb_friction_n"][i]
        low, high = d.friction_scale
        assert low * friction - 1e-9 <= mech.coulomb_friction_n <= high * friction + 1e-9
        assert mech.backlash_mm == p["backlash_mm"][i]
        assert d.backlash_mm[0] <= mech.backlash_mm <= d.backlash_mm[1]
    # what a plant needs of a machine (stable loops, a valid preset) holds: the env builds and steps
    # (controller and axes limits are untouched, so the bound and the planner's tables are the nominal ones)
    assert machine.controller == nominal.controller

    def limits_only(axes):
        return [dataclasses.replace(a, kv_1_s=0, velocity_loop_hz=0, feedforward=0) for a in axes]

    assert limits_only(machine.axes) == limits_only(nominal.axes)


def test_unknown_track_is_one_clear_error():
    with pytest.raises(CncGymError, match="--track must be one of nominal, perturbed, mujoco"):
        track_plant("wobbly", load_machine("vmc-small"), "s", "p")


def _bench(track, policies):
    config = BenchConfig(programs=[BenchProgram(name="ell", text=PROGRAM)], policies=policies, track=track)
    return {r["policy"]: r for r in run_bench(config)}


def test_perturbed_track_records_name_the_track_and_one_plant_for_every_policy():
    records = _bench("perturbed", ["classical", "nominal-oracle", "bound"])
    parameters = records["classical"]["plant_parameters"]
    assert parameters is not None and set(parameters) >= {"kv_1_s", "velocity_loop_hz", "feedforward",
                                                           "coulomb_friction_n", "backlash_mm"}  # fmt: skip
    for r in records.values():
        assert r["track"] == "perturbed" and r["record_version"] == RECORD_VERSION
        assert r["plant_parameters"] == parameters
    assert {records[p]["plant"] for p in ("classical", "nominal-oracle")} == {"mujoco"}
    # the bound is the nominal machine's: the same on every track
    nominal = _bench("nominal", ["bound"])
    assert math.isclose(records["bound"]["bound_s"], nominal["bound"]["bound_s"], rel_tol=1e-9)
    assert nominal["bound"]["track"] == "nominal" and nominal["bound"]["plant_parameters"] is None


def test_classical_plans_with_the_nominal_machine_on_other_tracks():
    from cnc_gym.policies.classical import ClassicalPlanner
    from cnc_gym.rollout import policy_env

    nominal = load_machine("vmc-small")
    true_machine, _ = track_plant("perturbed", nominal, "user", "ell")
    schedules = []
    for machine, told in ((nominal, None), (true_machine, nominal), (true_machine, None)):
        planner = ClassicalPlanner()
        planner.nominal_machine = told
        env = policy_env(planner, programs=[PROGRAM], machine=machine)
        env.reset(seed=0)
        planner.reset(env)
        schedules.append(planner.schedule.override.copy())
        env.close()
    assert schedules[0].tolist() == schedules[1].tolist()  # told the nominal machine: the nominal plan
    assert schedules[0].tolist() != schedules[2].tolist()  # the perturbed Kv would change the plan


def test_nominal_oracle_is_the_oracle_on_the_nominal_track():
    records = _bench("nominal", ["oracle", "nominal-oracle"])
    assert records["oracle"]["cycle_time_s"] == records["nominal-oracle"]["cycle_time_s"]
    assert records["oracle"]["violation_length_mm"] == records["nominal-oracle"]["violation_length_mm"]


def _record(policy, track, score=0.5):
    return {"record_version": 3, "suite": "s", "suite_sha256": "x", "split": "test", "machine": "m",
            "bound_version": 2, "track": track, "program": "p", "family": "f", "policy": policy, "seed": 0,
            "commit": "c", "score": score, "feasible": True, "finished": True, "time_ratio": 1 / score,
            "violation_length_mm": 0.0, "cut_length_mm": 10.0, "reference": False}  # fmt: skip


def test_leaderboard_makes_one_table_per_track_and_never_mixes_them():
    records = [_record("classical", "perturbed", 0.4), _record("classical", "nominal", 0.5),
               _record("oracle", "mujoco", 0.45)]  # fmt: skip
    text = render_markdown(records, ["r.jsonl"])
    order = [text.index(f"track `{t}`") for t in TRACKS]
    assert order == sorted(order)
    assert text.count("| classical |") == 2
    with pytest.raises(CncGymError, match="several tracks"):
        leaderboard_rows(records)


def test_records_without_a_track_are_nominal():
    old = _record("classical", None)
    del old["track"]
    assert "track `nominal`" in render_markdown([old], ["r.jsonl"])


def test_cli_refuses_plant_with_another_track(capsys):
    from cnc_gym.cli import main

    assert main(["bench", "--track", "mujoco", "--plant", "lti", "--per-family", "1"]) == 2
    assert "--plant sets the nominal track's plant" in capsys.readouterr().err


def test_residual_env_plans_on_the_machine_it_is_told():
    # The env's own planner (its planner entries, residual mode) must not learn the true plant on a track:
    # told the nominal machine, residual 0 on the true plant is the classical policy told the same.
    from cnc_gym.envs.feedrate import FeedrateEnv
    from cnc_gym.envs.feedrate_v1 import FeedrateEnvV1
    from cnc_gym.policies.classical import ClassicalPlanner
    from cnc_gym.rollout import run_episode

    nominal = load_machine("vmc-small")
    slow = dataclasses.replace(nominal, axes=tuple(dataclasses.replace(a, kv_1_s=0.6 * a.kv_1_s)
                                                   for a in nominal.axes))  # fmt: skip

    class Zero:
        def reset(self, env):
            return None

        def act(self, observation, info):
            return 0.0

    def outcome(info):
        return info["cycle_time_s"], info["contour_error_max_mm"]

    planner = ClassicalPlanner()
    planner.nominal_machine = nominal
    classical = outcome(run_episode(FeedrateEnv(programs=[PROGRAM], machine=slow), planner).info)
    results = []
    for told in (nominal, None):
        env = FeedrateEnvV1(programs=[PROGRAM], machine=slow, action_mode="residual",
                            planner_version=PLANNER_VERSION)  # fmt: skip
        env.plan_on(told)
        results.append(outcome(run_episode(env, Zero()).info))
    assert results[0] == classical
    assert results[1] != classical
