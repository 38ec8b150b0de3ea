"""Display helpers for 8-bit previews: upscaling to a readable size, text labels, distances in metres.

A light field's images have one pixel per micro lens (75 × 53 for the bundled sample), far too small
to look at. Previews are enlarged by an integer factor until their long side reaches at least
:data:`MIN_LONG_SIDE_PX` (default 512): ``"nearest"`` (the default) repeats each pixel, so every lens
stays one visible block and nothing is invented; ``"smooth"`` resamples bicubically (Pillow), which
looks softer and hides the lens grid. Labels are drawn with Pillow's built-in font in a black band
added below the image, so they never hide image content.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import LfprocError

#: default smallest long side of a preview, in display pixels
MIN_LONG_SIDE_PX = 512
UPSCALE_METHODS = ("nearest", "smooth")


def upscale_factor(shape, min_long_side: int = MIN_LONG_SIDE_PX) -> int:
    """The smallest integer factor that brings the long side of ``shape`` (H, W, …) to ``min_long_side``."""
    long_side = max(int(shape[0]), int(shape[1]), 1)
    return max(1, math.ceil(min_long_side / long_side))


def upscale(image: np.ndarray, factor: int, method: str = "nearest") -> np.ndarray:
    """Enlarge an 8-bit ``(H, W)`` or ``(H, W, C)`` image by an integer ``factor`` (see module docstring)."""
    if method not in UPSCALE_METHODS:
        raise LfprocError(f"unknown upscaling {method!r}; use one of {', '.join(UPSCALE_METHODS)}")
    if factor == 1:
        return image
    if method == "nearest":
        return np.repeat(np.repeat(image, factor, axis=0), factor, axis=1)
    from PIL import Image

    squeeze = image.ndim == 3 and image.shape[2] == 1
    pil = Image.fromarray(image[:, :, 0] if squeeze else image)
    out = np.asarray(pil.resize((image.shape[1] * factor, image.shape[0] * factor), Image.BICUBIC))
    return out[:, :, None] if squeeze else out


def as_rgb(image: np.ndarray) -> np.ndarray:
    """``(H, W, 3)`` uint8 from a grey ``(H, W)``/``(H, W, 1)`` or colour 8-bit image."""
    if image.ndim == 2:
        image = image[:, :, None]
    return np.repeat(image, 3, axis=2) if image.shape[2] == 1 else image[:, :, :3]


def add_label(image: np.ndarray, text: str) -> np.ndarray:
    """The 8-bit image with a black band below it holding ``text`` in white; returns ``(H + band, W, 3)``."""
    from PIL import Image, ImageDraw, ImageFont

    rgb = as_rgb(image)
    height, width = rgb.shape[:2]
    size = max(10, min(28, width // 34))
    band = int(round(size * 1.6))
    canvas = Image.new("RGB", (width, height + band), (0, 0, 0))
    canvas.paste(Image.fromarray(np.ascontiguousarray(rgb)), (0, 0))
    try:
        font = ImageFont.load_default(size=size)
    except (TypeError, OSError):  # Pillow < 10.1 or without FreeType: the small bitmap font
        font = ImageFont.load_default()
    ImageDraw.Draw(canvas).text((max(2, size // 3), height + (band - size) // 2), text, fill=(255, 255, 255),
                                font=font)
    return np.asarray(canvas)


def metres(distance_mm: float | None) -> str:
    """A distance from millimetres as metres to three significant digits (``"0.659 m"``, ``"inf"``)."""
    if distance_mm is None or not math.isfinite(distance_mm):
        return "inf"
    value = distance_mm / 1000.0
    if abs(value) >= 100:
        return f"{value:.0f} m"
    return f"{value:.3g} m" if abs(value) >= 1 else f"{value:.3f} m"


def slice_label(distance_mm: float, near_mm: float, far_mm: float) -> str:
    """``"focus 0.659 m | DOF 0.558 m - 0.782 m"``: the text each refocus frame carries."""
    return f"focus {metres(distance_mm)} | DOF {metres(near_mm)} - {metres(far_mm)}"
