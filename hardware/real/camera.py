"""The wrist depth cameras: the PrimeSense Carmine 1.09 through OpenNI2 (the ``openni``
binding, extra ``bearchair[carmine]``) and the RealSense D4xx (:class:`RealSenseCamera`).

What the PS1080 driver does unless told otherwise, and what :class:`CarmineCamera` does
about it:

* It opens depth at 320x240: both streams are set to 640x480 at 30 fps, depth in
  ``PIXEL_FORMAT_DEPTH_1_MM`` and colour in ``PIXEL_FORMAT_RGB888``, and the modes read
  back are checked.
* Registration is off: depth-to-colour registration is required (checked supported,
  then set and read back), so one pinhole model serves both images: the colour
  camera's, from the colour stream's field of view (``get_horizontal_fov``,
  ``get_vertical_fov``) unless the cell file gives calibrated ``camera_intrinsics``.
* Mirroring is on: the device's Mirror property defaults to on (``XnDeviceBase.cpp``)
  and new streams inherit it (the driver's ini comment says otherwise). A mirrored
  image decodes no ArUco tag or ChArUco board and its cloud does not fuse, so each
  stream is set unmirrored and read back, and the camera refuses to start if it stays on.
* Frames are unsynchronised: depth/colour sync is enabled, and a pair whose timestamps
  differ by more than :data:`MAX_PAIR_SKEW_S` is read again.
* ``read_frame`` blocks until a frame comes, forever: each read first waits for its
  stream with ``wait_for_any_stream`` and a bound (``timeout_s``), and a camera that
  stays silent raises :class:`~bearchair.hardware.real.bounded.DeviceTimeout`.
* A frame's buffer belongs to the frame object: it is copied while the frame is alive.
* Debian's ``libopenni2-0`` puts ``libOpenNI2.so`` in ``/usr/lib/<triplet>/``, which the
  binding does not search: the folder is given by the cell file (``openni_library_dir``).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from bearchair.core.errors import BackendUnavailable
from bearchair.hardware.interfaces import CameraIntrinsics
from bearchair.hardware.real import import_sdk
from bearchair.hardware.real.bounded import DeviceTimeout

CARMINE_INTRINSICS = CameraIntrinsics(640, 480, 570.3, 570.3, 319.5, 239.5)
"""The Carmine 1.09's nominal *depth* intrinsics at 640x480: for synthetic images only.
The backend takes the registered (colour) geometry from the stream or the cell file."""
WIDTH, HEIGHT = 640, 480
FPS = 30
READ_TIMEOUT_S = 2.0
"""Bound on waiting for one frame (seconds): 60 frame periods at 30 fps."""
MAX_PAIR_SKEW_S = 1.0 / 60.0
"""Half a frame period: a depth and colour pair further apart is not one moment."""
PAIR_ATTEMPTS = 5


class CarmineCamera:
    """RGB-D frames from a Carmine through OpenNI2, depth registered to colour.

    Args:
        openni2: the ``openni.openni2`` module (tests pass a stand-in with its signatures).
        library_dir: folder of ``libOpenNI2.so``; None for the binding's search path.
        intrinsics: the calibrated pinhole model of the registered 640x480 images (the
            cell file's ``camera_intrinsics``); None: from the colour stream's field of view.
        timeout_s: bound on waiting for one frame.

    Raises:
        BackendUnavailable: no library, no device, a missing stream, no registration,
            mirroring that stays on, or the driver refuses the 640x480 modes (each says which).
    """

    def __init__(
        self,
        openni2: Any | None = None,
        library_dir: str | None = None,
        intrinsics: CameraIntrinsics | None = None,
        timeout_s: float = READ_TIMEOUT_S,
    ) -> None:
        ni = openni2 or import_sdk("openni.openni2", "bearchair[carmine]")
        self._ni = ni
        self._timeout_s = timeout_s
        try:
            if library_dir is None:
                ni.initialize()
            else:
                ni.initialize(library_dir)
        except Exception as error:
            where = library_dir or "the binding's default folders"
            raise BackendUnavailable(
                f"cannot load libOpenNI2.so from {where} ({error}); install libopenni2-0 and "
                "set openni_library_dir in the cell file (Debian: /usr/lib/x86_64-linux-gnu)"
            ) from error
        try:
            self._device = ni.Device.open_any()
        except Exception as error:
            raise BackendUnavailable(f"no OpenNI2 camera found: {error}") from error
        self._depth = self._device.create_depth_stream()
        self._colour = self._device.create_color_stream()
        if self._depth is None or self._colour is None:
            missing = "depth" if self._depth is None else "colour"
            raise BackendUnavailable(f"the OpenNI2 camera has no {missing} stream")
        registration = ni.IMAGE_REGISTRATION_DEPTH_TO_COLOR
        if not self._device.is_image_registration_mode_supported(registration):
            raise BackendUnavailable("the OpenNI2 camera cannot register depth to colour")
        for name, stream, pixel_format in (
            ("depth", self._depth, ni.PIXEL_FORMAT_DEPTH_1_MM),
            ("colour", self._colour, ni.PIXEL_FORMAT_RGB888),
        ):
            _configure(stream, name, pixel_format)
        self._device.set_image_registration_mode(registration)
        if self._device.get_image_registration_mode() != registration:
            raise BackendUnavailable("the OpenNI2 camera did not keep depth-to-colour registration")
        self._device.set_depth_color_sync_enabled(True)
        self.intrinsics = intrinsics or intrinsics_from_fov(
            self._colour.get_horizontal_fov(), self._colour.get_vertical_fov()
        )
        self.intrinsics_source = "cell file" if intrinsics else "colour stream's field of view"
        self._depth.start()
        self._colour.start()

    def mode(self) -> dict[str, Any]:
        """The streams' modes, mirroring and intrinsics, for check-hardware (read back)."""
        depth, colour = self._depth.get_video_mode(), self._colour.get_video_mode()
        mirrored = [
            n
            for n, s in (("depth", self._depth), ("colour", self._colour))
            if s.get_mirroring_enabled()
        ]
        k = self.intrinsics
        return {
            "depth": f"{depth.resolutionX}x{depth.resolutionY}@{depth.fps} DEPTH_1_MM",
            "colour": f"{colour.resolutionX}x{colour.resolutionY}@{colour.fps} RGB888",
            "registration": "depth to colour",
            "mirroring": ("ON for " + ", ".join(mirrored)) if mirrored else "off",
            "intrinsics": f"fx {k.fx:.1f} fy {k.fy:.1f} cx {k.cx:.1f} cy {k.cy:.1f} px "
            f"({self.intrinsics_source})",
        }

    def read(self) -> tuple[np.ndarray, np.ndarray]:
        """One (rgb uint8 HxWx3, depth metres float32 HxW, 0 = missing) pair, synchronised.

        Raises:
            RuntimeError: no pair within :data:`MAX_PAIR_SKEW_S` in five attempts.
        """
        for _ in range(PAIR_ATTEMPTS):
            depth_mm, depth_stamp_us = self._copy(self._depth, np.uint16, 1)
            rgb, colour_stamp_us = self._copy(self._colour, np.uint8, 3)
            if abs(depth_stamp_us - colour_stamp_us) * 1e-6 <= MAX_PAIR_SKEW_S:
                return rgb, depth_mm.astype(np.float32) / 1000.0
        raise RuntimeError(
            f"the Carmine's depth and colour frames stayed more than {MAX_PAIR_SKEW_S * 1e3:.0f} ms apart"
        )

    def close(self) -> None:
        for stream in (self._depth, self._colour):
            stream.stop()

    def _copy(self, stream: Any, dtype: type, channels: int) -> tuple[np.ndarray, int]:
        h, w = self.intrinsics.height, self.intrinsics.width
        # read_frame blocks until a frame comes: wait for one with a bound first.
        if self._ni.wait_for_any_stream([stream], self._timeout_s) is None:
            name = "depth" if stream is self._depth else "colour"
            raise DeviceTimeout(f"the Carmine sent no {name} frame in {self._timeout_s:g} s")
        frame = stream.read_frame()
        if (frame.width, frame.height) != (w, h):
            raise RuntimeError(
                f"the Carmine sent a {frame.width}x{frame.height} frame, not {w}x{h}"
            )
        buffer = frame.get_buffer_as_uint16() if dtype is np.uint16 else frame.get_buffer_as_uint8()
        # Copy now: the buffer is released with the frame object.
        pixels = np.array(np.frombuffer(buffer, dtype=dtype), copy=True)
        stamp_us = int(frame.timestamp)
        del frame
        shape = (h, w) if channels == 1 else (h, w, channels)
        return pixels.reshape(shape), stamp_us


def _configure(stream: Any, name: str, pixel_format: int) -> None:
    """Sets a stream to 640x480 at :data:`FPS` in ``pixel_format``, unmirrored, and reads
    both back.

    Raises:
        BackendUnavailable: the mode or the mirroring did not take.
    """
    stream.configure_mode(WIDTH, HEIGHT, FPS, pixel_format)
    mode = stream.get_video_mode()
    if (mode.resolutionX, mode.resolutionY, mode.pixelFormat) != (WIDTH, HEIGHT, pixel_format):
        raise BackendUnavailable(
            f"the OpenNI2 {name} stream runs at {mode.resolutionX}x{mode.resolutionY} "
            f"format {mode.pixelFormat}, not {WIDTH}x{HEIGHT}"
        )
    stream.set_mirroring_enabled(False)
    if stream.get_mirroring_enabled():
        raise BackendUnavailable(
            f"the Carmine's {name} stream stays mirrored after set_mirroring_enabled(False): "
            "mirrored images decode no tag or board; not starting"
        )


def intrinsics_from_fov(horizontal_rad: float, vertical_rad: float) -> CameraIntrinsics:
    """The 640x480 pinhole model of a stream's fields of view (radians), centred."""
    if not (0.0 < horizontal_rad < math.pi and 0.0 < vertical_rad < math.pi):
        raise BackendUnavailable(
            f"the camera reports fields of view {horizontal_rad:.3f} x {vertical_rad:.3f} rad: "
            "set camera_intrinsics in the cell file"
        )
    fx = 0.5 * WIDTH / math.tan(0.5 * horizontal_rad)
    fy = 0.5 * HEIGHT / math.tan(0.5 * vertical_rad)
    return CameraIntrinsics(WIDTH, HEIGHT, fx, fy, (WIDTH - 1) / 2.0, (HEIGHT - 1) / 2.0)


class RealSenseCamera:
    """RGB-D frames from an Intel RealSense D4xx through ``pyrealsense2`` (extra
    ``bearchair[realsense]``), depth aligned to colour.

    Both streams are asked for at 640x480, 30 fps (depth ``z16``, colour ``rgb8``); each
    frameset is aligned to the colour camera (``rs.align(rs.stream.color)``), so the
    colour intrinsics the device reports serve both images; depth units come from the
    depth sensor's ``get_depth_scale()`` (metres per unit). Pixels are copied out of the
    frames before they go back to the SDK's pool.

    Args:
        rs: the ``pyrealsense2`` module (tests pass a stand-in with its signatures).
        serial: the camera's serial number; None for the first one found.
        timeout_s: how long one frameset may take.

    Raises:
        BackendUnavailable: no camera, or it refuses 640x480.
    """

    def __init__(self, rs: Any | None = None, serial: str | None = None, timeout_s: float = 2.0):
        sdk = rs or import_sdk("pyrealsense2", "bearchair[realsense]")
        self._rs = sdk
        self._timeout_ms = int(timeout_s * 1000)
        width, height = WIDTH, HEIGHT
        config = sdk.config()
        if serial is not None:
            config.enable_device(serial)
        config.enable_stream(sdk.stream.depth, width, height, sdk.format.z16, FPS)
        config.enable_stream(sdk.stream.color, width, height, sdk.format.rgb8, FPS)
        self._pipeline = sdk.pipeline()
        try:
            profile = self._pipeline.start(config)
        except RuntimeError as error:
            raise BackendUnavailable(f"no RealSense camera at 640x480 found: {error}") from error
        self.depth_scale_m = float(profile.get_device().first_depth_sensor().get_depth_scale())
        colour = profile.get_stream(sdk.stream.color).as_video_stream_profile().get_intrinsics()
        self.intrinsics = CameraIntrinsics(
            int(colour.width), int(colour.height), colour.fx, colour.fy, colour.ppx, colour.ppy
        )
        self._align = sdk.align(sdk.stream.color)

    def mode(self) -> dict[str, Any]:
        return {
            "depth": f"{self.intrinsics.width}x{self.intrinsics.height}@{FPS} z16 "
            f"({self.depth_scale_m * 1000:.3g} mm per unit)",
            "colour": f"{self.intrinsics.width}x{self.intrinsics.height}@{FPS} rgb8",
            "registration": "depth aligned to colour",
        }

    def read(self) -> tuple[np.ndarray, np.ndarray]:
        """One aligned (rgb uint8 HxWx3, depth metres float32 HxW, 0 = missing) pair."""
        try:
            frameset = self._pipeline.wait_for_frames(self._timeout_ms)
        except RuntimeError as error:  # "Frame didn't arrive within ..."
            raise DeviceTimeout(
                f"the RealSense sent no frameset in {self._timeout_ms / 1000:g} s ({error})"
            ) from error
        frames = self._align.process(frameset)
        depth, colour = frames.get_depth_frame(), frames.get_color_frame()
        if not depth or not colour:
            raise RuntimeError("the RealSense frameset lacks depth or colour")
        depth_units = np.array(np.asanyarray(depth.get_data()), dtype=np.float32, copy=True)
        rgb = np.array(np.asanyarray(colour.get_data()), dtype=np.uint8, copy=True)
        return rgb, depth_units * np.float32(self.depth_scale_m)

    def close(self) -> None:
        self._pipeline.stop()
