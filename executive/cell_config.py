"""The robot cell file (``bearchair run --robots cell.json``): typed and checked before use.

A cell file says where the robots are and how they are reached. Every field that has a
unit carries it in its name (``_m`` metres, ``_rad`` radians); transforms are 4x4
homogeneous matrices with translations in metres, named ``T_<to>_<from>``. Example::

    {
      "nao_url": "tcp://nao.local:9559",
      "panda_host": "172.16.0.2",
      "camera": "carmine",
      "T_world_base": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]],
      "T_flange_camera": [[0,1,0,0.065],[-1,0,0,0],[0,0,1,0.02],[0,0,0,1]],
      "nao_start_x_m": 1.9, "nao_start_y_m": 0.0, "nao_start_yaw_rad": 3.14159
    }

``T_flange_camera`` is the hand-eye calibration against the Panda's *flange* (libfranka's
F frame), not against the end effector set in Desk (``O_T_EE``): the backend removes
``F_T_EE`` from the arm's pose before composing it.

A device may come from a plug-in backend (``bearchair.hardware.backends``): a section
``"arm"``, ``"humanoid"`` or ``"speaker"`` names it, with the backend's own settings::

    "speaker": {"backend": "my-speaker", "volume": 0.5}

The other devices keep the built-in backends (``panda``, ``nao``); an arm from a plug-in
needs no ``panda_host`` nor ``T_flange_camera``, a humanoid and a speaker both from
plug-ins no ``nao_url``.

Checks (each failure is one line naming the field): unknown keys are refused (with the
nearest known name), rotations are proper and orthonormal (a scaled or mirrored matrix
is refused), translations are bounded (millimetres written as metres are refused), the
arm's base stands where the scan views assume it (:data:`bearchair.core.arena.DEFAULT_ARENA`,
within :data:`BASE_TOLERANCE_M` and :data:`BASE_TOLERANCE_RAD`), the NAO starts inside
the arena, headings are radians in [-pi, pi].
"""

from __future__ import annotations

import difflib
import json
import math
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

import numpy as np

from bearchair.core.arena import DEFAULT_ARENA, Arena
from bearchair.core.errors import BackendUnavailable
from bearchair.core.geometry import yaw_of
from bearchair.core.se2 import SE2Pose

ROTATION_TOLERANCE = 1e-3
"""Largest element of R^T R - I (and |det R - 1|) accepted: a 4-decimal matrix passes."""
BASE_TOLERANCE_M = 0.05
"""How far the arm's base may stand from where the scan views were planned (metres): the
views look at the chair area's centre from 0.6-0.9 m, so 5 cm moves the target 5 cm."""
BASE_TOLERANCE_RAD = math.radians(5.0)
"""How far the base may be turned or tilted from the planned one (5 deg: 5 cm at 0.6 m)."""
MAX_HAND_EYE_M = 0.25
"""The camera sits on the wrist: farther than 25 cm from the flange is a unit mistake."""
SPEED_FACTOR_RANGE = (0.01, 0.5)
"""panda-py's ``speed_factor`` (fraction of the joint velocity limits) allowed for scanning
with a person near the chair; the SDK's default is 0.2."""
CAMERAS = ("carmine", "realsense")

LEGACY_KEYS = {
    "T_hand_camera": "renamed T_flange_camera: the hand-eye calibration against the Panda's "
    "flange frame (not O_T_EE)",
    "nao_start": "now three fields: nao_start_x_m, nao_start_y_m, nao_start_yaw_rad",
}


class CellConfigError(BackendUnavailable):
    """The cell file cannot be used: the message names the file and the field."""


