#!/usr/bin/env python3
"""The MuJoCo plant's figures in docs/plant.md: agreement with the LTI plant, friction, backlash, speed.

Every run is a circle R 50 mm at F5000 (two turns, the last one measured) or a line, stepped through the
plant interface directly (no controller), as the tests in tests/plant/test_mujoco.py do.

    .venv/bin/python scripts/mujoco_plant.py            # all tables
    .venv/bin/python scripts/mujoco_plant.py --speed    # only the plant step timing
    .venv/bin/python scripts/mujoco_plant.py --plot docs/images/plant   # also the figures
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import statistics
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from cnc_gym.machine import MachineConfig, load_machine, with_plant_backend
from cnc_gym.plant import ServoPlant
from cnc_gym.plant.mujoco import MujocoPlant

PERIOD = 0.002
F5000 = 5000.0 / 60.0
# The friction tables build P-velocity-loop machines with friction on purpose (the plant warns about them).
warnings.filterwarnings("ignore", message=".*with a P velocity loop the Coulomb friction")


def with_mechanics(machine: MachineConfig | str, **mechanics) -> MachineConfig:
    machine = load_machine(machine)
    axes = machine.plant.axes
    changed = {n: dataclasses.replace(getattr(axes, n), **mechanics) for n in ("x", "y", "z")}
    plant = dataclasses.replace(machine.plant, backend="mujoco", axes=dataclasses.replace(axes, **changed))
    return dataclasses.replace(machine, plant=plant)


RIGID = {"coulomb_friction_n": 0.0, "viscous_damping_n_s_m": 0.0, "coupling_stiffness_n_um": 0.0,
         "backlash_mm": 0.0, "velocity_integral_time_s": 0.0}  # fmt: skip


def circle(radius: float = 50.0, speed: float = F5000, turns: float = 2.0) -> np.ndarray:
    omega = speed / radius
    t = np.arange(1, round(turns * 2 * math.pi / omega / PERIOD) + 1) * PERIOD
    return np.stack((radius * np.cos(omega * t), radius * np.sin(omega * t), np.zeros_like(t)), axis=1)


def radial_um(plant, ref: np.ndarray, radius: float = 50.0) -> tuple[np.ndarray, np.ndarray]:
    """(angle in degrees, radial error in µm) over the second half of ``ref``."""
    plant.reset(np.array([radius, 0.0, 0.0]))
    actual = plant.step(ref)
    half = slice(len(ref) // 2, None)
    angle = np.degrees(np.arctan2(ref[half, 1], ref[half, 0])) % 360
    return angle, (np.hypot(actual[half, 0], actual[half, 1]) - radius) * 1e3


def agreement() -> None:
    ref = circle()
    closed = 50 * (1 - 1 / math.sqrt(1 + (F5000 / (50 * 30)) ** 2)) * 1e3
    print("## Rigid, frictionless: MuJoCo against the LTI plant (circle R 50 F5000)\n")
    print("| preset | timestep | LTI radial error (µm) | MuJoCo (µm) | max |MuJoCo − LTI| position (µm) |")
    print("|---|---|---|---|---|")
    for preset in ("p-loop-30", "vmc-small"):
        for timestep in (0.001, 0.0005, 0.00025):
            machine = with_mechanics(preset, **RIGID)
            plant = dataclasses.replace(machine.plant, timestep_s=timestep)
            machine = dataclasses.replace(machine, plant=plant)
            lti, mj = ServoPlant(machine), MujocoPlant(machine)
            for p in (lti, mj):
                p.reset(np.array([50.0, 0, 0]))
            a, b = lti.step(ref), mj.step(ref)
            _, r_lti = radial_um(ServoPlant(machine), ref)
            _, r_mj = radial_um(MujocoPlant(machine), ref)
            print(f"| {preset} | {timestep * 1e3:g} ms | {r_lti.min():.2f} … {r_lti.max():.2f} | "
                  f"{r_mj.min():.2f} … {r_mj.max():.2f} | {np.abs(a - b).max() * 1e3:.3f} |")  # fmt: skip
    print(f"\np-loop-30 closed form R(1 − 1/√(1 + (v/(R·Kv))²)) = {-closed:.2f} µm\n")
    print("Presets without a plant section on MuJoCo (default mechanics: rigid, no friction), same circle:\n")
    print("| preset | max |MuJoCo − LTI| (µm) | over the second turn (µm) |")
    print("|---|---|---|")
    for preset in ("vmc-small", "p-loop-30", "gsk25i", "h4cm"):
        machine = with_plant_backend(load_machine(preset), "mujoco")
        lti, mj = ServoPlant(machine), MujocoPlant(machine)
        for p in (lti, mj):
            p.reset(np.array([50.0, 0, 0]))
        diff = np.abs(lti.step(ref) - mj.step(ref)) * 1e3
        print(f"| {preset} | {diff.max():.3f} | {diff[len(ref) // 2 :].max():.3f} |")
    print()


def friction() -> None:
    print("## Coulomb friction on vmc-small's loops (rigid axes; circle R 50 F5000)\n")
    print("| friction (N) | velocity loop | X: F/K (µm) | peak after X reversals (µm) | "
          "peak after Y reversals (µm) | largest 30° after to 2° before the next reversal (µm) |")
    print("|---|---|---|---|---|---|")
    ref = circle()
    for integral in (0.0, 0.01):
        base = with_mechanics("vmc-small", **{**RIGID, "velocity_integral_time_s": integral})
        angle, r0 = radial_um(MujocoPlant(base), ref)
        for force in (60.0, 120.0, 240.0):
            plant = MujocoPlant(with_mechanics(base, coulomb_friction_n=force))
            _, r = radial_um(plant, ref)
            dev = r - r0
            k = plant.loop_stiffness_n_m[0]
            after = [(angle >= c) & (np.abs((angle - c - 5 + 180) % 360 - 180) < 5)
                     for c in (0, 90, 180, 270)]  # fmt: skip
            px = max(np.abs(dev[after[0]]).max(), np.abs(dev[after[2]]).max())
            py = max(np.abs(dev[after[1]]).max(), np.abs(dev[after[3]]).max())
            away = np.ones_like(angle, dtype=bool)
            for c in (0, 90, 180, 270):
                away &= ~((angle >= c - 2) & (np.abs((angle - c - 14 + 180) % 360 - 180) < 16))
            loop = f"PI, Tn {integral * 1e3:g} ms" if integral else "P"
            print(f"| {force:g} | {loop} | {force / k[0] * 1e6:.1f} | {px:.1f} | {py:.1f} | "
                  f"{np.abs(dev[away]).max():.2f} |")  # fmt: skip
    print()


def backlash() -> None:
    print("## Backlash (vmc-small-mujoco, X out and back at F1000, friction 120 N, k 180 N/µm)\n")
    print("| dead band b (µm) | load − motor, forward (µm) | backward (µm) | jump (µm) | b + 2F/k (µm) |")
    print("|---|---|---|---|---|")
    t = np.arange(1, 1001) * PERIOD
    ref = np.stack((np.where(t < 1.0, t, 2.0 - t) * 1000 / 60, 0 * t, 0 * t), axis=1)
    for b in (0.0, 0.003, 0.01, 0.02):
        plant = MujocoPlant(with_mechanics("vmc-small-mujoco", backlash_mm=b, viscous_damping_n_s_m=0.0))
        plant.step(ref[:450])
        forward = (plant.position - plant.motor_position)[0, 0] * 1e3
        plant.step(ref[450:])
        back = (plant.position - plant.motor_position)[0, 0] * 1e3
        expected = b * 1e3 + 2 * 120 / 180e6 * 1e6
        print(f"| {b * 1e3:g} | {forward:.3f} | {back:.3f} | {back - forward:.3f} | {expected:.3f} |")
    print()


def effects() -> None:
    print("## vmc-small-mujoco: what each effect does to the circle R 50 F5000 (radial error, µm)\n")
    print("| plant | min | max |")
    print("|---|---|---|")
    ref = circle()
    _, r = radial_um(ServoPlant(load_machine("vmc-small")), ref)
    print(f"| LTI (vmc-small) | {r.min():.1f} | {r.max():.1f} |")
    full = load_machine("vmc-small-mujoco")
    cases = {
        "MuJoCo, rigid, no friction, P velocity loop": RIGID,
        "+ PI velocity loop (Tn 10 ms)": {**RIGID, "velocity_integral_time_s": 0.01},
        "+ viscous and Coulomb friction": {"coupling_stiffness_n_um": 0.0, "backlash_mm": 0.0},
        "+ screw compliance (180 N/µm)": {"backlash_mm": 0.0},
        "+ backlash 3 µm (the preset)": {},
    }
    for label, changes in cases.items():
        _, r = radial_um(MujocoPlant(with_mechanics(full, **changes)), ref)
        print(f"| {label} | {r.min():.1f} | {r.max():.1f} |")
    print()


def speed(repeats: int = 5, steps: int = 400) -> None:
    print("## Plant step, 5 servo samples (10 ms) per call, median of interleaved repeats\n")
    print("| machine | envs | LTI (µs/call) | MuJoCo (µs/call) | ratio |")
    print("|---|---|---|---|---|")
    for preset in ("vmc-small-mujoco",):
        machine = load_machine(preset)
        for n_envs in (1, 8):
            plants = {"lti": ServoPlant(machine, n_envs), "mujoco": MujocoPlant(machine, n_envs)}
            times: dict[str, list[float]] = {k: [] for k in plants}
            ref = np.zeros((n_envs, 5, 3))
            for p in plants.values():
                p.step(ref)  # compile / warm up
            for _ in range(repeats):
                for name, p in plants.items():
                    start = time.perf_counter()
                    for i in range(steps):
                        ref[:, :, 0] = i * 0.05
                        p.step(ref)
                    times[name].append((time.perf_counter() - start) / steps * 1e6)
            lti, mj = statistics.median(times["lti"]), statistics.median(times["mujoco"])
            print(f"| {preset} | {n_envs} | {lti:.1f} | {mj:.1f} | {mj / lti:.0f}× |")
    print()


def plots(folder: Path) -> None:
    """quadrant_glitches.png (radial error round the circle, friction off and on) and machine.png (MuJoCo's
    off-screen picture of vmc-small-mujoco cutting the star, where OpenGL can be had)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    folder.mkdir(parents=True, exist_ok=True)
    ref = circle()
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.6), sharey=True)
    for ax, integral in zip(axes, (0.0, 0.01), strict=True):
        base = with_mechanics("vmc-small", **{**RIGID, "velocity_integral_time_s": integral})
        for force in (0.0, 60.0, 120.0, 240.0):
            angle, r = radial_um(MujocoPlant(with_mechanics(base, coulomb_friction_n=force)), ref)
            order = np.argsort(angle)
            ax.plot(angle[order], r[order], lw=1.2, label=f"{force:g} N")
        for reversal in (0, 90, 180, 270):
            ax.axvline(reversal, color="0.8", lw=0.8, zorder=0)
        loop = f"PI velocity loop (Tn {integral * 1e3:g} ms)" if integral else "P velocity loop"
        ax.set_title(f"vmc-small loops, rigid axes, {loop}", fontsize=9)
        ax.set_xlabel("angle on the circle (°); axis reversals at 0, 90, 180, 270", fontsize=8)
        ax.set_xticks(range(0, 361, 45))
    axes[0].set_ylabel("radial error (µm)", fontsize=8)
    axes[1].legend(title="Coulomb friction", fontsize=7, title_fontsize=7)
    fig.suptitle("MuJoCo plant, circle R 50 mm at F5000: quadrant glitches", fontsize=10)
    fig.tight_layout()
    fig.savefig(folder / "quadrant_glitches.png", dpi=100)
    plt.close(fig)
    print(f"wrote {folder / 'quadrant_glitches.png'}")

    import gymnasium

    import cnc_gym  # noqa: F401  (registers the env ids)

    env = gymnasium.make("cnc_gym/Feedrate-v0", programs=["star"], machine="vmc-small-mujoco",
                         render_mode="rgb_array")  # fmt: skip
    env.reset(seed=0)
    for _ in range(400):
        env.step(np.array([0.6], dtype=np.float32))
    renderer = env.unwrapped._renderer
    image = env.render()
    if renderer._view is not None and renderer._view.available:
        plt.imsave(folder / "machine.png", image)
        print(f"wrote {folder / 'machine.png'}")
    else:
        print("no off-screen OpenGL here: machine.png not written")
    env.close()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--speed", action="store_true", help="only the step timing")
    parser.add_argument("--plot", metavar="DIR", help="also write the figures into DIR")
    args = parser.parse_args(argv)
    if args.plot:
        plots(Path(args.plot))
    if not args.speed:
        agreement()
        friction()
        backlash()
        effects()
    speed()
    return 0


if __name__ == "__main__":
    sys.exit(main())
