"""The named postures q = (ankle, knee, hip, shoulder, elbow) the seating motions start
or end in (radians)."""

from __future__ import annotations

import numpy as np

STANDING_POSTURE = np.array([0.0, 0.0, 0.0, 0.9208, 1.3629])
"""q = (ankle, knee, hip, shoulder, elbow) that starts the seating motion: standing
straight, the palms where the carrying posture (:data:`bearchair.core.nao_carrying.CARRYING_POSTURE_RAD`)
has them (within 3 mm and 2 deg, checked by a test), so the bear barely moves when the
arms switch to the planar posture during the lead-in."""
RAISED_POSTURE = np.array([0.0, 0.0, 0.0, 0.0, 0.41])
"""q with the bear raised for stepping up to a high seat: standing straight, the arms
forward, the bear's seat point 0.40 m high and 0.20 m ahead (0.32 m and 0.16 m in
:data:`STANDING_POSTURE`), tilted 0.2 deg. Over a seat higher than the carried bear
(0.32 m) the NAO stops where the carried bear is clear, raises it, and steps in:
standing there with the bear low, it could not reach the seat."""
HIGH_RAISED_POSTURE = np.array([0.0, 0.0, 0.0, -0.3, 0.11])
"""q with the bear raised higher, for a seat that :data:`RAISED_POSTURE`'s bear does not
clear: the arms 0.3 rad above the horizontal and the elbows bent 0.3 rad less, so the
forearms and the bear keep :data:`RAISED_POSTURE`'s tilt (0.2 deg), the bear's seat
point 0.43 m high and 0.20 m ahead. The NAO then reaches every seat the imagination sits
a child on (up to 0.425 m, :mod:`bearchair.skills.imagination.sam`) with the planner's
3 mm margin; without it, seats above 0.398 m were refused, and the scan's millimetre of
noise decided whether a 0.397 m seat was."""
RAISED_POSTURES = (RAISED_POSTURE, HIGH_RAISED_POSTURE)
"""The raised postures, lowest first: the NAO raises the bear to the first that clears the
seat (:func:`.raising.raised_posture`)."""
REST_POSTURE = np.array([0.0, 0.0, 0.0, 1.4, 0.4])
"""q after the retract: standing straight, arms down along the body."""
