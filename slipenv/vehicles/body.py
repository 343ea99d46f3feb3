"""Build a vehicle's PyBullet body from its :class:`VehicleSpec`.

Wheels collide as spheres: a sphere touches the ground at one point straight below its
centre, which is where the terramechanic force belongs, and sphere contacts stay smooth on
heightfields where cylinder edges chatter. The visual shape is a cylinder. Every contact
friction coefficient is set to zero so that PyBullet carries only normal contact and rigid-body
motion and the injected force law carries traction and side force (DESIGN §3).
"""

from __future__ import annotations

import hashlib
import math
import os
import re
import tempfile
from dataclasses import dataclass

import pybullet_data

from slipenv.contracts.constants import G_MPS2
from slipenv.pybullet_quiet import import_pybullet
from slipenv.vehicles.spec import VehicleSpec

p = import_pybullet()  # the banner-free first import (see slipenv.pybullet_quiet)

_CYLINDER_ALONG_Y = (math.sin(math.pi / 4), 0.0, 0.0, math.cos(math.pi / 4))
# The pivoting axle beam, as light as the steering links: its wheels carry the mass.
_PIVOT_AXLE_MASS_KG = 0.05


@dataclass
class VehicleBody:
    """Handles of a vehicle in one PyBullet client.

    Attributes
    ----------
    body_id : int
        Multibody id.
    wheel_links : list[int]
        Link index of each wheel, in ``spec.wheels`` order.
    spin_joints : list[int | None]
        Spin joint of each wheel (``None`` for castors).
    steer_joints : list[int | None]
        Steering joint of each wheel (``None`` if not steered).
    base_to_reference_m : tuple[float, float, float]
        Position of the chassis reference point (wheel-centre plane, midway between the
        contact lines) in the base frame [m].
    contact_radius_m : float
        Collision radius of the driven wheels: height of the wheel centres above the ground [m].
    pivot_joint : int | None
        The passive roll joint of ``spec.pivot_axle`` (``None`` without one). Its link comes
        before the wheels it carries, so their link indices are one higher than without it:
        always take them from ``wheel_links``.
    """

    body_id: int
    wheel_links: list[int]
    spin_joints: list[int | None]
    steer_joints: list[int | None]
    base_to_reference_m: tuple[float, float, float]
    contact_radius_m: float
    pivot_joint: int | None = None


def build_vehicle(
    spec: VehicleSpec,
    client: int,
    position: tuple[float, float, float],
    orientation: tuple[float, float, float, float],
) -> VehicleBody:
    """Create the vehicle in ``client`` with its base at ``position``/``orientation``."""
    if spec.urdf is not None:
        body = _load_urdf(spec, client, position, orientation)
    else:
        body = _create_multibody(spec, client, position, orientation)
    links = [-1, *range(p.getNumJoints(body.body_id, physicsClientId=client))]
    for link in links:
        p.changeDynamics(
            body.body_id, link, lateralFriction=0.0, spinningFriction=0.0, rollingFriction=0.0,
            linearDamping=0.0, angularDamping=0.0, physicsClientId=client,
        )
    # Compliant wheel-ground contact: stiffness from the static sinkage under an equal share of
    # the weight, damping at 0.7 of critical for that share (see VehicleSpec.contact_sinkage_m).
    share_kg = spec.mass_kg / len(spec.wheels)
    stiffness = share_kg * G_MPS2 / spec.contact_sinkage_m
    damping = 2.0 * 0.7 * math.sqrt(stiffness * share_kg)
    for link in body.wheel_links:
        p.changeDynamics(body.body_id, link, contactStiffness=stiffness, contactDamping=damping,
                         physicsClientId=client)
    for joint in body.spin_joints + body.steer_joints:
        if joint is not None:
            p.changeDynamics(body.body_id, joint, jointDamping=0.0, physicsClientId=client)
    if body.pivot_joint is not None and spec.pivot_axle is not None:
        _make_passive(body.body_id, body.pivot_joint, spec.pivot_axle.limit_rad,
                      spec.pivot_axle.damping_nms, client)
    return body


