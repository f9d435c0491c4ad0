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
REST_POSTURE = np.array([0.0, 0.0, 0.0, 1.4, 0.4])
"""q after the retract: standing straight, arms down along the body."""
