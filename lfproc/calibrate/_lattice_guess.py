"""Step 2 of calibration: a first pitch and rotation from the autocorrelation of a central crop.

The autocorrelation of a lattice pattern peaks at every lattice vector; its nearest peak is a
nearest-neighbour vector, whose length is a first pitch, with no assumption on the micro image shape.
"""

from __future__ import annotations

import math

import numpy as np

from ._monochrome import mono_window, repair_outlier_pixels

#: smallest and largest lattice pitch the autocorrelation looks for, in pixels
MIN_PITCH_PX = 4.0
MAX_PITCH_PX = 400.0


def central_crop(white: np.ndarray, cfa: str, crop: int = 1024) -> np.ndarray:
    """The central ``crop`` × ``crop`` window of a checked white image, monochrome and repaired."""
    h, w = white.shape[:2]
    ch, cw = min(h, crop), min(w, crop)
    y0, x0 = ((h - ch) // 2) & ~1, ((w - cw) // 2) & ~1  # even: the Bayer phase is kept
    return repair_outlier_pixels(mono_window(white, cfa, y0, y0 + ch, x0, x0 + cw))


def lattice_guess_from_autocorrelation(image: np.ndarray, crop: int = 1024,
                                       min_peak: float = 0.3) -> tuple[float, float] | None:
    """Pitch and rotation (radians) of the lattice from the nearest autocorrelation peak, or ``None``.

    The autocorrelation of a lattice pattern peaks at every lattice vector; its nearest peak beyond
    `MIN_PITCH_PX` that reaches ``min_peak`` of the zero-lag value is a nearest-neighbour vector. A central
    ``crop`` × ``crop`` window is used, Hann-tapered, with periods above 2 × `MAX_PITCH_PX` removed.
    """
    from scipy import ndimage
    h, w = image.shape
    ch, cw = min(h, crop), min(w, crop)
    y0, x0 = (h - ch) // 2, (w - cw) // 2
    patch = ndimage.gaussian_filter(image[y0:y0 + ch, x0:x0 + cw], 0.7)
    patch = (patch - patch.mean()) * np.outer(np.hanning(ch), np.hanning(cw))
    from scipy import fft
    # zero padded by half the crop: lags up to half the crop (all that is searched) do not wrap around
    ny, nx = (fft.next_fast_len(ch + ch // 2 + 1, real=True) + 1) & ~1, (fft.next_fast_len(cw + cw // 2 + 1, real=True) + 1) & ~1
    power = np.abs(fft.rfft2(patch, s=(ny, nx))) ** 2
    fy = np.fft.fftfreq(ny)[:, None]
    fx = np.fft.rfftfreq(nx)[None, :]
    power[np.hypot(fx, fy) < 1.0 / (2.0 * MAX_PITCH_PX)] = 0.0
    acf = np.fft.fftshift(fft.irfft2(power, s=(ny, nx)))
    zero = acf[ny // 2, nx // 2]
    if not (np.isfinite(zero) and zero > 0):
        return None
    acf /= zero
    ly = np.arange(ny)[:, None] - ny // 2
    lx = np.arange(nx)[None, :] - nx // 2
    lag = np.hypot(lx, ly)
    peaks = (acf == ndimage.maximum_filter(acf, size=3)) & (acf >= min_peak)
    peaks &= (lag >= MIN_PITCH_PX) & (lag <= min(MAX_PITCH_PX, min(ch, cw) / 2.0))
    if not peaks.any():
        return None
    iy, ix = np.nonzero(peaks)
    k = int(np.argmin(lag[iy, ix]))
    py, px = iy[k], ix[k]
    dy = _parabola_vertex(acf[py - 1, px], acf[py, px], acf[py + 1, px])
    dx = _parabola_vertex(acf[py, px - 1], acf[py, px], acf[py, px + 1])
    vy, vx = ly[py, 0] + dy, lx[0, px] + dx
    return float(math.hypot(vx, vy)), float(math.atan2(vy, vx))


def _parabola_vertex(left: float, centre: float, right: float) -> float:
    """Offset of the vertex of the parabola through three equally spaced samples (within ±0.5)."""
    denom = left - 2.0 * centre + right
    if denom >= 0:
        return 0.0
    return float(np.clip(0.5 * (left - right) / denom, -0.5, 0.5))