def _make_passive(body_id: int, joint: int, limit_rad: float, damping_nms: float,
                  client: int) -> None:
    """A free revolute joint: no motor, optional viscous damping, symmetric stops.

    PyBullet puts a velocity motor on every revolute joint it creates (target 0, which holds
    the joint like a brake); a zero force limit removes it, so the contact loads alone set
    the pivot angle.
    """
    p.setJointMotorControl2(body_id, joint, p.VELOCITY_CONTROL, targetVelocity=0.0, force=0.0,
                            physicsClientId=client)
    p.changeDynamics(body_id, joint, jointDamping=damping_nms, jointLowerLimit=-limit_rad,
                     jointUpperLimit=limit_rad, physicsClientId=client)


def sphere_wheel_urdf(spec: VehicleSpec) -> str:
    """Path of a copy of ``spec.urdf`` whose wheels collide as spheres of ``radius_m``.

    The ``pybullet_data`` URDF wheels are cylinders; PyBullet gives them a contact manifold
    spread over the tread (up to a few cm behind the axle) whose normal forces put a
    fluctuating moment on the wheel, like a tyre rolling on a flat. A sphere touches the
    ground once, under the axle, as the force law assumes. Meshes, masses and inertias are
    the original's (mesh paths made absolute). The copy is written once to a cache folder.
    """
    if spec.urdf is None:
        raise ValueError(f"{spec.name}: built from primitives, it has no URDF to copy")
    source = os.path.join(pybullet_data.getDataPath(), spec.urdf)
    folder = os.path.dirname(source)
    with open(source) as fh:
        text = fh.read()
    radius = spec.wheels[0].radius_m
    text = re.sub(r'<cylinder length="[0-9.]+" radius="[0-9.]+"\s*/>',
                  f'<sphere radius="{radius}"/>', text)
    text = text.replace('filename="meshes/', f'filename="{folder}/meshes/')
    text = _explicit_default_inertials(text)
    digest = hashlib.sha1(text.encode()).hexdigest()[:12]
    cache = os.path.join(tempfile.gettempdir(), "slipenv_urdf")
    os.makedirs(cache, exist_ok=True)
    path = os.path.join(cache, f"{os.path.basename(spec.urdf)[:-5]}_{digest}.urdf")
    if not os.path.exists(path):
        tmp = f"{path}.{os.getpid()}"
        with open(tmp, "w") as fh:
            fh.write(text)
        os.replace(tmp, path)  # atomic: parallel test workers may race here
    return path


# PyBullet's default for a link without <inertial>: 1 kg, unit inertia (it warns on stdout).
_DEFAULT_INERTIAL = ('<inertial><mass value="1"/><origin xyz="0 0 0"/>'
                     '<inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>')


def _explicit_default_inertials(text: str) -> str:
    """Write PyBullet's default inertial into links that have none: same physics, no warning."""
    text = re.sub(r'<link name="([^"]+)"\s*/>',
                  lambda m: f'<link name="{m.group(1)}">{_DEFAULT_INERTIAL}</link>', text)

    def fill(match: re.Match) -> str:
        block = match.group(0)
        if "<inertial" in block:
            return block
        return block.replace(">", f">{_DEFAULT_INERTIAL}", 1)

    return re.sub(r'<link name="[^"]+">.*?</link>', fill, text, flags=re.S)


def _load_urdf(
    spec: VehicleSpec,
    client: int,
    position: tuple[float, float, float],
    orientation: tuple[float, float, float, float],
) -> VehicleBody:
    body_id = p.loadURDF(sphere_wheel_urdf(spec), position, orientation,
                         physicsClientId=client)
    names = {
        p.getJointInfo(body_id, j, physicsClientId=client)[1].decode(): j
        for j in range(p.getNumJoints(body_id, physicsClientId=client))
    }
    missing = [n for n in spec.urdf_wheel_joints if n not in names]
    if missing:
        raise ValueError(f"URDF {spec.urdf!r} has no joints {missing}")
    joints = [names[n] for n in spec.urdf_wheel_joints]
    spin_joints: list[int | None] = list(joints)
    steer_joints: list[int | None] = [None] * len(joints)
    # husky.urdf: wheel centres 0.0783 m above base_footprint, midway at x = 0.0875 m.
    return VehicleBody(body_id, joints, spin_joints, steer_joints,
                       (0.0875, 0.0, 0.07828), spec.wheels[0].radius_m)


