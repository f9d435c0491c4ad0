"""The person who turns the chair when asked, and the voice that asks."""

from __future__ import annotations

import logging
import math
import re
from typing import Literal, NamedTuple

import numpy as np

from bearchair.core.geometry import make_transform, rot_z
from bearchair.hardware.interfaces import Speaker
from bearchair.hardware.sim.chair import SimChair
from bearchair.hardware.sim.clock import SimClock

log = logging.getLogger(__name__)

HelperMode = Literal["obeys", "disobeys", "ignores"]

_INSTRUCTION = re.compile(
    r"rotate\s+the\s+chair.*?\b(counter-?clockwise|anti-?clockwise|clockwise)\b.*?"
    r"(\d+(?:\.\d+)?)\s*deg",
    re.IGNORECASE | re.DOTALL,
)

MAX_ANGLE_ERROR_DEG = 10.0
MAX_JITTER_M = 0.01
REACTION_S = (0.2, 0.5)


class HeardInstruction(NamedTuple):
    """What the helper understood: counterclockwise (seen from above) is positive."""

    clockwise: bool
    angle_deg: float

    @property
    def signed_angle_rad(self) -> float:
        """The requested rotation about +z in radians (clockwise is negative)."""
        return math.radians(-self.angle_deg if self.clockwise else self.angle_deg)


def parse_instruction(sentence: str) -> HeardInstruction | None:
    """Parses "... rotate the chair ... {clockwise|counterclockwise} for N degrees"; None if not."""
    match = _INSTRUCTION.search(sentence)
    if match is None:
        return None
    direction = match.group(1).lower().replace("-", "")
    return HeardInstruction(direction == "clockwise", float(match.group(2)))


class HelperAction(NamedTuple):
    """What the helper did about one instruction (for run records and tests).

    Attributes:
        sentence: what was heard.
        requested_rad: the rotation asked for (counterclockwise positive).
        performed_rad: the rotation the helper applied.
        translation_m: (2,) the unintended shift of the chair's centre.
        start_s, end_s: simulated times of the motion.
    """

    sentence: str
    requested_rad: float
    performed_rad: float
    translation_m: np.ndarray
    start_s: float
    end_s: float


class SimHelper:
    """Implements :class:`bearchair.hardware.interfaces.Helper`: turns the chair over simulated time.

    Modes:
        obeys: turns by the requested angle plus an error uniform in ±10 deg, and shifts
            the centre by at most 1 cm.
        disobeys: the first instruction is turned the wrong way or not at all (chosen by
            the seed); every later instruction is obeyed.
        ignores: never turns the chair.

    A turn starts 0.2-0.5 s after the sentence is heard and lasts 2-4 s (2 s plus 1 s per
    90 deg, at most 4 s), with a smooth (cosine) speed profile about the chair frame's
    vertical axis; the chair is moved kinematically and left at rest.

    Attributes:
        actions: every action taken, in order (including refusals with 0 rotation).
    """

    def __init__(
        self, clock: SimClock, chair: SimChair, mode: HelperMode, rng: np.random.Generator
    ) -> None:
        if mode not in ("obeys", "disobeys", "ignores"):
            raise ValueError(f"unknown helper mode {mode!r} (obeys, disobeys or ignores)")
        self.mode: HelperMode = mode
        self._clock = clock
        self._chair = chair
        self._rng = rng
        self._heard = 0
        self._disobedience: Literal["wrong_way", "no_turn"] = (
            "wrong_way" if rng.random() < 0.5 else "no_turn"
        )
        self.actions: list[HelperAction] = []
        self.sentences: list[str] = []
        self._pending: list[tuple[HelperAction, np.ndarray | None]] = []
        clock.add_process(self._step)

    @property
    def moving(self) -> bool:
        """True while a turn is scheduled or under way."""
        return bool(self._pending)

    def hear(self, sentence: str) -> None:
        """Receives a sentence; a parsable instruction schedules a turn (depending on mode)."""
        self.sentences.append(sentence)
        instruction = parse_instruction(sentence)
        if instruction is None:
            log.info("helper: did not understand %r", sentence)
            return
        self._heard += 1
        requested = instruction.signed_angle_rad
        performed = requested + math.radians(
            self._rng.uniform(-MAX_ANGLE_ERROR_DEG, MAX_ANGLE_ERROR_DEG)
        )
        jitter_direction = self._rng.uniform(0.0, 2.0 * math.pi)
        jitter = self._rng.uniform(0.0, MAX_JITTER_M) * np.array(
            [math.cos(jitter_direction), math.sin(jitter_direction)]
        )
        if self.mode == "ignores":
            performed, jitter = 0.0, np.zeros(2)
        elif self.mode == "disobeys" and self._heard == 1:
            if self._disobedience == "wrong_way":
                performed = -performed
            else:
                performed, jitter = 0.0, np.zeros(2)
        start = self._clock.now() + self._rng.uniform(*REACTION_S)
        duration = min(4.0, 2.0 + abs(math.degrees(performed)) / 90.0)
        action = HelperAction(sentence, requested, performed, jitter, start, start + duration)
        self.actions.append(action)
        log.info(
            "helper (%s): asked %.0f deg, turns %.1f deg",
            self.mode,
            math.degrees(requested),
            math.degrees(performed),
        )
        if performed != 0.0 or np.any(jitter):
            self._pending.append((action, None))

    def _step(self, now_s: float, dt_s: float) -> None:
        if not self._pending:
            return
        action, T_world_start = self._pending[0]
        if now_s < action.start_s:
            return
        if T_world_start is None:
            T_world_start = self._chair.T_world_chair()
            self._pending[0] = (action, T_world_start)
        progress = min(1.0, (now_s - action.start_s) / (action.end_s - action.start_s))
        eased = 0.5 - 0.5 * math.cos(math.pi * progress)
        centre = T_world_start[:3, 3]
        motion = make_transform(
            rot_z(action.performed_rad * eased),
            centre + np.append(action.translation_m * eased, 0.0),
        ) @ make_transform(np.eye(3), -centre)
        self._chair.set_T_world_chair(motion @ T_world_start)
        if progress >= 1.0:
            self._pending.pop(0)


class SimSpeaker:
    """Implements :class:`bearchair.hardware.interfaces.Speaker`: logs, speaks (if a voice is given) and
    lets the helper hear the sentence.

    Attributes:
        spoken: every sentence, in order (the name every speaker uses).
    """

    def __init__(self, helper: SimHelper | None, voice: Speaker | None = None) -> None:
        self._helper = helper
        self._voice = voice
        self.spoken: list[str] = []

    def say(self, sentence: str) -> None:
        """Says one sentence."""
        log.info("robot says: %s", sentence)
        self.spoken.append(sentence)
        if self._voice is not None:
            self._voice.say(sentence)
        else:
            print(f"[robot] {sentence}", flush=True)
        if self._helper is not None:
            self._helper.hear(sentence)
