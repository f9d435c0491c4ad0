"""The sitting imagination's parameters: the paper's drops (8 rotations, 3 or 7
positions L_sit apart, the start jitter) and what the project adds (the vote's window,
the split vote's settling). The procedure is :mod:`bearchair.skills.imagination.imagine`,
the choice of the rotation :mod:`bearchair.skills.imagination.vote`."""

from __future__ import annotations

import math

N_ROTATIONS = 8
FIRST_POSITIONS = (0, -1, 1)
EXTRA_POSITIONS = (-2, 2, -3, 3)
L_SIT_RATIO = 0.15
"""L_sit = L_SIT_RATIO × the OBB's mean horizontal side (metres)."""
JITTER_POSITION_M = 0.005
JITTER_YAW_RAD = math.radians(2.0)
WINDOW_HALF_WIDTH = 1
"""Beyond the paper: the rotations at ±45 degrees of α_i vote with it when the best
rotation is chosen (see :func:`bearchair.skills.imagination.vote.choose_sitting_pose`);
the pose is still averaged over the chosen rotation's own sittings. On round or wide
seats the diagonals also sit, and the paper's tie-break by mean J + L then picks one;
the window keeps the rotation whose neighbours agree (measurements: docs/decisions.md)."""
SPLIT_SETTLE_REPEATS = 1
"""A split vote (below) is settled by dropping again, this many more times, at the first
three positions of every contested rotation, with fresh start jitter."""
PULL_MIN_RAD = 2.0 * JITTER_YAW_RAD
"""A sitter turned further than twice the start jitter toward a direction was turned by
the chair, not by how it was dropped."""
MORE_POSITIONS_MAX_CORRECT = 1
"""The paper: the four extra drop positions run when at most this many of the first 24
drops were correct sittings."""
MIN_CORRECT = 1
"""Correct sittings the best rotation needs for a sitting pose to be reported."""
