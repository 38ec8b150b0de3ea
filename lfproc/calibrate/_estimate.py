"""The public estimate: a white image in, the fitted `LensGrid` (and the evidence behind it) out.

Steps (each a module of this package): 1 monochrome (`_monochrome`), 2 lattice guess from the
autocorrelation of a central crop (`_lattice_guess`), 3–4 flattening, candidates and sub-pixel
point-symmetry centres in windows (`_measure`), 5 indexing and the lattice fit (`_assign`, `_lattice`,
`_smooth_fit`): rigid by default; a smooth non-rigid lattice where the rigid one leaves residuals a
smooth deviation removes. Then the listed lenses (`_grid_extent`) and the plausibility checks
(`_checks`) whose findings become one-line warnings.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import LfprocError
from ..grid import ROW_SPACING, LensGrid
from ._assign import NoLattice, assign_and_fit
from ._checks import trust_warning, white_texture
from ._grid_extent import grid_from_fit, lattice_indices_on_sensor
from ._lattice import LatticeModel, neighbour_lattice, robust_fit
from ._lattice_guess import central_crop, lattice_guess_from_autocorrelation
from ._measure import measure_window, plan_windows
from ._monochrome import check_white
from ._smooth_fit import MIN_DEGREE, best_smooth_fit, cross_validated_rms, rms, robust_smooth_fit

#: fewest well-measured lenses a lattice fit accepts
MIN_LENSES = 6
#: relative difference between the fitted pitch and the camera file's pitch that is an error
PITCH_TOLERANCE = 0.05
#: a rigid lattice whose inlier RMS exceeds this (px), or that rejects over 5 % of the centres, is
#: compared with a smooth one
RIGID_SUSPECT_RMS_PX = 0.03


@dataclass(frozen=True)
class GridEstimate:
    """The fitted lattice plus the measurements behind it (for plots and diagnostics).

    Attributes
    ----------
    grid : LensGrid
        The fitted lattice; ``grid.residual_rms_px`` is the RMS distance of the inlier centres from it,
        ``grid.model`` says ``"rigid"`` or ``"smooth"``.
    centers_xy_px : ndarray, shape (N, 2)
        Every micro image centre measured to sub-pixel accuracy (x, y), inliers and rejected ones.
    inlier : ndarray of bool, shape (N,)
        Centres used in the final least-squares fit.
    asymmetry : ndarray, shape (N,)
        Remaining point asymmetry of each micro image (0 = perfectly symmetric, ``inf`` = not measured).
    pitch_sigma_px : float
        Standard error of the fitted (rigid) pitch, from the residuals.
    texture : float
        The texture ratio (`_checks.white_texture`): how much the micro images differ from their
        neighbours, near 0 for a white image, near 1 for a capture of a textured scene. Judged (refused or
        warned about) by `lfproc.inputs.check_white_is_white`, not here.
    warnings : tuple of str
        One-line warnings (an untrustworthy residual), each naming the image.
    """

    grid: LensGrid
    centers_xy_px: np.ndarray
    inlier: np.ndarray
    asymmetry: np.ndarray
    pitch_sigma_px: float = 0.0
    texture: float = 0.0
    warnings: tuple = ()


def estimate_grid(white, kind: str | None = None, approx_pitch_px: float | None = None, *,
                  smoothing: float = 0.08, cfa: str = "none", source: str = "white image") -> LensGrid:
    """Fit the micro lens lattice to a white image.

    Parameters
    ----------
    white : array_like
        The white image: 2-D (H, W) or channels-last (H, W, C), float or integer (e.g. uint16), linear.
        A black level that was not subtracted is removed with the floor between the micro images.
    kind : {"rectangular", "hexagonal"} or None
        The lattice kind of the camera file (``mla.grid``); ``None`` detects it (4 or 6 nearest neighbours).
    approx_pitch_px : float or None
        The pitch the camera file predicts (`Camera.pitch_px`); the fitted pitch must lie within 5 % of it.
    smoothing : float
        Gaussian smoothing before the sub-pixel centring, as a fraction of the pitch (at least 0.7 px).
    cfa : str
        ``"none"`` or a Bayer pattern (``"RGGB"`` …): a 2-D mosaic is low-passed first.
    source : str
        Name of the image in error messages and warnings.

    Returns
    -------
    LensGrid
        Rigid, or rigid plus a smooth deviation (``grid.model``). Lens (0, 0) is the first lens of the
        top row; ``rows × cols`` is the smallest index rectangle holding every lattice position whose
        cell lies on the sensor, less edge rows and columns with centres off the sensor.

    Raises
    ------
    LfprocError
        No lattice in the image (flat, black or noise), too few lenses, or a lattice kind or pitch that
        does not match the camera file.
    """
    return find_grid(white, kind, approx_pitch_px, smoothing=smoothing, cfa=cfa, source=source).grid


def find_grid(white, kind: str | None = None, approx_pitch_px: float | None = None, *,
              smoothing: float = 0.08, cfa: str = "none", source: str = "white image") -> GridEstimate:
    """Like :func:`estimate_grid`, but also return the measured centres, inliers, asymmetries and warnings."""
    if kind is not None and kind not in ROW_SPACING:
        raise LfprocError(f"unknown grid kind {kind!r}; use rectangular or hexagonal")
    if approx_pitch_px is not None and not (math.isfinite(approx_pitch_px) and approx_pitch_px > 0):
        raise LfprocError(f"approximate pitch must be a positive number of pixels, got {approx_pitch_px!r}")
    if not (math.isfinite(smoothing) and smoothing >= 0):
        raise LfprocError(f"smoothing must be a non-negative fraction of the pitch, got {smoothing!r}")
    arr = check_white(white, source)
    cfa = cfa if arr.ndim == 2 else "none"
    guess = lattice_guess_from_autocorrelation(central_crop(arr, cfa))
    if guess is None and approx_pitch_px is None:
        raise LfprocError(_no_grid(source))
    pitch0 = guess[0] if guess is not None else float(approx_pitch_px)
    return _fit_at_pitch(arr, cfa, pitch0, kind, approx_pitch_px, smoothing, source, retry=True)


def _no_grid(source: str) -> str:
    return (f"{source}: no micro lens grid found (the image is flat, black or noise); use a white image, "
            f"a capture of a uniform bright surface through the camera")


def _fit_at_pitch(arr, cfa, pitch0, kind, approx_pitch_px, smoothing, source, retry) -> GridEstimate:
    shape = arr.shape[:2]
    measured = [measure_window(arr, cfa, window, pitch0, smoothing, shape)
                for window in plan_windows(shape, pitch0, kind)]
    xy = np.concatenate([m.xy for m in measured])
    asym = np.concatenate([m.asymmetry for m in measured])
    if len(xy) < MIN_LENSES:
        raise LfprocError(_no_grid(source))
    xy, asym = _merge_duplicates(xy, asym, 0.3 * pitch0)
    usable = np.isfinite(asym) & (asym <= _asymmetry_limit(asym))
    neighbours = neighbour_lattice(xy[usable])
    if neighbours is None:
        raise LfprocError(_no_grid(source))
    seen_kind, pitch1, rotation1, support = neighbours
    if retry and abs(pitch1 - pitch0) > 0.1 * pitch0:
        return _fit_at_pitch(arr, cfa, pitch1, kind, approx_pitch_px, smoothing, source, retry=False)
    if kind is not None and seen_kind != kind and support >= 2 * MIN_LENSES:
        raise LfprocError(f"{source}: the camera file says mla.grid = {kind!r} but the white image shows a "
                          f"{seen_kind} lattice; set mla.grid = \"{seen_kind}\" in the camera file")
    fit_kind = kind or seen_kind
    h, w = shape
    center, half = ((w - 1) / 2.0, (h - 1) / 2.0), (w / 2.0, h / 2.0)
    try:
        _, index, st, indexed = assign_and_fit(xy, usable, fit_kind, pitch1, rotation1, center, half)
    except NoLattice:
        raise LfprocError(_no_grid(source)) from None
    clean = indexed & (asym <= _clean_limit(asym[indexed]))
    if clean.sum() < max(MIN_LENSES, 0.3 * indexed.sum()):
        clean = indexed
    model, inlier, residual = _choose_model(xy, st, indexed, clean, center, half)
    if inlier.sum() < MIN_LENSES or len(np.unique(index[inlier, 0])) < 2 or len(np.unique(index[inlier, 1])) < 2:
        raise LfprocError(f"{source}: only {int(inlier.sum())} micro lenses could be measured and a grid fit "
                          f"needs {MIN_LENSES} in 2 rows and columns; use a larger or brighter white image")
    pitch = model.rigid.pitch
    if residual > 0.1 * pitch:
        raise LfprocError(_no_grid(source))
    if approx_pitch_px is not None and abs(pitch - approx_pitch_px) > PITCH_TOLERANCE * approx_pitch_px:
        raise LfprocError(f"{source}: the camera file's micro lens pitch ({approx_pitch_px:.3f} px = mla.pitch_mm "
                          f"/ sensor.pixel_pitch_mm) does not match the white image ({pitch:.3f} px); "
                          f"check both pitches in the camera file, or the white image")
    grid = grid_from_fit(fit_kind, model, lattice_indices_on_sensor(fit_kind, model, shape), shape, residual)
    texture = white_texture(arr, cfa, grid)
    warnings = tuple(w for w in (trust_warning(source, residual, pitch, int(inlier.sum()), int(indexed.sum())),) if w)
    return GridEstimate(grid=grid, centers_xy_px=xy, inlier=inlier, asymmetry=asym,
                        pitch_sigma_px=_pitch_sigma(model, xy, st, inlier, residual), texture=texture,
                        warnings=warnings)


def _choose_model(xy, st, indexed, clean, center, half) -> tuple[LatticeModel, np.ndarray, float]:
    """The rigid lattice where it fits; a smooth one where that predicts the centres clearly better.

    The rigid fit (robust, over all ``indexed`` centres) is suspect when its inlier RMS exceeds
    `RIGID_SUSPECT_RMS_PX` or it rejects over 5 % of them. Then the decision is taken on the ``clean``
    centres only (`_clean_limit`): smooth fits are scored against the rigid one by cross-validation
    (`_smooth_fit`), and a smooth one wins if its score is below 0.8 times the rigid one's; it is then
    refitted over all indexed centres.
    """
    rigid, inlier = robust_fit(xy, st, indexed)
    rigid_model = LatticeModel(rigid)
    residual = rms(rigid_model, xy, st, inlier)
    if residual <= RIGID_SUSPECT_RMS_PX and inlier.sum() >= 0.95 * indexed.sum():
        return rigid_model, inlier, residual
    # score the rigid lattice on the centres a smooth fit would keep (its own inliers drop the drift)
    loose, _ = robust_smooth_fit(xy, st, clean, MIN_DEGREE, center, half)
    residual_loose = np.hypot(*(xy - loose.xy(st)).T)
    kept = clean & (residual_loose <= max(4.0 * float(np.median(residual_loose[clean])) / 1.1774, 0.01))
    smooth = best_smooth_fit(xy, st, kept, center, half, cross_validated_rms(xy, st, kept, 0, center, half))
    if smooth is None:
        return rigid_model, inlier, residual
    model, inlier = robust_smooth_fit(xy, st, indexed, smooth[0].deviation.degree, center, half)
    if inlier.sum() < MIN_LENSES:
        return rigid_model, robust_fit(xy, st, indexed)[1], residual
    return model, inlier, rms(model, xy, st, inlier)


def _pitch_sigma(model: LatticeModel, xy, st, inlier, residual) -> float:
    """Uncertainty of the pitch: the larger of its standard error (residual per axis over the spread of the
    inliers' lattice coordinates) and how much it differs between halves of the sensor (`_half_pitches`: a
    lens array's pitch varies over the sensor by more than a fit of thousands of centres resolves, and a
    nominal pitch is the pitch somewhere, not the average)."""
    spread = float(np.sum((st[inlier] - st[inlier].mean(0)) ** 2))
    if not spread > 0:
        return math.inf
    statistical = (residual / math.sqrt(2.0)) / math.sqrt(spread)
    halves = _half_pitches(xy, st, inlier)
    return max(statistical, float(np.std(halves, ddof=1)) if len(halves) >= 2 else 0.0)


def _half_pitches(xy, st, inlier) -> list:
    """Rigid pitches fitted to the left, right, top and bottom halves of the inlier centres (halves of fewer
    than `MIN_LENSES` centres, or of a single row or column, left out)."""
    from ._lattice import fit_similarity

    pitches = []
    for axis in (0, 1):
        middle = float(np.median(xy[inlier, axis]))
        for half in (xy[:, axis] < middle, xy[:, axis] >= middle):
            use = inlier & half
            if use.sum() >= MIN_LENSES and np.ptp(st[use, 0]) > 0 and np.ptp(st[use, 1]) > 0:
                pitches.append(fit_similarity(xy[use], st[use]).pitch)
    return pitches


def _asymmetry_limit(values: np.ndarray) -> float:
    """Asymmetry above which a micro image is not used.

    Four times the lower quartile (the cleanly symmetric micro images set the scale, so micro images cut
    by the main lens's rim in vignetted corners, whose centres drift outwards, are left out), but
    never below the median (half the lenses are always used) nor below 1e-4.
    """
    values = values[np.isfinite(values)]
    if values.size == 0:
        return 0.0
    low, med = np.percentile(values, [25, 50])
    return max(4.0 * float(low), float(med), 1e-4)


def _clean_limit(values: np.ndarray) -> float:
    """Asymmetry up to which a micro image takes part in the lattice fit: 2.5 times the lower quartile.

    Micro images cut by the main lens's rim (vignetted corners) are measured off-centre, outwards, by
    amounts a smooth deviation could follow; their asymmetry gives them away, so the fits use only the
    cleanly symmetric ones (at least 30 % of the indexed lenses, else all of them).
    """
    values = values[np.isfinite(values)]
    if values.size == 0:
        return 0.0
    return max(2.5 * float(np.percentile(values, 25)), 1e-4)


def _merge_duplicates(xy: np.ndarray, asym: np.ndarray, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """Of centres that converged within ``radius`` of each other keep the most symmetric."""
    from scipy.spatial import cKDTree
    order = np.argsort(asym, kind="stable")
    xy, asym = xy[order], asym[order]
    pairs = cKDTree(xy).query_pairs(radius, output_type="ndarray")
    keep = np.ones(len(xy), bool)
    if len(pairs):
        keep[np.max(pairs, axis=1)] = False  # sorted by asymmetry: the later one of a pair goes
    return xy[keep], asym[keep]
