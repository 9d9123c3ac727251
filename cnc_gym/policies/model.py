"""Trained Stable-Baselines3 models as policies, loaded without running any code from the model file.

SB3's own loader (``PPO.load``) unpickles several entries of a model zip's ``data`` JSON (``policy_class``,
``lr_schedule``, the spaces …) with cloudpickle, so a crafted ``.zip`` runs whatever code it carries the
moment it is loaded. cnc-gym therefore never calls it and never unpickles anything from the file:

1. ``data`` is read as JSON (size-capped); its pickled (``":serialized:"``) entries are never decoded.
2. The policy class comes from a fixed list, picked by the class name SB3 records in plain text beside the
   pickle: ``ActorCriticPolicy`` (PPO, A2C ``MlpPolicy``), ``SACPolicy`` (SAC), ``TD3Policy`` (TD3, DDPG).
3. The observation and action spaces are rebuilt from their recorded shape, dtype and bounds (``Box``
   only).
4. ``policy_kwargs`` are rebuilt from plain values (layer sizes, flags, numbers) and a fixed list of
   activation, optimizer and feature-extractor classes, named by their recorded text.
5. The weights (``policy.pth``) are read with ``torch.load(weights_only=True)``, which refuses anything but
   tensors, and loaded strictly (every tensor, right shapes, all finite) into that policy.

Nothing else in the zip is read (no optimizer state, no schedules, no replay buffers): a policy that
acts needs none of them, except one plain JSON entry of ``data`` that ``scripts/train.py`` writes,
``cnc_gym_env``: the env id and the few keyword arguments that fix what the model's observation and action
mean (``action_mode``, ``control_period_s``, ``residual_range``, ``lookahead_mm``, ``lookahead_points``),
checked against a fixed list of ids and keys, so ``cnc-gym bench`` and ``cnc-gym run`` run the model in the
env it was trained for (models without it run in ``cnc_gym/Feedrate-v0``); and ``cnc_gym_shield``, the
shield a residual policy acts through (:mod:`cnc_gym.policies.shield`: plain numbers, checked), which
:class:`ModelPolicy` applies.

A model outside this list (a custom policy class, image or dict observations)
is refused with one line; there is no unsafe fallback. Such a model can still be loaded in your own code
with SB3's loader, at your own risk, and run as any object with ``reset(env)`` and ``act(obs, info)``
(:class:`cnc_gym.policies.base.Policy`). docs/security.md says what a model file can and cannot do.
"""

from __future__ import annotations

import dataclasses
import io
import itertools
import json
import math
import re
import warnings
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from cnc_gym import ENV_IDS
from cnc_gym.config import escaped
from cnc_gym.errors import CncGymError
from cnc_gym.policies.shield import BoundShield, PlannerShield

#: Largest ``data`` entry read (SB3 writes a few KB).
MAX_DATA_BYTES = 4 << 20
#: Largest ``policy.pth`` read (a 64×64 policy is about 50 KB).
MAX_WEIGHTS_BYTES = 256 << 20
#: Most observation entries / action entries a model may declare.
MAX_OBSERVATION_SIZE = 100_000
MAX_ACTION_SIZE = 1_000
#: Most weights in a policy (what ``policy_kwargs`` may ask to build before the weights are checked).
MAX_PARAMETERS = 50_000_000

#: Policy classes by the name SB3 records (``"<function ActorCriticPolicy.__init__ at …>"``) and module,
#: with the algorithm they come from (for messages).
_FAMILIES = {
    ("stable_baselines3.common.policies", "ActorCriticPolicy"): "PPO/A2C",
    ("stable_baselines3.sac.policies", "SACPolicy"): "SAC",
    ("stable_baselines3.td3.policies", "TD3Policy"): "TD3",
}
_CLASS_KEYS = ("activation_fn", "optimizer_class", "features_extractor_class")


class ModelError(CncGymError):
    """A model file that cnc-gym cannot or will not load (one line, naming the file)."""


@dataclass(frozen=True)
class LoadedModel:
    """A policy rebuilt from an SB3 model zip, ready to act."""

    policy: Any  # stable_baselines3.common.policies.BasePolicy
    algorithm: str
    observation_space: Any  # gymnasium.spaces.Box
    action_space: Any  # gymnasium.spaces.Box
    sb3_version: str
    env_id: str = "cnc_gym/Feedrate-v0"
    env_kwargs: dict[str, Any] = dataclasses.field(default_factory=dict)
    #: The shield the model acts through (``cnc_gym_shield``), or None.
    shield: PlannerShield | None = None

    def predict(self, observation: np.ndarray, deterministic: bool = True) -> np.ndarray:
        action, _ = self.policy.predict(observation, deterministic=deterministic)
        return action


