"""The depth-adaptive anti-aliasing filter of Stefanoiu et al. ("Artifact-free deconvolution in light field
microscopy", Opt. Express 27(22), 2019), as oLaF computes its width.

A light-field microscope samples a plane at depth z through the lenslets as pinholes: the image of that
plane lies Δ = z·M²/n from the lenslets, which project it onto the sensor with magnification λ(z) = f_s/|Δ|.
Near the native object plane (λ large) only one sample per lens survives; further away the views interleave
and finer detail is recoverable. The filter keeps each plane below the frequency the light field samples it
at: a Lanczos-windowed sinc of width

    w(z) = min(p/2, p·λ(z))      at the lenslets (p the lens pitch),

in voxels W = 2·w·S/p (at most S: one lens; W ≤ 1, a plane sampled at the voxel rate, is not filtered), kernel
sinc(x/W)·sinc(x/(4W)) over |x| ≤ 3W, normalised to sum 1 — separable here (oLaF's is cut radially), applied
to each plane after every Richardson–Lucy update (with mirrored borders, not oLaF's periodic ones).

W is kept as it is, not rounded as oLaF rounds it (down to an odd whole number). The paper defines the filter
by its cut-off frequency, which follows λ(z) continuously; oLaF's rounding makes it jump between neighbouring
planes. At S = 3 it leaves only W = 1 (nothing) or 3 (a lens): for 20x/0.5 water lenslets of 125 µm and
f_s 2433 µm, W = 2.43 at z = ±20 µm becomes 3 (filtered as hard as the native plane) and W = 1.62 at ±30 µm
becomes 1 (not filtered). Richardson–Lucy then draws a point at ±20 µm as a lens-wide blob on its own plane
plus a sharp point on the unfiltered ±30 µm plane, whose peak is the brighter: the beads of
docs/deconvolution.md were found one plane off. With W as it is (2.43 and 1.62) every bead is on its own
plane, its light and its peak (tests/test_deconvolve.py).
oLaF subtracts a lenslet blur term b = (p/2)·|1/z₃ − 1/f_s| that is below 0.05 µm (its two terms have
different units; its source comments out the form with units); it is left out here, so the widths are
oLaF's widths, with the immersion index in Δ (oLaF's width formula takes z in air).
"""

from __future__ import annotations

import math

import numpy as np

#: the Lanczos window: sinc(x/(WINDOW·W)), cut at CUT·W
WINDOW = 4
CUT = 3


def filter_widths(operators) -> np.ndarray:
    """W per plane (floats ≥ 1), in voxels."""
    delta = np.abs(np.asarray(operators.z_um, dtype=np.float64)) * operators.objective_magnification ** 2 \
        / operators.immersion_index
    p = operators.pitch_um
    with np.errstate(divide="ignore"):
        width = np.minimum(p / 2.0, p * operators.lenslet_focal_um / delta)
    return np.maximum(2.0 * width * operators.superres / p, 1.0)


def lanczos_kernel(width: float) -> np.ndarray:
    """The 1-D kernel of width W (W ≤ 1: the identity), over the whole voxels |x| ≤ 3W."""
    if width <= 1:
        return np.ones(1)
    half = int(math.floor(CUT * width))
    x = np.arange(-half, half + 1, dtype=np.float64)
    k = np.sinc(x / width) * np.sinc(x / (WINDOW * width))
    return k / k.sum()


def apply_filter(volume, widths, backend):
    """Each plane of ``volume`` (Z, Y, X) filtered with its kernel along y and x, mirrored at the borders, and
    clipped at 0 (the kernels' negative lobes must not make emission negative)."""
    xp = backend.xp
    out = volume
    for i, width in enumerate(widths):
        kernel = lanczos_kernel(float(width))
        if kernel.size == 1:
            continue
        half = kernel.size // 2
        plane = volume[i]
        for axis in (0, 1):
            pad = [(0, 0), (0, 0)]
            pad[axis] = (half, half)
            padded = xp.pad(plane, pad, mode="reflect" if plane.shape[axis] > half else "edge")
            acc = xp.zeros_like(plane)
            for j, weight in enumerate(kernel):
                acc += np.float32(weight) * (padded[j:j + plane.shape[0]] if axis == 0
                                             else padded[:, j:j + plane.shape[1]])
            plane = acc
        out[i] = xp.maximum(plane, 0)
    return out
