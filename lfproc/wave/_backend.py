"""The one place where the array library is chosen: NumPy (with SciPy's FFTs) on the CPU, or CuPy on a GPU.

The projections and Richardson–Lucy do all their arithmetic through a :class:`Backend`: ``xp`` (the array
module: ``numpy`` or ``cupy``), its real FFTs and the move back to NumPy. CuPy is never required and
never imported unless asked for (``backend="cupy"``); lfproc's tests and CI run the NumPy backend.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

from ..errors import LfprocError

BACKENDS = ("numpy", "cupy")


@dataclass(frozen=True)
class Backend:
    """An array module and its real 2-D FFTs over the last two axes.

    Attributes
    ----------
    name : {"numpy", "cupy"}
    xp : module
        ``numpy`` or ``cupy``.
    workers : int
        Threads of SciPy's FFTs (NumPy backend).
    """

    name: str
    xp: object
    workers: int = 1

    def rfft2(self, a):
        if self.name == "numpy":
            from scipy import fft
            return fft.rfft2(a, axes=(-2, -1), workers=self.workers)
        return self.xp.fft.rfft2(a, axes=(-2, -1))

    def irfft2(self, a, shape):
        if self.name == "numpy":
            from scipy import fft
            return fft.irfft2(a, s=shape, axes=(-2, -1), workers=self.workers)
        return self.xp.fft.irfft2(a, s=shape, axes=(-2, -1))

    def asarray(self, a, dtype=None):
        return self.xp.asarray(a, dtype=dtype)

    def to_numpy(self, a) -> np.ndarray:
        return a if isinstance(a, np.ndarray) else self.xp.asnumpy(a)


def backend(name: str = "numpy") -> Backend:
    """The backend ``name`` ("numpy", or "cupy" where CuPy and a GPU are installed)."""
    if isinstance(name, Backend):
        return name
    if name == "numpy":
        return Backend("numpy", np, max(1, os.cpu_count() or 1))
    if name == "cupy":
        try:
            import cupy
        except ImportError:
            raise LfprocError("backend='cupy' needs CuPy and a GPU (pip install cupy-cuda12x); use backend='numpy'") \
                from None
        return Backend("cupy", cupy)
    raise LfprocError(f"backend= must be one of {', '.join(BACKENDS)}, got {name!r}")
