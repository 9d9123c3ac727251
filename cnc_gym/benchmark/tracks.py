"""Benchmark tracks: which plant the episodes run on, against the nominal machine the planners know.

==============  ====================================================================================
``nominal``     the suite's machine as its preset gives it: the plant is the nominal machine (default)
``mujoco``      the MuJoCo plant of the machine's preset (masses, guideway friction, ball-screw
                compliance, backlash): the loops of the nominal machine driving real mechanics
``perturbed``   the ``mujoco`` plant with its loop and mechanics parameters drawn, per program, from
                :data:`PERTURBATION` (seeded by the track version, the suite and the program): a
                machine that differs from its parameter table as real ones do
==============  ====================================================================================

On every track the time-optimal bound is the nominal machine's (it depends on the path and the
controller's limits only, which no track changes), the deployable planner plans on the nominal machine
(it cannot know the true plant), the ``oracle`` simulates the true plant, and ``nominal-oracle`` plans
by simulating the nominal machine and then runs that schedule on the true plant. The records name the
track and, on ``perturbed``, the drawn parameters (:func:`track_plant`), and every policy of a program
meets the same plant.

The ``mujoco`` plant of a preset ``M``: the preset ``M-mujoco`` where it exists and has the same
controller and axes as ``M`` (``vmc-small-mujoco`` for the default ``vmc-small``), else ``M``'s own
``plant`` section, run with the MuJoCo backend.
"""

from __future__ import annotations

import dataclasses
import hashlib
from dataclasses import dataclass
from typing import Any

import numpy as np

from cnc_gym.errors import CncGymError
from cnc_gym.machine import AXIS_NAMES, MachineConfig, load_machine, machine_names, with_plant_backend

TRACKS = ("nominal", "perturbed", "mujoco")
DEFAULT_TRACK = "nominal"
#: Version of the perturbed track's distribution and its seeding: a change is a new version.
PERTURBED_VERSION = 1


@dataclass(frozen=True)
class Perturbation:
    """The perturbed track's distribution: every draw uniform in its range, per program.

    - ``kv_scale``: one factor on every axis's position-loop gain Kv (the machine's gains drift from
      the table: load, temperature, retuning);
    - ``kv_mismatch``: each axis's Kv further × (1 + u), u in this range (unequal gains between axes,
      the classic source of contour error of a P position loop);
    - ``velocity_loop_scale``: each axis's velocity-loop bandwidth × this (inertia and tuning spread);
    - ``feedforward_error``: added to each axis's velocity feed-forward fraction (kept in [0, 1]);
    - ``friction_scale``: each axis's guideway Coulomb friction × this;
    - ``backlash_mm``: each axis's ball-screw backlash (replaces the preset's).
    """

    kv_scale: tuple[float, float] = (0.85, 1.15)
    kv_mismatch: tuple[float, float] = (-0.05, 0.05)
    velocity_loop_scale: tuple[float, float] = (0.7, 1.3)
    feedforward_error: tuple[float, float] = (-0.1, 0.1)
    friction_scale: tuple[float, float] = (0.5, 2.0)
    backlash_mm: tuple[float, float] = (0.0, 0.010)


#: The distribution of the perturbed track (version :data:`PERTURBED_VERSION`); docs/benchmark.md gives
#: each range with its source.
PERTURBATION = Perturbation()


def check_track(track: str) -> str:
    if track not in TRACKS:
        raise CncGymError(f"--track must be one of {', '.join(TRACKS)}, got {track!r}")
    return track


def mujoco_machine(nominal: MachineConfig) -> MachineConfig:
    """The MuJoCo plant of ``nominal``'s preset (the module docstring): a machine with ``nominal``'s
    controller and axes and the mechanics of ``<name>-mujoco`` where that preset matches it."""
    companion = f"{nominal.name}-mujoco"
    mechanics = nominal.plant
    if nominal.plant.backend != "mujoco" and companion in machine_names():
        other = load_machine(companion)
        if other.controller == nominal.controller and other.axes == nominal.axes:
            mechanics = other.plant
    return with_plant_backend(dataclasses.replace(nominal, plant=mechanics), "mujoco")


def _rng(suite: str, program: str) -> np.random.Generator:
    digest = hashlib.sha256(f"cnc-gym perturbed track v{PERTURBED_VERSION}\0{suite}\0{program}".encode())
    return np.random.default_rng(int.from_bytes(digest.digest()[:8], "little"))


def perturbed_machine(nominal: MachineConfig, suite: str, program: str,
                      dist: Perturbation = PERTURBATION) -> tuple[MachineConfig, dict[str, Any]]:  # fmt: skip
    """The perturbed track's plant for one program of a suite: ``(machine, parameters)``, the same on
    every call (and so for every policy); ``parameters`` are what the record keeps."""
    base = mujoco_machine(nominal)
    rng = _rng(suite, program)

    def draw(pair: tuple[float, float], size: int | None = None) -> Any:
        return rng.uniform(pair[0], pair[1], size)

    level = float(draw(dist.kv_scale))
    mismatch = draw(dist.kv_mismatch, 3)
    loop = draw(dist.velocity_loop_scale, 3)
    ff_err = draw(dist.feedforward_error, 3)
    friction = draw(dist.friction_scale, 3)
    backlash = draw(dist.backlash_mm, 3)
    axes = []
    for i, axis in enumerate(base.axes):
        axes.append(dataclasses.replace(
            axis, kv_1_s=float(axis.kv_1_s * level * (1.0 + mismatch[i])),
            velocity_loop_hz=float(axis.velocity_loop_hz * loop[i]),
            feedforward=float(np.clip(axis.feedforward + ff_err[i], 0.0, 1.0))))  # fmt: skip
    mech = {}
    for i, name in enumerate(AXIS_NAMES):
        m = getattr(base.plant.axes, name)
        # A dead band sits between two bodies: an axis without a coupling stays rigid (no backlash).
        lash = float(backlash[i]) if m.coupling_stiffness_n_um > 0 else 0.0
        mech[name] = dataclasses.replace(m, coulomb_friction_n=float(m.coulomb_friction_n * friction[i]),
                                         backlash_mm=lash)  # fmt: skip
    plant = dataclasses.replace(base.plant, axes=dataclasses.replace(base.plant.axes, **mech))
    machine = load_machine(dataclasses.replace(base, axes=tuple(axes), plant=plant))
    parameters = {
        "version": PERTURBED_VERSION,
        **{f"{k}": [float(getattr(a, k)) for a in machine.axes] for k in ("kv_1_s", "velocity_loop_hz",
                                                                          "feedforward")},
        "coulomb_friction_n": [float(getattr(plant.axes, n).coulomb_friction_n) for n in AXIS_NAMES],
        "backlash_mm": [float(getattr(plant.axes, n).backlash_mm) for n in AXIS_NAMES],
    }  # fmt: skip
    return machine, parameters


def track_plant(track: str, nominal: MachineConfig, suite: str,
                program: str) -> tuple[MachineConfig, dict[str, Any] | None]:  # fmt: skip
    """The machine the episodes of ``program`` run on under ``track`` and the parameters a record keeps
    (None on ``nominal`` and ``mujoco``, whose plant is the preset's)."""
    check_track(track)
    if track == "nominal":
        return nominal, None
    if track == "mujoco":
        return mujoco_machine(nominal), None
    return perturbed_machine(nominal, suite, program)
