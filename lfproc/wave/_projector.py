"""Forward and back projection of a light-field microscope at the lens rate: batched matrix products per frequency.

The forward projection y[u](j) = Σ_p Σ_k h[p, u](k) · vol[p](j − k) (p = (z, s), :mod:`._operators`) is, at each
lens-rate spatial frequency f, a small dense matrix A_f (U outputs × Z·S² inputs) times a vector; the back
projection is its conjugate transpose (a correlation). A_f for the whole image would take GBs, so the image
is cut into overlap-save tiles of T × T lenses (T − 2R lenses of output each, R the kernels' reach): A_f is
computed once on the T × T frequency grid, and each projection is one FFT of every input tile, one batched
matrix product over the frequencies (all tiles at once: matrix-matrix products, BLAS cgemm) and one inverse
FFT. The tile size trades memory (A: T·(T/2 + 1)·U·Z·S² complex64) against arithmetic (the overlap is
computed twice); :func:`choose_tile` takes the cheapest within a memory budget.

Volumes are ``(Z·S², Ny, Nx)`` lens-rate images (index z·S² + sy·S + sx), data ``(U, Ny, Nx)``. Outside the
light field the volume is 0 and the data are missing: the projections are exact adjoints of each other.
"""

from __future__ import annotations

import math

import numpy as np

from ._backend import backend as make_backend

#: tile sizes tried (FFT-friendly)
TILE_SIZES = (8, 10, 12, 15, 16, 18, 20, 24, 25, 27, 30, 32, 36, 40, 45, 48, 50, 54, 60, 64, 72, 80, 90, 96, 100,
              108, 120, 128, 144, 160)
#: default budget for A (bytes)
DEFAULT_MEMORY = 512 * 2 ** 20
#: bytes of tile spectra handled at once
CHUNK_BYTES = 128 * 2 ** 20


def choose_tile(lens_shape, radius: int, outputs: int, inputs: int, memory: int = DEFAULT_MEMORY) -> int:
    """T: the tile size with the least arithmetic (frequencies × tiles) whose A fits in ``memory`` bytes (the
    smallest possible tile when none fits)."""
    ny, nx = lens_shape
    candidates = [t for t in TILE_SIZES if t > 2 * radius] or [2 * radius + 2]
    fitting = [t for t in candidates if t * (t // 2 + 1) * outputs * inputs * 8 <= memory] or candidates[:1]

    def cost(t):
        valid = t - 2 * radius
        return t * (t // 2 + 1) * math.ceil(ny / valid) * math.ceil(nx / valid), t

    return min(fitting, key=cost)


class Projector:
    """The projections of one lens grid (Ny × Nx lenses) with one set of operators.

    Parameters
    ----------
    operators : WaveOperators
    lens_shape : (int, int)
        Ny, Nx of the light field.
    views : ndarray of bool (U,), optional
        Which of the operators' views are data (default: all).
    backend : str or Backend
        "numpy" (default) or "cupy" (:mod:`._backend`).
    memory : int
        Budget in bytes for the per-frequency matrices.
    """

    def __init__(self, operators, lens_shape, views=None, backend="numpy", memory: int = DEFAULT_MEMORY):
        self.backend = make_backend(backend)
        xp = self.backend.xp
        kernels = operators.kernels if views is None else operators.kernels[:, :, np.asarray(views, dtype=bool)]
        z, classes, outputs, k, _ = kernels.shape
        self.lens_shape = (int(lens_shape[0]), int(lens_shape[1]))
        self.radius = (k - 1) // 2
        self.inputs, self.outputs = z * classes, outputs
        self.tile = choose_tile(self.lens_shape, self.radius, outputs, self.inputs, memory)
        t = self.tile
        self.frequencies = t * (t // 2 + 1)
        matrix = xp.empty((self.frequencies, outputs, self.inputs), dtype=xp.complex64)
        for i in range(z):                                      # one plane at a time bounds the temporaries
            g = xp.zeros((classes, outputs, t, t), dtype=xp.float32)
            g[:, :, :k, :k] = self.backend.asarray(kernels[i])
            g = xp.roll(g, (-self.radius, -self.radius), axis=(2, 3))   # offset k at index k mod T
            spectra = self.backend.rfft2(g).reshape(classes, outputs, self.frequencies)
            matrix[:, :, i * classes:(i + 1) * classes] = spectra.transpose(2, 1, 0)
        self.matrix = matrix

    @property
    def nbytes(self) -> int:
        return int(self.matrix.nbytes)

    def forward(self, volume):
        """y = H·vol: ``(Z·S², Ny, Nx)`` → ``(U, Ny, Nx)`` (float32, on the backend)."""
        return self._apply(volume, self.outputs, adjoint=False)

    def backward(self, data):
        """Hᵀ·y: ``(U, Ny, Nx)`` → ``(Z·S², Ny, Nx)`` (float32, on the backend)."""
        return self._apply(data, self.inputs, adjoint=True)

    def _apply(self, images, channels_out: int, adjoint: bool):
        xp, t, r = self.backend.xp, self.tile, self.radius
        ny, nx = self.lens_shape
        valid = t - 2 * r
        rows, cols = math.ceil(ny / valid), math.ceil(nx / valid)
        images = self.backend.asarray(images, dtype=xp.float32)
        channels_in = images.shape[0]
        padded = xp.zeros((channels_in, rows * valid + 2 * r, cols * valid + 2 * r), dtype=xp.float32)
        padded[:, r:r + ny, r:r + nx] = images
        out = xp.empty((channels_out, rows * valid, cols * valid), dtype=xp.float32)
        origins = [(a, b) for a in range(rows) for b in range(cols)]
        per_tile = self.frequencies * max(channels_in, channels_out) * 8
        step = max(1, int(CHUNK_BYTES // per_tile))
        for first in range(0, len(origins), step):
            chunk = origins[first:first + step]
            tiles = xp.stack([padded[:, a * valid:a * valid + t, b * valid:b * valid + t] for a, b in chunk], axis=1)
            spectra = self.backend.rfft2(tiles).reshape(channels_in, len(chunk), self.frequencies)
            spectra = xp.ascontiguousarray(spectra.transpose(2, 0, 1))                 # (F, C_in, n)
            if adjoint:     # Aᴴ·R = (Rᴴ·A)ᴴ: A stays contiguous
                product = xp.matmul(spectra.conj().transpose(0, 2, 1), self.matrix).conj()   # (F, n, C_out)
                product = product.transpose(2, 1, 0)
            else:
                product = xp.matmul(self.matrix, spectra).transpose(1, 2, 0)                   # (C_out, n, F)
            result = self.backend.irfft2(xp.ascontiguousarray(product).reshape(channels_out, len(chunk), t, t // 2 + 1),
                                         (t, t))
            for i, (a, b) in enumerate(chunk):
                out[:, a * valid:(a + 1) * valid, b * valid:(b + 1) * valid] = result[:, i, r:r + valid, r:r + valid]
        return out[:, :ny, :nx]
