"""The pyrealsense2 stand-in (see :mod:`bearchair.hardware.real.standins`).

Depth comes in the depth camera's own geometry: :data:`DEPTH_TO_COLOUR_SHIFT_PX` columns
off the colour image (the D4xx's depth and colour imagers sit apart), and only
``align(stream.color).process`` brings it onto the colour pixels, so a backend that
skips the alignment reads depth beside its colour.
"""

from __future__ import annotations

import enum
from collections.abc import Callable
from typing import Any

import numpy as np

from bearchair.hardware.real.standins.openni import _wall

DEPTH_TO_COLOUR_SHIFT_PX = 24
"""How far (columns) unaligned depth sits from colour: a 15 mm baseline at 0.4 m, 615 px."""


def _shift(depth: np.ndarray, columns: int) -> np.ndarray:
    """``depth`` moved ``columns`` to the right (left if negative), zeros (no depth) let in."""
    out = np.zeros_like(depth)
    if columns >= 0:
        out[:, columns:] = depth[:, : depth.shape[1] - columns]
    else:
        out[:, :columns] = depth[:, -columns:]
    return out


_RealSenseStream = enum.Enum("stream", {"depth": 1, "color": 2})
_RealSenseFormat = enum.Enum("format", {"z16": 1, "rgb8": 5})


class _RealSenseFrame:
    def __init__(self, data: np.ndarray) -> None:
        self._data = data

    def get_data(self) -> np.ndarray:
        return self._data

    def __bool__(self) -> bool:
        return True


class _RealSenseFrameset:
    def __init__(self, depth: np.ndarray, colour: np.ndarray) -> None:
        self._depth, self._colour = depth, colour

    def get_depth_frame(self) -> _RealSenseFrame:
        return _RealSenseFrame(self._depth)

    def get_color_frame(self) -> _RealSenseFrame:
        return _RealSenseFrame(self._colour)


class _RealSenseIntrinsics:
    width, height, fx, fy, ppx, ppy = 640, 480, 615.0, 615.0, 320.0, 240.0


class _RealSenseProfile:
    """What ``pipeline.start`` returns: the device (its depth scale) and stream profiles."""

    def __init__(self, standin: RealSenseStandin) -> None:
        self._standin = standin

    def get_device(self) -> Any:
        standin = self._standin
        sensor = type("depth_sensor", (), {"get_depth_scale": lambda s: standin.depth_scale_m})
        return type("device", (), {"first_depth_sensor": lambda s: sensor()})()

    def get_stream(self, stream_type: Any) -> Any:
        video = type(
            "video_stream_profile", (), {"get_intrinsics": lambda s: _RealSenseIntrinsics()}
        )
        return type("stream_profile", (), {"as_video_stream_profile": lambda s: video()})()


class RealSenseStandin:
    """The ``pyrealsense2`` calls :class:`bearchair.hardware.real.camera.RealSenseCamera` makes.

    A D435-like camera: depth in units of :attr:`depth_scale_m`, colour intrinsics as
    given; frames from ``render`` (default a grey wall 1 m away); ``devices=0`` makes
    ``pipeline.start`` fail as the SDK does ("No device connected").
    """

    def __init__(
        self,
        render: Callable[[int, int], tuple[np.ndarray, np.ndarray]] | None = None,
        devices: int = 1,
        depth_scale_m: float = 0.001,
    ) -> None:
        self.render = render or _wall
        self.depth_scale_m = depth_scale_m
        self.enabled: list[tuple[Any, ...]] = []
        self.aligned_to: Any = None
        self.serial: str  # set by config.enable_device
        standin = self

        class config:
            def enable_device(self, serial: str) -> None:
                standin.serial = serial

            def enable_stream(self, stream_type, width, height, fmt, framerate) -> None:
                standin.enabled.append((stream_type, width, height, fmt, framerate))

        class pipeline:
            def start(self, cfg: Any) -> _RealSenseProfile:
                if standin._devices == 0:
                    raise RuntimeError("No device connected")
                return _RealSenseProfile(standin)

            def wait_for_frames(self, timeout_ms: int = 5000) -> _RealSenseFrameset:
                w, h = standin.enabled[0][1], standin.enabled[0][2]
                rgb, depth_mm = standin.render(w, h)
                units = np.round(depth_mm.astype(np.float64) / 1000.0 / standin.depth_scale_m)
                raw = _shift(units.astype(np.uint16), DEPTH_TO_COLOUR_SHIFT_PX)
                return _RealSenseFrameset(raw, rgb)

            def stop(self) -> None:
                pass

        class align:
            def __init__(self, align_to: Any) -> None:
                standin.aligned_to = align_to

            def process(self, frames: Any) -> Any:
                if standin.aligned_to is not standin.stream.color:
                    return frames
                frames = getattr(frames, "_impl", frames)  # the SDK double's stand-in
                depth = _shift(frames._depth, -DEPTH_TO_COLOUR_SHIFT_PX)
                return _RealSenseFrameset(depth, frames._colour)

        self._devices = devices
        self.stream, self.format, self.config = _RealSenseStream, _RealSenseFormat, config
        self.pipeline, self.align = pipeline, align
