"""The depth stage (the estimate behind ``lfproc.depth_map``): metric depth, its bounds and confidence, and an
all-in-focus image from one light field.

Steps (each in its own module):

1. :mod:`._search` — the refocus parameters to visit, from the depth range asked for, narrowed by a
   coarse pass to the range the scene occupies (:func:`occupied_range`);
2. :mod:`._cost` — one fused refocus of the views' luminance and its square gives, per slice, the
   variance across the views behind every lens (correspondence) and the refocused luminance;
3. :mod:`._refine` — the cost averaged over 5 × 5 lenses, its minimum refined between slices, and
   its basin;
4. :mod:`._confidence` — the basin against the slice's DOF, checked by the sharpest-slice (defocus)
   cue; unknown (NaN) where the confidence is below :data:`MIN_CONFIDENCE`;
5. :mod:`._metric` — ``a`` to positions in the camera's object space (mm; a microscope's µm) and bounds;
6. :mod:`._allfocus` — the all-in-focus image.
"""

from __future__ import annotations

import time

import numpy as np

from ..errors import LfprocError
from ._confidence import MIN_CONFIDENCE
from ._result import DepthMap

#: sweeps with more slices than this start with a coarse pass that finds the occupied range
COARSE_PASS_MIN_SLICES = 16

#: confidence of the coarse pass's estimates that counts as a surface found (low: missing a surface costs
#: more than sweeping a little more)
COARSE_PASS_CONFIDENCE = 0.2


def occupied_range(sweep, a_lo, a_hi, step, center_index) -> tuple[float, float]:
    """The part of ``[a_lo, a_hi]`` the scene occupies, from a sweep at twice the step on lenses binned
    2 × 2 (a quarter of the samples, parallax a/2), with linear interpolation (its pull towards integer
    ``a`` is far below the coarse step): from the least to the largest ``a`` estimated with some
    confidence, widened by one coarse step. The fine sweep grows beyond it where surfaces lie at its ends
    (:func:`extended_sweep`). Where nothing is confidently known the whole range is kept."""
    from ._confidence import confidence, cost_floor
    from ._cost import cost_volume
    from ._refine import aggregate, refine_minimum
    from ._search import sweep_parameters

    coarse = sweep_parameters(a_lo, a_hi, 2.0 * step, center_index)
    bin_lenses = 2 if min(sweep.y.shape[2:4]) >= 16 else 1
    volume = cost_volume(sweep, coarse, interpolation="linear", bin_lenses=bin_lenses)
    found = refine_minimum(aggregate(volume.cost), coarse, cost_floor(volume.luminance))
    conf = confidence(found.a, found.a_low, found.a_high, found.a, center_index, resolution=bin_lenses)
    known = found.interior & (conf >= COARSE_PASS_CONFIDENCE)
    if not known.any():
        return a_lo, a_hi
    return (max(a_lo, float(found.a[known].min()) - 2.0 * step),
            min(a_hi, max(float(found.a[known].max()) + 2.0 * step, a_lo)))


#: local contrast of the central view (3 × 3 lenses, relative to the median luminance) below which a half
#: aperture's estimate is not trusted: a textureless lens next to a textured surface would take its depth
HALF_APERTURE_MIN_CONTRAST = 0.03