@dataclass(frozen=True)
class CellConfig:
    """A checked cell description (see the module docstring).

    Attributes:
        nao_url: NAOqi endpoint, ``tcp://host:9559`` or ``tcps://host:9503`` (NAOqi >= 2.9);
            None when the humanoid and the speaker both come from plug-ins.
        panda_host: the Panda controller's address (FCI); None when the arm comes from a
            plug-in.
        T_world_base: 4x4 pose of the arm's base in the world (metres).
        T_flange_camera: 4x4 camera optical frame in the Panda's flange frame (metres);
            the identity when the arm comes from a plug-in (its backend calibrates its own).
        nao_start_x_m, nao_start_y_m, nao_start_yaw_rad: where the NAO stands at the
            start, in the world: odometry is counted from here.
        nao_user, nao_password: credentials for ``tcps://`` (None for ``tcp://``).
        camera: the wrist camera, "carmine" (OpenNI2) or "realsense".
        openni_library_dir: the folder holding ``libOpenNI2.so`` (Debian installs it
            outside the binding's search path); None to use the binding's default.
        panda_speed_factor: fraction of the Panda's joint velocity limits for scan moves.
        devices: per role ("arm", "humanoid", "speaker") that a plug-in backend fills,
            its section: ``{"backend": name, ...settings}``.
        source: the file this came from.
    """

    nao_url: str | None
    panda_host: str | None
    T_world_base: np.ndarray
    T_flange_camera: np.ndarray
    nao_start_x_m: float
    nao_start_y_m: float
    nao_start_yaw_rad: float
    nao_user: str | None = None
    nao_password: str | None = None
    camera: str = "carmine"
    openni_library_dir: str | None = None
    panda_speed_factor: float = 0.2
    devices: dict[str, dict[str, Any]] = field(default_factory=dict)
    source: Path | None = None

    @property
    def nao_start(self) -> SE2Pose:
        return SE2Pose(self.nao_start_x_m, self.nao_start_y_m, self.nao_start_yaw_rad)

    def to_json(self) -> dict[str, Any]:
        """The checked configuration as JSON (the password masked), for the run record."""
        out: dict[str, Any] = {}
        for item in fields(self):
            value = getattr(self, item.name)
            if item.name == "source":
                value = str(value) if value else None
            elif isinstance(value, np.ndarray):
                value = value.tolist()
            elif item.name == "nao_password" and value:
                value = "***"
            out[item.name] = value
        return out


_REQUIRED = (
    "nao_url",
    "panda_host",
    "T_world_base",
    "T_flange_camera",
    "nao_start_x_m",
    "nao_start_y_m",
    "nao_start_yaw_rad",
)
DEVICE_ROLES = ("arm", "humanoid", "speaker")
"""The sections that select a plug-in backend (``bearchair.hardware.backends.ROLES``)."""
BUILT_IN_BACKENDS = {"arm": "panda", "humanoid": "nao", "speaker": "nao"}
_KNOWN = (
    *(item.name for item in fields(CellConfig) if item.name not in ("source", "devices")),
    *DEVICE_ROLES,
)


def load_cell_config(path: Path, arena: Arena = DEFAULT_ARENA) -> CellConfig:
    """Reads and checks a cell file (JSON; YAML when PyYAML is installed).

    Raises:
        CellConfigError: the file is missing, unparsable or any field is wrong; the
            message is one line naming the file and the field.
    """
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as error:
        raise CellConfigError(f"{path}: cannot read the cell file ({error.strerror})") from error
    try:
        if path.suffix.lower() in (".yaml", ".yml"):
            try:
                import yaml
            except ImportError as error:
                raise CellConfigError(
                    f"{path}: YAML cell files need PyYAML (pip install pyyaml), or write JSON"
                ) from error
            raw = yaml.safe_load(text)
        else:
            raw = json.loads(text)
    except CellConfigError:
        raise
    except Exception as error:  # JSON and YAML parsers raise their own types
        first_line = str(error).splitlines()[0] if str(error) else type(error).__name__
        raise CellConfigError(f"{path}: not valid JSON/YAML ({first_line})") from error
    try:
        return parse_cell_config(raw, arena, source=path)
    except CellConfigError as error:
        raise CellConfigError(f"{path}: {error}") from None


