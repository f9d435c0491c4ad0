"""The chair check's advice on units and posture: what it sees, from geometry alone.

Generated chairs turned every way (synthetic, always run) and the calibration meshes
(skipped where ``../shared/chairs`` is absent): an upright chair is never warned, a y-up
file "lies on its side", a rolled one "tips over by about N degrees", an upside-down one
"seems upside down"; a flat sheet and a mesh 1e30 units wide are refused with what they are.
"""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from bearchair.core.meshes import MeshLoadError, box_chair_mesh, check_chair_mesh, load_mesh
from bearchair.core.posture import MAX_REST_TILT_DEG, posture_warning, rest_faces
from bearchair.executive import cli
from bearchair.testing.chairgen import FAMILIES, generate_chair

ROTATE = trimesh.transformations.rotation_matrix
WITH_BACKREST = ("four_legs", "armchair", "round", "sled", "footrest")


def turned(mesh: trimesh.Trimesh, angle_deg: float, axis) -> trimesh.Trimesh:
    """The mesh rotated and put back on the floor (lowest point z = 0), as a file would be."""
    copy = mesh.copy()
    copy.apply_transform(ROTATE(np.radians(angle_deg), axis))
    copy.apply_translation([0.0, 0.0, -copy.bounds[0][2]])
    return copy


@pytest.mark.parametrize("family", FAMILIES)
def test_an_upright_generated_chair_stands_and_is_not_warned(family):
    chair = generate_chair(seed=5, family=family).mesh
    assert rest_faces(chair)["-z"][0] <= MAX_REST_TILT_DEG
    assert check_chair_mesh(chair, "c.obj") == []


@pytest.mark.parametrize("axis", [[1, 0, 0], [0, 1, 0]], ids=["y-up", "x-up"])
@pytest.mark.parametrize("sign", [1, -1])
def test_a_file_with_another_up_axis_lies_on_its_side(axis, sign):
    (warning,) = check_chair_mesh(turned(box_chair_mesh(), sign * 90.0, axis), "c.obj")
    side = "y" if axis[0] else "x"
    assert "lie on its side" in warning and f"±{side}" in warning and "z up" in warning


@pytest.mark.parametrize("angle", [25.0, 35.0, 50.0])
def test_a_rolled_chair_tips_over_by_its_angle_not_a_wrong_axis(angle):
    (warning,) = check_chair_mesh(turned(box_chair_mesh(), angle, [1, 0, 0]), "c.obj")
    assert "tip over" in warning and "side" not in warning and "-up" not in warning
    said = float(warning.split("about ")[1].split(" degrees")[0])
    # It comes to rest on its legs again (the roll) or on a nearer face of its hull.
    assert 0.5 * angle <= said <= angle + 1.0


@pytest.mark.parametrize("family", WITH_BACKREST)
def test_an_upside_down_chair_is_warned(family):
    chair = turned(generate_chair(seed=2, family=family).mesh, 180.0, [1, 0, 0])
    (warning,) = check_chair_mesh(chair, "c.obj")
    assert "upside down" in warning or "tip over" in warning


def test_the_upside_down_box_chair_is_called_upside_down():
    (warning,) = check_chair_mesh(turned(box_chair_mesh(), 180.0, [1, 0, 0]), "c.obj")
    assert "seems upside down" in warning and "turn it over" in warning


def test_a_chair_on_uneven_legs_still_stands():
    chair = box_chair_mesh()
    lifted = chair.vertices[:, 0] > 0.1  # the front legs' feet 1.5 cm short
    chair.vertices[lifted & (chair.vertices[:, 2] < 1e-6), 2] = 0.015
    assert posture_warning(chair) is None


def test_a_flat_sheet_is_refused_not_a_qhull_error(tmp_path, capsys):
    sheet = trimesh.creation.box(extents=(0.4, 0.4, 0.1))
    sheet.vertices[:, 2] = 0.0
    path = tmp_path / "sheet.obj"
    sheet.export(path)
    with pytest.raises(MeshLoadError, match="flat"):
        check_chair_mesh(load_mesh(path), path)
    assert cli.main(["run", "--chair", str(path), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "flat (a sheet)" in err[0] and not (tmp_path / "o").exists()


@pytest.mark.parametrize(
    ("scale", "said"),
    [
        (1e30, "no chair in any length unit"),
        (1e6, "no chair in any length unit"),
        (1000.0, "millimetres: scale it by 0.001"),
        (100.0, "centimetres: scale it by 0.01"),
    ],
)
def test_the_scale_check_says_what_it_sees(scale, said):
    chair = box_chair_mesh()
    chair.apply_scale(scale)
    with pytest.raises(MeshLoadError) as raised:
        check_chair_mesh(chair, "c.obj")
    assert said in str(raised.value)
    if scale > 1e5:
        assert "millimetres" not in str(raised.value)


@pytest.mark.slow
def test_over_the_calibration_meshes_upright_is_never_warned_and_turned_mostly_is(
    shared_chairs, shared_manifest
):
    upright_warned, turned_warned, rolled_tips, total = [], 0, 0, 0
    for entry in shared_manifest:
        mesh = load_mesh(shared_chairs / entry["file"])
        if posture_warning(mesh, entry["file"]) is not None:
            upright_warned.append(entry["file"])
        total += 1
        turned_warned += posture_warning(turned(mesh, 90.0, [1, 0, 0])) is not None
        rolled = posture_warning(turned(mesh, 35.0, [0, 1, 0])) or ""
        rolled_tips += "tip over" in rolled
    assert upright_warned == []  # whatever its kind: tables, boxes, shelves too
    assert turned_warned >= 0.9 * total
    assert rolled_tips >= 0.9 * total
