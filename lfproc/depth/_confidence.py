"""How far each estimate can be trusted: the basin of the cost and a second, independent cue.

Correspondence (the variance across the views, :mod:`._cost`) is precise where there is texture.
Where there is none its cost is flat: the basin (:mod:`._refine`) is wide. The confidence of an
estimate compares the basin's half-width ``s`` with half the DOF ``h`` of the slice at that ``a``
(the depth resolution the camera itself has there, Eqs. 23–31):

    confidence_corr = 1 / (1 + (s / h)²)

The *defocus* cue — the sharpest slice of the refocused stack by its local gradient energy — comes
from the same sweep at no extra cost and fails differently (it sees contrast, not agreement between
views). Where both agree within the DOF the estimate stands; the further they disagree the lower the
confidence:

    confidence = confidence_corr / (1 + (Δ / 2h)⁴),   Δ = |a_corr − a_defocus|

Estimates below :data:`MIN_CONFIDENCE`, or whose best slice is an end of the sweep, are unknown (NaN).

**No depth without light.** Where no light fell (a black border, the dark background of a fluorescence
capture) the views hold noise and an offset, and their agreement says nothing about a surface. A lens whose
luminance averaged over the views is below :data:`UNLIT_FRACTION` of the light field's bright level (the 99th
percentile of that average over the lenses) is unlit (`lit_lenses`): its confidence is 0 and its depth
unknown, in the depth map, its preview and the viewer. Devignetted views are in units of the white image, so
this is also a fraction of the white image's level wherever the capture's brightest parts are as bright as
the white.
"""

from __future__ import annotations

import numpy as np

from ._refine import aggregate, minimum_position
from ._search import dof_half_width_a

#: estimates less confident than this are reported as unknown (NaN)
MIN_CONFIDENCE = 0.1

#: share of the bright level (99th percentile of the lenses' mean luminance) below which a lens is unlit
UNLIT_FRACTION = 0.05

#: contrast (relative to the median luminance) below which a texture counts as absent
NOISE_CONTRAST = 0.01


def lit_lenses(views: np.ndarray, weight: np.ndarray | None = None) -> np.ndarray:
    """``(Ny, Nx)`` booleans: lenses whose luminance averaged over the views (``weight``: those that carry
    light; channels averaged) reaches :data:`UNLIT_FRACTION` of the 99th percentile over the lenses (module
    docstring). All False where nothing is lit."""
    views = np.asarray(views)
    m = views.shape[0]
    use = np.ones((m, m), bool) if weight is None else np.asarray(weight, bool)
    mean = np.zeros(views.shape[2:4])
    for ky, kx in zip(*np.nonzero(use)):                           # view by view: no copy of the light field
        mean += views[ky, kx].mean(axis=-1, dtype=np.float64)
    mean /= max(int(use.sum()), 1)
    finite = np.isfinite(mean)
    top = float(np.percentile(mean[finite], 99)) if finite.any() else 0.0
    if not top > 0:
        return np.zeros(mean.shape, bool)
    return finite & (mean >= UNLIT_FRACTION * top)


def cost_floor(luminance: np.ndarray) -> float:
    """The cost (a variance) of a texture of :data:`NOISE_CONTRAST` relative contrast."""
    level = float(np.median(luminance)) if luminance.size else 0.0
    return (NOISE_CONTRAST * max(level, 1e-12)) ** 2


def defocus_estimate(luminance: np.ndarray, a_values: np.ndarray, lenses: np.ndarray | None = None) -> np.ndarray:
    """The ``a`` of the sharpest slice per lens: largest aggregated gradient energy of the refocused luminance
    (``(K, Ny, Nx)``), refined between slices like the correspondence cost. With ``lenses`` (``(Ny, Nx)``
    booleans) only those lenses' slices are searched (NaN elsewhere); their ``a`` is the same."""
    energy = np.zeros_like(luminance)
    if luminance.shape[1] > 1:      # squared forward differences, each shared by the two lenses it joins
        d = np.diff(luminance, axis=1)
        d *= d
        energy[:, 1:] += d
        energy[:, :-1] += d
    if luminance.shape[2] > 1:
        d = np.diff(luminance, axis=2)
        d *= d
        energy[:, :, 1:] += d
        energy[:, :, :-1] += d
    energy = aggregate(energy)
    top = energy.max()
    if lenses is None:
        return minimum_position(np.subtract(top, energy, out=energy), a_values)
    a = np.full(energy.shape[1:], np.nan)
    a[lenses] = minimum_position(np.subtract(top, energy[:, lenses]), a_values)
    return a


#: share of the views a slice must average at a lens for its sharpness (the defocus cue) to count there
DEFOCUS_MIN_COVERAGE = 0.75


def view_coverage(a: np.ndarray, reach: int, view_step: int = 1) -> np.ndarray:
    """Per lens ``(Ny, Nx)``: the share of the views ``c + step·t`` (``|step·t| ≤ reach``) whose sample
    lies on the image in the slice ``a`` of that lens (per axis, multiplied): 1 in the interior, less near
    the image border, where views shift off it."""
    ny, nx = a.shape
    t = np.arange(-(reach // view_step), reach // view_step + 1) * view_step
    a = np.nan_to_num(np.asarray(a, dtype=np.float64))[..., None]

    def along(index, n):
        pos = index[..., None] + a * t      # the contract's j + a·(c − k) for every view offset
        return np.mean((pos >= 0) & (pos <= n - 1), axis=-1)

    rows = np.arange(ny, dtype=np.float64)[:, None] + np.zeros((1, nx))
    cols = np.arange(nx, dtype=np.float64)[None, :] + np.zeros((ny, 1))
    return along(rows, ny) * along(cols, nx)


def confidence(a_corr: np.ndarray, a_low: np.ndarray, a_high: np.ndarray, a_defocus: np.ndarray,
               center_index: int, resolution: float = 1.0, coverage: np.ndarray | None = None) -> np.ndarray:
    """The confidence (0–1) of each estimate (module docstring); ``resolution`` > 1 widens ``h`` for a
    sweep on a coarser lens grid (binned b × b lenses see b times less parallax per unit of ``a``).

    ``coverage`` (:func:`view_coverage`): where a slice averages fewer than :data:`DEFOCUS_MIN_COVERAGE` of
    the views (near the image border) its sharpness says nothing (fewer views blur less) and the
    defocus cue is left out: the basin of the correspondence cost decides alone."""
    h = dof_half_width_a(a_corr, center_index) * resolution
    with np.errstate(invalid="ignore"):
        spread = np.maximum(a_corr - a_low, a_high - a_corr)
        corr = 1.0 / (1.0 + (spread / h) ** 2)
        corr = np.where(np.isfinite(spread), corr, 0.0)
        delta = np.abs(a_corr - a_defocus)
        agreement = 1.0 / (1.0 + (delta / (2.0 * h)) ** 4)
        if coverage is not None:
            agreement = np.where(coverage >= DEFOCUS_MIN_COVERAGE, agreement, 1.0)
    return np.nan_to_num(corr * agreement).astype(np.float32)
