"""The NAO as a planar, bilaterally symmetric model in its sagittal plane.

Everything is parsed from qibullet's ``nao.urdf`` (kinematics, joint limits, link masses
and centres of mass); its meshes are not needed. The seating motion uses only the five
pitch degrees of freedom of the paper, shared by both sides:

    q = (ankle, knee, hip, shoulder, elbow)  [radians]

and maps onto qibullet's joint names (both sides) as follows:

* ankle a:    ``LAnklePitch = RAnklePitch = a``
* knee k:     ``LKneePitch = RKneePitch = k``
* hip h:      ``LHipPitch = RHipPitch = h``
* shoulder s: ``LShoulderPitch = RShoulderPitch = s``
* elbow e:    ``LElbowYaw = -π/2, LElbowRoll = -e``; ``RElbowYaw = +π/2, RElbowRoll = +e``
* wrists:     ``LWristYaw = +π/2``; ``RWristYaw = -π/2``

Every pitch axis in the URDF is +y on both sides, so the pitch values are equal (not
negated). The NAO's elbow has no pitch joint: ``ElbowRoll`` turns about the upper arm's
z axis. With ``ElbowYaw`` (about the upper arm's long axis) at -π/2 on the left and +π/2
on the right, that z axis becomes the +y axis on the left and the -y axis on the right,
and the URDF's roll limits (left [-1.54, -0.03], right [0.03, 1.54]) mirror each other.
So ``e`` > 0 is elbow flexion in the sagittal plane: the forearm's pitch is
``torso pitch + s - e`` (positive pitch = pointing down). Shoulder roll, hip roll, ankle
roll, hip yaw-pitch and head are held at zero, so the arms point straight ahead
at ``s = 0`` and every motion is planar. The wrist yaws (about the forearm) undo the
elbow yaws (``LWristYaw = +π/2``, ``RWristYaw = -π/2``), so both palm frames are
``R_y(torso pitch + s - e)``: x along the forearm, z up, the same on both sides.

Frames: the NAO frame ``nao`` has its origin on the floor midway between the soles
(below the ankles), x forward, z up. The feet are fixed flat on the floor, so the
torso's pose follows from the leg joints; the torso pitch is ``-(a + k + h)``.
"""

from __future__ import annotations

import math
import os
import xml.etree.ElementTree as ElementTree
from functools import lru_cache
from typing import NamedTuple, cast

import casadi as ca
import numpy as np

PLANAR_NAMES = ("ankle", "knee", "hip", "shoulder", "elbow")
"""The planar variables, in the order of q."""

DRIVEN_JOINTS = (
    "LAnklePitch",
    "LKneePitch",
    "LHipPitch",
    "LShoulderPitch",
    "LElbowYaw",
    "LElbowRoll",
    "RAnklePitch",
    "RKneePitch",
    "RHipPitch",
    "RShoulderPitch",
    "RElbowYaw",
    "RElbowRoll",
    "LShoulderRoll",
    "RShoulderRoll",
    "LHipRoll",
    "RHipRoll",
    "LAnkleRoll",
    "RAnkleRoll",
    "LHipYawPitch",
    "RHipYawPitch",
    "LWristYaw",
    "RWristYaw",
)
"""qibullet's joint names a seating plan drives (every joint the planar model fixes too)."""

ELBOW_YAW_RAD = math.pi / 2.0
"""|ElbowYaw| that turns ElbowRoll into an elbow pitch (left -, right +)."""


class UrdfJoint(NamedTuple):
    """One URDF joint: the child's frame is origin · rotation(axis, angle)."""

    name: str
    kind: str
    parent: str
    child: str
    xyz: np.ndarray
    rpy: np.ndarray
    axis: np.ndarray
    lower: float
    upper: float
    velocity: float


class UrdfLink(NamedTuple):
    """One URDF link's inertial data: mass (kg) and centre of mass in the link frame."""

    name: str
    mass_kg: float
    com: np.ndarray


def nao_urdf_path() -> str:
    """Path of qibullet's ``nao.urdf``."""
    import qibullet

    return os.path.join(os.path.dirname(qibullet.__file__), "robot_data", "nao.urdf")


