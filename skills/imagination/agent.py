"""The virtual sitter: a child-sized articulated humanoid generated as a URDF.

The agent has the height and mass of a two-to-three-year-old (about 0.9 m standing,
13 kg) and is built from primitives (boxes, capsules, a sphere) so that pybullet needs
no mesh files. Its base link is the pelvis. Every link frame is parallel to the pelvis
frame when all joint angles are zero, and zero is the *sitting* posture: thighs
forward (+x), shanks down (-z), torso and head upright, arms hanging. The agent faces
+x.

Joint sign conventions (right-handed rotations about the pelvis axes):
    * ``*_pitch`` joints turn about +y: a positive chest pitch leans the torso forward,
      a positive hip pitch lowers the thigh, a negative knee pitch straightens the leg.
    * ``*_hip_roll`` joints turn about +x (abduction for the left leg when negative).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import NamedTuple

AGENT_VERSION = "v3"
"""Bumped whenever the generated body changes, so cached URDFs are regenerated."""


class AgentJoint(NamedTuple):
    """One revolute joint of the agent.

    Attributes:
        name: joint name in the URDF.
        parent: parent link.
        child: child link.
        origin_m: joint origin in the parent link frame (metres).
        axis: rotation axis in the joint frame.
        lower_rad: lower limit.
        upper_rad: upper limit.
        max_torque_nm: the weak motor's maximal torque holding the posture.
        pre_sitting_rad: angle set before each drop.
        key_rad: angle of the key sitting configuration C_key.
        weight: w_J of the joint angle score.
    """

    name: str
    parent: str
    child: str
    origin_m: tuple[float, float, float]
    axis: tuple[float, float, float]
    lower_rad: float
    upper_rad: float
    max_torque_nm: float
    pre_sitting_rad: float
    key_rad: float
    weight: float


class AgentLink(NamedTuple):
    """One link: its collision/visual primitive and mass.

    Attributes:
        name: link name.
        shape: ``box`` (size = x, y, z), ``sphere`` (size = radius,) or ``capsule``
            (size = radius, cylinder length) along the axis given by ``along``.
        size: see ``shape`` (metres).
        centre_m: primitive centre in the link frame (metres).
        along: capsule axis ``x`` or ``z``.
        mass_kg: link mass.
        body_part: ``upper`` (chest, head: the back that a backrest supports), ``lower``
            (pelvis and legs: what a seat supports) or ``arm`` (counted in neither).
        link_weight: w_L of the link rotation score.
    """

    name: str
    shape: str
    size: tuple[float, ...]
    centre_m: tuple[float, float, float]
    along: str
    mass_kg: float
    body_part: str
    link_weight: float


RECLINE_RAD = -0.25
"""Key chest pitch: a relaxed sitter leans back about 14 degrees against the backrest."""

LINKS: tuple[AgentLink, ...] = (
    AgentLink("pelvis", "box", (0.10, 0.17, 0.10), (0.0, 0.0, 0.0), "z", 2.6, "lower", 1.0),
    AgentLink("chest", "box", (0.10, 0.18, 0.20), (0.0, 0.0, 0.10), "z", 3.6, "upper", 1.0),
    AgentLink("head", "sphere", (0.075,), (0.0, 0.0, 0.10), "z", 2.0, "upper", 0.5),
    AgentLink("left_arm", "capsule", (0.03, 0.22), (0.0, 0.0, -0.14), "z", 0.6, "arm", 0.0),
    AgentLink("right_arm", "capsule", (0.03, 0.22), (0.0, 0.0, -0.14), "z", 0.6, "arm", 0.0),
    AgentLink("left_hip", "sphere", (0.02,), (0.0, 0.0, 0.0), "z", 0.05, "lower", 0.0),
    AgentLink("right_hip", "sphere", (0.02,), (0.0, 0.0, 0.0), "z", 0.05, "lower", 0.0),
    AgentLink("left_thigh", "capsule", (0.045, 0.13), (0.10, 0.0, 0.0), "x", 1.1, "lower", 0.0),
    AgentLink("right_thigh", "capsule", (0.045, 0.13), (0.10, 0.0, 0.0), "x", 1.1, "lower", 0.0),
    AgentLink("left_shank", "capsule", (0.035, 0.16), (0.0, 0.0, -0.115), "z", 0.7, "lower", 0.0),
    AgentLink("right_shank", "capsule", (0.035, 0.16), (0.0, 0.0, -0.115), "z", 0.7, "lower", 0.0),
)

# fmt: off
_JOINT_TABLE = (
    # name, parent, child, origin (m), axis, lower, upper (rad), max torque (N m),
    # pre-sitting, key (rad), w_J
    ("chest_pitch", "pelvis", "chest", (0.0, 0.0, 0.05), (0, 1, 0),
     -0.9, 0.9, 1.5, RECLINE_RAD, RECLINE_RAD, 1.0),
    ("neck_pitch", "chest", "head", (0.0, 0.0, 0.20), (0, 1, 0),
     -0.6, 0.6, 1.5, 0.0, 0.0, 0.3),
    ("left_shoulder_pitch", "chest", "left_arm", (0.0, 0.125, 0.17), (0, 1, 0),
     -1.5, 3.0, 1.0, -0.3, -0.3, 0.05),
    ("right_shoulder_pitch", "chest", "right_arm", (0.0, -0.125, 0.17), (0, 1, 0),
     -1.5, 3.0, 1.0, -0.3, -0.3, 0.05),
    ("left_hip_roll", "pelvis", "left_hip", (0.0, 0.055, -0.03), (1, 0, 0),
     -0.5, 0.5, 4.0, 0.0, 0.0, 0.5),
    ("right_hip_roll", "pelvis", "right_hip", (0.0, -0.055, -0.03), (1, 0, 0),
     -0.5, 0.5, 4.0, 0.0, 0.0, 0.5),
    ("left_hip_pitch", "left_hip", "left_thigh", (0.0, 0.0, 0.0), (0, 1, 0),
     -1.2, 1.7, 6.0, 0.0, 0.0, 1.0),
    ("right_hip_pitch", "right_hip", "right_thigh", (0.0, 0.0, 0.0), (0, 1, 0),
     -1.2, 1.7, 6.0, 0.0, 0.0, 1.0),
    ("left_knee_pitch", "left_thigh", "left_shank", (0.20, 0.0, 0.0), (0, 1, 0),
     -1.6, 0.6, 3.0, 0.0, 0.0, 0.5),
    ("right_knee_pitch", "right_thigh", "right_shank", (0.20, 0.0, 0.0), (0, 1, 0),
     -1.6, 0.6, 3.0, 0.0, 0.0, 0.5),
)
# fmt: on
JOINTS: tuple[AgentJoint, ...] = tuple(AgentJoint(*row) for row in _JOINT_TABLE)

LINK_NAMES: tuple[str, ...] = tuple(link.name for link in LINKS)
TOTAL_MASS_KG = sum(link.mass_kg for link in LINKS)

BALANCE_LEAN_M = 0.05
"""How far a sitter without a backrest shifts its centre of mass to stay upright
(metres): a young child on a stool leans its trunk a few centimetres and braces its
feet and hands; 5 cm is about half the depth of the agent's pelvis (0.10 m)."""
BALANCE_TORQUE_MAX_NM = TOTAL_MASS_KG * 9.81 * BALANCE_LEAN_M
"""The largest righting torque of an upright sitter (N m): its weight times
``BALANCE_LEAN_M``, about 6.4 N m for the 13.1 kg agent."""
BALANCE_FULL_TILT_RAD = math.radians(5.0)
"""Pelvis tilt at which the righting torque reaches its maximum (radians)."""


