"""The shield (cnc_gym/policies/shield.py): where it engages, what it holds, what it refuses."""

from __future__ import annotations

import numpy as np
import pytest

from cnc_gym.errors import CncGymError
from cnc_gym.policies.shield import PlannerShield
from cnc_gym.programs import ProgramText

V5 = "cnc_gym/Feedrate-v5"
#: A line, a 90° corner 2 mm after a long run, then a reversal (180°).
CORNERS = "G90 G21 G17\nG00 X0 Y0 Z1\nG01 Z0 F600\nG01 X40 F3000\nG01 Y20\nG01 Y0\nG00 Z5\nM30\n"


def _env(action_mode: str = "residual", **kwargs):
    import gymnasium

    import cnc_gym  # noqa: F401

    return gymnasium.make(V5, programs=[ProgramText(CORNERS, "corners")], action_mode=action_mode,
                          residual_range=1.25, **kwargs)  # fmt: skip


def test_it_binds_to_the_envs_turn_angle_bins_and_error_entry():
    env = _env()
    structure = env.unwrapped.observation_structure
    bound = PlannerShield(2, 0.25, 0.5).bind(env)
    turn, error = structure["turn_angle"], structure["contour_error_step"]
    assert (bound.first, bound.stop, bound.error_index) == (turn[0], turn[0] + 2, error[0])


def test_its_error_rule_falls_back_from_a_large_contour_error():
    env = _env()
    up = np.array([0.7], np.float32)
    obs = np.zeros(env.observation_space.shape, np.float32)
    with_rule, without = PlannerShield(1, 0.25, 0.5).bind(env), PlannerShield(1, 0.25).bind(env)
    obs[with_rule.error_index] = 0.49
    assert with_rule.apply(obs, up) == pytest.approx(0.7)
    obs[with_rule.error_index] = 0.5  # half the tolerance over the last step
    assert with_rule.apply(obs, up) == 0.0 and without.apply(obs, up) == pytest.approx(0.7)


def test_it_holds_a_raise_at_the_planner_where_a_sharp_turn_is_in_reach():
    env = _env()
    bound = PlannerShield(1, 0.25).bind(env)
    obs = np.zeros(env.observation_space.shape, np.float32)
    up, down = np.array([0.7], np.float32), np.array([-0.4], np.float32)
    assert bound.apply(obs, up) == pytest.approx(0.7) and bound.apply(obs, down) == pytest.approx(-0.4)
    obs[bound.first] = 0.25  # a 45° junction in the first bin
    assert bound.engaged(obs)
    assert bound.apply(obs, up) == 0.0 and bound.apply(obs, down) == pytest.approx(-0.4)
    obs[bound.first] = 0.2
    obs[bound.first + 1] = 1.0  # a reversal, but beyond the shield's one bin
    assert not bound.engaged(obs) and bound.apply(obs, up) == pytest.approx(0.7)
    assert bound.apply(obs, up).dtype == np.float32


def test_its_hold_keeps_a_raise_at_the_planner_for_hold_periods_after_a_junction_leaves_the_reach():
    env = _env()
    bound = PlannerShield(1, 0.25, hold=3).bind(env)
    up = np.array([0.7], np.float32)
    corner = np.zeros(env.observation_space.shape, np.float32)
    corner[bound.first] = 0.5  # a 90° junction in the first bin
    past = np.zeros(env.observation_space.shape, np.float32)  # ... which the tool has now reached
    assert bound.apply(past, up) == pytest.approx(0.7)  # no junction yet: nothing to hold
    assert bound.apply(corner, up) == 0.0 and bound.apply(corner, up) == 0.0
    held = [float(bound.apply(past, up)[0]) for _ in range(5)]
    assert held == [0.0, 0.0, 0.0, pytest.approx(0.7), pytest.approx(0.7)]
    assert bound.apply(past, np.array([-0.4], np.float32)) == pytest.approx(-0.4)  # slower is always free
    # A new junction restarts the count; without a hold the shield lets go at once.
    assert bound.apply(corner, up) == 0.0 and bound.apply(past, up) == 0.0
    plain = PlannerShield(1, 0.25).bind(env)
    assert plain.apply(corner, up) == 0.0 and plain.apply(past, up) == pytest.approx(0.7)
    # Binding again (the next episode) starts with nothing held.
    assert PlannerShield(1, 0.25, hold=3).bind(env).apply(past, up) == pytest.approx(0.7)


