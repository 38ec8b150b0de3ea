"""Display helpers for 8-bit previews: enlarging to a readable size, text labels, distances in metres.

A light field's images have one pixel per micro lens (75 × 53 for the bundled sample), far too small
to look at. Previews are enlarged by an integer factor until their long side reaches at least
:data:`MIN_LONG_SIDE_PX` (default 512): ``"lanczos"`` (the default) resamples with OpenCV's Lanczos-4
kernel (8 × 8 lenses), the band-limited interpolation between lens samples, so the picture shows what
the lenses sampled without a lens grid of blocks; ``"nearest"`` repeats each pixel, so every lens
stays one visible block (for inspecting single lenses); ``"smooth"`` resamples bicubically (Pillow).
Labels are drawn with Pillow's default font in a black band added below the image, so they never hide
image content, and are sized (smaller font, then more lines) so that they never leave it.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import LfprocError

#: default smallest long side of a preview, in display pixels
MIN_LONG_SIDE_PX = 512
UPSCALE_METHODS = ("lanczos", "nearest", "smooth")
#: how previews are enlarged unless told otherwise
DEFAULT_UPSCALE = "lanczos"


def upscale_factor(shape, min_long_side: int = MIN_LONG_SIDE_PX) -> int:
    """The smallest integer factor that brings the long side of ``shape`` (H, W, …) to ``min_long_side``."""
    long_side = max(int(shape[0]), int(shape[1]), 1)
    return max(1, math.ceil(min_long_side / long_side))


def upscale(image: np.ndarray, factor: int, method: str = DEFAULT_UPSCALE) -> np.ndarray:
    """Enlarge an 8-bit ``(H, W)`` or ``(H, W, C)`` image by an integer ``factor`` (see module docstring).

    Pixel centres keep their places (pixel j's centre lands at (j + 0.5)·factor); Lanczos ringing is
    clipped to 0–255.
    """
    if method not in UPSCALE_METHODS:
        raise LfprocError(f"unknown upscaling {method!r}; use one of {', '.join(UPSCALE_METHODS)}")
    if factor == 1:
        return image
    if method == "nearest":
        return np.repeat(np.repeat(image, factor, axis=0), factor, axis=1)
    if method == "lanczos":
        import cv2

        size = (image.shape[1] * factor, image.shape[0] * factor)
        out = cv2.resize(np.ascontiguousarray(image), size, interpolation=cv2.INTER_LANCZOS4)
        return out.reshape(size[1], size[0], *image.shape[2:])
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


def _font(size: int):
    """The labels' font at ``size`` px (`lfproc.io.label_font`: one with µ)."""
    from ..io import label_font

    return label_font(size)


def _text_width(font, text: str) -> int:
    left, _, right, _ = font.getbbox(text)
    return int(math.ceil(right - min(left, 0)))


def label_layout(width: int, text: str, max_size: int | None = None) -> tuple[int, list[str], int, int]:
    """(font size, lines, band height, margin) of a label under an image ``width`` pixels wide.

    The largest font from ``max_size`` (width/34, 10 to 28 px) down to 8 px that holds the text on one
    line inside the margins; below that, the text wraps at ``" | "`` and spaces (several lines, each
    inside the margins). Every line is measured with the font that draws it, so no label is clipped.
    """
    size = max_size or max(10, min(28, width // 34))
    margin = max(2, size // 3)
    from ..io import label_text

    text = label_text(text, _font(size))
    while size > 8 and _text_width(_font(size), text) > width - 2 * margin:
        size -= 1
        margin = max(2, size // 3)
    font = _font(size)
    lines = _wrap(font, text, width - 2 * margin)
    step = int(round(size * 1.25))
    band = int(round(size * 1.6)) + step * (len(lines) - 1)
    return size, lines, band, margin


def _wrap(font, text: str, room: int) -> list[str]:
    """``text`` in lines no wider than ``room``: broken after ``" | "`` first, then at spaces, then anywhere."""
    if _text_width(font, text) <= room:
        return [text]
    words = [w for part in text.split(" | ") for w in (part.split(" ") + ["|"])][:-1]
    lines, line = [], ""
    for word in words:
        candidate = word if not line else f"{line} {word}"
        if _text_width(font, candidate) <= room or not line:
            line = candidate
        else:
            lines.append(line)
            line = "" if word == "|" else word
    if line:
        lines.append(line)
    out = []
    for line in lines:   # a single word wider than the room: cut it
        line = line.strip(" |")
        while _text_width(font, line) > room and len(line) > 1:
            cut = len(line)
            while cut > 1 and _text_width(font, line[:cut]) > room:
                cut -= 1
            out.append(line[:cut])
            line = line[cut:]
        out.append(line)
    return [line for line in out if line]


def add_label(image: np.ndarray, text: str) -> np.ndarray:
    """The 8-bit image with a black band below it holding ``text`` in white: ``(H + band, W)`` for a grey
    ``(H, W)`` image, else ``(H + band, W, 3)``.

    The text never leaves the image (:func:`label_layout`: a smaller font, then more lines).
    """
    from PIL import Image, ImageDraw

    grey = image.ndim == 2
    pixels = image if grey else as_rgb(image)
    height, width = pixels.shape[:2]
    size, lines, band, margin = label_layout(width, text)   # lines as the font can draw them (label_text)
    font = _font(size)
    canvas = Image.new("L" if grey else "RGB", (width, height + band), 0 if grey else (0, 0, 0))
    canvas.paste(Image.fromarray(np.ascontiguousarray(pixels)), (0, 0))
    draw = ImageDraw.Draw(canvas)
    step = int(round(size * 1.25))
    top = height + (int(round(size * 1.6)) - size) // 2
    for k, line in enumerate(lines):
        draw.text((margin, top + k * step), line, fill=255 if grey else (255, 255, 255), font=font)
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
    """``"focus 0.659 m | DOF 0.558 m to 0.782 m"``: the text each refocus frame carries, near to far."""
    return f"focus {metres(distance_mm)} | DOF {metres(near_mm)} to {metres(far_mm)}"
