"""Animated GIF previews (Pillow, imported inside the writer)."""

from __future__ import annotations

import math
import os
from typing import Sequence

import numpy as np

from ..atomic import atomic_path
from ..errors import LfprocError
from ._write import srgb_encode


def write_gif(path: str | os.PathLike, frames: Sequence[np.ndarray] | np.ndarray, duration_ms: float) -> None:
    """Write an animated, endlessly looping GIF of float32 linear frames, atomically (Pillow).

    Frames (each ``(H, W)``, ``(H, W, 1)`` or ``(H, W, 3)``, all the same shape) are clipped to
    [0, 1], sRGB-encoded and rounded to 8 bits; colour frames are reduced to a 256-colour palette
    by Pillow, grey frames are exact. ``duration_ms`` is the display time of each frame (GIF
    stores hundredths of a second).
    """
    from PIL import Image

    path = os.fspath(path)
    if not (isinstance(duration_ms, (int, float)) and math.isfinite(duration_ms) and duration_ms > 0):
        raise LfprocError(f"{path}: GIF frame duration {duration_ms!r} ms must be a positive number")
    stack = [np.asarray(frame) for frame in frames]
    if not stack:
        raise LfprocError(f"{path}: no frames to write; pass at least one image")
    shape = stack[0].shape
    if any(frame.shape != shape for frame in stack):
        raise LfprocError(f"{path}: GIF frames differ in shape; pass frames of one size")
    if not (len(shape) == 2 or (len(shape) == 3 and shape[2] in (1, 3))) or 0 in shape:
        raise LfprocError(f"{path}: GIF frames of shape {shape} are not (H, W), (H, W, 1) or (H, W, 3)")
    if not all(np.all(np.isfinite(frame)) for frame in stack):
        raise LfprocError(f"{path}: a GIF frame contains NaN or infinite values; fix the computation first")
    images = []
    for frame in stack:
        pixels = np.round(srgb_encode(frame) * 255.0).astype(np.uint8)
        if pixels.ndim == 3 and pixels.shape[2] == 1:
            pixels = pixels[:, :, 0]
        images.append(Image.fromarray(pixels))  # uint8 (H, W) -> "L", (H, W, 3) -> "RGB"
    try:
        with atomic_path(path, suffix=".gif") as tmp:
            images[0].save(tmp, format="GIF", save_all=True, append_images=images[1:],
                           duration=int(round(duration_ms)), loop=0)
    except OSError as exc:
        raise LfprocError(f"{path}: cannot write GIF ({exc.strerror or exc}); check the folder and permissions") \
            from None