def _floats(text: str | None, default: str) -> np.ndarray:
    return np.array([float(v) for v in (text or default).split()])


def _required(element: ElementTree.Element | None, key: str) -> str:
    """The ``key`` attribute of a URDF element that must be there and have it.

    Raises:
        ValueError: the element or its attribute is missing.
    """
    value = None if element is None else element.get(key)
    if value is None:
        raise ValueError(f"URDF element without its {key!r} attribute")
    return value


@lru_cache(maxsize=1)
def parse_urdf(path: str | None = None) -> tuple[dict[str, UrdfJoint], dict[str, UrdfLink]]:
    """Joints by name and links by name from a URDF (inertial data only, no geometry)."""
    root = ElementTree.parse(path or nao_urdf_path()).getroot()
    links: dict[str, UrdfLink] = {}
    for link in root.findall("link"):
        inertial = link.find("inertial")
        mass, com = 0.0, np.zeros(3)
        if inertial is not None:
            mass_el = inertial.find("mass")
            origin_el = inertial.find("origin")
            mass = float(_required(mass_el, "value")) if mass_el is not None else 0.0
            com = _floats(origin_el.get("xyz") if origin_el is not None else None, "0 0 0")
        name = _required(link, "name")
        links[name] = UrdfLink(name, mass, com)
    joints: dict[str, UrdfJoint] = {}
    for joint in root.findall("joint"):
        origin = joint.find("origin")
        axis = joint.find("axis")
        limit = joint.find("limit")
        name = _required(joint, "name")
        joints[name] = UrdfJoint(
            name=name,
            kind=_required(joint, "type"),
            parent=_required(joint.find("parent"), "link"),
            child=_required(joint.find("child"), "link"),
            xyz=_floats(origin.get("xyz") if origin is not None else None, "0 0 0"),
            rpy=_floats(origin.get("rpy") if origin is not None else None, "0 0 0"),
            axis=_floats(axis.get("xyz") if axis is not None else None, "1 0 0"),
            lower=float(limit.get("lower", "nan")) if limit is not None else math.nan,
            upper=float(limit.get("upper", "nan")) if limit is not None else math.nan,
            velocity=float(limit.get("velocity", "nan")) if limit is not None else math.nan,
        )
    return joints, links


def _rpy_matrix(rpy: np.ndarray) -> np.ndarray:
    roll, pitch, yaw = rpy
    cr, sr, cp, sp, cy, sy = (
        math.cos(roll),
        math.sin(roll),
        math.cos(pitch),
        math.sin(pitch),
        math.cos(yaw),
        math.sin(yaw),
    )
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return rz @ ry @ rx


def _axis_rotation(axis: np.ndarray, angle):
    """Rodrigues' rotation about a unit axis; ``angle`` may be a casadi SX."""
    axis = axis / np.linalg.norm(axis)
    x, y, z = axis
    c, s = ca.cos(angle), ca.sin(angle)
    t = 1 - c
    return ca.vertcat(
        ca.horzcat(t * x * x + c, t * x * y - s * z, t * x * z + s * y),
        ca.horzcat(t * x * y + s * z, t * y * y + c, t * y * z - s * x),
        ca.horzcat(t * x * z - s * y, t * y * z + s * x, t * z * z + c),
    )


def joint_values(q) -> dict[str, object]:
    """qibullet joint angles (radians) of the planar posture ``q`` (numpy or casadi)."""
    ankle, knee, hip, shoulder, elbow = (q[i] for i in range(5))
    values: dict[str, object] = {name: 0.0 for name in DRIVEN_JOINTS}
    for side in "LR":
        values[f"{side}AnklePitch"] = ankle
        values[f"{side}KneePitch"] = knee
        values[f"{side}HipPitch"] = hip
        values[f"{side}ShoulderPitch"] = shoulder
    values["LElbowYaw"] = -ELBOW_YAW_RAD
    values["RElbowYaw"] = ELBOW_YAW_RAD
    values["LElbowRoll"] = -elbow
    values["RElbowRoll"] = elbow
    # Rolling the wrists back aligns both palm frames with the body (x forward, z up):
    # the mean of the two palms' orientations (the hands frame) is then well defined.
    values["LWristYaw"] = ELBOW_YAW_RAD
    values["RWristYaw"] = -ELBOW_YAW_RAD
    return values


