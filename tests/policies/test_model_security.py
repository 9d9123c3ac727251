"""Model files cannot run code: crafted SB3 zips with payloads in every pickled place.

Every payload here, when unpickled, creates a marker file (``open(marker, "w")``). The controls show that
each payload is live (an unsafe loader would run it); the tests show that cnc-gym's loader never does: the
marker never appears, and a model that cannot be loaded safely is one error line naming the file.
"""

from __future__ import annotations

import base64
import io
import json
import pickle
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest

from cnc_gym.errors import CncGymError
from cnc_gym.policies import make_policy
from cnc_gym.policies.model import ModelError, ModelPolicy, load_sb3_model

REPO = Path(__file__).resolve().parents[2]


class Touch:
    """Unpickling this creates the marker file: a stand-in for any code an attacker would run."""

    def __init__(self, marker: Path) -> None:
        self.marker = str(marker)

    def __reduce__(self):
        return (open, (self.marker, "w"))


def payload(marker: Path) -> str:
    """The base64 pickle SB3 would hand to cloudpickle.loads."""
    return base64.b64encode(pickle.dumps(Touch(marker))).decode()


def torch_payload(marker: Path) -> bytes:
    import torch

    buffer = io.BytesIO()
    torch.save({"log_std": Touch(marker)}, buffer)
    return buffer.getvalue()


@pytest.fixture(scope="module")
def model_zip(tmp_path_factory) -> Path:
    """An untrained PPO model of Feedrate-v0, saved by SB3 (what scripts/train.py writes)."""
    from stable_baselines3 import PPO

    from cnc_gym.envs.feedrate import FeedrateEnv

    env = FeedrateEnv(programs=["circle"])
    model = PPO("MlpPolicy", env, n_steps=64, batch_size=32, seed=0, device="cpu",
                policy_kwargs={"net_arch": [16, 16], "log_std_init": -1.0})  # fmt: skip
    path = tmp_path_factory.mktemp("model") / "model.zip"
    model.save(path)
    return path


#: A valid shield record (cnc_gym/policies/shield.py).
SHIELD = {"kind": "planner-fallback", "bins": 1, "turn": 0.25, "error": 0.5}


def rewrite(source: Path, target: Path, *, data=None, members: dict[str, bytes] | None = None) -> Path:
    """A copy of the model zip with ``data`` changed by ``data(dict)`` and members replaced."""
    with zipfile.ZipFile(source) as zin, zipfile.ZipFile(target, "w", zipfile.ZIP_DEFLATED) as zout:
        for name in zin.namelist():
            content = zin.read(name)
            if name == "data" and data is not None:
                loaded = json.loads(content)
                data(loaded)
                content = json.dumps(loaded).encode()
            if members and name in members:
                content = members[name]
            zout.writestr(name, content)
    return target


def set_serialized(key: str, marker: Path):
    def change(data: dict) -> None:
        entry = data.get(key)
        if not isinstance(entry, dict):
            entry = {":type:": "<class 'dict'>"}
            data[key] = entry
        entry[":serialized:"] = payload(marker)

    return change


def assert_one_clean_line(message: str, path: Path) -> None:
    assert "\n" not in message and "Traceback" not in message and "\x1b" not in message
    assert message.startswith(str(path)), message
    assert len(message) < 400


# ------------------------------------------------------------------------------------------ controls
def test_the_payloads_are_live(tmp_path):
    # What an unsafe loader does with them: the marker appears. Without this the tests below prove nothing.
    import torch

    marker = tmp_path / "ran"
    pickle.loads(base64.b64decode(payload(marker)))
    assert marker.exists()
    marker.unlink()
    torch.load(io.BytesIO(torch_payload(marker)), weights_only=False)
    assert marker.exists()


def test_sb3s_own_loader_runs_a_policy_class_payload(model_zip, tmp_path):
    # The threat of issue 17: PPO.load unpickles policy_class (SB3 tries it before anything else).
    from stable_baselines3 import PPO

    marker = tmp_path / "ran"
    crafted = rewrite(model_zip, tmp_path / "crafted.zip", data=set_serialized("policy_class", marker))
    with pytest.raises(Exception):  # noqa: B017  (the payload returns a file, not a class)
        PPO.load(crafted, device="cpu")
    assert marker.exists()


