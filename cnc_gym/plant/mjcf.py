"""The MJCF model of a 3-axis vertical machining centre, built from a machine preset's ``plant`` section.

Layout (a C-frame VMC, SI units: metres, kilograms, newtons)::

    world ── bed, column (fixed)
      ├── saddle          slide Y (axis −Y: the saddle moves opposite to the tool's Y)
      │     └── table     slide X (axis −X), carried by the saddle
      │     └── X motor   slide X (compliant axes only), mounted on the saddle
      ├── Y motor         slide Y (compliant axes only)
      ├── head            slide Z (+Z), on the column
      └── Z motor         slide Z (compliant axes only)

Every joint coordinate is the machine coordinate of its axis in metres (the table and the saddle move
opposite to the tool, so their joint axes point the other way), so the tool tip relative to the table
is exactly ``(x, y, z)``. A rigid axis is one body; the motor side's inertia is the joint's
``armature`` (a reflected inertia: it resists that axis's acceleration only, and the axes that carry it
do not feel it). A compliant axis has a second body for the motor side (a small mass whose ``armature``
is the motor-side inertia) joined to the load by a fixed tendon ``load − motor`` with the coupling's
stiffness and damping; backlash is the tendon spring's dead band (``springlength`` = ±backlash/2; the
tendon's damping has no dead band, so it also acts inside the gap).

Guideway friction acts on the load joints: viscous ``damping`` and Coulomb ``frictionloss``. Gravity is
off (a VMC's Z is counterbalanced; X and Y move horizontally) and so are contacts (nothing touches).

One model holds ``n_envs`` machines (bodies ``e<i>_…``), stepped together by one ``mj_step``: the mass
matrix is block-diagonal, so machines do not interact. Only machine 0 is drawn; the others' geoms are in
geom group 5, hidden by default.
"""

from __future__ import annotations

from dataclasses import dataclass

from cnc_gym.machine import AXIS_NAMES, AxisMechanicsConfig, MachineConfig

#: Mass of the motor-side body of a compliant axis (its inertia along the axis is the joint's armature).
MOTOR_BODY_KG = 1e-3
#: Height of the tool tip above the table top at Z = 0 (drawing only).
TOOL_TIP_ABOVE_TABLE_M = 0.05
_HIDDEN_GROUP = 5
_COLOURS = {"bed": "0.35 0.37 0.4 1", "saddle": "0.55 0.58 0.62 1", "table": "0.7 0.72 0.75 1",
            "head": "0.25 0.45 0.7 1", "tool": "0.85 0.85 0.2 1"}  # fmt: skip


@dataclass(frozen=True)
class AxisNames:
    """MJCF names of one axis of one machine."""

    load_joint: str
    motor_joint: str | None
    actuator: str


def axis_names(env: int, axis: int, mechanics: AxisMechanicsConfig) -> AxisNames:
    """The joint and actuator names of ``axis`` (0, 1, 2 = X, Y, Z) of machine ``env``."""
    name = f"e{env}_{AXIS_NAMES[axis]}"
    compliant = mechanics.coupling_stiffness_n_um > 0
    return AxisNames(f"{name}_load", f"{name}_motor" if compliant else None, name)


def _f(x: float) -> str:
    return repr(float(x))


def _joint(name: str, axis: str, mech: AxisMechanicsConfig, load: bool, timestep_s: float) -> str:
    attrs = [f'name="{name}"', 'type="slide"', f'axis="{axis}"']
    if load:
        attrs.append(f'damping="{_f(mech.viscous_damping_n_s_m)}"')
        if mech.coulomb_friction_n > 0:
            # The stiffest friction constraint MuJoCo allows at this timestep (time constant 2·timestep),
            # close to hard: a force below the friction level leaves the axis (almost) still.
            attrs += [f'frictionloss="{_f(mech.coulomb_friction_n)}"',
                      f'solreffriction="{_f(2 * timestep_s)} 1"', 'solimpfriction="0.99 0.999 0.001"']
        if mech.coupling_stiffness_n_um == 0:
            attrs.append(f'armature="{_f(mech.motor_mass_kg)}"')
    else:
        attrs.append(f'armature="{_f(mech.motor_mass_kg)}"')
    return f"<joint {' '.join(attrs)}/>"


def _box(size: str, pos: str, colour: str, group: int) -> str:
    return (f'<geom type="box" size="{size}" pos="{pos}" rgba="{colour}" group="{group}" '
            'contype="0" conaffinity="0"/>')  # fmt: skip


def _motor_body(env: int, axis: int, mech: AxisMechanicsConfig, joint_axis: str, timestep_s: float) -> str:
    names = axis_names(env, axis, mech)
    if names.motor_joint is None:
        return ""
    joint = _joint(names.motor_joint, joint_axis, mech, load=False, timestep_s=timestep_s)
    return (f'<body name="{names.motor_joint}"><inertial pos="0 0 0" mass="{MOTOR_BODY_KG}" '
            f'diaginertia="1e-6 1e-6 1e-6"/>{joint}</body>')  # fmt: skip


