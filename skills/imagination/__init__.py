"""Sitting imagination: find how to sit on an unseen chair by physical simulation.

Public entry point: :func:`imagine_sitting` (the ``imagine_sitting`` skill of
``bearchair.skills.mission_skills``). See ``imagine.py`` for the procedure, ``vote.py`` for the choice of the rotation,
``workers.py`` for the worker processes, ``drop_parameters.py`` for the drops' numbers, ``agent.py`` for the
generated child-sized agent, ``chair.py`` for g_obb and the chair's preparation,
``simulation.py`` for the drops and ``sam.py`` for the sitting affordance model.

The names below are imported from ``imagine.py`` on first use, not with the package:
the drop worker processes import ``simulation.py`` only, and importing ``imagine.py``
(trimesh, scipy) would be about half a second of each worker's start-up.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from bearchair.skills.imagination.imagine import (
        ImaginationDetails,
        imagine_sitting,
        imagine_sitting_details,
    )
    from bearchair.skills.imagination.workers import shutdown_workers, warm_up

DEFAULT_WORKERS = 2
"""Worker processes the imagination drops in unless told otherwise (1: the caller's own);
the result is the same for any number."""

__all__ = [
    "ImaginationDetails",
    "imagine_sitting",
    "imagine_sitting_details",
    "shutdown_workers",
    "warm_up",
]


def __getattr__(name: str) -> Any:
    if name in __all__:
        module = "workers" if name in ("shutdown_workers", "warm_up") else "imagine"
        return getattr(importlib.import_module(f"bearchair.skills.imagination.{module}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