def test_a_hold_record_round_trips_and_bad_holds_are_one_line():
    shield = PlannerShield(1, 0.25, 0.5, hold=10)
    assert shield.record()["hold"] == 10 and PlannerShield.from_record(shield.record()) == shield
    assert "hold" not in PlannerShield(1, 0.25).record()  # the record of a shield without one is as before
    for hold in (-1, 1001, 2.5, True):
        with pytest.raises(CncGymError, match="hold must be an integer"):
            PlannerShield(1, 0.25, hold=hold)


def test_a_shielded_full_raise_stays_at_the_planner_before_each_corner():
    # The policy "always +1" through the shield: the env's own observation engages it before each corner,
    # and the override commanded there is the planner's.
    env = _env()
    bound = PlannerShield(1, 0.25).bind(env)
    obs, _ = env.reset(seed=0)
    engaged = free = 0
    done = False
    while not done:
        action = bound.apply(obs, np.ones(1, np.float32))
        if bound.engaged(obs):
            engaged += 1
            assert action[0] == 0.0
        else:
            free += 1
            assert action[0] == 1.0
        obs, _, terminated, truncated, _ = env.step(action)
        done = terminated or truncated
    assert engaged > 0 and free > engaged and terminated


@pytest.mark.parametrize(("bins", "turn", "fragment"), [
    (0, 0.25, "bins must be an integer >= 1"), (1.5, 0.25, "bins must be"), (True, 0.25, "bins must be"),
    (1, 0.0, r"turn must be in \(0, 1\]"), (1, 1.5, "turn must be"), (1, "0.3", "turn must be"),
])  # fmt: skip
def test_bad_settings_are_one_line(bins, turn, fragment):
    with pytest.raises(CncGymError, match=fragment):
        PlannerShield(bins, turn)


@pytest.mark.parametrize("error", [0.0, -1.0, 6.0, "0.5", True, float("nan")])
def test_a_bad_error_bound_is_one_line(error):
    with pytest.raises(CncGymError, match=r"error must be in \(0, 5\]"):
        PlannerShield(1, 0.25, error)


def test_it_refuses_an_override_env_and_a_reach_past_the_preview():
    with pytest.raises(CncGymError, match="'override' action mode"):
        PlannerShield(1, 0.25).bind(_env("override"))
    with pytest.raises(CncGymError, match="reads 9 bin"):
        PlannerShield(9, 0.25).bind(_env())


def test_its_record_round_trips_and_malformed_records_are_refused():
    for shield in (PlannerShield(3, 0.4), PlannerShield(1, 0.25, 0.6)):
        assert PlannerShield.from_record(shield.record()) == shield
    for record in ({"kind": "planner-fallback", "bins": 1, "turn": 0.3},
                   {"kind": "other", "bins": 1, "turn": 0.3, "error": None}, "planner-fallback", None):
        with pytest.raises(CncGymError, match="not a planner-fallback shield"):
            PlannerShield.from_record(record)


# ----------------------------------------------------------------------------------------- envelope
ENVELOPE = (("kv", 0.6, 1.5), ("feedforward", 0.5, 0.9))


def test_outside_its_envelope_it_hands_the_knob_to_the_planner():
    env = _env()
    bound = PlannerShield(1, 0.25, 0.5, ENVELOPE).bind(env)
    structure = env.unwrapped.observation_structure
    kv, ff = structure["kv"][0], structure["feedforward"][0]
    obs = np.zeros(env.observation_space.shape, np.float32)
    obs[kv], obs[ff] = 1.0, 0.7
    up, down = np.array([0.7], np.float32), np.array([-0.4], np.float32)
    assert not bound.outside(obs)
    assert bound.apply(obs, up) == pytest.approx(0.7) and bound.apply(obs, down) == pytest.approx(-0.4)
    for index, value in ((ff, 0.0), (ff, 0.95), (kv, 0.5), (kv, 1.6)):
        off = obs.copy()
        off[index] = value
        assert bound.outside(off)
        assert bound.apply(off, up) == 0.0 and bound.apply(off, down) == 0.0  # not even slower
        assert bound.apply(off, up).dtype == np.float32
    edge = obs.copy()
    edge[ff] = np.float32(0.9) + np.float32(5e-5)  # within the slack: the same machine on another CPU
    assert not bound.outside(edge)