def parse_cell_config(
    raw: Any, arena: Arena = DEFAULT_ARENA, source: Path | None = None
) -> CellConfig:
    """Checks a decoded cell description (see :func:`load_cell_config`)."""
    _check_fields(raw)
    devices = _device_sections(raw)
    needs_nao = not ("humanoid" in devices and "speaker" in devices)
    _check_required(raw, "arm" not in devices, needs_nao)
    nao_url, nao_user, nao_password = _nao_connection(raw) if needs_nao else (None, None, None)
    camera = _text(raw, "camera", "carmine")
    if camera not in CAMERAS:
        raise CellConfigError(f"camera: {camera!r} is not one of {', '.join(CAMERAS)}")
    speed = _number(raw, "panda_speed_factor", 0.2)
    if not SPEED_FACTOR_RANGE[0] <= speed <= SPEED_FACTOR_RANGE[1]:
        raise CellConfigError(
            f"panda_speed_factor: {speed:g} outside [{SPEED_FACTOR_RANGE[0]}, {SPEED_FACTOR_RANGE[1]}]"
        )

    T_world_base = _rigid(raw, "T_world_base", max_translation_m=3.0)
    _check_base(T_world_base, arena)
    T_flange_camera = (
        _rigid(raw, "T_flange_camera", max_translation_m=MAX_HAND_EYE_M)
        if "arm" not in devices
        else np.eye(4)
    )
    x_m, y_m, yaw_rad = _nao_start(raw, arena)
    return CellConfig(
        nao_url=nao_url,
        panda_host=_text(raw, "panda_host") if "arm" not in devices else None,
        T_world_base=T_world_base,
        T_flange_camera=T_flange_camera,
        nao_start_x_m=x_m,
        nao_start_y_m=y_m,
        nao_start_yaw_rad=yaw_rad,
        nao_user=nao_user,
        nao_password=nao_password,
        camera=camera,
        openni_library_dir=_optional_text(raw, "openni_library_dir"),
        panda_speed_factor=speed,
        devices=devices,
        source=source,
    )


def _check_fields(raw: Any) -> None:
    """Raises CellConfigError unless ``raw`` is an object of known fields (a legacy field
    gets its own message, a misspelt one a suggestion)."""
    if not isinstance(raw, dict):
        raise CellConfigError(
            f"the cell file must be an object of fields, got {type(raw).__name__}"
        )
    for key in raw:
        if key in LEGACY_KEYS:
            raise CellConfigError(f"{key}: {LEGACY_KEYS[key]}")
        if key not in _KNOWN:
            near = difflib.get_close_matches(str(key), _KNOWN, n=1, cutoff=0.6)
            hint = f" (did you mean {near[0]}?)" if near else ""
            raise CellConfigError(f"unknown field {key!r}{hint}; known: {', '.join(_KNOWN)}")


def _check_required(raw: dict[str, Any], needs_panda: bool, needs_nao: bool) -> None:
    """Raises CellConfigError naming the first required field missing (the Panda's and
    the NAO's fields are required only of the built-in backends)."""
    skipped = set()
    if not needs_panda:
        skipped |= {"panda_host", "T_flange_camera"}
    if not needs_nao:
        skipped.add("nao_url")
    missing = [key for key in _REQUIRED if key not in raw and key not in skipped]
    if missing:
        raise CellConfigError(f"missing field {missing[0]}")


