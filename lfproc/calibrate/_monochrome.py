"""Step 1 of calibration: a white image (or a window of it) as one float64 brightness channel.

Channels are averaged; a Bayer mosaic is low-passed by [1, 2, 1]/4 along each axis (two 2 × 2 box
averages, hence centred), which removes the period-2 colour pattern exactly. Isolated hot or dead pixels
are replaced by their neighbours' median.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import LfprocError


def check_white(white, source: str = "white image") -> np.ndarray:
    """The white image as an array after the checks every step relies on (no conversion, no copy).

    Raises `LfprocError` for non-numeric pixels, a shape that is not (H, W) or (H, W, C) of at least
    8 × 8, and NaN or infinite pixels.
    """
    arr = np.asarray(white)
    if not (np.issubdtype(arr.dtype, np.number) and not np.iscomplexobj(arr)) or arr.dtype == np.bool_:
        raise LfprocError(f"{source}: pixel type {arr.dtype} is not a real number type; pass an image")
    if arr.ndim not in (2, 3) or min(arr.shape[:2]) < 8:
        raise LfprocError(f"{source}: expected a 2-D image (or channels-last colour image) of at least 8x8 "
                          f"pixels, got shape {np.shape(white)}; pass the white image itself")
    if np.issubdtype(arr.dtype, np.floating) and not _all_finite(arr):
        raise LfprocError(f"{source}: the image has NaN or infinite pixels; re-export the white image")
    return arr


def _all_finite(arr: np.ndarray, rows_per_block: int = 512) -> bool:
    """``np.isfinite(arr).all()`` in row blocks (no full-size boolean temporary)."""
    return all(bool(np.isfinite(arr[r:r + rows_per_block]).all()) for r in range(0, arr.shape[0], rows_per_block))


def white_to_mono(white, cfa: str = "none", source: str = "white image") -> np.ndarray:
    """A float64 2-D image: channels averaged, a Bayer mosaic low-passed by [1, 2, 1]/4 ⊗ [1, 2, 1]/4.

    The kernel is two 2 × 2 box averages in a row: centred (no half-pixel shift), with a zero at the
    Nyquist frequency, so a white image's period-2 colour pattern vanishes while the much coarser micro
    images keep their centres.
    """
    arr = check_white(white, source)
    if arr.ndim == 3:
        image = arr.astype(np.float64).mean(axis=2)
        cfa = "none"  # colour planes are whole images: no mosaic to low-pass
    else:
        image = arr.astype(np.float64)
    if cfa not in (None, "", "none"):
        from scipy import ndimage
        kernel = np.array([0.25, 0.5, 0.25])
        image = ndimage.correlate1d(image, kernel, axis=0, mode="mirror")
        image = ndimage.correlate1d(image, kernel, axis=1, mode="mirror")
    return image


def mono_window(white: np.ndarray, cfa: str, y0: int, y1: int, x0: int, x1: int) -> np.ndarray:
    """:func:`white_to_mono` of the window ``[y0:y1, x0:x1]`` of an already checked white image.

    A Bayer window starts on an even row and column, so the CFA phase is that of the whole image; the
    low-pass of a window equals that of the whole image except in its outermost pixel.
    """
    return white_to_mono(white[y0:y1, x0:x1], cfa)

def repair_outlier_pixels(image: np.ndarray, threshold: float = 5.0) -> np.ndarray:
    """Replace hot and dead pixels by the median of their 3 × 3 neighbourhood.

    A pixel is an outlier when it exceeds the largest of its 8 neighbours (or falls below the smallest)
    by more than ``threshold`` robust noise deviations and 5 % of the image's range: micro images are
    larger than a pixel, so no real pixel stands alone like that.
    """
    from scipy import ndimage
    # noise from differences of vertical neighbours (every few columns): their lower quartile, as edges
    # between micro images may well make up half of all pairs; |N(0, 2σ²)| has its quartile at 0.3186·√2·σ
    step = np.diff(image[:, ::max(1, image.shape[1] // 512)], axis=0)
    noise = float(np.percentile(np.abs(step), 25)) / (0.3186 * math.sqrt(2.0))
    stride = max(1, int(math.sqrt(image.size / 250_000)))  # the range from a subsample
    lo, hi = np.percentile(image[::stride, ::stride], [0.1, 99.9])
    margin = max(threshold * noise, 0.05 * float(hi - lo), np.finfo(float).tiny)
    # only a 3 × 3 maximum (minimum) can exceed its 8 neighbours: test those candidates exactly
    padded = np.pad(image, 1, mode="edge")
    bad = []
    for extreme, sign in ((ndimage.maximum_filter(image, size=3, mode="nearest"), 1.0),
                          (ndimage.minimum_filter(image, size=3, mode="nearest"), -1.0)):
        iy, ix = np.nonzero(image == extreme)
        ring = np.stack([padded[iy + dy, ix + dx] for dy in range(3) for dx in range(3) if (dy, dx) != (1, 1)], -1)
        nearest = ring.max(-1) if sign > 0 else ring.min(-1)
        keep = sign * (image[iy, ix] - nearest) > margin
        bad.append((iy[keep], ix[keep]))
    iy, ix = np.concatenate([b[0] for b in bad]), np.concatenate([b[1] for b in bad])
    if iy.size == 0:
        return image
    reflected = np.pad(image, 1, mode="reflect")
    patches = np.stack([reflected[iy + dy, ix + dx] for dy in range(3) for dx in range(3)], -1)
    repaired = image.copy()
    repaired[iy, ix] = np.median(patches, axis=-1)
    return repaired