def upright_targets() -> list[float]:
    """Joint targets of a sitter without a backrest: the pre-sitting posture with the
    torso upright instead of reclined (nothing to lean back against), in JOINTS order."""
    return [0.0 if joint.name == "chest_pitch" else joint.pre_sitting_rad for joint in JOINTS]


def agent_urdf_text() -> str:
    """The agent's URDF as a string (primitives only, inertias of the primitives)."""
    parts = ['<?xml version="1.0"?>', f'<robot name="sitting_agent_{AGENT_VERSION}">']
    for link in LINKS:
        parts.append(_link_xml(link))
    for joint in JOINTS:
        parts.append(_joint_xml(joint))
    parts.append("</robot>")
    return "\n".join(parts) + "\n"


def agent_urdf_path() -> Path:
    """Writes the agent URDF into the cache directory (once per version) and returns it."""
    # Imported here: the drop workers import this module and need no mesh library.
    from bearchair.core.meshes import cache_dir

    path = cache_dir() / "agent" / f"sitting_agent_{AGENT_VERSION}.urdf"
    text = agent_urdf_text()
    if not path.exists() or path.read_text() != text:
        path.parent.mkdir(parents=True, exist_ok=True)
        scratch = path.with_suffix(f".{_pid()}.tmp")
        scratch.write_text(text)
        scratch.replace(path)
    return path


