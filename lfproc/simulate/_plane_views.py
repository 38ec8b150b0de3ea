"""Exact light fields of a textured plane at a fractional refocus parameter (interpolation-bias ground truth).

View k of a Lambertian plane in focus at refocus parameter a0 sees the plane's texture shifted by
a0·(c − k) lenses (the contract's centred Eq. 9), each sample the texture integrated over its lens. The
texture is random with natural-image statistics (power ∝ 1/f², Field 1987), synthesised on a grid
``oversample`` times finer than the lenses and shifted exactly in the Fourier domain (periodic over
the array), so the lens integration (a box of one pitch) and the aliasing of detail finer than the
lenses are those of a capture. Pure numpy.
"""

from __future__ import annotations

import numpy as np


def plane_views(m: int, n: int, a0: float, seed: int = 0, oversample: int = 4, band: float | None = None,
                exponent: float = 2.0) -> np.ndarray:
    """``(m, m, n, n, 1)`` float32 views of a textured plane whose slice ``a0`` is in focus.

    Parameters
    ----------
    m : int
        m̂, odd: views per axis.
    n : int
        Lenses per axis (the texture repeats every n lenses).
    a0 : float
        The plane's refocus parameter.
    seed : int
        The texture's random phases.
    oversample : int
        Texture samples per lens before the lens integration (1: no aliasing).
    band : float or None
        No frequency at or above ``band`` cycles per lens on either axis (``None``: all).
    exponent : float
        Power spectrum ∝ f^(−exponent) (2: natural images).
    """
    rng = np.random.default_rng(seed)
    size = n * oversample
    f = np.fft.fftfreq(size, d=1.0 / oversample)           # cycles per lens
    fy, fx = f[:, None], f[None, :]
    radius = np.hypot(fy, fx)
    radius[0, 0] = 1.0
    spectrum = radius ** (-exponent / 2.0) * np.exp(2j * np.pi * rng.random((size, size)))
    spectrum[0, 0] = 0.0
    spectrum *= np.sinc(fy) * np.sinc(fx)                   # integrated over the lens (a box of one pitch)
    if band is not None:
        spectrum *= (np.abs(fy) < band) & (np.abs(fx) < band)
    c = (m - 1) // 2
    views = np.empty((m, m, n, n, 1), np.float32)
    for ky in range(m):
        shift_y = np.exp(-2j * np.pi * a0 * fy * (c - ky))
        for kx in range(m):
            shifted = spectrum * shift_y * np.exp(-2j * np.pi * a0 * fx * (c - kx))
            views[ky, kx, :, :, 0] = np.fft.ifft2(shifted).real[::oversample, ::oversample]
    return views
