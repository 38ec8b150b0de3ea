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

    Returns
    -------
    ndarray (m, m, n, n, 1) float32
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


def fourier_refocus(views: np.ndarray, a, view_mask: np.ndarray | None = None) -> np.ndarray:
    """``(K, Ny, Nx, 1)`` float64: Eq. 9 (centred) of ``views`` (channel 0) with exact shifts — periodic
    Fourier phase ramps, no interpolation between lenses — for each a, averaged over the views
    ``view_mask`` marks (all without one): the reference that a kernel's slices are compared with (on a
    band-limited plane it peaks exactly at a0; on an aliased one it shows the pull of aliasing alone)."""
    m, _, ny, nx = views.shape[:4]
    c = (m - 1) // 2
    mask = np.ones((m, m)) if view_mask is None else np.asarray(view_mask, dtype=np.float64)
    fy, fx = np.fft.fftfreq(ny), np.fft.fftfreq(nx)
    spectra = np.fft.fft2(views[..., 0].astype(np.float64)) * mask[:, :, None, None]
    k = c - np.arange(m)
    out = []
    for value in np.atleast_1d(a):
        phase_y = np.exp(2j * np.pi * value * k[:, None] * fy[None, :])       # (m, ny)
        phase_x = np.exp(2j * np.pi * value * k[:, None] * fx[None, :])       # (m, nx)
        total = np.einsum("yb,yxba,xa->ba", phase_y, spectra, phase_x)
        out.append(np.fft.ifft2(total / mask.sum()).real)
    return np.array(out)[..., None]