def _machine(env: int, machine: MachineConfig) -> str:
    """The bodies of machine ``env``."""
    plant = machine.plant
    group = 0 if env == 0 else _HIDDEN_GROUP
    mx, my, mz = plant.axes.x, plant.axes.y, plant.axes.z
    h = plant.timestep_s
    c = _COLOURS
    tip = TOOL_TIP_ABOVE_TABLE_M
    parts = []
    if env == 0:
        parts += [_box("0.55 0.5 0.1", "0 0 -0.3", c["bed"], 0),  # the bed
                  _box("0.3 0.12 0.7", "0 0.62 0.3", c["bed"], 0)]  # the column  # fmt: skip
    parts.append(
        f'<body name="e{env}_saddle"><inertial pos="0 0 0" mass="{_f(my.load_mass_kg)}" diaginertia="1 1 1"/>'
        f'{_joint(axis_names(env, 1, my).load_joint, "0 -1 0", my, True, h)}'
        f'{_box("0.28 0.3 0.04", "0 0 -0.14", c["saddle"], group)}'
        f'<body name="e{env}_table"><inertial pos="0 0 0" mass="{_f(mx.load_mass_kg)}" diaginertia="1 1 1"/>'
        f'{_joint(axis_names(env, 0, mx).load_joint, "-1 0 0", mx, True, h)}'
        f'{_box("0.45 0.2 0.04", "0 0 -0.05", c["table"], group)}'
        f'<site name="e{env}_work" pos="0 0 {tip}" group="5"/></body>'
        f'{_motor_body(env, 0, mx, "-1 0 0", h)}</body>'
    )
    parts.append(_motor_body(env, 1, my, "0 -1 0", h))
    parts.append(
        f'<body name="e{env}_head" pos="0 0 {tip}"><inertial pos="0 0 0" mass="{_f(mz.load_mass_kg)}" '
        f'diaginertia="1 1 1"/>{_joint(axis_names(env, 2, mz).load_joint, "0 0 1", mz, True, h)}'
        f'{_box("0.1 0.2 0.15", "0 0.3 0.32", c["head"], group)}'  # the head on the column's ways
        f'{_box("0.065 0.08 0.1", "0 0.08 0.22", c["head"], group)}'  # the spindle's nose
        f'<geom type="cylinder" size="0.045 0.07" pos="0 0 0.16" rgba="{c["head"]}" group="{group}" '
        f'contype="0" conaffinity="0"/>'
        f'<geom type="cylinder" size="0.005 0.045" pos="0 0 0.045" rgba="{c["tool"]}" group="{group}" '
        f'contype="0" conaffinity="0"/><site name="e{env}_tool" pos="0 0 0" group="5"/></body>'
    )
    parts.append(_motor_body(env, 2, mz, "0 0 1", h))
    return "".join(parts)


def _tendons(env: int, machine: MachineConfig) -> str:
    out = []
    for axis in range(3):
        mech = machine.plant.axes.axis(axis)
        names = axis_names(env, axis, mech)
        if names.motor_joint is None:
            continue
        half_gap = mech.backlash_mm / 2000.0
        out.append(
            f'<fixed name="{names.actuator}_coupling" stiffness="{_f(mech.coupling_stiffness_n_um * 1e6)}" '
            f'damping="{_f(mech.coupling_damping_n_s_m)}" springlength="{_f(-half_gap)} {_f(half_gap)}">'
            f'<joint joint="{names.load_joint}" coef="1"/>'
            f'<joint joint="{names.motor_joint}" coef="-1"/></fixed>'
        )
    return "".join(out)


def _actuators(env: int, machine: MachineConfig) -> str:
    """One actuator per axis on the motor side (the load of a rigid axis). Gains are set after compiling
    (:class:`~cnc_gym.plant.mujoco.MujocoPlant` tunes them to the compiled masses)."""
    out = []
    for axis, servo in enumerate(machine.axes):
        mech = machine.plant.axes.axis(axis)
        names = axis_names(env, axis, mech)
        joint = names.motor_joint or names.load_joint
        if servo.velocity_loop_hz > 0:  # force command (the current loop's output)
            out.append(f'<motor name="{names.actuator}" joint="{joint}"/>')
        else:  # velocity command; the velocity feedback −Kp·v is the actuator's bias (integrated implicitly)
            out.append(f'<general name="{names.actuator}" joint="{joint}" gainprm="1" biastype="affine" '
                       'biasprm="0 0 -1"/>')  # fmt: skip
    return "".join(out)


def machine_mjcf(machine: MachineConfig, n_envs: int = 1, width: int = 640, height: int = 480) -> str:
    """The MJCF text of ``n_envs`` copies of ``machine`` (offscreen buffer ``width`` × ``height``)."""
    bodies = "".join(_machine(e, machine) for e in range(n_envs))
    tendons = "".join(_tendons(e, machine) for e in range(n_envs))
    actuators = "".join(_actuators(e, machine) for e in range(n_envs))
    return (
        f'<mujoco model="vmc-{machine.name}">'
        f'<option timestep="{_f(machine.plant.timestep_s)}" gravity="0 0 0" integrator="implicitfast">'
        '<flag contact="disable"/></option>'
        f'<visual><global offwidth="{width}" offheight="{height}"/><quality shadowsize="0"/></visual>'
        '<worldbody><light pos="0.5 -1 1.5" dir="-0.3 0.6 -1" diffuse="0.8 0.8 0.8"/>'
        f"{bodies}</worldbody>"
        f"{'<tendon>' + tendons + '</tendon>' if tendons else ''}"
        f"<actuator>{actuators}</actuator></mujoco>"
    )
