"""The viewer's 8-bit sRGB images: slices, views and depth maps, written in parallel.

Images are stored at the light field's own resolution (one pixel per lens) and the page enlarges
them (the browser's smooth scaling by default, CSS ``image-rendering: pixelated`` for ``nearest`` and always for
the depth map, whose unknown lenses must stay grey) to at
least :data:`lfproc.outputs.MIN_LONG_SIDE_PX` on the long side. Small images (long side under that)
are PNG, lossless and tiny; larger ones JPEG (quality 90, no chroma subsampling), which encodes an
Illum-sized view in a few milliseconds.
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from ..atomic import atomic_path
from ..colours import colour_scale
from ..errors import LfprocError
from ..outputs import MIN_LONG_SIDE_PX

JPEG_QUALITY = 90


def image_extension(lens_shape) -> str:
    """``.png`` for images whose long side is below the display size, ``.jpg`` otherwise."""
    return ".png" if max(lens_shape) < MIN_LONG_SIDE_PX else ".jpg"


def save_8bit(path: str, pixels: np.ndarray) -> None:
    """Write an 8-bit ``(H, W)``/``(H, W, 1)``/``(H, W, 3)`` image as PNG or JPEG (by extension), atomically."""
    from PIL import Image

    if pixels.ndim == 3 and pixels.shape[2] == 1:
        pixels = pixels[:, :, 0]
    image = Image.fromarray(np.ascontiguousarray(pixels))
    extension = os.path.splitext(path)[1].lower()
    try:
        with atomic_path(path) as tmp:
            if extension == ".png":
                image.save(tmp, format="PNG", compress_level=3)
            else:
                image.save(tmp, format="JPEG", quality=JPEG_QUALITY, subsampling=0)
    except OSError as exc:
        raise LfprocError(f"{path}: cannot write ({exc.strerror or exc}); check the folder and permissions") from None


def write_all(jobs, workers: int | None = None) -> None:
    """Run ``(path, make_pixels)`` jobs: each ``make_pixels()`` gives the 8-bit image for ``path``.

    Pillow and the numpy tone mapping release the GIL, so threads use every core.
    """
    def run(job):
        path, make = job
        save_8bit(path, make())

    workers = workers or min(8, os.cpu_count() or 1)
    with ThreadPoolExecutor(max_workers=workers) as pool:
        for _ in pool.map(run, jobs):
            pass


def depth_colours(a_map: np.ndarray, confidence: np.ndarray, a_far: float, a_near: float,
                  min_confidence: float) -> np.ndarray:
    """RGB of a depth map coloured by its refocus parameter (linear in disparity, far dark, near yellow);
    lenses under ``min_confidence`` are grey."""
    span = a_near - a_far if a_near > a_far else 1.0
    t = (np.asarray(a_map, dtype=np.float64) - a_far) / span
    t = np.where(np.asarray(confidence) >= min_confidence, t, np.nan)
    return colour_scale(t)