def _create_multibody(
    spec: VehicleSpec,
    client: int,
    position: tuple[float, float, float],
    orientation: tuple[float, float, float, float],
) -> VehicleBody:
    lx, ly, lz = spec.chassis_size_m
    base_col = p.createCollisionShape(
        p.GEOM_BOX, halfExtents=[lx / 2, ly / 2, lz / 2], physicsClientId=client
    )
    base_vis = p.createVisualShape(
        p.GEOM_BOX, halfExtents=[lx / 2, ly / 2, lz / 2], rgbaColor=[0.8, 0.55, 0.2, 1],
        physicsClientId=client,
    )
    masses, cols, viss, poss, parents, types, axes = [], [], [], [], [], [], []
    wheel_links: list[int] = []
    spin_joints: list[int | None] = []
    steer_joints: list[int | None] = []
    h = spec.chassis_center_height_m
    pivot = spec.pivot_origin_m()
    pivot_joint = None
    if pivot is not None:
        # The axle beam: a light link on a revolute joint along the chassis x axis; a link's
        # parent must precede it, so it is link 0 and carries the axle's wheels.
        half_span = max(abs(w.position_m[1]) for w in spec.wheels)
        masses.append(_PIVOT_AXLE_MASS_KG)
        cols.append(-1)
        viss.append(p.createVisualShape(
            p.GEOM_BOX, halfExtents=[0.02, half_span, 0.015], rgbaColor=[0.4, 0.4, 0.45, 1],
            physicsClientId=client))
        poss.append([pivot[0], pivot[1], pivot[2] - h])
        parents.append(0)
        types.append(p.JOINT_REVOLUTE)
        axes.append([1, 0, 0])
        pivot_joint = 0
    on_axle = set(spec.pivot_axle.wheels) if spec.pivot_axle is not None else set()
    for wheel in spec.wheels:
        x, y, z = wheel.position_m
        col = p.createCollisionShape(p.GEOM_SPHERE, radius=wheel.radius_m, physicsClientId=client)
        vis = p.createVisualShape(
            p.GEOM_CYLINDER, radius=wheel.radius_m, length=wheel.width_m,
            visualFrameOrientation=_CYLINDER_ALONG_Y, rgbaColor=[0.15, 0.15, 0.15, 1],
            physicsClientId=client,
        )
        parent = 0
        offset = [x, y, z - h]
        if wheel.name in on_axle and pivot is not None and pivot_joint is not None:
            parent = pivot_joint + 1  # createMultiBody's parents: 0 the base, i + 1 link i
            offset = [x - pivot[0], y - pivot[1], z - pivot[2]]
        if wheel.steered:
            masses.append(0.05)
            cols.append(-1)
            viss.append(-1)
            poss.append(offset)
            parents.append(parent)
            types.append(p.JOINT_REVOLUTE)
            axes.append([0, 0, 1])
            steer_joints.append(len(masses) - 1)
            parent, offset = len(masses), [0.0, 0.0, 0.0]
        else:
            steer_joints.append(None)
        masses.append(wheel.mass_kg)
        cols.append(col)
        viss.append(vis)
        poss.append(offset)
        parents.append(parent)
        if wheel.role == "caster":
            types.append(p.JOINT_FIXED)
            spin_joints.append(None)
        else:
            types.append(p.JOINT_REVOLUTE)
            spin_joints.append(len(masses) - 1)
        axes.append([0, 1, 0])
        wheel_links.append(len(masses) - 1)
    n = len(masses)
    body_id = p.createMultiBody(
        baseMass=spec.chassis_mass_kg,
        baseCollisionShapeIndex=base_col,
        baseVisualShapeIndex=base_vis,
        basePosition=position,
        baseOrientation=orientation,
        linkMasses=masses,
        linkCollisionShapeIndices=cols,
        linkVisualShapeIndices=viss,
        linkPositions=poss,
        linkOrientations=[[0, 0, 0, 1]] * n,
        linkInertialFramePositions=[[0, 0, 0]] * n,
        linkInertialFrameOrientations=[[0, 0, 0, 1]] * n,
        linkParentIndices=parents,
        linkJointTypes=types,
        linkJointAxis=axes,
        physicsClientId=client,
    )
    # Reference point: midway between the driven contact lines, in the wheel-centre plane (the
    # log-format's reference; for a 2WD vehicle with castors, the driven-axle midpoint).
    driven = [w for w in spec.wheels if w.role == "driven"]
    ref = tuple(sum(w.position_m[i] for w in driven) / len(driven) for i in range(3))
    return VehicleBody(body_id, wheel_links, spin_joints, steer_joints,
                       (ref[0], ref[1], ref[2] - h),
                       sum(w.radius_m for w in driven) / len(driven), pivot_joint)
