"""One pybullet connection shared by every simulated device, behind one lock.

The executive calls the world from worker threads while the main thread may poll it, so
every pybullet call of a world goes through :class:`LockedBullet`, which holds the
world's single ``threading.RLock`` for the duration of each call. Callers that need
several calls to be atomic (read, then write) hold ``bullet.lock`` around them.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import os
import threading
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pybullet
from pybullet_utils import bullet_client

from bearchair.core.bullet_poses import matrix_to_pose, pose_to_matrix
from bearchair.core.meshes import cache_dir
from bearchair.core.streams import silenced_fds


def sim_cache_dir() -> Path:
    """Where generated simulation assets (URDFs, OBJs, textures) are written."""
    path = cache_dir() / "sim"
    path.mkdir(parents=True, exist_ok=True)
    return path


def cached_asset(stem: str, text: str, suffix: str) -> Path:
    """Writes ``text`` into :func:`sim_cache_dir` once per content and returns the file.

    The name carries a digest of the content (``STEM-DIGEST.SUFFIX``); the file is
    written under a process-private name and renamed, so processes building the same
    world at once never read a half-written file.
    """
    digest = hashlib.sha1(text.encode()).hexdigest()[:12]
    path = sim_cache_dir() / f"{stem}-{digest}{suffix}"
    if not path.exists():
        scratch = path.with_suffix(f".{os.getpid()}.tmp")
        scratch.write_text(text)
        os.replace(scratch, path)
    return path


class LockedBullet:
    """A pybullet client whose every call holds the world's re-entrant lock.

    Attributes:
        lock: the world's lock; hold it to make a sequence of calls atomic.
        client: the underlying ``BulletClient`` (use through this wrapper only).
    """

    def __init__(self, gui: bool = False) -> None:
        self.lock = threading.RLock()
        # BulletClient prints a bare "argv[0]=" (and in GUI mode OpenGL details) from C.
        with silenced_fds(1):
            self.client = bullet_client.BulletClient(
                connection_mode=pybullet.GUI if gui else pybullet.DIRECT
            )
        self.gui = gui
        self._closed = False
        self._inertial_frames: dict[int, tuple[Any, Any]] = {}

    def __getattr__(self, name: str) -> Any:
        attribute = getattr(self.client, name)
        if not callable(attribute):
            return attribute

        @functools.wraps(attribute)
        def locked(*args: Any, **kwargs: Any) -> Any:
            with self.lock:
                if self._closed:
                    raise RuntimeError("the simulated world is closed")
                return attribute(*args, **kwargs)

        # Kept, so later calls skip this method: the world makes thousands of calls per
        # simulated second, and building the wrapper cost more than many of the calls.
        self.__dict__[name] = locked
        return locked

    def local_inertial_frame(self, body: int) -> tuple[Any, Any]:
        """(position, orientation) of a body's base inertial frame in its link frame.

        Fixed for the life of a body, so read once.
        """
        frame = self._inertial_frames.get(body)
        if frame is None:
            frame = tuple(self.getDynamicsInfo(body, -1)[3:5])
            self._inertial_frames[body] = frame
        return frame

    @property
    def closed(self) -> bool:
        """True once :meth:`disconnect_once` has run."""
        return self._closed

    def disconnect_once(self) -> None:
        """Disconnects from the physics server; later calls do nothing."""
        with self.lock:
            if self._closed:
                return
            self._closed = True
            with contextlib.suppress(pybullet.error):
                self.client.disconnect()


StepProcess = Callable[[float, float], None]
"""A process advanced by the clock before each physics step: ``process(now_s, dt_s)``."""


def T_world_base_link(bullet: LockedBullet, body: int) -> np.ndarray:
    """The base's link frame in the world (pybullet reports the inertial frame instead)."""
    with bullet.lock:
        position, orientation = bullet.getBasePositionAndOrientation(body)
        local_position, local_orientation = bullet.local_inertial_frame(body)
    T_world_inertial = pose_to_matrix(position, orientation)
    T_link_inertial = pose_to_matrix(local_position, local_orientation)
    return T_world_inertial @ np.linalg.inv(T_link_inertial)


def reset_base_link(bullet: LockedBullet, body: int, T_world_link: np.ndarray) -> None:
    """Teleports a body so that its base link frame is ``T_world_link``; zeroes its velocity."""
    with bullet.lock:
        local_position, local_orientation = bullet.local_inertial_frame(body)
        T_world_inertial = T_world_link @ pose_to_matrix(local_position, local_orientation)
        position, orientation = matrix_to_pose(T_world_inertial)
        bullet.resetBasePositionAndOrientation(body, position, orientation)
        bullet.resetBaseVelocity(body, [0.0, 0.0, 0.0], [0.0, 0.0, 0.0])


def T_world_link(bullet: LockedBullet, body: int, link: int) -> np.ndarray:
    """A link's URDF frame in the world, by forward kinematics of the current joint state."""
    if link < 0:
        return T_world_base_link(bullet, body)
    state = bullet.getLinkState(body, link, computeForwardKinematics=True)
    return pose_to_matrix(state[4], state[5])


def joint_index_by_name(bullet: LockedBullet, body: int) -> dict[str, int]:
    """Joint name -> index for every joint of a body."""
    return {
        bullet.getJointInfo(body, index)[1].decode(): index
        for index in range(bullet.getNumJoints(body))
    }


def link_index_by_name(bullet: LockedBullet, body: int) -> dict[str, int]:
    """Link name -> index (the base link is -1)."""
    names = {bullet.getBodyInfo(body)[0].decode(): -1}
    for index in range(bullet.getNumJoints(body)):
        names[bullet.getJointInfo(body, index)[12].decode()] = index
    return names
