"""Sitting imagination: find how to sit on an unseen chair by physical simulation.

Public entry point: :func:`imagine_sitting` (the ``imagine_sitting`` skill of
``skills.toolbox``). See ``imagine.py`` for the procedure, ``agent.py`` for the
generated child-sized agent, ``chair.py`` for g_obb and the chair's preparation,
``simulation.py`` for the drops and ``sam.py`` for the sitting affordance model.
"""

from skills.imagination.imagine import (
    ImaginationDetails,
    imagine_sitting,
    imagine_sitting_details,
    shutdown_workers,
    warm_up,
)

__all__ = [
    "ImaginationDetails",
    "imagine_sitting",
    "imagine_sitting_details",
    "shutdown_workers",
    "warm_up",
]
