"""The Franka Panda through ``panda_py`` (extra ``bearchair[panda]``) with its wrist camera.

SDK facts this backend is written against (panda-python 1.1.1, libfranka 0.9.2; the
PyPI wheel fits the original Panda (FER) with robot system >= 4.2.1: research interface
version 5; other systems need the panda-py build for their libfranka version):

* ``Panda.get_pose()`` is ``O_T_EE``, the end effector set in Desk (with the Franka Hand
  10.34 cm along z and -45 deg about z from the flange). The hand-eye calibration is
  against the flange, so the camera pose is ``T_world_base @ O_T_EE @ inv(F_T_EE) @
  T_flange_camera`` with ``F_T_EE`` read from the robot state (column-major 16-vectors).
* ``move_to_joint_position`` blocks, returns False on failure (the libfranka error is
  kept for ``raise_error()``), and *first runs automatic error recovery* when the robot
  is in reflex: :meth:`PandaArm.move_to` therefore checks the robot's mode and errors
  itself and raises :class:`ArmFault` instead of letting a move recover silently.
* panda-py adds virtual joint walls :data:`JOINT_WALL_MARGIN_RAD` inside each limit
  (the PD zone of its ``VirtualWallController``): a target inside them is not reached.
* ``get_robot().stop()`` (libfranka ``Robot::stop``) preempts a running motion from
  another thread: :meth:`PandaArm.emergency_stop` uses it.
* ``Panda(host)`` blocks in libfranka's connect (up to a minute against a peer that
  accepts and stays silent), releasing the GIL: it runs in a worker with a bound
  (:func:`~bearchair.hardware.real.bounded.call_within`).
* The joint limits come from the robot (``get_joint_limits_lower/upper``: panda-py picks
  the FER's or the FR3's from the server version); the FER's are the fallback.
* A move's timeout is its planned duration (panda-py's ``motion.JointTrajectory`` at the
  configured speed factor, the trajectory ``move_to_joint_position`` follows) times
  :data:`MOVE_TIME_MARGIN` plus :data:`MOVE_SETTLE_S`.
* :meth:`PandaArm.activate` sets libfranka's collision thresholds
  (:data:`COLLISION_TORQUE_NM`, :data:`COLLISION_FORCE_N`) and the wrist camera's payload
  (``set_load``): without them the robot keeps whatever the last program set.
"""

from __future__ import annotations

import contextlib
import logging
import threading
import time
from collections.abc import Sequence
from typing import Any

import numpy as np

from bearchair.core.errors import BackendError, BackendUnavailable
from bearchair.hardware.interfaces import CameraIntrinsics, RGBDFrame
from bearchair.hardware.real import EmergencyStopped, import_sdk
from bearchair.hardware.real.bounded import DeviceTimeout, call_within
from bearchair.hardware.real.camera import CARMINE_INTRINSICS, CarmineCamera

__all__ = ["CARMINE_INTRINSICS", "ArmFault", "CarmineCamera", "PandaArm"]

log = logging.getLogger(__name__)

JOINT_LIMITS_LOWER_RAD = (-2.8973, -1.7628, -2.8973, -3.0718, -2.8973, -0.0175, -2.8973)
JOINT_LIMITS_UPPER_RAD = (2.8973, 1.7628, 2.8973, -0.0698, 2.8973, 3.7525, 2.8973)
"""The Panda's (FER) joint limits, as libfranka and panda-py give them: the fallback when
the robot object cannot say (``get_joint_limits_lower/upper``)."""
CONNECT_TIMEOUT_S = 10.0
"""Bound on connecting to the arm's controller (libfranka's own is 60 s)."""
MOVE_TIME_MARGIN = 1.5
MOVE_SETTLE_S = 2.0
"""A move may take its planned duration times :data:`MOVE_TIME_MARGIN` plus this long
(seconds): panda-py ends a move when the joints are slower than ``dq_threshold`` after
the trajectory, which takes up to a second or two with the default impedance."""
COLLISION_TORQUE_NM = (20.0, 20.0, 18.0, 18.0, 16.0, 14.0, 12.0)
COLLISION_FORCE_N = (20.0, 20.0, 20.0, 25.0, 25.0, 25.0)
"""libfranka's collision thresholds (joint torques, then Cartesian forces and torques) as
its example programs set them for slow motions: a reflex stops the arm on a contact
above them, well before the defaults (up to 100 N) would."""
CAMERA_MASS_KG = 0.16
"""The wrist camera as payload: a Carmine 1.09 weighs about 160 g (PrimeSense
datasheet); with its mount, set ``payload_mass_kg`` in the cell file to the weighed value."""
CAMERA_BOX_M = (0.18, 0.035, 0.05)
"""The Carmine's housing (metres), for the payload's inertia as a solid box."""
JOINT_WALL_MARGIN_RAD = (0.12, 0.09, 0.09, 0.09, 0.0349, 0.0349, 0.0349)
"""panda-py's virtual wall PD-zone widths (``kPDZoneWidth``): it pushes joints out of this
band inside each limit."""
MAX_WALL_SHIFT_RAD = 0.1
"""A target at most this far inside the walls is moved to their edge (the camera pose
comes from the arm's own kinematics, so the view stays known); farther is refused."""
STILL_DURING_CAPTURE_M = 0.002
FAULT_MODES = ("kReflex", "kOther", "kUserStopped", "kAutomaticErrorRecovery")