def test_the_envelope_tells_a_machine_without_feed_forward_from_the_one_it_was_trained_on():
    # vmc-small (feed-forward 0.7, Kv 38-45) lies inside; p-loop-30 (no feed-forward) does not, and a
    # full raise through the shield stays at the planner's override for its whole episode.
    inside, outside = _env(machine="vmc-small"), _env(machine="p-loop-30")
    shield = PlannerShield(1, 0.25, 0.5, ENVELOPE)
    obs, _ = inside.reset(seed=0)
    assert not shield.bind(inside).outside(obs)
    bound = shield.bind(outside)
    obs, _ = outside.reset(seed=0)
    done, steps = False, 0
    while not done:
        assert bound.outside(obs)
        action = bound.apply(obs, np.ones(1, np.float32))
        assert action[0] == 0.0
        obs, _, terminated, truncated, _ = outside.step(action)
        done, steps = terminated or truncated, steps + 1
    assert terminated and steps > 10


def test_an_envelope_record_round_trips_and_an_old_record_has_none():
    shield = PlannerShield(1, 0.25, 0.5, ENVELOPE)
    record = shield.record()
    assert record["envelope"] == {"kv": [0.6, 1.5], "feedforward": [0.5, 0.9]}
    assert PlannerShield.from_record(record) == shield
    old = {"kind": "planner-fallback", "bins": 1, "turn": 0.25, "error": 0.5}
    assert PlannerShield.from_record(old).envelope == () and "envelope" not in PlannerShield(1, 0.25).record()


@pytest.mark.parametrize("envelope", [[0.6, 1.5], {"kv": [1.0]}, {"kv": "0.6-1.5"}, {"kv": [1.5, 0.6]},
                                      {"kv": [0.6, float("inf")]}, {"kv": ["0.6", 1.5]}])  # fmt: skip
def test_a_malformed_envelope_record_is_one_line(envelope):
    record = {"kind": "planner-fallback", "bins": 1, "turn": 0.25, "error": None, "envelope": envelope}
    with pytest.raises(CncGymError, match="envelope"):
        PlannerShield.from_record(record)


def test_an_envelope_entry_the_env_lacks_is_refused_when_bound():
    with pytest.raises(CncGymError, match="envelope reads the observation's spindle_load"):
        PlannerShield(1, 0.25, None, (("spindle_load", 0.0, 1.0),)).bind(_env())
    with pytest.raises(CncGymError, match="envelope reads the observation's turn_angle"):  # not one entry
        PlannerShield(1, 0.25, None, (("turn_angle", 0.0, 1.0),)).bind(_env())


def test_a_model_outside_its_envelope_says_so_once_and_runs_as_the_planner(tmp_path):
    # The committed distilled student records its envelope (feed-forward 0.5-0.9 among others):
    # on p-loop-30 (no feed-forward) it warns, naming the entries, and its episode is the planner's.
    import warnings
    from pathlib import Path

    from cnc_gym.policies import make_policy
    from cnc_gym.rollout import policy_env, run_episode

    model = Path(__file__).resolve().parents[2] / "docs/results/models/distill-shielded-residual-s0.zip"
    policy = make_policy(str(model))
    env = policy_env(policy, programs=[ProgramText(CORNERS, "corners")], machine="p-loop-30")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        episode = run_episode(env, policy, seed=0)
    messages = [str(w.message) for w in caught if "envelope" in str(w.message)]
    assert len(messages) == 1 and "feedforward 0 not in [0.5" in messages[0]
    assert "it acts as the planner" in messages[0]
    planner = run_episode(policy_env(make_policy("classical"), programs=[ProgramText(CORNERS, "corners")],
                                     machine="p-loop-30"), make_policy("classical"), seed=0)  # fmt: skip
    assert episode.finished and episode.steps == planner.steps
    assert episode.info["cycle_time_s"] == pytest.approx(planner.info["cycle_time_s"], abs=0.011)
