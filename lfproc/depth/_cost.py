"""Matching cost of a sweep over the refocus parameter ``a``: the spread of the views behind each lens.

For a scene point in focus at ``a`` every view ``k`` shows it at lens ``j + a·(c − k)`` (the contract's
centred Eq. 9), so the samples that the refocused slice ``a`` averages all agree there: their variance
across the views is only noise. Out of focus they sample different points and the variance grows
(the *correspondence* cue). The variance is ``E[Y²] − E[Y]²`` over the views, and both means are what
:func:`lfproc.refocus` computes when it refocuses a light field whose channels are ``Y`` and ``Y²``:
the whole cost volume is one call of the fused multi-slice kernel, one pass over the views.

Views outside the main lens aperture carry no light, and the decoder delivers views it cannot sample
without bias as 0 everywhere (``LightField.view_mask``, else :func:`delivered_views`); these are left out:
the sweep refocuses ``Y`` and ``Y²`` as a light field with that view mask, whose refocusing averages over
the views that carry light only (:func:`lfproc.refocus`).
With many views a sub-lattice of every ``step``-th view around the central one is used: the same
baseline at a fraction of the cost, its refocus parameter ``step·a``. The outer ring of views is left
out by default (its samples straddle the border of the micro image: crosstalk after decoding).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: view samples (views × lenses) above which the sweep uses every second view (or more)
FULL_VIEW_BUDGET = 20_000_000


@dataclass(frozen=True, eq=False)
class CostVolume:
    """The sweep's cost and refocused luminance, both ``(K, Ny, Nx)`` float32, at refocus parameters ``a``."""

    a: np.ndarray           # (K,) float64, increasing
    cost: np.ndarray        # variance of the views' luminance behind each lens, per slice
    luminance: np.ndarray   # the refocused luminance (the slice itself), per slice
    view_step: int


