"""Turning blackboard values into small JSON for run records."""

from __future__ import annotations

import math
from typing import Any

import numpy as np


def to_jsonable(value: Any, depth: int = 0) -> Any:
    """A compact JSON-friendly view of ``value``.

    Results that know their JSON (``to_json()``) give it; arrays and meshes are
    described by their shape, never dumped.
    """
    if depth > 4:
        return repr(value)[:80]
    if value is None or isinstance(value, bool | int | str):
        return value
    if isinstance(value, float | np.floating):
        number = float(value)
        return round(number, 6) if math.isfinite(number) else str(number)
    if isinstance(value, np.integer):
        return int(value)
    if callable(getattr(value, "to_json", None)):
        return to_jsonable(value.to_json(), depth + 1)
    if isinstance(value, np.ndarray):
        if value.size <= 16:
            return [to_jsonable(v, depth + 1) for v in value.tolist()]
        return f"ndarray{tuple(value.shape)}"
    if type(value).__name__ == "Trimesh":
        return f"Trimesh({len(value.vertices)} vertices, {len(value.faces)} faces)"
    if hasattr(value, "_asdict"):
        return {k: to_jsonable(v, depth + 1) for k, v in value._asdict().items()}
    if isinstance(value, dict):
        return {str(k): to_jsonable(v, depth + 1) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [to_jsonable(v, depth + 1) for v in value]
    return repr(value)[:200]