# ----------------------------------------------------------------------------------- the safe loader
def test_the_safe_loader_acts_like_sb3s(model_zip):
    from stable_baselines3 import PPO

    from cnc_gym.envs.feedrate import FeedrateEnv

    ours = load_sb3_model(model_zip)
    reference = PPO.load(model_zip, device="cpu")
    assert ours.algorithm == "PPO" and ours.observation_space.shape == (41,)
    env = FeedrateEnv(programs=["circle"])
    observation, _ = env.reset(seed=0)
    rng = np.random.default_rng(0)
    for _ in range(50):
        expected, _ = reference.predict(observation, deterministic=True)
        np.testing.assert_array_equal(ours.predict(observation), expected)
        observation, *_ = env.step(rng.uniform(-1, 1, size=1).astype(np.float32))


SERIALIZED_KEYS = ["policy_class", "lr_schedule", "clip_range", "observation_space", "action_space",
                   "policy_kwargs", "rollout_buffer_class", "an_extra_key"]  # fmt: skip


@pytest.mark.parametrize("key", SERIALIZED_KEYS)
def test_a_payload_in_any_serialized_entry_never_runs(model_zip, tmp_path, key):
    marker = tmp_path / "ran"
    crafted = rewrite(model_zip, tmp_path / "crafted.zip", data=set_serialized(key, marker))
    policy = make_policy(str(crafted))  # loads: the pickles are not needed, so never decoded
    assert isinstance(policy, ModelPolicy)
    action = policy.act(np.zeros(41, dtype=np.float32), {})
    assert action.shape == (1,) and np.isfinite(action).all()
    assert not marker.exists()


@pytest.mark.parametrize("member", ["policy.pth", "pytorch_variables.pth", "policy.optimizer.pth"])
def test_a_payload_in_a_torch_file_never_runs(model_zip, tmp_path, member):
    marker = tmp_path / "ran"
    crafted = rewrite(model_zip, tmp_path / "crafted.zip", members={member: torch_payload(marker)})
    if member == "policy.pth":  # the weights are needed: refused, one line
        with pytest.raises(ModelError) as err:
            load_sb3_model(crafted)
        assert_one_clean_line(str(err.value), crafted)
        assert "could run code" in str(err.value)
    else:  # never read: the model loads
        load_sb3_model(crafted)
    assert not marker.exists()


def readable(key: str, attribute: str, value):
    def change(data: dict) -> None:
        data[key][attribute] = value

    return change


@pytest.mark.parametrize(
    ("change", "fragment"),
    [
        (readable("policy_class", "__init__", "<function EvilPolicy.__init__ at 0x1>"), "policy class"),
        (readable("policy_class", "__module__", "evil"), "policy class"),
        (readable("observation_space", ":type:", "<class 'gymnasium.spaces.dict.Dict'>"), "not a Box"),
        (readable("observation_space", "_shape", [10**12]), "unusable shape"),
        (readable("action_space", "low", "[nan]"), "bounds are not finite"),
        (readable("action_space", "high", "[1. ... 1.]"), "not a readable list"),
        (lambda d: d.update(policy_kwargs={"activation_fn": "<class 'os.system'>"}), "activation_fn"),
        (lambda d: d.update(policy_kwargs={"net_arch": [16, 16], "evil": 1}), "policy_kwargs key evil"),
        (lambda d: d.update(policy_kwargs={"net_arch": [100000, 100000]}), "asks for"),
        (lambda d: d.update(policy_kwargs={"net_arch": [32, 32]}), "weights do not fit"),
        (lambda d: d.update(policy_kwargs={"features_extractor_class": "<class 'evil.Extractor'>"}),
         "features_extractor_class"),
        (lambda d: d.update(cnc_gym_env={"id": "evil/Env-v0", "kwargs": {}}), "names no known env"),
        (lambda d: d.update(cnc_gym_env={"id": "cnc_gym/Feedrate-v1", "kwargs": {"programs": ["x"]}}),
         "cnc_gym_env.kwargs.programs is not"),
        (lambda d: d.update(cnc_gym_env={"id": "cnc_gym/Feedrate-v1", "kwargs": {"residual_range": "2"}}),
         "cnc_gym_env.kwargs.residual_range is not"),
        (lambda d: d.update(cnc_gym_env={":type:": "<class 'dict'>", ":serialized:": "gAR9lC4="}),
         "names no known env"),
        (lambda d: d.update(cnc_gym_shield={**SHIELD, "kind": "exec"}), "not a planner-fallback shield"),
        (lambda d: d.update(cnc_gym_shield={**SHIELD, "bins": 0}), "bins must be"),
        (lambda d: d.update(cnc_gym_shield={**SHIELD, "turn": "0.25"}), "turn must be"),
        (lambda d: d.update(cnc_gym_shield={**SHIELD, "error": [0.5]}), "error must be"),
        (lambda d: d.update(cnc_gym_shield=[1, 0.25]), "not a planner-fallback shield"),
    ],
)
def test_models_outside_the_known_list_are_refused_in_one_line(model_zip, tmp_path, change, fragment):
    crafted = rewrite(model_zip, tmp_path / "odd.zip", data=change)
    with pytest.raises(CncGymError) as err:
        load_sb3_model(crafted)
    assert_one_clean_line(str(err.value), crafted)
    assert fragment in str(err.value)