def to_joint_positions(q_rows: np.ndarray) -> np.ndarray:
    """(K, 5) planar postures -> (K, len(DRIVEN_JOINTS)) qibullet joint angles."""
    q_rows = np.atleast_2d(q_rows)
    out = np.zeros((len(q_rows), len(DRIVEN_JOINTS)))
    for row, q in enumerate(q_rows):
        values = cast(dict[str, float], joint_values(q))  # numbers, as q is numeric
        out[row] = [float(values[name]) for name in DRIVEN_JOINTS]
    return out


class PlanarNao:
    """The NAO's forward kinematics and mass model over the planar posture q.

    Attributes:
        q_lower, q_upper: (5,) joint limits of q (both sides' URDF limits intersected).
        velocity_limit: (5,) URDF velocity limits of q (rad/s).
        total_mass_kg: the NAO's mass.
        support_x: (x_back, x_front) of the feet's support polygon along x in the NAO
            frame: from the rear force sensors to the front bumpers (inside the sole).
    """

    def __init__(self, urdf_path: str | None = None) -> None:
        self.joints, self.links = parse_urdf(urdf_path)
        self._children: dict[str, list[UrdfJoint]] = {}
        for joint in self.joints.values():
            self._children.setdefault(joint.parent, []).append(joint)
        self.q_lower, self.q_upper, self.velocity_limit = self._planar_limits()
        self.total_mass_kg = sum(link.mass_kg for link in self.links.values())
        # The sole's extent: from the rear force sensors to the front bumpers.
        foot_x = [
            j.xyz[0]
            for j in self.joints.values()
            if j.parent == "l_ankle" and ("FSR" in j.name or "Bumper" in j.name)
        ]
        self.support_x = (float(min(foot_x)), float(max(foot_x)))
        self._q = ca.SX.sym("q", 5)
        self._frames = self._forward(self._q)
        self._frame_function = ca.Function(
            "nao_frames",
            [self._q],
            [ca.vertcat(*[ca.vec(T) for T in self._frames.values()])],
        )
        self._frame_names = list(self._frames)

    def _planar_limits(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        lower, upper, velocity = np.zeros(5), np.zeros(5), np.zeros(5)
        for i, base in enumerate(("AnklePitch", "KneePitch", "HipPitch", "ShoulderPitch")):
            left, right = self.joints["L" + base], self.joints["R" + base]
            lower[i] = max(left.lower, right.lower)
            upper[i] = min(left.upper, right.upper)
            velocity[i] = min(left.velocity, right.velocity)
        left, right = self.joints["LElbowRoll"], self.joints["RElbowRoll"]
        lower[4] = max(-left.upper, right.lower)
        upper[4] = min(-left.lower, right.upper)
        velocity[4] = min(left.velocity, right.velocity)
        return lower, upper, velocity

    def _forward(self, q) -> dict[str, ca.SX]:
        """4x4 ``T_nao_link`` of every link, as casadi expressions of q."""
        values = joint_values(q)
        T_torso: dict[str, ca.SX] = {"torso": ca.SX.eye(4)}
        stack = ["torso"]
        while stack:
            parent = stack.pop()
            for joint in self._children.get(parent, []):
                T_origin = np.eye(4)
                T_origin[:3, :3] = _rpy_matrix(joint.rpy)
                T_origin[:3, 3] = joint.xyz
                T = ca.mtimes(T_torso[parent], ca.SX(T_origin))
                if joint.kind in ("revolute", "continuous"):
                    rotation = _axis_rotation(joint.axis, values.get(joint.name, 0.0))
                    T_joint = ca.SX.eye(4)
                    T_joint[:3, :3] = rotation
                    T = ca.mtimes(T, T_joint)
                T_torso[joint.child] = T
                stack.append(joint.child)
        # The NAO frame: the left sole's frame moved to the midpoint between the soles.
        T_torso_lsole = T_torso["l_sole"]
        half_stance = float(self.joints["LHipYawPitch"].xyz[1])
        T_lsole_nao = np.eye(4)
        T_lsole_nao[1, 3] = -half_stance
        T_torso_nao = ca.mtimes(T_torso_lsole, ca.SX(T_lsole_nao))
        rotation = T_torso_nao[:3, :3]
        T_nao_torso = ca.SX.eye(4)
        T_nao_torso[:3, :3] = rotation.T
        T_nao_torso[:3, 3] = -ca.mtimes(rotation.T, T_torso_nao[:3, 3])
        return {name: ca.mtimes(T_nao_torso, T) for name, T in T_torso.items()}

    def frames(self, q) -> dict[str, ca.SX]:
        """``T_nao_link`` (4x4) of every link as expressions of ``q`` (SX or MX-free SX)."""
        if isinstance(q, ca.SX) and q.shape == (5, 1) and ca.is_equal(q, self._q):
            return self._frames
        flat = self._frame_function(q)
        return {
            name: ca.reshape(flat[16 * i : 16 * (i + 1)], 4, 4)
            for i, name in enumerate(self._frame_names)
        }

    def point(self, frames: dict[str, ca.SX], link: str, offset=(0.0, 0.0, 0.0)) -> ca.SX:
        """(x, z) in the NAO frame of a point fixed in ``link`` (offset in link frame)."""
        T = frames[link]
        p = ca.mtimes(T[:3, :3], ca.DM(offset)) + T[:3, 3]
        return ca.vertcat(p[0], p[2])

    def centre_of_mass(self, frames: dict[str, ca.SX]) -> tuple[ca.SX, float]:
        """(x, z) of the NAO's centre of mass in the NAO frame, and its mass (kg)."""
        total = ca.SX.zeros(2)
        mass = 0.0
        for name, link in self.links.items():
            if link.mass_kg <= 0.0 or name not in frames:
                continue
            total += link.mass_kg * self.point(frames, name, link.com)
            mass += link.mass_kg
        return total / mass, mass

    def numeric_frames(self, q: np.ndarray) -> dict[str, np.ndarray]:
        """``T_nao_link`` as numpy arrays for a numeric posture."""
        flat = np.asarray(self._frame_function(np.asarray(q, dtype=float))).ravel()
        return {
            name: flat[16 * i : 16 * (i + 1)].reshape(4, 4, order="F")
            for i, name in enumerate(self._frame_names)
        }


def link_transforms(
    joint_angles: dict[str, float], urdf_path: str | None = None
) -> dict[str, np.ndarray]:
    """``T_nao_link`` (numpy 4x4) of every link for any joint angles (missing ones 0).

    The NAO frame as in :class:`PlanarNao`: the left sole flat on the floor, the origin
    half the stance to its right. Used for postures outside the planar family (the
    carrying posture).
    """
    joints, _ = parse_urdf(urdf_path)
    children: dict[str, list[UrdfJoint]] = {}
    for joint in joints.values():
        children.setdefault(joint.parent, []).append(joint)
    T_torso: dict[str, np.ndarray] = {"torso": np.eye(4)}
    stack = ["torso"]
    while stack:
        parent = stack.pop()
        for joint in children.get(parent, []):
            T = T_torso[parent].copy()
            T_origin = np.eye(4)
            T_origin[:3, :3] = _rpy_matrix(joint.rpy)
            T_origin[:3, 3] = joint.xyz
            T = T @ T_origin
            if joint.kind in ("revolute", "continuous"):
                T_joint = np.eye(4)
                T_joint[:3, :3] = np.asarray(
                    ca.DM(_axis_rotation(joint.axis, float(joint_angles.get(joint.name, 0.0))))
                )
                T = T @ T_joint
            T_torso[joint.child] = T
            stack.append(joint.child)
    T_torso_nao = T_torso["l_sole"].copy()
    T_torso_nao[:3, 3] += T_torso_nao[:3, :3] @ np.array(
        [0.0, -float(joints["LHipYawPitch"].xyz[1]), 0.0]
    )
    T_nao_torso = np.linalg.inv(T_torso_nao)
    return {name: T_nao_torso @ T for name, T in T_torso.items()}


@lru_cache(maxsize=1)
def planar_nao() -> PlanarNao:
    """The process-wide NAO model (parsing and building the FK once)."""
    return PlanarNao()