def auto_view_step(reach: int, lens_count: int) -> int:
    """The smallest view step whose views (offsets up to ``reach`` from the centre) stay within
    :data:`FULL_VIEW_BUDGET` samples."""
    for step in range(1, max(reach, 1) + 1):
        n = 2 * (reach // step) + 1
        if n * n * lens_count <= FULL_VIEW_BUDGET or n <= 3:
            return step
    return 1


def delivered_views(views: np.ndarray, rows: int = 16) -> np.ndarray:
    """``(m̂, m̂)`` booleans: views that carry a signal. The decoder delivers views it cannot sample without
    bias (and views outside the aperture) as 0 everywhere; ``rows`` evenly spread lens rows are enough to
    tell."""
    sample = views[:, :, ::max(1, views.shape[2] // rows)]
    return np.any(sample != 0, axis=tuple(range(2, views.ndim)))


def luminance(views: np.ndarray) -> np.ndarray:
    """``(…, C)`` float32 → ``(…)`` float32: the matching signal, the mean of the channels.

    Equal weights, not Rec. 709 luma: a demosaiced view's missing colours are interpolated from the
    neighbouring pixels of the micro image, i.e. from the neighbouring *views* of the same lens, which
    see a surface at ``a`` displaced by ``±a`` lenses. Which colour is measured and which interpolated
    changes from view to view and lens to lens (the Bayer phase under each lens), so luma (72 % green)
    mixes neighbouring views with a kernel that changes from sample to sample (centre weight 0.72 at a
    green site, 0.21 at a red one): the views disagree at the true ``a`` and the cost's minimum scatters,
    the more the larger ``|a|``. With equal weights every site has one measured channel of three and two
    interpolated ones: centre weight 1/3 at every site, and the rest spread over the same 3 × 3
    neighbourhood, a nearly uniform angular blur, under which the views agree again at the true ``a``
    (docs/depth.md, "Depth at the edges of the scene"). This holds for bilinear demosaicing (and helps
    under OpenCV's edge-aware one). The default Bayer decoder is now rim-aware (docs/decoding.md): every
    channel of a sample carries the pixel's own detail, scaled by its micro image's hue, so a site's
    channels differ by that hue rather than by which neighbours were interpolated, and the channel mean
    is close to the pixel's own sample (measured on the edges render: R and B a median 1.4 % off it);
    equal weights keep every site alike there too."""
    return views.mean(axis=-1, dtype=np.float32)


def picked_views(m_hat: int, view_step: int, reach: int | None = None) -> np.ndarray:
    """Indices ``c + step·t`` with ``|step·t| ≤ reach`` (default c) of the views the sweep uses."""
    c = (m_hat - 1) // 2
    reach = c if reach is None else min(int(reach), c)
    half = reach // view_step
    return c + view_step * np.arange(-half, half + 1)


@dataclass(frozen=True, eq=False)
class SweepLuminance:
    """The luminance of the views a sweep uses, computed once for the coarse and the fine sweep.

    ``y`` is ``(n, n, Ny, Nx)`` float32 for the views ``picked`` (:func:`picked_views`), ``weight`` their
    ``(n, n)`` weights (``None`` = all 1), and a sweep at refocus parameter ``a`` shifts them by
    ``view_step·a`` per step of the sub-lattice; ``slopes``, where given, is the per-view shift table
    (σ_y, σ_x) of the picked views in units of that step (a microscope's sine-condition shifts,
    :func:`lfproc.geometry.refocus_slopes`, divided by the step): the sweep's slice ``a`` is then exactly
    the refocused slice ``a`` of the light field, whose depth the geometry tags.
    """

    y: np.ndarray
    weight: np.ndarray | None
    view_step: int
    slopes: tuple | None = None


def sweep_luminance(views: np.ndarray, view_step: int = 1, reach: int | None = None,
                    view_weight: np.ndarray | None = None, view_slopes=None) -> SweepLuminance:
    """Luminance and weights of the views ``c + step·t``, ``|step·t| ≤ reach`` (:func:`picked_views`);
    ``view_slopes`` (σ_y, σ_x) ``(m̂, m̂)`` each: the light field's per-view shift table (``None``: Eq. 9)."""
    picked = picked_views(views.shape[0], view_step, reach)
    weight = None if view_weight is None else np.asarray(view_weight, dtype=np.float32)[np.ix_(picked, picked)]
    if weight is not None and np.all(weight == 1):
        weight = None
    slopes = None if view_slopes is None else tuple(np.asarray(t, dtype=np.float64)[np.ix_(picked, picked)] / view_step
                                                    for t in view_slopes)
    return SweepLuminance(luminance(views[np.ix_(picked, picked)]), weight, int(view_step), slopes)


def binned(y: np.ndarray, bin_lenses: int) -> np.ndarray:
    """Views' luminance ``(n, n, Ny, Nx)`` averaged over ``bin_lenses`` × ``bin_lenses`` lenses (a coarser grid)."""
    if bin_lenses <= 1:
        return y
    b = bin_lenses
    n, _, ny, nx = y.shape
    return y[:, :, :ny // b * b, :nx // b * b].reshape(n, n, ny // b, b, nx // b, b).mean(axis=(3, 5))


def sweep_views(sweep: SweepLuminance, bin_lenses: int = 1) -> np.ndarray:
    """The light field a sweep refocuses: channels ``w·Y`` and ``w·Y²``; with ``bin_lenses`` = b the
    luminance is first averaged over b × b lenses (a coarser lens grid, on which parallax is a/b)."""
    y = binned(sweep.y, bin_lenses)
    out = np.empty(y.shape + (2,), dtype=np.float32)
    np.multiply(y, y, out=out[..., 1])
    out[..., 0] = y
    if sweep.weight is not None:
        w = sweep.weight[:, :, None, None]
        out[..., 0] *= w
        out[..., 1] *= w
    return out


def cost_volume(sweep: SweepLuminance, a_values, *, interpolation: str = "linear",
                bin_lenses: int = 1) -> CostVolume:
    """Variance across the views behind every lens for each refocus parameter (one fused refocus call).

    Parameters
    ----------
    sweep : SweepLuminance
        The views' luminance (:func:`sweep_luminance`).
    a_values : sequence of float
        Refocus parameters of the sweep.
    interpolation : str
        Interpolation of the refocus kernel between lenses.
    bin_lenses : int
        Sweep on lenses binned b × b (:func:`sweep_views`); the volume is on that coarser grid.

    Returns
    -------
    CostVolume
    """
    from ..lightfield import LightField
    from ..refocusing import refocus

    a = np.asarray(a_values, dtype=np.float64)
    shift = a * sweep.view_step / bin_lenses
    mask = None if sweep.weight is None else sweep.weight > 0
    stack = refocus(LightField.from_views(sweep_views(sweep, bin_lenses), view_mask=mask), shift,
                    interpolation=interpolation, view_shifts=sweep.slopes)
    mean, mean_sq = stack[..., 0], stack[..., 1]
    cost = mean_sq
    cost -= mean * mean
    np.maximum(cost, np.float32(0), out=cost)
    return CostVolume(a, cost, mean, sweep.view_step)


#: a half aperture counts at a lens and slice where it keeps at least this share of its views inside the image
HALF_APERTURE_COMPLETE = 0.9

#: the half apertures of the occlusion- and border-aware sweep: views with k ≤ c or k ≥ c along one axis
HALF_APERTURES = (("x", -1), ("x", +1), ("y", -1), ("y", +1))


def half_aperture_weights(n: int, weight: np.ndarray | None) -> list[np.ndarray]:
    """``(n, n)`` weights of the four half apertures of a sweep's ``n × n`` views (:data:`HALF_APERTURES`):
    each keeps the views on one side of the central row or column, the central one included."""
    centre = (n - 1) // 2
    t = np.arange(n) - centre
    base = np.ones((n, n), np.float32) if weight is None else np.asarray(weight, np.float32)
    halves = []
    for axis, side in HALF_APERTURES:
        along = (side * t >= 0).astype(np.float32)
        halves.append(base * (along[None, :] if axis == "x" else along[:, None]))
    return halves


def half_aperture_volumes(sweep: SweepLuminance, a_values, *, interpolation: str = "linear",
                          bin_lenses: int = 1, all_views: bool = False) -> list[CostVolume]:
    """The cost volume of each half aperture (:func:`half_aperture_weights`), exact at the image border.

    Near the border of the image and next to a nearer occluder, some views of a lens see something else
    (they shift off the image, or onto the occluder), and the variance over all views has no clean
    minimum. The views on one side of the centre usually all see the surface: a lens at the right border
    keeps every view that looks left, a surface left of an occluder every view that looks away from it
    (the angular split of occlusion-aware depth estimation, Wang et al., ICCV 2015). Each half's mean
    and mean square are the sums of ``w·Y`` and ``w·Y²`` over the views of the half inside the image
    divided by the sum of their weights ``w``. Where a half has lost views off the image
    (:data:`HALF_APERTURE_COMPLETE`) its cost is ``inf``: a half counts only where it is whole.

    A half is a block of whole view columns (or rows), so it is refocused alone
    (:func:`lfproc.refocusing._block.refocus_view_block`: only its views are read, 2 channels) and the
    weights' sums come from the sampling plans; ``all_views=True`` (and a per-view shift table, a
    microscope's) takes the straightforward way instead: one fused refocus of ``w``, ``w·Y`` and
    ``w·Y²`` of both halves of an axis over every view of the sweep (the views outside a half are zero
    channels), the same volumes up to float rounding at 2.5 × the refocusing work.
    """
    if all_views or sweep.slopes is not None:
        return _half_aperture_volumes_all_views(sweep, a_values, interpolation, bin_lenses)
    from ..refocusing import refocus_view_block, view_weight_inside

    a = np.asarray(a_values, dtype=np.float64)
    shift = a * sweep.view_step / bin_lenses
    n = sweep.y.shape[0]
    centre = (n - 1) // 2
    halves = half_aperture_weights(n, sweep.weight)
    union = (sweep.weight > 0 if sweep.weight is not None else np.ones((n, n), bool)).astype(np.float32)
    y = binned(sweep.y, bin_lenses)
    union_inside = view_weight_inside(shift, union, y.shape[2:4], interpolation)
    volumes = []
    for h, (axis, side) in enumerate(HALF_APERTURES):
        block = slice(0, centre + 1) if side < 0 else slice(centre, n)
        rows, cols = (slice(0, n), block) if axis == "x" else (block, slice(0, n))
        w = halves[h][rows, cols]
        yb = y[rows, cols]
        channels = np.empty(yb.shape + (2,), dtype=np.float32)
        np.multiply(yb, w[:, :, None, None], out=channels[..., 0])
        np.multiply(channels[..., 0], yb, out=channels[..., 1])
        stack, share = refocus_view_block(channels, shift, n, rows, cols, w, interpolation)
        del channels
        complete_share = float(halves[h].sum() / union.sum())
        whole = (share >= HALF_APERTURE_COMPLETE * complete_share * union_inside) & (share > 0)
        volumes.append(_half_volume(a, stack[..., 0], stack[..., 1], whole, sweep.view_step))
    return volumes


def _half_volume(a, mean, mean_sq, whole, view_step) -> CostVolume:
    """A half aperture's :class:`CostVolume` from its mean and mean square; ``inf`` cost (and NaN luminance)
    where it is not ``whole``: fewer samples give a smaller variance and false minima."""
    cost = mean_sq - mean * mean
    empty = ~whole
    cost[empty] = np.inf
    mean[empty] = np.nan
    np.maximum(cost, np.float32(0), out=cost)
    return CostVolume(a, cost.astype(np.float32, copy=False), mean.astype(np.float32, copy=False), view_step)


def _half_aperture_volumes_all_views(sweep, a_values, interpolation, bin_lenses) -> list[CostVolume]:
    """:func:`half_aperture_volumes` the straightforward way: one fused refocus per axis of ``w``, ``w·Y``
    and ``w·Y²`` of both its halves over every view; the ratios are each half's mean and mean square."""
    from ..lightfield import LightField
    from ..refocusing import refocus

    a = np.asarray(a_values, dtype=np.float64)
    shift = a * sweep.view_step / bin_lenses
    n = sweep.y.shape[0]
    halves = half_aperture_weights(n, sweep.weight)
    union = sweep.weight > 0 if sweep.weight is not None else np.ones((n, n), bool)
    y = binned(sweep.y, bin_lenses)
    volumes = []
    for pair in ((0, 1), (2, 3)):
        channels = np.empty(y.shape + (3 * len(pair),), dtype=np.float32)
        for slot, h in enumerate(pair):
            w = halves[h][:, :, None, None]
            channels[..., 3 * slot] = w
            np.multiply(y, w, out=channels[..., 3 * slot + 1])
            np.multiply(channels[..., 3 * slot + 1], y, out=channels[..., 3 * slot + 2])
        stack = refocus(LightField.from_views(channels, view_mask=union), shift, interpolation=interpolation,
                        view_shifts=sweep.slopes)
        del channels
        for slot, h in enumerate(pair):
            share = stack[..., 3 * slot]
            with np.errstate(divide="ignore", invalid="ignore"):
                mean = stack[..., 3 * slot + 1] / share
                mean_sq = stack[..., 3 * slot + 2] / share
            # the half's share of the views there below its share of all views: it lost views off the image
            complete_share = float(halves[h].sum() / union.sum())
            volumes.append(_half_volume(a, mean, mean_sq, share >= HALF_APERTURE_COMPLETE * complete_share,
                                        sweep.view_step))
    return volumes