def _pid() -> int:
    import os

    return os.getpid()


def _fmt(values: tuple[float, ...]) -> str:
    return " ".join(f"{v:.6g}" for v in values)


def _geometry_xml(link: AgentLink) -> tuple[str, str]:
    """The geometry element and the origin rpy placing the primitive in the link frame."""
    if link.shape == "box":
        return f'<box size="{_fmt(link.size)}"/>', "0 0 0"
    if link.shape == "sphere":
        return f'<sphere radius="{link.size[0]:.6g}"/>', "0 0 0"
    radius, length = link.size
    rpy = "0 1.5707963 0" if link.along == "x" else "0 0 0"
    return f'<capsule radius="{radius:.6g}" length="{length:.6g}"/>', rpy


def _inertia(link: AgentLink) -> tuple[float, float, float]:
    """Principal moments (kg m^2) of the primitive about its centre, in the link axes."""
    m = link.mass_kg
    if link.shape == "box":
        x, y, z = link.size
        return (m * (y * y + z * z) / 12, m * (x * x + z * z) / 12, m * (x * x + y * y) / 12)
    if link.shape == "sphere":
        r = link.size[0]
        moment = 0.4 * m * r * r
        return (moment, moment, moment)
    # A capsule as a solid cylinder of the full length: close enough for dynamics.
    r, length = link.size
    full = length + 2 * r
    axial = 0.5 * m * r * r
    transverse = m * (3 * r * r + full * full) / 12
    if link.along == "x":
        return (axial, transverse, transverse)
    return (transverse, transverse, axial)


def _link_xml(link: AgentLink) -> str:
    geometry, rpy = _geometry_xml(link)
    ixx, iyy, izz = _inertia(link)
    origin = f'<origin xyz="{_fmt(link.centre_m)}" rpy="{rpy}"/>'
    colour = "0.85 0.55 0.3 1" if link.body_part == "upper" else "0.6 0.4 0.25 1"
    return (
        f'  <link name="{link.name}">\n'
        f'    <inertial><origin xyz="{_fmt(link.centre_m)}" rpy="0 0 0"/>'
        f'<mass value="{link.mass_kg:.6g}"/>'
        f'<inertia ixx="{ixx:.6g}" ixy="0" ixz="0" iyy="{iyy:.6g}" iyz="0" izz="{izz:.6g}"/>'
        f"</inertial>\n"
        f"    <visual>{origin}<geometry>{geometry}</geometry>"
        f'<material name="{link.name}_colour"><color rgba="{colour}"/></material></visual>\n'
        f"    <collision>{origin}<geometry>{geometry}</geometry></collision>\n"
        f"  </link>"
    )


def _joint_xml(joint: AgentJoint) -> str:
    return (
        f'  <joint name="{joint.name}" type="revolute">'
        f'<parent link="{joint.parent}"/><child link="{joint.child}"/>'
        f'<origin xyz="{_fmt(joint.origin_m)}" rpy="0 0 0"/><axis xyz="{_fmt(joint.axis)}"/>'
        f'<limit lower="{joint.lower_rad:.6g}" upper="{joint.upper_rad:.6g}" '
        f'effort="{joint.max_torque_nm:.6g}" velocity="{4 * math.pi:.6g}"/>'
        f'<dynamics damping="0.05" friction="0.0"/></joint>'
    )
