"""How the NAO carries the bear: the one definition shared by the planner and the simulator.

The NAO is handed the bear standing straight with its arms in
:data:`CARRYING_POSTURE_RAD`; the bear is upright, faces the NAO and is held between the
palms with its seat point (the bottom centre of its torso) :data:`BEAR_SEAT_BELOW_HANDS_M`
below the palms' middle. From then on the bear moves rigidly with the hands frame.

Frames:

* palm: the centre of the hand, :data:`PALM_IN_WRIST_M` in the ``l_wrist`` / ``r_wrist``
  link frames of qibullet's ``nao.urdf`` (x along the hand, z out of its back);
* hands frame: the two palms' middle, oriented as the mean (normalised quaternion sum)
  of the two palms' orientations.

Where the carrying posture holds the bear (standing straight, the NAO frame on the floor
between the soles, x forward, z up; computed from the URDF and checked by
tests/test_wholebody.py): the palms' middle about 0.156 m ahead of the ankles and
0.388 m above the soles, so the bear's seat point is about 0.323 m above the floor
(high enough to carry it over seats up to about 0.30 m) and its ears, at 0.573 m, stay
below the head's ArUco tag (0.58 m). The palms are about 7 cm either side of the
mid-plane, squeezing the bear's torso (0.10 m wide). The centre of mass with the bear
stays about 2 cm ahead of the ankles, well inside the feet.
"""

from __future__ import annotations

CARRYING_POSTURE_RAD: dict[str, float] = {
    "LShoulderPitch": 0.8,
    "LShoulderRoll": 0.065,
    "LElbowYaw": -1.033,
    "LElbowRoll": -1.3,
    "LWristYaw": 1.3,
    "RShoulderPitch": 0.8,
    "RShoulderRoll": -0.065,
    "RElbowYaw": 1.033,
    "RElbowRoll": 1.3,
    "RWristYaw": -1.3,
}
"""qibullet joint angles (radians) of the arms while carrying; every other joint is 0
(standing straight). Mirror-symmetric: the right side's rolls and yaws are the left's
negated. Within the URDF's joint limits."""

BEAR_SEAT_BELOW_HANDS_M = 0.065
"""Height (metres) of the palms' middle above the bear's seat point when it is handed
over: the palms hold the middle of the bear's torso."""

PALM_IN_WRIST_M: tuple[float, float, float] = (0.045, 0.0, -0.008)
"""The palm's centre (metres) in the ``l_wrist`` / ``r_wrist`` link frames."""

BEAR_SEAT_CLEARANCE_M = 0.01
"""The bear's seat point is let go at most this high over the scanned seat's top (metres),
not at the imagined sitting pose's height (the sitter's pelvis, 6 to 10 cm over the seat:
a bear released there tips over the seat's front edge). It covers the scan's error in the
seat's height, which put the scanned seat 2-5 mm above the true one in the campaign
trials. Released from 2 cm the bear lands at 0.6 m/s and bounced off curved or railed
seats and the NAO's wrists; from 1 cm, at 0.44 m/s. Over a seat lower than the NAO's
crouch reaches, the bear is let go at the lowest height a goal posture holds it, up to
``LOW_SEAT_RELEASE_GAP_M`` over the seat."""

LOW_SEAT_RELEASE_GAP_M = 0.06
"""Over a seat the NAO cannot hold the bear 1 cm over bent at the hips (lower than about
0.19 m), the bear's seat point is let go higher, at most this high over the seat (metres;
``bearchair.skills.planning.wholebody.release_height``); a lower seat is out of reach.
Released from up to 6 cm onto the seat, the bear stayed seated in the release
imagination on flat seats (8 cm too) and in the whole missions of ``bench/low_seats.py``
(docs/decisions.md): it falls on its own base, upright, and settles there."""

BEAR_TORSO_DEPTH_M = 0.085
"""Fore-aft depth of the bear's torso (metres), the part it sits on: its legs stick out
forward from it."""

BEAR_COM_AHEAD_M = 0.013
"""How far the bear's centre of mass lies ahead of its seat point (metres), for a
uniformly dense bear (its legs stick out forward)."""

BEAR_COM_HEIGHT_M = 0.10
"""Height of the bear's centre of mass over its seat point (metres), for a uniformly dense
bear."""

PLACEMENT_TOLERANCE_M = 0.015
"""How far (metres, in the NAO frame) the whole-body goal posture may set the bear's seat
point from the sitting point g: the goal problem's placement box
(``bearchair.skills.planning.wholebody.optimisation``), which a reach-limited goal uses to put the
bear nearer the NAO. Along x either way; along z only down, never up: the bear is let go
where the hands hold it and drops what it hangs over the seat. Above g a posture is
cheaper (less crouching), so a box open upward made every goal let go at its top,
``BEAR_SEAT_CLEARANCE_M`` plus this over the scanned seat, and bears released 4 cm over
the seat landed on a wrist and tipped."""