def load_sb3_model(path: str | Path) -> LoadedModel:
    """Rebuild the policy of an SB3 model zip without unpickling anything from it (see the module
    docstring); any problem is one :class:`ModelError` line naming the file."""
    path = Path(path)
    name = escaped(str(path), 200)
    if not path.is_file():
        raise ModelError(f"{name}: no such model file")
    try:
        import stable_baselines3  # noqa: F401
        import torch
    except ImportError:  # pragma: no cover - rl extra not installed
        raise ModelError("loading a trained model needs the rl extra: pip install -e '.[rl]'") from None
    if not zipfile.is_zipfile(path):
        raise ModelError(f"{name}: not a Stable-Baselines3 model (an SB3 model is a .zip file)")
    try:
        with zipfile.ZipFile(path) as archive:
            data_bytes = _member(archive, "data", MAX_DATA_BYTES)
            weights_bytes = _member(archive, "policy.pth", MAX_WEIGHTS_BYTES)
            version = b"?"
            if "_stable_baselines3_version" in archive.namelist():
                version = _member(archive, "_stable_baselines3_version", 100)
    except _Refused as exc:
        raise ModelError(f"{name}: {exc}") from None
    except Exception as exc:  # zipfile.BadZipFile, zlib.error, encrypted or unsupported members, OSError
        raise ModelError(f"{name}: not a readable model zip ({type(exc).__name__}: "
                         f"{escaped(str(exc), 120)})") from None  # fmt: skip
    import warnings

    # Only the one error line, ever: the libraries' warnings about what a crafted file holds (torch's
    # pickle protocol note, gymnasium's precision note on Box bounds) add nothing to it.
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            data = _json(data_bytes)
            family, algorithm = _family(data)
            observation_space = _box(data, "observation_space", MAX_OBSERVATION_SIZE, bounds=False)
            action_space = _box(data, "action_space", MAX_ACTION_SIZE, bounds=True)
            kwargs = _policy_kwargs(data, family)
            weights = _weights(weights_bytes, torch)
            policy = _build(family, observation_space, action_space, kwargs, weights, torch)
            env_id, env_kwargs = _env(data)
            shield = _shield(data)
        except _Refused as exc:
            raise ModelError(f"{name}: {exc}") from None
    sb3_version = escaped(version.decode("ascii", "replace"), 40)
    return LoadedModel(policy=policy, algorithm=algorithm, observation_space=observation_space,
                       action_space=action_space, sb3_version=sb3_version, env_id=env_id,
                       env_kwargs=env_kwargs, shield=shield)  # fmt: skip


def _shield(data: dict[str, Any]) -> PlannerShield | None:
    """The shield ``data["cnc_gym_shield"]`` records (plain JSON, checked), or None."""
    recorded = data.get("cnc_gym_shield")
    if recorded is None:
        return None
    try:
        return PlannerShield.from_record(recorded)
    except CncGymError as exc:
        raise _Refused(str(exc).removeprefix("shield: ")) from None


class _Refused(Exception):
    """Why a model is refused (the loader adds the file name)."""


def _member(archive: zipfile.ZipFile, member: str, limit: int) -> bytes:
    if member not in archive.namelist():
        raise _Refused(f"not a Stable-Baselines3 model (no {member!r} in the zip)")
    with archive.open(member) as f:
        content = f.read(limit + 1)  # bounded whatever the header claims (a zip bomb stops here)
    if len(content) > limit:
        raise _Refused(f"{member!r} is larger than {limit >> 20} MiB")
    return content


def _json(data_bytes: bytes) -> dict[str, Any]:
    try:
        data = json.loads(data_bytes.decode("utf-8"))
    except (UnicodeDecodeError, ValueError, RecursionError):
        raise _Refused("its 'data' entry is not valid JSON") from None
    if not isinstance(data, dict):
        raise _Refused("its 'data' entry is not a JSON object")
    return data


#: Env ids a model may name, and the keyword arguments it may record with their types.
_ENV_IDS = ENV_IDS
_ENV_KEYS: dict[str, tuple[type, ...]] = {"action_mode": (str,), "control_period_s": (int, float),
                                          "residual_range": (int, float), "lookahead_mm": (int, float),
                                          "lookahead_points": (int,)}  # fmt: skip


