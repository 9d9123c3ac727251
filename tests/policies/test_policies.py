"""Policy specs (`constant:<x>`, `classical`, a model path) and the constant-override baseline."""

from __future__ import annotations

import numpy as np
import pytest

from cnc_gym.errors import CncGymError
from cnc_gym.policies import ClassicalPlanner, ConstantOverride, make_policy
from cnc_gym.policies.base import override_action


@pytest.mark.parametrize(("spec", "override"), [("constant:1.0", 1.0), ("constant:0.5", 0.5),
                                                 ("constant:2", 2.0), (" constant:1.25 ", 1.25)])  # fmt: skip
def test_constant_spec(spec, override):
    policy = make_policy(spec)
    assert isinstance(policy, ConstantOverride)
    assert policy.override == override
    # The env maps action a to override a + 1, so the action is override − 1.
    action = policy.act(np.zeros(4), {})
    assert action.dtype == np.float32 and action.shape == (1,)
    assert action[0] == pytest.approx(override - 1.0)


def test_classical_spec():
    assert isinstance(make_policy("classical"), ClassicalPlanner)


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        ("constant:fast", "needs a number"),
        ("constant:3", "within 0..2"),
        ("constant:-0.1", "within 0..2"),
        ("constant:nan", "within 0..2"),
        ("greedy", "unknown policy"),
        ("no/such/model.zip", "no such model file"),
    ],
)
def test_bad_specs_are_one_clear_error(spec, message):
    with pytest.raises(CncGymError, match=message):
        make_policy(spec)


def test_a_file_that_is_not_a_model(tmp_path):
    fake = tmp_path / "model.zip"
    fake.write_bytes(b"not a zip at all")
    with pytest.raises(CncGymError, match="not a Stable-Baselines3 model"):
        make_policy(str(fake))


def test_override_action_clips_to_the_action_box():
    assert override_action(0.0)[0] == -1.0
    assert override_action(2.0)[0] == 1.0
    assert override_action(5.0)[0] == 1.0  # beyond 200 %: clipped to the box
    assert override_action(1.5)[0] == pytest.approx(0.5)


@pytest.mark.parametrize(("spec", "message"), [
    ("os:system", "built-in callable"),  # would run a shell command with the observation
    ("json:dumps", "arguments fit neither"),
    ("builtins:exit", "callable Quitter"),  # called as a factory, it exited 0 with no word
    ("os:abort", "built-in callable"),  # a factory call would kill the process
    ("builtins:input", "built-in callable"),  # ... or wait on stdin
    ("math:pi", "float value"),
    ("json:JSONEncoder", "returned JSONEncoder"),  # a class that makes no policy
])  # fmt: skip
def test_a_module_callable_of_the_wrong_kind_is_refused_without_running_it(spec, message):
    with pytest.raises(CncGymError, match=message) as err:
        make_policy(spec)
    assert "\n" not in str(err.value) and len(str(err.value)) < 300


def test_a_factory_that_exits_or_fails_and_an_act_function_that_raises_are_one_line(tmp_path, monkeypatch):
    (tmp_path / "odd_policies.py").write_text(
        "import sys\n"
        "def leaves():\n    sys.exit(0)\n"
        "def breaks():\n    raise RuntimeError('no model here')\n"
        "def act(observation, info):\n    return observation['knob']\n"
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    with pytest.raises(CncGymError, match=r"calling leaves\(\) failed: SystemExit"):
        make_policy("odd_policies:leaves")
    with pytest.raises(CncGymError, match="calling breaks\\(\\) failed: RuntimeError: no model here"):
        make_policy("odd_policies:breaks")
    with pytest.raises(CncGymError, match=r"act\(observation, info\) failed: IndexError"):
        make_policy("odd_policies:act").act(np.zeros(3), {})


def test_the_cli_refuses_a_wrong_kind_of_callable_in_one_line():
    import subprocess
    import sys

    for spec in ("os:system", "builtins:exit"):
        result = subprocess.run([sys.executable, "-m", "cnc_gym.cli", "run", "circle", "--policy", spec],
                                capture_output=True, text=True, timeout=300, stdin=subprocess.DEVNULL)
        assert result.returncode == 2 and result.stdout == "", (spec, result)
        assert len(result.stderr.splitlines()) == 1 and "not a policy" in result.stderr, result.stderr