def central_texture(sweep, bin_lenses: int = 1) -> np.ndarray:
    """Lenses whose own neighbourhood (3 × 3 lenses of the central view) has texture: where a half aperture's
    estimate can describe the surface the lens sees, not one that only some of its views see."""
    from scipy import ndimage

    from ._cost import binned

    n = sweep.y.shape[0]
    y = binned(sweep.y[n // 2:n // 2 + 1, n // 2:n // 2 + 1], bin_lenses)[0, 0].astype(np.float64)
    mean = ndimage.uniform_filter(y, 3, mode="nearest")
    spread = np.sqrt(np.maximum(ndimage.uniform_filter(y * y, 3, mode="nearest") - mean * mean, 0.0))
    return spread >= HALF_APERTURE_MIN_CONTRAST * max(float(np.median(y)), 1e-12)


#: share of the lenses whose cost minimum may sit at an end of the sweep before the sweep grows there
OPEN_END_SHARE = 0.02


def extended_sweep(sweep, volume, full_range, step, center_index, interpolation):
    """The cost volume grown slice by slice beyond an end of the sweep (up to ``full_range``) while more
    than :data:`OPEN_END_SHARE` of the lenses have their least cost within the padding at that end: a
    surface the coarse pass placed too near (or missed) still gets a basin that closes inside the sweep."""
    from ._cost import CostVolume, cost_volume
    from ._refine import aggregate
    from ._search import PADDING_SLICES, dof_half_width_a

    a = volume.a
    textured = central_texture(sweep)
    while True:
        best = np.argmin(aggregate(volume.cost), axis=0)
        grow = []
        for end, sign, limit in ((0, -1, full_range[0]), (len(a) - 1, +1, full_range[1])):
            near_end = ((best <= PADDING_SLICES) if end == 0 else (best >= end - PADDING_SLICES)) & textured
            beyond = sign * (limit - a[end]) > 1e-9
            if beyond and near_end.mean() > OPEN_END_SHARE:
                count = max(PADDING_SLICES, int(np.ceil(float(dof_half_width_a(a[end], center_index)) / step)))
                extra = a[end] + sign * step * np.arange(1, count + 1)
                extra = extra[sign * (limit - extra) >= -1e-9]
                grow.append((sign, np.round(extra, 12)))
        if not grow:
            return volume
        for sign, extra in grow:
            more = cost_volume(sweep, extra, interpolation=interpolation)
            if sign < 0:
                order = slice(None, None, -1)
                volume = CostVolume(np.concatenate([extra[order], volume.a]),
                                    np.concatenate([more.cost[order], volume.cost]),
                                    np.concatenate([more.luminance[order], volume.luminance]), volume.view_step)
            else:
                volume = CostVolume(np.concatenate([volume.a, extra]), np.concatenate([volume.cost, more.cost]),
                                    np.concatenate([volume.luminance, more.luminance]), volume.view_step)
        a = volume.a


def best_of_half_apertures(sweep, a_values, interpolation, volume, minimum, conf, center_index, bin_lenses=1):
    """Per lens, the most confident of the full aperture's estimate and the four half apertures' ones
    (:func:`lfproc.depth._cost.half_aperture_volumes`); returns the chosen :class:`CostMinimum` and confidence."""
    from ._confidence import confidence, cost_floor, defocus_estimate
    from ._cost import half_aperture_volumes
    from ._refine import aggregate_edge_aware, refine_minimum

    floor = cost_floor(volume.luminance)
    textured = central_texture(sweep, bin_lenses)
    best = minimum
    for half in half_aperture_volumes(sweep, a_values, interpolation=interpolation, bin_lenses=bin_lenses):
        cost = half.cost
        finite = np.isfinite(cost)
        if not finite.any():
            continue
        cost = np.where(finite, cost, np.float32(10.0 * float(cost[finite].max()) + 1.0))
        found = refine_minimum(aggregate_edge_aware(cost), a_values, floor)
        usable = found.interior & finite.all(axis=0) & textured
        # the defocus cue only lowers a confidence (agreement ≤ 1; with a_defocus = a_corr it is 1): where the
        # correspondence part alone does not beat the current confidence, the half cannot win: no cue there
        upper = confidence(found.a, found.a_low, found.a_high, found.a, center_index, resolution=bin_lenses)
        lenses = usable & (upper > conf)
        if not lenses.any():
            continue
        lum = np.where(np.isfinite(half.luminance), half.luminance, volume.luminance)
        conf_half = confidence(found.a, found.a_low, found.a_high, defocus_estimate(lum, a_values, lenses),
                               center_index, resolution=bin_lenses)
        conf_half = np.where(lenses, conf_half, np.float32(0.0))
        take = conf_half > conf
        if take.any():
            best = found.where(take, best)
            conf = np.where(take, conf_half, conf)
    return best, conf


def depth(lf, *, depth_range_mm=None, a_range=None, step=None, view_step=None, camera=None,
          min_confidence: float = MIN_CONFIDENCE, interpolation: str = "cubic", outer_views: bool = False,
          coarse_pass: bool = True, half_apertures: bool = True) -> DepthMap:
    """Metric depth map of a light field (module docstring for the method).

    Parameters
    ----------
    lf : LightField
        Decoded light field with its camera (or pass ``camera``).
    depth_range_mm : (near, far), optional
        Search only these distances from the sensor (``far`` may be ``inf``): fewer slices, and no
        surface outside them can be mistaken for one inside.
    a_range : (low, high), optional
        Search these refocus parameters instead (default: from the slice at infinity to 3 nearer).
    step : float, optional
        Sweep step in ``a`` (default about 1/(2c), half the DOF at a = 0).
    view_step : int, optional
        Use every ``view_step``-th view around the central one for the sweep (default: 1 for light
        fields up to 20 M view samples, more above; the baseline stays the same).
    coarse_pass : bool
        With more than :data:`COARSE_PASS_MIN_SLICES` slices to visit, first find the part of the
        range the scene occupies with a cheap sweep (twice the step, lenses binned 2 × 2, linear
        interpolation: under a tenth of the fine sweep's work) and sweep finely only there (default).
        A surface the coarse pass misses comes out unknown.
    outer_views : bool
        Also use the outer ring of views (default: not). Their samples lie on the border of the
        micro image, where decoding mixes in the neighbouring micro image (crosstalk): on decoded
        captures they pull the estimate about 7 % of the DOF farther (docs/depth.md).
    half_apertures : bool
        Where the estimate from all views is not confident, also estimate from each half of the
        aperture (the views on one side of the centre) and keep the most confident: lenses near the
        image border, whose outer views shift off the image, and surfaces next to a nearer occluder,
        which some views see instead, get a depth from the views that see them (default; about twice
        the sweep's work).
    camera : Camera, optional
        Overrides ``lf.camera``.
    min_confidence : float
        Estimates less confident than this are NaN.
    interpolation : {"linear", "cubic"}
        Between-lens interpolation of the sweep and the all-in-focus image (cubic: less pull towards
        integer ``a``).

    Returns
    -------
    DepthMap

    Raises
    ------
    LfprocError
        No camera, micro images below 3 px, a bad range or step.
    """
    from .. import geometry
    from ._allfocus import allfocus
    from ._confidence import confidence, cost_floor, defocus_estimate, lit_lenses, view_coverage
    from ._cost import auto_view_step, cost_volume, delivered_views, sweep_luminance
    from ._metric import metric_depth
    from ._refine import aggregate_edge_aware, refine_minimum
    from ._search import default_step, search_range_a, sweep_parameters

    views = np.asarray(getattr(lf, "views", lf))
    camera = camera if camera is not None else getattr(lf, "camera", None)
    if camera is None:
        raise LfprocError("depth needs the light field's camera (distances come from its geometry); "
                          "pass `camera=`, or a LightField that carries it")
    if views.ndim != 5 or views.shape[0] != views.shape[1] or views.shape[0] % 2 == 0:
        raise LfprocError(f"depth needs views shaped (m, m, Ny, Nx, C) with m odd, got {views.shape}")
    m, _, ny, nx, _ = views.shape
    c = (m - 1) // 2
    if c < 1:
        raise LfprocError("depth needs micro images of 3 px or more (micro_image_px >= 3)")
    if not 0.0 <= min_confidence <= 1.0:
        raise LfprocError(f"min_confidence must be in [0, 1], got {min_confidence}")
    timings = {}
    t0 = time.perf_counter()
    a_lo, a_hi = search_range_a(camera, depth_range_mm, a_range)
    step = default_step(c) if step is None else float(step)
    a_values = sweep_parameters(a_lo, a_hi, step, c)
    full_range = a_values[0], a_values[-1]
    reach = c if outer_views or c < 2 else c - 1
    view_step = auto_view_step(reach, ny * nx) if view_step is None else int(view_step)
    if not 1 <= view_step <= reach:
        raise LfprocError(f"view_step must be an integer from 1 to {reach}, got {view_step}")
    mask = getattr(lf, "view_mask", None)
    weight = delivered_views(views) if mask is None else np.array(mask, dtype=bool)
    if camera.main_optics.image_aperture_sine is not None:   # the optics' aperture: a lens's f-number, an NA
        weight &= geometry.views_inside_aperture(camera)
    if not weight[c, c]:
        raise LfprocError("the central view of this light field is dark (0 everywhere): nothing to estimate "
                          "depth from; check the capture and the white image")
    timings["plan"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    # optics that refocus by the sine condition sweep with the same per-view shifts (exact z); None: a·(c − k)
    slopes = geometry.refocus_slopes(camera, centre=getattr(lf, "view_centre", None))
    sweep = sweep_luminance(views, view_step, reach, weight, slopes)
    timings["luminance of the views"] = time.perf_counter() - t0

    if coarse_pass and len(a_values) > COARSE_PASS_MIN_SLICES:
        t0 = time.perf_counter()
        a_lo, a_hi = occupied_range(sweep, a_lo, a_hi, step, c)
        a_values = sweep_parameters(a_lo, a_hi, step)
        timings["coarse pass (occupied range)"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    volume = cost_volume(sweep, a_values, interpolation=interpolation)
    if coarse_pass:   # what the coarse pass cut off but the scene has: surfaces whose minimum sits at an end
        volume = extended_sweep(sweep, volume, full_range, step, c, interpolation)
        a_values = volume.a
    timings["cost volume (fused refocus)"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    minimum = refine_minimum(aggregate_edge_aware(volume.cost), a_values, cost_floor(volume.luminance))
    timings["aggregation and sub-slice minimum"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    a_defocus = defocus_estimate(volume.luminance, a_values)
    conf = confidence(minimum.a, minimum.a_low, minimum.a_high, a_defocus, c,
                      coverage=view_coverage(minimum.a, reach, view_step))
    conf = np.where(minimum.interior, conf, np.float32(0.0))
    timings["confidence (defocus cue)"] = time.perf_counter() - t0

    if half_apertures and (conf < min_confidence).any():
        t0 = time.perf_counter()
        minimum, conf = best_of_half_apertures(sweep, a_values, interpolation, volume, minimum, conf, c)
        timings["half apertures (borders, occlusions)"] = time.perf_counter() - t0
    lit = lit_lenses(views, weight)
    conf = np.where(lit, conf, np.float32(0.0))   # no depth where no light fell
    known = conf >= min_confidence
    a_known = np.where(known, minimum.a, np.nan)

    t0 = time.perf_counter()
    offsets = np.abs(np.arange(weight.shape[0]) - c)
    summed = weight & (offsets[:, None] <= reach) & (offsets[None, :] <= reach)
    summed &= (offsets[:, None] % view_step == 0) & (offsets[None, :] % view_step == 0)
    extent = geometry.summed_view_extent(summed)   # the DOF of the views the sweep sums
    metric = metric_depth(camera, a_known, minimum.a_low, minimum.a_high, extent)
    timings["metric distance"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    sharp = allfocus(views, minimum.a, c, interpolation, slopes, view_mask=weight)
    timings["all-in-focus"] = time.perf_counter() - t0

    f32 = lambda x: np.asarray(x, dtype=np.float32)
    # virtual cameras on a lens have an equivalent f-number; orthographic views (an objective's) an NA instead
    positional = not geometry.place_views(camera, [0]).orthographic
    return DepthMap(depth=f32(metric.depth), confidence=f32(conf), near=f32(metric.near), far=f32(metric.far),
                    a=f32(a_known), allfocus=sharp, a_searched=a_values, view_step=view_step, view_reach=reach,
                    timings_s=timings, space=metric.space, lit=lit, min_confidence=float(min_confidence),
                    aperture_f_number=geometry.equivalent_f_number(camera, geometry.summed_view_extent(mask))
                    if mask is not None and positional else None)
