"""A loadable NAO model: qibullet's nao.urdf with its meshes replaced by primitives.

qibullet ships the NAO's kinematics, joint limits, masses and inertias in
``robot_data/nao.urdf``, but its visual and collision meshes are not usable (see
../shared/NOTES.md). :func:`nao_urdf` keeps every joint and inertial element, drops
every mesh and gives each body link boxes, capsules or spheres sized after the NAO
H25 V5 (0.574 m tall), plus a link ``aruco_tag`` carrying the tag plate on the head.
The sensor frames and the fingers, shapeless and massless, are left out (:func:`_dropped`).
The URDF is written into the cache directory at run time.
"""

from __future__ import annotations

import math
import os
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import NamedTuple

import qibullet

from bearchair.hardware.sim.bullet import cached_asset

QIBULLET_NAO_URDF = Path(os.path.dirname(qibullet.__file__)) / "robot_data" / "nao.urdf"

SOLE_TO_TORSO_M = 0.085 + 0.1 + 0.1029 + 0.04511
"""Height of the torso frame above the soles when standing straight (all leg joints 0)."""

SOLE_TO_HEAD_M = SOLE_TO_TORSO_M + 0.1265
"""Height of the Head link frame above the soles when standing straight."""

TAG_LINK = "aruco_tag"


class Primitive(NamedTuple):
    """One collision-and-visual primitive in a link frame.

    Attributes:
        kind: "box" (size = x, y, z extents), "capsule" (size = radius, cylinder length,
            along the local z axis after ``rpy``) or "sphere" (size = radius,).
        size: metres.
        xyz: centre in the link frame, metres.
        rpy: orientation in the link frame, radians.
        colour: RGBA.
    """

    kind: str
    size: tuple[float, ...]
    xyz: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)
    colour: tuple[float, float, float, float] = (0.92, 0.92, 0.9, 1.0)


_WHITE = (0.92, 0.92, 0.9, 1.0)
_GREY = (0.35, 0.37, 0.4, 1.0)
_ORANGE = (1.0, 0.45, 0.05, 1.0)
_ALONG_X = (0.0, math.pi / 2.0, 0.0)


def _leg(side: str) -> dict[str, list[Primitive]]:
    return {
        f"{side}Thigh": [Primitive("capsule", (0.034, 0.06), (0.0, 0.0, -0.05), colour=_WHITE)],
        f"{side}Tibia": [Primitive("capsule", (0.03, 0.06), (0.0, 0.0, -0.052), colour=_WHITE)],
        f"{side.lower()}_ankle": [
            Primitive("box", (0.16, 0.088, 0.02), (0.02, 0.0, -0.04511 + 0.01), colour=_GREY),
            Primitive("box", (0.06, 0.05, 0.03), (0.0, 0.0, -0.02), colour=_WHITE),
        ],
    }


def _arm(side: str) -> dict[str, list[Primitive]]:
    sign = 1.0 if side == "L" else -1.0
    wrist = "l_wrist" if side == "L" else "r_wrist"
    return {
        f"{side}Shoulder": [Primitive("sphere", (0.03,), colour=_ORANGE)],
        f"{side}Bicep": [
            Primitive("capsule", (0.028, 0.06), (0.055, sign * 0.008, 0.0), _ALONG_X, _WHITE)
        ],
        f"{side}ForeArm": [Primitive("capsule", (0.024, 0.03), (0.03, 0.0, 0.0), _ALONG_X, _WHITE)],
        wrist: [Primitive("box", (0.06, 0.035, 0.05), (0.045, 0.0, -0.008), colour=_GREY)],
    }


NAO_PRIMITIVES: dict[str, list[Primitive]] = {
    "torso": [
        Primitive("box", (0.085, 0.13, 0.19), (-0.005, 0.0, 0.02), colour=_WHITE),
        Primitive("box", (0.06, 0.1, 0.03), (-0.005, 0.0, -0.07), colour=_GREY),
    ],
    "Neck": [Primitive("capsule", (0.02, 0.02), (0.0, 0.0, -0.015), colour=_GREY)],
    "Head": [
        # Flat top just below the tag plate, which sits at the tag's standard height.
        Primitive("box", (0.11, 0.13, 0.1), (-0.005, 0.0, 0.0685), colour=_WHITE),
        Primitive("sphere", (0.02,), (0.045, 0.0, 0.05), colour=_ORANGE),
    ],
    **_leg("L"),
    **_leg("R"),
    **_arm("L"),
    **_arm("R"),
}


