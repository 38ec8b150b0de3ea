"""How sharp each slice of a focal stack is, in the band of spatial frequencies a light field resolves.

A plane at refocus parameter a0 is sharpest in the slice a0, but only for the detail the lens grid
samples faithfully. Detail finer than a lens (a capture's micro lenses integrate over their pitch, a box
that passes much above the grid's Nyquist frequency of 1/2 cycle per lens) aliases: in view k a
component of frequency F appears at f = F − round(F) with the view's parallax scaled by F/f, so it comes
into focus at a0·F/f, not at a0, and drags a sharpness measure that counts it away from a0 — exact
(Fourier) shifts included (docs/microscope-imaging.md). And near 1/2 cycle per lens no interpolation
between lenses keeps its response, so slices between whole lenses lose that band and a full-band
measure favours whole lenses. Below a quarter cycle per lens both effects are small: aliases from
beyond 3/4 cycle, attenuated by the lens integration, and a cubic spline flat to within a few per cent.
"""

from __future__ import annotations

import numpy as np

#: the band of :func:`slice_sharpness`: spatial frequencies below this many cycles per lens
SHARPNESS_BAND = 0.25


def slice_sharpness(stack: np.ndarray, border: int = 0, band: float = SHARPNESS_BAND) -> np.ndarray:
    """Sharpness of each slice of a focal stack: its power below ``band`` cycles per lens.

    Parameters
    ----------
    stack : ndarray
        ``(K, Ny, Nx)`` or ``(K, Ny, Nx, C)`` slices (:func:`lfproc.refocus` with a sequence of a; the
        channels are summed), on the lens grid (``upsample = 1``).
    border : int
        Lenses left out at each edge (the band that views shift off: ``ceil(max|a|·c)``).
    band : float
        Radial frequency limit, cycles per lens (default :data:`SHARPNESS_BAND`).

    Returns
    -------
    ndarray, float64, (K,)
        The variance of each slice's detail below ``band`` (mean removed; the inner region Hann
        windowed so that its edges add no power).
    """
    stack = np.asarray(stack, dtype=np.float64)
    if stack.ndim == 4:
        stack = stack.sum(axis=3)
    inner = stack[:, border:stack.shape[1] - border, border:stack.shape[2] - border]
    window = np.outer(np.hanning(inner.shape[1]), np.hanning(inner.shape[2]))
    inner = (inner - inner.mean(axis=(1, 2), keepdims=True)) * window
    spectrum = np.fft.rfft2(inner)
    fy = np.fft.fftfreq(inner.shape[1])[:, None]
    fx = np.fft.rfftfreq(inner.shape[2])[None, :]
    weight = np.where(fx > 0, 2.0, 1.0) * (np.hypot(fy, fx) < band)   # rfft: the other half-plane twice
    return (np.abs(spectrum) ** 2 * weight).sum(axis=(1, 2)) / window.size