def _env(data: dict[str, Any]) -> tuple[str, dict[str, Any]]:
    """The env a model acts in: ``data["cnc_gym_env"]`` (plain JSON, checked), or Feedrate-v0."""
    recorded = data.get("cnc_gym_env")
    if recorded is None:
        return "cnc_gym/Feedrate-v0", {}
    if not isinstance(recorded, dict) or set(recorded) != {"id", "kwargs"} or recorded["id"] not in _ENV_IDS:
        raise _Refused(f"its cnc_gym_env record names no known env (one of {', '.join(_ENV_IDS)})")
    kwargs = recorded["kwargs"]
    if not isinstance(kwargs, dict):
        raise _Refused("its cnc_gym_env.kwargs are not a mapping")
    for key, value in kwargs.items():
        if key not in _ENV_KEYS or isinstance(value, bool) or not isinstance(value, _ENV_KEYS[key]):
            raise _Refused(f"its cnc_gym_env.kwargs.{escaped(str(key), 40)} is not an env setting a model "
                           "records")  # fmt: skip
        _check_plain(value, f"cnc_gym_env.kwargs.{key}")
    return str(recorded["id"]), dict(kwargs)


def _family(data: dict[str, Any]) -> tuple[type, str]:
    """The policy class, from the plain-text name SB3 records beside the pickled ``policy_class``."""
    recorded = data.get("policy_class")
    if not isinstance(recorded, dict):
        raise _Refused("its data has no policy_class record")
    module, init = recorded.get("__module__"), recorded.get("__init__")
    match = re.match(r"<function (\w+)\.__init__ at ", init) if isinstance(init, str) else None
    key = (module, match.group(1) if match else None)
    if key not in _FAMILIES:
        shown = escaped(f"{module}.{key[1]}", 100)
        raise _Refused(f"policy class {shown} is not one cnc-gym rebuilds without running code from the "
                       "file (MLP policies of PPO, A2C, SAC, TD3)")  # fmt: skip
    algorithm = _FAMILIES[key]
    if algorithm == "PPO/A2C":
        algorithm = "PPO" if "clip_range" in data else "A2C"
    from stable_baselines3.common.policies import ActorCriticPolicy
    from stable_baselines3.sac.policies import SACPolicy
    from stable_baselines3.td3.policies import TD3Policy

    classes = {"PPO": ActorCriticPolicy, "A2C": ActorCriticPolicy, "SAC": SACPolicy, "TD3": TD3Policy}
    return classes[algorithm], algorithm


def _box(data: dict[str, Any], key: str, max_size: int, bounds: bool) -> Any:
    """A ``Box`` space from its recorded ``_shape``, ``dtype`` and (for actions) ``low``/``high`` text."""
    import gymnasium

    recorded = data.get(key)
    if not isinstance(recorded, dict) or not str(recorded.get(":type:", "")).endswith(".spaces.box.Box'>"):
        raise _Refused(f"its {key} is not a Box (cnc-gym models observe and act in boxes)")
    shape = recorded.get("_shape")
    if (not isinstance(shape, list) or not 1 <= len(shape) <= 4
            or not all(isinstance(n, int) and not isinstance(n, bool) and n >= 1 for n in shape)
            or math.prod(shape) > max_size):  # fmt: skip
        raise _Refused(f"its {key} has an unusable shape {escaped(str(shape), 60)}")
    dtype = recorded.get("dtype")
    if dtype not in ("float32", "float64"):
        raise _Refused(f"its {key} has dtype {escaped(str(dtype), 40)} (float32 or float64 expected)")
    if not bounds:  # the policy needs only the observation's shape and dtype
        return gymnasium.spaces.Box(-np.inf, np.inf, shape=tuple(shape), dtype=dtype)
    low, high = (_numbers(recorded.get(side), math.prod(shape), f"{key}.{side}") for side in ("low", "high"))
    if not (np.all(np.isfinite(low)) and np.all(np.isfinite(high)) and np.all(low < high)):
        raise _Refused(f"its {key} bounds are not finite with low < high")
    low, high = (side.reshape(shape).astype(dtype) for side in (low, high))
    return gymnasium.spaces.Box(low, high, dtype=dtype)


def _numbers(text: Any, count: int, what: str) -> np.ndarray:
    """The numbers of a numpy array's printed form (``"[-1. -1.]"``)."""
    if not isinstance(text, str) or "..." in text or len(text) > 64 * count + 64:
        raise _Refused(f"its {what} is not a readable list of numbers")
    try:
        values = np.array([float(x) for x in text.replace("[", " ").replace("]", " ").split()])
    except ValueError:
        raise _Refused(f"its {what} is not a readable list of numbers") from None
    if values.size != count:
        raise _Refused(f"its {what} has {values.size} numbers, the shape needs {count}")
    return values