def _add_geometry(link: ET.Element, primitive: Primitive, index: int) -> None:
    for tag in ("visual", "collision"):
        element = ET.SubElement(link, tag, name=f"{link.get('name')}_{tag}_{index}")
        ET.SubElement(
            element,
            "origin",
            xyz=" ".join(f"{v:.5f}" for v in primitive.xyz),
            rpy=" ".join(f"{v:.5f}" for v in primitive.rpy),
        )
        geometry = ET.SubElement(element, "geometry")
        if primitive.kind == "box":
            ET.SubElement(geometry, "box", size=" ".join(f"{v:.5f}" for v in primitive.size))
        elif primitive.kind == "capsule":
            ET.SubElement(
                geometry,
                "capsule",
                radius=f"{primitive.size[0]:.5f}",
                length=f"{primitive.size[1]:.5f}",
            )
        elif primitive.kind == "sphere":
            ET.SubElement(geometry, "sphere", radius=f"{primitive.size[0]:.5f}")
        else:
            raise ValueError(f"unknown primitive kind {primitive.kind!r}")
        if tag == "visual":
            material = ET.SubElement(element, "material", name=f"{link.get('name')}_m{index}")
            ET.SubElement(material, "color", rgba=" ".join(f"{v:.3f}" for v in primitive.colour))


def _dropped(link_name: str) -> bool:
    """Links the simulation leaves out: the sensor frames and the fingers.

    None of them has a shape here (the hand's shape is the wrist's box) or a mass above
    2 mg, and no one reads them; each link costs the physics step as much as a real one
    (the 79-link model stepped about 4x slower than the 33 links kept).
    """
    return link_name.endswith("_frame") or "Finger" in link_name or "Thumb" in link_name


def build_nao_urdf_text(tag_mesh_path: Path, tag_height_m: float) -> str:
    """The rewritten URDF as text.

    Args:
        tag_mesh_path: OBJ of the tag plate (its top face at z = 0 of its own frame).
        tag_height_m: height of the tag's centre above the soles when standing straight.
    """
    root = ET.parse(QIBULLET_NAO_URDF).getroot()
    for joint in root.findall("joint"):
        child_element = joint.find("child")
        if child_element is None:
            raise ValueError(f"{QIBULLET_NAO_URDF}: joint {joint.get('name')} has no child")
        child = child_element.get("link", "")
        if _dropped(child):
            root.remove(joint)
    for link in root.findall("link"):
        if _dropped(link.get("name", "")):
            root.remove(link)
    for link in root.findall("link"):
        for tag in ("visual", "collision"):
            for element in link.findall(tag):
                link.remove(element)
        for index, primitive in enumerate(NAO_PRIMITIVES.get(link.get("name", ""), [])):
            _add_geometry(link, primitive, index)
    tag_link = ET.SubElement(root, "link", name=TAG_LINK)
    inertial = ET.SubElement(tag_link, "inertial")
    ET.SubElement(inertial, "mass", value="0.001")
    ET.SubElement(inertial, "origin", xyz="0 0 0", rpy="0 0 0")
    ET.SubElement(
        inertial, "inertia", ixx="1e-7", ixy="0", ixz="0", iyy="1e-7", iyz="0", izz="1e-7"
    )
    visual = ET.SubElement(tag_link, "visual")
    ET.SubElement(visual, "origin", xyz="0 0 0", rpy="0 0 0")
    geometry = ET.SubElement(visual, "geometry")
    ET.SubElement(geometry, "mesh", filename=str(tag_mesh_path), scale="1 1 1")
    joint = ET.SubElement(root, "joint", name="aruco_tag_fixedjoint", type="fixed")
    ET.SubElement(joint, "parent", link="Head")
    ET.SubElement(joint, "child", link=TAG_LINK)
    ET.SubElement(joint, "origin", xyz=f"0 0 {tag_height_m - SOLE_TO_HEAD_M:.5f}", rpy="0 0 0")
    return ET.tostring(root, encoding="unicode")


def nao_urdf(tag_mesh_path: Path, tag_height_m: float) -> Path:
    """Writes the primitive-geometry NAO URDF into the cache (once per content) and returns it."""
    return cached_asset("nao", build_nao_urdf_text(tag_mesh_path, tag_height_m), ".urdf")
