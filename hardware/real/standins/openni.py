"""The ``openni.openni2`` stand-in, with the PS1080 driver's defaults.

What the driver does and the stand-in models: streams open at 320x240; every stream starts
*mirrored* (the device's Mirror property defaults to on in OpenNI2's PS1080
``XnDeviceBase.cpp``, and streams inherit it), and a mirrored stream's frames are
flipped left to right; a frame's buffer is reused once the frame is released;
``wait_for_any_stream`` returns None when no frame comes within its timeout. The colour
stream's fields of view are a Carmine 1.09's (:data:`COLOUR_FOV_RAD`).
"""

from __future__ import annotations

import ctypes
import math
import threading
import time
from collections.abc import Callable
from typing import Any

import numpy as np

COLOUR_FOV_RAD = (2.0 * math.atan(320.0 / 525.0), 2.0 * math.atan(240.0 / 525.0))
"""(horizontal, vertical) field of view of the stand-in colour stream: a 525 px focal length
at 640x480, as PrimeSense colour cameras report (not the depth camera's 570 px)."""


class _VideoMode:
    def __init__(self, resolutionX: int, resolutionY: int, fps: int, pixelFormat: int) -> None:
        self.resolutionX, self.resolutionY, self.fps, self.pixelFormat = (
            resolutionX,
            resolutionY,
            fps,
            pixelFormat,
        )


class _Frame:
    def __init__(self, data: np.ndarray, width: int, height: int, timestamp_us: int) -> None:
        self._buffer = (ctypes.c_uint8 * data.nbytes).from_buffer_copy(data.tobytes())
        self.width, self.height, self.timestamp = width, height, timestamp_us
        self.dataSize = data.nbytes

    def get_buffer_as_uint8(self) -> Any:
        return (ctypes.c_uint8 * self.dataSize).from_buffer(self._buffer)

    def get_buffer_as_uint16(self) -> Any:
        return (ctypes.c_uint16 * (self.dataSize // 2)).from_buffer(self._buffer)

    def __del__(self) -> None:
        # OpenNI hands the buffer back to the driver on release: it is reused.
        ctypes.memset(self._buffer, 0xAB, self.dataSize)


class _Stream:
    def __init__(self, source: OpenNI2Standin, kind: str) -> None:
        self._source, self._kind = source, kind
        pixel = source.PIXEL_FORMAT_DEPTH_1_MM if kind == "depth" else source.PIXEL_FORMAT_RGB888
        self._mode = _VideoMode(320, 240, 30, pixel)  # the PS1080 driver's default
        self._mirrored = True  # XnDeviceBase.cpp: the Mirror property defaults to on
        self.started = False

    def configure_mode(self, width: int, height: int, fps: int, pixel_format: int) -> None:
        self._mode = _VideoMode(width, height, fps, pixel_format)

    def get_video_mode(self) -> _VideoMode:
        return self._mode

    def set_mirroring_enabled(self, enabled: bool) -> None:
        if not self._source.mirroring_stuck:
            self._mirrored = bool(enabled)

    def get_mirroring_enabled(self) -> bool:
        return self._mirrored

    def get_horizontal_fov(self) -> float:
        return COLOUR_FOV_RAD[0]

    def get_vertical_fov(self) -> float:
        return COLOUR_FOV_RAD[1]

    def start(self) -> None:
        self.started = True

    def stop(self) -> None:
        self.started = False

    def read_frame(self) -> _Frame:
        if not self.started:
            raise RuntimeError("OpenNI: stream not started")
        if self._source.silent:
            threading.Event().wait()  # the real read_frame blocks until a frame comes
        w, h = self._mode.resolutionX, self._mode.resolutionY
        rgb, depth_mm = self._source.render(w, h)
        stamp_us = self._source.stamp_us()
        data = depth_mm.astype(np.uint16) if self._kind == "depth" else rgb.astype(np.uint8)
        if self._mirrored:
            data = data[:, ::-1]
        return _Frame(np.ascontiguousarray(data), w, h, stamp_us)


class OpenNI2Standin:
    """The ``openni.openni2`` module as :class:`bearchair.hardware.real.camera.CarmineCamera` uses it.

    Args:
        render: ``(width, height) -> (rgb uint8 HxWx3, depth uint16 mm HxW)``; default a
            grey wall 1 m away.
        library_dir: the only folder from which ``initialize`` loads the library.
        devices: how many cameras are plugged in.
        stamp_us: the frames' timestamps in microseconds (default: the wall clock).
        mirroring_stuck: the streams stay mirrored whatever they are told.
        silent: no frame ever comes (a camera that enumerates but does not stream).
    """

    PIXEL_FORMAT_DEPTH_1_MM = 100
    PIXEL_FORMAT_RGB888 = 200
    IMAGE_REGISTRATION_OFF = 0
    IMAGE_REGISTRATION_DEPTH_TO_COLOR = 1

    def __init__(
        self,
        render: Callable[[int, int], tuple[np.ndarray, np.ndarray]] | None = None,
        library_dir: str | None = None,
        devices: int = 1,
        stamp_us: Callable[[], int] | None = None,
        mirroring_stuck: bool = False,
        silent: bool = False,
    ) -> None:
        self.render = render or _wall
        self.stamp_us = stamp_us or (lambda: int(time.monotonic() * 1e6))
        self._library_dir = library_dir
        self._devices = devices
        self.mirroring_stuck = mirroring_stuck
        self.silent = silent
        self.registration = self.IMAGE_REGISTRATION_OFF
        self.sync = False
        standin = self

        class Device:
            @classmethod
            def open_any(cls) -> Device:
                if standin._devices == 0:
                    raise RuntimeError("OniError: DeviceOpen using default: no devices found")
                return cls()

            def create_depth_stream(self) -> _Stream:
                return _Stream(standin, "depth")

            def create_color_stream(self) -> _Stream:
                return _Stream(standin, "colour")

            def is_image_registration_mode_supported(self, mode: int) -> bool:
                return mode == standin.IMAGE_REGISTRATION_DEPTH_TO_COLOR

            def set_image_registration_mode(self, mode: int) -> None:
                standin.registration = mode

            def get_image_registration_mode(self) -> int:
                return standin.registration

            def set_depth_color_sync_enabled(self, enable: bool) -> None:
                standin.sync = bool(enable)

        self.Device = Device

    def initialize(self, dll_directories: Any = None) -> None:
        if self._library_dir is not None and dll_directories != self._library_dir:
            raise RuntimeError(f"OpenNI2 library not found in {dll_directories!r}")

    def wait_for_any_stream(self, streams: list[Any], timeout: float | None = None) -> Any:
        """The first stream with a frame, or None after ``timeout`` seconds without one."""
        if self.silent:
            time.sleep(timeout if timeout is not None else 3600.0)
            return None
        return streams[0]


def _wall(width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    return np.full((height, width, 3), 128, np.uint8), np.full((height, width), 1000, np.uint16)
