"""The ArUco tag on the NAO's head: marker image and textured plate, made at run time."""

from __future__ import annotations

import os
from pathlib import Path

import cv2
import numpy as np

from bearchair.core.arena import TagSpec
from bearchair.hardware.sim.bullet import sim_cache_dir

QUIET_MODULES = 1
"""White quiet border around the black square, in modules."""


def marker_modules(tag: TagSpec) -> int:
    """Modules across the marker (bits plus the black border) for the tag's dictionary."""
    bits = int(tag.dictionary.split("_")[1].split("X")[0])
    return bits + 2


def plate_side_m(tag: TagSpec) -> float:
    """Side of the printed plate: the black square plus a white quiet border of one module."""
    modules = marker_modules(tag)
    return tag.side_m * (modules + 2 * QUIET_MODULES) / modules


def tag_image(tag: TagSpec, pixels_per_module: int = 32) -> np.ndarray:
    """The marker with its white quiet border, as a (N, N, 3) uint8 image, top row first."""
    dictionary = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, tag.dictionary))
    modules = marker_modules(tag)
    marker = cv2.aruco.generateImageMarker(dictionary, tag.marker_id, modules * pixels_per_module)
    border = QUIET_MODULES * pixels_per_module
    padded = cv2.copyMakeBorder(
        marker, border, border, border, border, cv2.BORDER_CONSTANT, value=255
    )
    return cv2.cvtColor(padded, cv2.COLOR_GRAY2RGB)


def tag_assets(tag: TagSpec) -> tuple[Path, Path]:
    """Writes the tag texture (PNG) and plate (OBJ) into the cache; returns their paths.

    The plate is a square of :func:`plate_side_m` in its own frame's z = 0 plane, facing
    +z, centred on the origin. Texture coordinates put the image's top edge at +y and its
    right edge at +x, so the marker's own x axis (OpenCV's convention: from corner 0 to
    corner 1) is the plate frame's +x.
    """
    folder = sim_cache_dir()
    stem = f"tag-{tag.dictionary}-{tag.marker_id}-{tag.side_m:.4f}"
    texture = folder / f"{stem}.png"
    plate = folder / f"{stem}.obj"
    if not texture.exists():
        scratch = texture.with_suffix(f".{os.getpid()}.tmp.png")
        cv2.imwrite(str(scratch), cv2.cvtColor(tag_image(tag), cv2.COLOR_RGB2BGR))
        os.replace(scratch, texture)
    if not plate.exists():
        half = plate_side_m(tag) / 2.0
        text = "\n".join(
            [
                "# ArUco tag plate (generated)",
                f"v {-half:.6f} {-half:.6f} 0",
                f"v {half:.6f} {-half:.6f} 0",
                f"v {half:.6f} {half:.6f} 0",
                f"v {-half:.6f} {half:.6f} 0",
                "vt 0 0",
                "vt 1 0",
                "vt 1 1",
                "vt 0 1",
                "vn 0 0 1",
                "f 1/1/1 2/2/1 3/3/1",
                "f 1/1/1 3/3/1 4/4/1",
                "",
            ]
        )
        scratch = plate.with_suffix(f".{os.getpid()}.tmp")
        scratch.write_text(text)
        os.replace(scratch, plate)
    return texture, plate