def test_the_env_record_is_read_as_plain_json(model_zip, tmp_path):
    record = {"id": "cnc_gym/Feedrate-v1", "kwargs": {"action_mode": "residual", "residual_range": 2.0}}
    crafted = rewrite(model_zip, tmp_path / "v1.zip", data=lambda d: d.update(cnc_gym_env=record))
    policy = ModelPolicy(crafted)
    assert (policy.env_id, policy.env_kwargs) == (record["id"], record["kwargs"])
    assert (ModelPolicy(model_zip).env_id, ModelPolicy(model_zip).env_kwargs) == ("cnc_gym/Feedrate-v0", {})


def test_a_recorded_shield_is_read_and_needs_a_residual_env(model_zip, tmp_path):
    from cnc_gym.envs.feedrate import FeedrateEnv
    from cnc_gym.policies.shield import PlannerShield

    record = {"kind": "planner-fallback", "bins": 2, "turn": 0.3, "error": None}
    crafted = rewrite(model_zip, tmp_path / "shielded.zip", data=lambda d: d.update(cnc_gym_shield=record))
    policy = ModelPolicy(crafted)
    assert policy.model.shield == PlannerShield(2, 0.3) and ModelPolicy(model_zip).model.shield is None
    with pytest.raises(CncGymError) as err:  # Feedrate-v0 in override mode: nothing to hold at the planner
        policy.reset(FeedrateEnv(programs=["circle"]))
    message = str(err.value)
    assert "\n" not in message and message.startswith("shielded.zip: the shield holds a residual")
    assert "'override' action mode" in message


def test_damaged_and_oversized_members_are_one_line(model_zip, tmp_path):
    import torch

    cases = {
        "bomb.zip": {"data": b"{" + b" " * (8 << 20) + b"}"},  # 8 MiB of spaces: compresses to a few KB
        "notjson.zip": {"data": b"\xff\xfe not json"},
        "deep.zip": {"data": b"[" * 100_000},
        "nan.zip": {"policy.pth": _tensor_file(torch, float("nan"))},
        "garbage.zip": {"policy.pth": b"PK\x03\x04 not a torch file"},
    }
    for name, members in cases.items():
        crafted = rewrite(model_zip, tmp_path / name, members=members)
        with pytest.raises(ModelError) as err:
            load_sb3_model(crafted)
        assert_one_clean_line(str(err.value), crafted)


def _tensor_file(torch, value: float) -> bytes:
    from stable_baselines3 import PPO  # noqa: F401  (torch is imported)

    buffer = io.BytesIO()
    torch.save({"log_std": torch.tensor([value])}, buffer)
    return buffer.getvalue()


def test_a_file_name_with_control_characters_is_escaped(tmp_path):
    path = tmp_path / "evil\x1b[2J.zip"
    path.write_bytes(b"PK\x05\x06" + b"\0" * 18)  # an empty zip
    with pytest.raises(ModelError) as err:
        load_sb3_model(path)
    assert "\x1b" not in str(err.value) and "\\x1b[2J" in str(err.value)


@pytest.mark.parametrize("kind", ["torch file", "raw pickle"])
def test_the_cli_prints_one_line_and_runs_nothing(model_zip, tmp_path, kind):
    marker = tmp_path / "ran"
    # A bare pickle (protocol 4) as policy.pth: torch warns about the protocol in two lines of its own
    # before it refuses the file; the user sees the one error line only.
    pth = torch_payload(marker) if kind == "torch file" else pickle.dumps({"log_std": Touch(marker)}, 4)
    crafted = rewrite(model_zip, tmp_path / "crafted.zip", members={"policy.pth": pth})
    command = [sys.executable, "-m", "cnc_gym.cli", "run", "circle", "--policy", str(crafted)]
    result = subprocess.run(command, cwd=REPO, capture_output=True, text=True, timeout=300)
    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "could run code" in lines[0], result.stderr
    assert not marker.exists()
