"""The skills' parameters a user tunes (``[scan]`` and ``[imagination]`` of a mission
configuration): :class:`SkillParameters`, numbers only, cheap to import.

``None`` keeps a skill's own default, so ``SkillParameters()`` is the skills as shipped.
"""

from __future__ import annotations

from dataclasses import dataclass

SCAN_VIEW_COUNT = 9
"""How many scan configurations there are (``perception.views.SCAN_CONFIGURATIONS``; a
test keeps the two in step, so that checking a configuration imports no perception)."""
MIN_SCAN_VIEWS = 5
"""Fewest views a scan accepts (``perception.scan_capture.MIN_SCAN_VIEWS``, likewise)."""


@dataclass(frozen=True)
class SkillParameters:
    """What :class:`bearchair.skills.default_skills.DefaultSkills` passes its skills.

    Attributes:
        scan_views: indices of ``perception.views.SCAN_CONFIGURATIONS`` the scan visits,
            in order; None: all of them.
        voxel_size_m: the reconstruction's TSDF voxel edge (metres); None: 8 mm.
        max_drop_time_s: simulated seconds after which an imagined drop is stopped;
            None: ``SimulationSettings.max_time_s``.
        drop_clearance_m: how high above the chair's bounding box the imagined agent is
            dropped (metres); None: the paper's 15 cm.
    """

    scan_views: tuple[int, ...] | None = None
    voxel_size_m: float | None = None
    max_drop_time_s: float | None = None
    drop_clearance_m: float | None = None