def _policy_kwargs(data: dict[str, Any], family: type) -> dict[str, Any]:
    """``policy_kwargs`` from plain values and known classes only."""
    import inspect

    import torch
    from stable_baselines3.common.sb2_compat.rmsprop_tf_like import RMSpropTFLike
    from stable_baselines3.common.torch_layers import FlattenExtractor

    recorded = data.get("policy_kwargs", {})
    if recorded is None:
        recorded = {}
    if not isinstance(recorded, dict):
        raise _Refused("its policy_kwargs are not a mapping")
    recorded = {k: v for k, v in recorded.items() if k not in (":type:", ":serialized:")}
    nn, optim = torch.nn, torch.optim
    activations = (nn.Tanh, nn.ReLU, nn.ELU, nn.LeakyReLU, nn.GELU, nn.SiLU, nn.Mish, nn.SELU, nn.CELU,
                   nn.Sigmoid, nn.Softplus, nn.Hardtanh, nn.ReLU6)  # fmt: skip
    optimizers = (optim.Adam, optim.AdamW, optim.RMSprop, optim.SGD, RMSpropTFLike)
    known_classes: dict[str, dict[str, type]] = {
        "activation_fn": {str(c): c for c in activations},
        "optimizer_class": {str(c): c for c in optimizers},
        "features_extractor_class": {str(FlattenExtractor): FlattenExtractor},
    }
    fixed = {"observation_space", "action_space", "lr_schedule"}
    allowed = set(inspect.signature(family).parameters) - fixed
    kwargs: dict[str, Any] = {}
    for key, value in recorded.items():
        if key not in allowed:
            shown = escaped(str(key), 40)
            raise _Refused(f"policy_kwargs key {shown} is not an argument of {family.__name__}")
        if key in _CLASS_KEYS:
            if value not in known_classes[key]:
                raise _Refused(f"policy_kwargs.{key} {escaped(str(value), 80)} is not one cnc-gym rebuilds "
                               "without running code from the file")  # fmt: skip
            kwargs[key] = known_classes[key][value]
        elif key == "features_extractor_kwargs":
            if value:
                raise _Refused("policy_kwargs.features_extractor_kwargs must be empty (FlattenExtractor)")
        else:
            _check_plain(value, f"policy_kwargs.{key}")
            kwargs[key] = value
    n_critics = kwargs.get("n_critics", 2)
    if isinstance(n_critics, bool) or not isinstance(n_critics, int) or not 1 <= n_critics <= 10:
        raise _Refused("policy_kwargs.n_critics must be an integer from 1 to 10")
    if family.__name__ == "ActorCriticPolicy" and isinstance(data.get("use_sde"), bool):
        kwargs.setdefault("use_sde", data["use_sde"])  # PPO/A2C pass use_sde beside policy_kwargs
    return kwargs


def _check_plain(value: Any, what: str, depth: int = 0) -> None:
    """JSON data only: numbers, flags, short text, and short lists and mappings of them."""
    if depth > 4:
        raise _Refused(f"{what} is nested too deeply")
    if value is None or isinstance(value, bool | int | float):
        if isinstance(value, float) and not math.isfinite(value):
            raise _Refused(f"{what} holds a non-finite number")
        return
    if isinstance(value, str) and len(value) <= 40:
        return
    if isinstance(value, list) and len(value) <= 64:
        for item in value:
            _check_plain(item, what, depth + 1)
        return
    if isinstance(value, dict) and len(value) <= 64:
        for key, item in value.items():
            _check_plain(item, f"{what}.{escaped(str(key), 40)}", depth + 1)
        return
    raise _Refused(f"{what} is not a plain value")


def _weights(weights_bytes: bytes, torch: Any) -> dict[str, Any]:
    try:
        weights = torch.load(io.BytesIO(weights_bytes), map_location="cpu", weights_only=True)
    except Exception:  # pickle.UnpicklingError for anything but tensors, RuntimeError for a broken file …
        raise _Refused("'policy.pth' holds something other than tensors, or is damaged (refused: "
                       "loading it could run code)") from None  # fmt: skip
    if not isinstance(weights, dict) or not all(
        isinstance(k, str) and isinstance(v, torch.Tensor) for k, v in weights.items()
    ):
        raise _Refused("'policy.pth' is not a mapping of names to tensors")
    if sum(int(v.numel()) for v in weights.values()) > MAX_PARAMETERS:
        raise _Refused(f"'policy.pth' holds more than {MAX_PARAMETERS} weights")
    for key, tensor in weights.items():
        if not torch.is_floating_point(tensor) or not bool(torch.isfinite(tensor).all()):
            raise _Refused(f"weight {escaped(key, 60)} is not finite floating-point")
    return weights