class ArmFault(BackendError, RuntimeError):
    """The Panda reported an error (libfranka's message); recover it with the operator."""


def wall_limits(
    limits: tuple[Sequence[float], Sequence[float]] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """The joint range panda-py's walls leave (lower, upper) in radians inside ``limits``
    (the robot's; default the FER's)."""
    lower, upper = limits or (JOINT_LIMITS_LOWER_RAD, JOINT_LIMITS_UPPER_RAD)
    margin = np.asarray(JOINT_WALL_MARGIN_RAD)
    return np.asarray(lower, dtype=float) + margin, np.asarray(upper, dtype=float) - margin


def into_walls(
    target: np.ndarray, limits: tuple[Sequence[float], Sequence[float]] | None = None
) -> tuple[np.ndarray, list[str]]:
    """The target moved inside panda-py's walls, and a note per joint that moved.

    Raises:
        ValueError: a joint is more than :data:`MAX_WALL_SHIFT_RAD` beyond the walls.
    """
    lower, upper = wall_limits(limits)
    clipped = np.clip(target, lower, upper)
    notes = []
    for joint in np.flatnonzero(np.abs(clipped - target) > 0.0):
        shift = float(clipped[joint] - target[joint])
        if abs(shift) > MAX_WALL_SHIFT_RAD:
            raise ValueError(
                f"joint {joint + 1} target {target[joint]:.4f} rad is {abs(shift):.3f} rad inside "
                f"panda-py's joint wall [{lower[joint]:.4f}, {upper[joint]:.4f}]: unreachable"
            )
        notes.append(f"joint {joint + 1} {target[joint]:.4f} -> {clipped[joint]:.4f} rad")
    return clipped, notes


def planned_duration_s(start: np.ndarray, target: np.ndarray, speed_factor: float) -> float:
    """The duration (s) of panda-py's joint trajectory from ``start`` to ``target``.

    panda-py's own planner when installed; otherwise the slowest joint at the speed
    factor times the Panda's lowest joint speed limit, 2.175 rad/s, doubled for the ramps.
    """
    try:
        from panda_py import motion
    except ImportError:
        return 2.0 * float(np.max(np.abs(target - start))) / (2.175 * speed_factor)
    if np.allclose(start, target, atol=1e-6):
        return 0.0
    return float(motion.JointTrajectory([start, target], speed_factor=speed_factor).get_duration())


def _robot_joint_limits(robot: Any) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """The connected robot's joint limits (FER or FR3, as panda-py reads the server)."""
    try:
        lower, upper = robot.get_joint_limits_lower(), robot.get_joint_limits_upper()
    except AttributeError:  # a panda-py without them: the FER's
        return JOINT_LIMITS_LOWER_RAD, JOINT_LIMITS_UPPER_RAD
    return tuple(map(float, np.ravel(lower))), tuple(map(float, np.ravel(upper)))


def _box_inertia(mass_kg: float, size_m: tuple[float, float, float]) -> np.ndarray:
    """The 3x3 inertia (kg m^2) of a solid box about its centre."""
    x, y, z = size_m
    return np.diag([y * y + z * z, x * x + z * z, x * x + y * y]) * mass_kg / 12.0


def _mode_name(mode: Any) -> str:
    return getattr(mode, "name", str(mode).rsplit(".", 1)[-1])


STOP_POLL_S = 0.005
"""How often (seconds) a running move checks whether a stop must be repeated."""


class PandaArm:
    """:class:`bearchair.hardware.interfaces.ScanningArm` on a real Panda.

    Args:
        robot: a ``panda_py.Panda`` (tests pass
            :class:`bearchair.hardware.real.standins.PandaStandin`).
        camera: the wrist camera (``read() -> (rgb, depth_m)`` and ``intrinsics``).
        T_world_base: the arm base in the world frame.
        T_flange_camera: the hand-eye calibration (camera optical frame in the flange frame).
        speed_factor: fraction of the arm's velocity limits for scanning moves.
        clock: what move timeouts are counted on (default wall time; a simulation's).
        payload_mass_kg: the wrist camera and its mount, set as the payload at activation.
    """

    def __init__(
        self,
        robot: Any,
        camera: Any,
        T_world_base: np.ndarray,
        T_flange_camera: np.ndarray,
        speed_factor: float = 0.2,
        clock: Any | None = None,
        payload_mass_kg: float = CAMERA_MASS_KG,
    ) -> None:
        self._robot = robot
        self._camera = camera
        self._T_world_base = np.asarray(T_world_base, dtype=float)
        self._T_flange_camera = np.asarray(T_flange_camera, dtype=float)
        self.speed_factor = speed_factor
        self._now = clock.now if clock is not None else time.monotonic
        self._payload_mass_kg = payload_mass_kg
        self._start = time.monotonic()
        self._stopped = False
        self.joint_limits = _robot_joint_limits(robot)

    @classmethod
    def connect(
        cls,
        host: str,
        T_world_base: np.ndarray,
        T_flange_camera: np.ndarray,
        speed_factor: float = 0.2,
        openni_library_dir: str | None = None,
        camera: str = "carmine",
        camera_intrinsics: CameraIntrinsics | None = None,
        timeout_s: float = CONNECT_TIMEOUT_S,
        payload_mass_kg: float = CAMERA_MASS_KG,
    ) -> PandaArm:
        """Connects to the arm's controller at ``host`` within ``timeout_s`` and opens the
        wrist camera ("carmine" or "realsense"); moves nothing.

        Raises:
            BackendUnavailable: panda-py is missing, or the arm or camera is unreachable
                (a :class:`~bearchair.hardware.real.bounded.DeviceTimeout` when silent).
        """
        panda_py = import_sdk("panda_py", "bearchair[panda]")
        try:
            robot = call_within(timeout_s, lambda: panda_py.Panda(host), f"the Panda at {host}")
        except DeviceTimeout:
            raise
        except Exception as error:
            raise BackendUnavailable(f"cannot reach the Panda at {host}: {error}") from error
        if camera == "realsense":
            from bearchair.hardware.real.camera import RealSenseCamera

            wrist: Any = RealSenseCamera()
        else:
            wrist = CarmineCamera(library_dir=openni_library_dir, intrinsics=camera_intrinsics)
        return cls(
            robot,
            wrist,
            T_world_base,
            T_flange_camera,
            speed_factor,
            payload_mass_kg=payload_mass_kg,
        )

    @property
    def camera(self) -> Any:
        return self._camera

    def activate(self) -> None:
        """Sets libfranka's collision thresholds and the camera's payload (moves nothing)."""
        libfranka = self._robot.get_robot()
        torque, force = list(COLLISION_TORQUE_NM), list(COLLISION_FORCE_N)
        libfranka.set_collision_behavior(torque, torque, force, force)
        libfranka.set_load(
            self._payload_mass_kg,
            self._T_flange_camera[:3, 3].tolist(),
            _box_inertia(self._payload_mass_kg, CAMERA_BOX_M).reshape(-1).tolist(),
        )

    def state(self) -> dict[str, Any]:
        """Mode and errors, for check-hardware (reads only)."""
        state = self._robot.get_state()
        return {
            "mode": _mode_name(state.robot_mode),
            "errors": str(state.current_errors) if bool(state.current_errors) else "none",
            "q_rad": np.round(np.asarray(state.q, dtype=float), 4).tolist(),
        }

    def health(self) -> str | None:
        """Why the arm cannot go on (a reflex, a user stop, errors), or None."""
        state = self._robot.get_state()
        mode = _mode_name(state.robot_mode)
        if mode in FAULT_MODES or bool(state.current_errors):
            return f"the Panda is in {mode} with errors {state.current_errors}"
        return None

    def joint_positions(self) -> np.ndarray:
        return np.asarray(self._robot.get_state().q, dtype=float)

    def planned_duration_s(self, target: np.ndarray) -> float:
        """How long panda-py's trajectory from here to ``target`` takes at the speed factor."""
        return planned_duration_s(self.joint_positions(), target, self.speed_factor)

    def move_to(self, joint_positions_rad: Sequence[float], timeout_s: float | None = None) -> None:
        """Moves to a joint configuration within ``timeout_s`` (default: the planned
        duration with a margin); the arm is stopped if not, or on Ctrl-C.

        Raises:
            ValueError: not 7 finite angles, or beyond panda-py's joint walls.
            ArmFault: the arm is in reflex, user-stopped or reports errors (never
                recovered here), or libfranka raised during the move.
            TimeoutError: not reached in time (the arm was stopped).
            EmergencyStopped: the arm was emergency-stopped.
        """
        self._refuse_if_stopped()
        target = np.asarray(joint_positions_rad, dtype=float).reshape(-1)
        if target.shape != (7,) or not np.all(np.isfinite(target)):
            raise ValueError(f"the Panda has 7 joints, got {target.shape}")
        target, notes = into_walls(target, self.joint_limits)
        if notes:
            log.warning("Panda target moved inside the joint walls: %s", "; ".join(notes))
        self._raise_if_faulted()
        if timeout_s is None:
            timeout_s = self.planned_duration_s(target) * MOVE_TIME_MARGIN + MOVE_SETTLE_S
        outcome = self._run_move(target, timeout_s)
        self._refuse_if_stopped()
        if "error" in outcome:
            raise ArmFault(f"the Panda faulted: {outcome['error']}") from outcome["error"]
        if not outcome.get("reached"):
            try:
                self._robot.raise_error()
            except Exception as error:
                raise ArmFault(f"the Panda faulted: {error}") from error
            raise TimeoutError(f"the Panda stopped short of {np.round(target, 3).tolist()}")

    def _run_move(self, target: np.ndarray, timeout_s: float) -> dict[str, Any]:
        """Runs panda-py's blocking move in a worker, stopping the arm on a timeout, a
        stop, or an exception here (Ctrl-C); what the move returned or raised."""
        outcome: dict[str, Any] = {}

        def run() -> None:
            try:
                outcome["reached"] = self._robot.move_to_joint_position(
                    target, speed_factor=self.speed_factor
                )
            except Exception as error:  # libfranka's exceptions arrive here
                outcome["error"] = error

        worker = threading.Thread(target=run, name="panda-move", daemon=True)
        worker.start()
        deadline = self._now() + timeout_s
        try:
            while worker.is_alive() and self._now() < deadline:
                # Polled at 200 Hz: a stop that lands between two moves is repeated within 5 ms.
                worker.join(STOP_POLL_S)
                if self._stopped and worker.is_alive():
                    # A stop sent just before the move began has nothing to stop: repeat it.
                    self._stop_robot()
        except BaseException:  # Ctrl-C or SIGTERM while moving: the arm stops first
            self._stop_robot()
            raise
        if worker.is_alive():
            self._stop_robot()
            worker.join(2.0)
            raise TimeoutError(f"the Panda did not reach its target in {timeout_s:.1f} s (stopped)")
        return outcome

    def capture(self) -> RGBDFrame:
        T_base_flange = self._T_base_flange()
        rgb, depth_m = self._camera.read()
        moved_m = float(np.linalg.norm(self._T_base_flange()[:3, 3] - T_base_flange[:3, 3]))
        if moved_m > STILL_DURING_CAPTURE_M:
            raise RuntimeError(f"the Panda moved {moved_m * 1000:.1f} mm during a capture")
        return RGBDFrame(
            rgb=rgb,
            depth_m=depth_m,
            intrinsics=self._camera.intrinsics,
            T_world_camera=self._T_world_base @ T_base_flange @ self._T_flange_camera,
            stamp_s=time.monotonic() - self._start,
        )

    def emergency_stop(self) -> None:
        """Preempts any running move through libfranka's ``Robot::stop``; latching."""
        self._stopped = True
        self._stop_robot()

    def _T_base_flange(self) -> np.ndarray:
        state = self._robot.get_state()
        O_T_EE = np.asarray(state.O_T_EE, dtype=float).reshape(4, 4).T
        F_T_EE = np.asarray(state.F_T_EE, dtype=float).reshape(4, 4).T
        return O_T_EE @ np.linalg.inv(F_T_EE)

    def _raise_if_faulted(self) -> None:
        state = self._robot.get_state()
        mode = _mode_name(state.robot_mode)
        if mode in FAULT_MODES or bool(state.current_errors):
            raise ArmFault(
                f"the Panda is in {mode} with errors {state.current_errors}: clear it with the "
                "operator (Desk, or panda.recover() with nobody near the arm), then run again"
            )

    def _stop_robot(self) -> None:
        with contextlib.suppress(Exception):
            self._robot.get_robot().stop()

    def _refuse_if_stopped(self) -> None:
        if self._stopped:
            raise EmergencyStopped("the Panda is emergency-stopped: motion refused")
