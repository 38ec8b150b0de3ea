"""Step 3 of calibration: flatten a white image and find one candidate centre per micro image.

The slowly varying floor (the gaps between micro images) and envelope (vignetting) are divided out; in
the result every micro image is equally bright, and the lit points farthest from any dark pixel are one
candidate centre per micro image.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Flattened:
    """Results of :func:`flatten`.

    Attributes
    ----------
    flat : ndarray
        (image − floor) / envelope where ``valid``, else 0: micro images of equal brightness.
    valid : ndarray of bool
        Pixels whose envelope reaches a tenth of its 99th percentile (not vignetted to black).
    above_floor : ndarray
        (image − floor) / 99th percentile of the envelope: the micro images with their vignetting.
    """

    flat: np.ndarray
    valid: np.ndarray
    above_floor: np.ndarray


def flatten(image: np.ndarray, pitch: float, valid_fraction: float = 0.1) -> Flattened:
    """Remove the floor and divide out the envelope of a white image.

    floor = Gaussian(σ = pitch) of the local minimum over 1.3 pitches (every such window holds a gap
    between micro images); envelope = Gaussian(σ = pitch) of image − floor, the local mean (σ = pitch damps
    the lattice's ripple by exp(−2π²) ≈ 3e-9).
    """
    from scipy import ndimage
    denoised = ndimage.gaussian_filter(image, 1.0)  # light: narrow gaps between fat micro images survive
    floor = smooth_large(ndimage.minimum_filter(denoised, size=_odd(1.3 * pitch)), pitch)
    above = image - floor
    envelope = smooth_large(above, pitch)
    reference = float(np.percentile(envelope, 99))
    scale = float(np.percentile(np.abs(image), 99.9))
    if not reference > 1e-6 * max(scale, np.finfo(float).tiny):
        return Flattened(np.zeros_like(image), np.zeros(image.shape, bool), np.zeros_like(image))
    valid = envelope >= valid_fraction * reference
    flat = np.where(valid, above / np.where(valid, envelope, 1.0), 0.0)
    return Flattened(flat, valid, above / reference)


def smooth_large(image: np.ndarray, sigma: float) -> np.ndarray:
    """Gaussian smoothing for large σ, computed on a block-averaged copy and interpolated back.

    Blocks of k ≈ σ/4 pixels leave the result smooth on the scale of a pixel (the error of the linear
    interpolation is of order (k/σ)²/8 of the curvature) while the cost no longer grows with σ.
    """
    from scipy import ndimage
    k = int(sigma // 4)
    if k < 2:
        return ndimage.gaussian_filter(image, sigma, mode="reflect")
    h, w = image.shape
    hb, wb = -(-h // k), -(-w // k)
    padded = np.pad(image, ((0, hb * k - h), (0, wb * k - w)), mode="reflect")
    blocks = padded.reshape(hb, k, wb, k).mean(axis=(1, 3))
    sigma_blocks = math.sqrt(max(sigma * sigma - k * k / 12.0, 0.0)) / k  # the block mean blurs by k²/12
    low = ndimage.gaussian_filter(blocks, sigma_blocks, mode="reflect")
    return _interpolate_blocks(_interpolate_blocks(low, k, h, axis=0), k, w, axis=1)


def _interpolate_blocks(low: np.ndarray, k: int, n: int, axis: int) -> np.ndarray:
    """Linear interpolation along ``axis`` from block centres ((b + 1/2)·k − 1/2) back to ``n`` pixels."""
    pos = np.clip((np.arange(n) - (k - 1) / 2.0) / k, 0.0, low.shape[axis] - 1.0)
    i0 = np.minimum(np.floor(pos).astype(int), low.shape[axis] - 1)
    i1 = np.minimum(i0 + 1, low.shape[axis] - 1)
    frac = pos - i0
    shape = [1, 1]
    shape[axis] = n
    frac = frac.reshape(shape)
    return np.take(low, i0, axis=axis) * (1.0 - frac) + np.take(low, i1, axis=axis) * frac


def candidate_centres(flat: np.ndarray, valid: np.ndarray, pitch: float) -> np.ndarray:
    """Approximate (x, y) of the lit points farthest from any dark pixel: one per micro image.

    ``flat`` is thresholded at half its 90th percentile; the maxima of the distance to the nearest dark
    pixel are the centres of thin disks and of cells dark only at their corners alike. Maxima nearer than
    0.15 pitch to the dark are specks and dropped; a plateau of equal maxima counts once (its centroid).
    """
    from scipy import ndimage
    smooth = ndimage.gaussian_filter(flat, 1.0)
    level = 0.5 * float(np.percentile(smooth[valid], 90)) if valid.any() else 0.0
    lit = (smooth > level) & valid
    if not lit.any() or lit.all():
        return np.zeros((0, 2))
    distance = ndimage.distance_transform_edt(lit)
    peaks = (distance == ndimage.maximum_filter(distance, size=_odd(0.6 * pitch), mode="nearest"))
    peaks &= distance >= 0.15 * pitch
    labels, count = ndimage.label(peaks, structure=np.ones((3, 3)))
    if count == 0:
        return np.zeros((0, 2))
    centres = np.array(ndimage.center_of_mass(peaks, labels, np.arange(1, count + 1)))
    return centres[:, ::-1].astype(np.float64)


def _odd(size: float) -> int:
    n = max(int(round(size)), 3)
    return n if n % 2 else n + 1