def _device_sections(raw: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """The device sections that name a plug-in backend, each checked to be an object
    with a non-empty ``backend``; a section naming the built-in backend is dropped."""
    devices = {}
    for role in DEVICE_ROLES:
        if role not in raw:
            continue
        section = raw[role]
        if not isinstance(section, dict):
            raise CellConfigError(
                f'{role}: an object {{"backend": NAME, ...}} is needed, got {section!r}'
            )
        backend = section.get("backend")
        if not isinstance(backend, str) or not backend.strip():
            raise CellConfigError(f"{role}.backend: a backend name is needed, got {backend!r}")
        if backend == BUILT_IN_BACKENDS[role]:
            if len(section) > 1:
                raise CellConfigError(
                    f"{role}: the built-in {backend} backend takes its settings from the "
                    f"cell's own fields, not {', '.join(sorted(set(section) - {'backend'}))}"
                )
            continue
        devices[role] = {**section, "backend": backend.strip()}
    return devices


def _nao_connection(raw: dict[str, Any]) -> tuple[str, str | None, str | None]:
    """(nao_url, nao_user, nao_password), checked: credentials go together, over tcps only."""
    nao_url = _text(raw, "nao_url")
    if not nao_url.startswith(("tcp://", "tcps://")):
        raise CellConfigError(f"nao_url: {nao_url!r} must start with tcp:// or tcps://")
    nao_user = _optional_text(raw, "nao_user")
    nao_password = _optional_text(raw, "nao_password")
    if (nao_user is None) != (nao_password is None):
        raise CellConfigError("nao_user and nao_password go together")
    if nao_user is not None and not nao_url.startswith("tcps://"):
        raise CellConfigError("nao_user: credentials are only sent over tcps:// (port 9503)")
    return nao_url, nao_user, nao_password


def _nao_start(raw: dict[str, Any], arena: Arena) -> tuple[float, float, float]:
    """The NAO's start (x m, y m, yaw rad), checked to be inside the arena, yaw in [-pi, pi]."""
    x_m = _number(raw, "nao_start_x_m")
    y_m = _number(raw, "nao_start_y_m")
    yaw_rad = _number(raw, "nao_start_yaw_rad")
    if not -math.pi - 1e-6 <= yaw_rad <= math.pi + 1e-6:
        raise CellConfigError(
            f"nao_start_yaw_rad: {yaw_rad:g} is outside [-pi, pi] (radians, not degrees)"
        )
    if not arena.contains(x_m, y_m):
        raise CellConfigError(
            f"nao_start_x_m, nao_start_y_m: ({x_m:g}, {y_m:g}) m is outside the arena "
            f"x [{arena.x_min}, {arena.x_max}], y [{arena.y_min}, {arena.y_max}] m"
        )
    return x_m, y_m, yaw_rad


def check_rigid(T: np.ndarray, name: str, max_translation_m: float) -> None:
    """Raises CellConfigError unless ``T`` is a proper rigid transform with a bounded translation."""
    if T.shape != (4, 4):
        raise CellConfigError(f"{name}: a 4x4 matrix is needed, got shape {T.shape}")
    if not np.all(np.isfinite(T)):
        raise CellConfigError(f"{name}: has non-finite entries")
    if not np.allclose(T[3], [0.0, 0.0, 0.0, 1.0], atol=1e-9):
        raise CellConfigError(f"{name}: the last row must be [0, 0, 0, 1], got {T[3].tolist()}")
    rotation = T[:3, :3]
    orthogonality = float(np.max(np.abs(rotation.T @ rotation - np.eye(3))))
    determinant = float(np.linalg.det(rotation))
    if orthogonality > ROTATION_TOLERANCE or abs(determinant - 1.0) > ROTATION_TOLERANCE:
        raise CellConfigError(
            f"{name}: the rotation is not a rotation (max |R^T R - I| = {orthogonality:.3g}, "
            f"det = {determinant:.3g}): no scale or mirror allowed"
        )
    distance = float(np.linalg.norm(T[:3, 3]))
    if distance > max_translation_m:
        raise CellConfigError(
            f"{name}: translation {distance:.3g} m exceeds {max_translation_m} m "
            "(translations are metres, not millimetres)"
        )


def _check_base(T_world_base: np.ndarray, arena: Arena) -> None:
    offset = T_world_base[:2, 3] - np.asarray(arena.arm_base_xy)
    if np.linalg.norm(offset) > BASE_TOLERANCE_M or abs(T_world_base[2, 3]) > BASE_TOLERANCE_M:
        raise CellConfigError(
            f"T_world_base: the arm's base at {np.round(T_world_base[:3, 3], 3).tolist()} m is "
            f"more than {BASE_TOLERANCE_M} m from where the scan views assume it "
            f"({list(arena.arm_base_xy)}, on the floor)"
        )
    yaw = yaw_of(T_world_base)
    tilt = math.acos(float(np.clip(T_world_base[2, 2], -1.0, 1.0)))
    if abs(yaw) > BASE_TOLERANCE_RAD or tilt > BASE_TOLERANCE_RAD:
        raise CellConfigError(
            f"T_world_base: the base is turned {math.degrees(yaw):.1f} deg and tilted "
            f"{math.degrees(tilt):.1f} deg; the scan views assume it facing +x, level "
            f"(within {math.degrees(BASE_TOLERANCE_RAD):.0f} deg)"
        )


def _rigid(raw: dict[str, Any], key: str, max_translation_m: float) -> np.ndarray:
    try:
        T = np.asarray(raw[key], dtype=float)
    except (TypeError, ValueError) as error:
        raise CellConfigError(f"{key}: not a 4x4 matrix of numbers ({error})") from None
    check_rigid(T, key, max_translation_m)
    return T


def _number(raw: dict[str, Any], key: str, default: float | None = None) -> float:
    value = raw.get(key, default)
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise CellConfigError(f"{key}: a finite number is needed, got {value!r}")
    return float(value)


def _text(raw: dict[str, Any], key: str, default: str | None = None) -> str:
    value = raw.get(key, default)
    if not isinstance(value, str) or not value.strip():
        raise CellConfigError(f"{key}: a non-empty string is needed, got {value!r}")
    return value.strip()


def _optional_text(raw: dict[str, Any], key: str) -> str | None:
    if raw.get(key) is None:
        return None
    return _text(raw, key)