def _build(family: type, observation_space: Any, action_space: Any, kwargs: dict[str, Any],
           weights: dict[str, Any], torch: Any) -> Any:  # fmt: skip
    """The policy, built from known classes and plain values, with exactly the file's weights."""
    n_weights = sum(int(v.numel()) for v in weights.values())
    _check_size(kwargs.get("net_arch"), math.prod(observation_space.shape), n_weights)
    # Acting needs no optimizer: the policy gets a stand-in (a torch optimizer's first use imports
    # torch's compiler, seconds of start-up for nothing); the file's optimizer choice is checked above.
    kwargs = {**kwargs, "optimizer_class": _NoOptimizer, "optimizer_kwargs": {}}
    try:
        policy = family(observation_space, action_space, lambda _: 0.0, **kwargs)
    except (TypeError, ValueError, AssertionError, KeyError) as exc:
        why = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise _Refused(f"its policy_kwargs do not build a {family.__name__}: {escaped(why, 120)}") from None
    try:
        policy.load_state_dict(weights, strict=True)
    except RuntimeError as exc:
        first = escaped(" ".join(str(exc).split()), 160)
        raise _Refused(f"its weights do not fit the policy its data describes ({first})") from None
    policy.set_training_mode(False)
    return policy


class _NoOptimizer:
    """Stands in for the training optimizer a policy builds; a loaded policy only acts."""

    def __init__(self, params: Any, **kwargs: Any) -> None:
        self.param_groups: list[dict[str, Any]] = []


def _check_size(net_arch: Any, n_inputs: int, n_weights: int) -> None:
    """Refuse a ``net_arch`` that asks for a much larger network than the file's weights (a small file
    must not make the loader allocate gigabytes before the weights are compared)."""
    if net_arch is None:
        return
    layers = list(net_arch.values()) if isinstance(net_arch, dict) else [net_arch]
    wanted = 0
    for sizes in layers:
        if not isinstance(sizes, list) or not all(type(n) is int and n >= 1 for n in sizes):
            raise _Refused("policy_kwargs.net_arch must be lists of positive layer sizes")
        widths = [n_inputs, *sizes]
        wanted += sum(a * b for a, b in itertools.pairwise(widths))
    if wanted > 4 * n_weights + 10_000:
        raise _Refused(f"policy_kwargs.net_arch asks for {wanted} weights, the file holds {n_weights}")


class ModelPolicy:
    """A trained SB3 model (deterministic actions) driving the env, through the shield its zip
    records, if any (:mod:`cnc_gym.policies.shield`)."""

    def __init__(self, path: str | Path, deterministic: bool = True) -> None:
        self.path = Path(path)
        self.name = self.path.name
        self.deterministic = deterministic
        self.model = load_sb3_model(self.path)
        #: The env the model acts in (what ``cnc-gym bench`` and ``cnc-gym run`` build for it).
        self.env_id = self.model.env_id
        self.env_kwargs = dict(self.model.env_kwargs)
        self._shield: BoundShield | None = None
        self._first_step = False

    def reset(self, env: Any) -> None:
        want = self.model.observation_space.shape
        have = env.observation_space.shape
        if want != have:
            raise CncGymError(
                f"{self.name}: model expects observations of shape {want}, the env gives {have}"
            )
        if self.model.action_space.shape != env.action_space.shape:
            raise CncGymError(f"{self.name}: model acts in shape {self.model.action_space.shape}, "
                              f"the env expects {env.action_space.shape}")  # fmt: skip
        shield = self.model.shield
        if shield is not None:
            try:
                self._shield = shield.bind(env)
            except CncGymError as exc:
                raise CncGymError(f"{self.name}: {exc}") from None
        self._first_step = True

    def act(self, observation: np.ndarray, info: dict[str, Any]) -> np.ndarray:
        action = self.model.predict(observation, deterministic=self.deterministic)
        action = np.asarray(action, dtype=np.float32)
        if self._shield is not None:
            if self._first_step and self._shield.outside(observation):
                # Once per machine and process (the warnings module shows a message once per place).
                warnings.warn(f"{self.name}: the machine lies outside the envelope the model was trained "
                              f"on ({self._shield.outside_entries(observation)}); it acts as the planner",
                              stacklevel=2)  # fmt: skip
            self._first_step = False
            return self._shield.apply(observation, action)
        return action
