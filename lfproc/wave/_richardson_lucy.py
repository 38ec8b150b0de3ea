"""Richardson–Lucy deconvolution of a light field into a volume, guarded and filtered.

The measurement y (views × lenses) is modelled as y ≈ H·x + b: H the forward projection (:mod:`._projector`),
x ≥ 0 the volume, b ≥ 0 a background per view (autofluorescence, stray light, what a dark frame leaves).
With weights w (1 where a sample was measured, 0 where not: views outside the NA, lenses the white image
left dark) the multiplicative update that increases the Poisson likelihood is

    x ← x · Hᵀ(w·y / (H·x + b)) / Hᵀw

followed by the depth-adaptive anti-aliasing filter of each plane (:mod:`._filter`). Guards: voxels whose
Hᵀw is below ``SEEN_SHARE`` of its largest value are not estimated (0; at most the volume's outermost voxels,
which little of the measurement sees: dividing by a tiny Hᵀw is how pyolaf's reconstruction diverged at
the border), the prediction is floored at a tiny positive value, negative and non-finite data count as 0
with weight 0. No NaN or infinity can arise: the update keeps Σ x·Hᵀw ≤ Σ w·y (the light measured), so every
voxel stays below Σ w·y / (``SEEN_SHARE``·max Hᵀw). Each iteration records the relative misfit
‖w·(H·x + b − y)‖ / ‖w·y‖ of its result; an optional tolerance stops when an iteration improves it by less
than that fraction.
"""

from __future__ import annotations

import numpy as np

from ._filter import apply_filter

#: voxels seen by less than this share of the largest Hᵀw are left at 0
SEEN_SHARE = 0.05
#: the prediction's floor, as a share of the data's mean
PREDICTION_FLOOR = 1e-6


def polyphase_to_volume(poly, z_count: int, superres: int, backend):
    """``(Z·S², Ny, Nx)`` lens-rate images → ``(Z, Ny·S, Nx·S)`` voxels (voxel (jy·S + sy, jx·S + sx))."""
    _, ny, nx = poly.shape
    s = superres
    return backend.xp.ascontiguousarray(poly.reshape(z_count, s, s, ny, nx).transpose(0, 3, 1, 4, 2)) \
        .reshape(z_count, ny * s, nx * s)


def volume_to_polyphase(volume, superres: int, backend):
    """The inverse of :func:`polyphase_to_volume`."""
    z, height, width = volume.shape
    s = superres
    ny, nx = height // s, width // s
    return backend.xp.ascontiguousarray(volume.reshape(z, ny, s, nx, s).transpose(0, 2, 4, 1, 3)) \
        .reshape(z * s * s, ny, nx)


def richardson_lucy(projector, data, weights, background, iterations: int, *, superres: int, widths=None,
                    tolerance: float | None = None, callback=None):
    """Deconvolve ``data`` with ``projector``.

    Parameters
    ----------
    projector : Projector
    data : ndarray (U, Ny, Nx)
        The measurement in the operators' views.
    weights : ndarray (U, Ny, Nx) or None
        1 where measured, 0 where not (None: everywhere measured).
    background : ndarray (U,) or float
        b per view, in the data's units.
    iterations : int
        The most updates to run.
    superres : int
        S (the volume's layout).
    widths : sequence of float, optional
        The anti-aliasing filter's width per plane (:func:`._filter.filter_widths`); None: no filter.
    tolerance : float, optional
        Stop once an update lowers the misfit by less than this fraction of it.
    callback : callable, optional
        ``callback(done, total, misfit)`` after each update.

    Returns
    -------
    volume : ndarray, float32, shape (Z, Ny·S, Nx·S)
    misfits : list of float
        The relative misfit after each update run.
    """
    be = projector.backend
    xp = be.xp
    y = be.asarray(data, dtype=xp.float32)
    w = xp.ones_like(y) if weights is None else be.asarray(weights, dtype=xp.float32)
    bad = ~xp.isfinite(y) | (y < 0)
    w = xp.where(bad, 0, w).astype(xp.float32)
    y = xp.where(bad | (w == 0), 0, y).astype(xp.float32)
    b = xp.broadcast_to(be.asarray(np.asarray(background, dtype=np.float32).reshape(-1, 1, 1)), y.shape)
    wy = w * y
    seen = projector.backward(w)
    live = seen > SEEN_SHARE * float(seen.max())
    norm = xp.where(live, seen, 1).astype(xp.float32)
    z_count = projector.inputs // (superres * superres)
    x = live.astype(xp.float32)
    uniform = projector.forward(x)            # a uniform start with the data's total light
    scale = np.float32(max(float(xp.sum(w * xp.maximum(y - b, 0))) / max(float(xp.sum(w * uniform)), 1e-30), 1e-12))
    x *= scale
    prediction = uniform * scale + b
    floor = np.float32(PREDICTION_FLOOR * max(float(xp.mean(y)), 1e-30))
    norm_y = max(float(xp.sqrt(xp.sum(w * y * y))), 1e-30)
    misfits: list[float] = []
    for done in range(1, int(iterations) + 1):
        ratio = wy / xp.maximum(prediction, floor)
        x = xp.where(live, x * projector.backward(ratio) / norm, 0).astype(xp.float32)
        if widths is not None and any(float(v) > 1 for v in widths):
            volume = apply_filter(polyphase_to_volume(x, z_count, superres, be), widths, be)
            x = volume_to_polyphase(volume, superres, be)
        prediction = projector.forward(x) + b
        misfits.append(float(xp.sqrt(xp.sum(w * (prediction - y) ** 2))) / norm_y)
        if callback is not None:
            callback(done, int(iterations), misfits[-1])
        if tolerance is not None and done > 1 and misfits[-2] - misfits[-1] < tolerance * misfits[-2]:
            break
    return be.to_numpy(polyphase_to_volume(x, z_count, superres, be)).astype(np.float32), misfits
