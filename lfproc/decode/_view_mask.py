"""Which views carry light, and where to read them so that each sample stands for its own ray.

A decoded sample is ``K·capture / K·white`` for the sampling kernel K of that sample (the sensor pixel,
the demosaicing and the interpolation together, all linear for ``"fast"`` demosaicing). As a function
of the ray direction it reads, its *white-weighted centroid* is ``K·(white·x) / K·white``. The geometry
(and refocusing) assume that centroid is the view's nominal position, the lens centre plus
(k − c)·pitch/m̂. Where K reaches past the edge of the lens's lit micro image that fails: dark pixels
(outside the main lens aperture, the gaps between micro images) weigh nothing after the division, so
the centroid moves *inwards*, the view's parallax is compressed and a refocus sweep peaks at a lower
a (issue 13). Lit pixels of the neighbouring micro image (crosstalk) are kept out by reading every
lens from its own cell (:mod:`._cells`).

This probe works on the white image alone, at up to :data:`PROBED_LENSES` lenses away from the sensor
border (their patches side by side, so that one ``remap`` reads them all), by reading the white image
and the white image times each pixel's offset from the lens centre with the decoder's own kernel (own
cell, demosaicing, interpolation); the kernel's own centroid (a flat image read the same way) is taken
off, so that nearest-neighbour reading is not counted against the white image:

1. **The lit disc.** Its centre off the grid's lens centres is fitted to its edge, per Bayer phase
   on the phase's own pixels (:mod:`._disc_centre`: unbiased by channel gains and by cells that cut
   the disc), :attr:`ViewSampling.centre_offset_px`. Where it is off by more than
   :data:`CENTRE_TOLERANCE` effective pixels (and three standard errors), every view is read around
   it (:data:`CENTRE_DECODING`): the delivered set is centred on the disc, not on the lens centre.
2. **Views inside it.** View k is lit at a lens where its white sample at the nominal position is at
   least :data:`LIT_FRACTION` of the central view's (channel mean). The edge of a blurred disc reads
   half its interior, so this keeps the views whose ray passes through the aperture (or the
   objective's NA), and never one that reads the dark gaps between micro images, however much the
   division by the white image would amplify them.
3. **Where to read them.** A view whose centroid is right at nominal (within ``tolerance`` at
   :data:`REQUIRED_FRACTION` of the lenses it is lit on) is read there. Any other view is moved off
   nominal until the white-weighted centroid of its samples, averaged over the probed lenses on which
   they read light in every channel, is the nominal position (:data:`ITERATIONS` fixed-point steps, at
   most :data:`MAX_SHIFT` effective pixels; a larger move over-corrected the renders, +0.011 in a). A
   pixel the rim of the micro image crosses counts at the centre of its lit part
   (:func:`_lit_part_offsets`): without that the outer ring stayed compressed (−0.03…−0.07 in a).

A view is delivered where it is lit at :data:`REQUIRED_FRACTION` of the probed lenses and its
(corrected) centroid is right; the set is made symmetric (a view and its mirror images both or
neither), so slices stay evenly bright, and :func:`carrying_views` drops views whose samples carry no
signal on most lenses after all. Everything is a pure function of (white, grid, m̂, CFA, settings).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..grid import LensGrid
from ._cells import cell_classes, cell_shares, class_weight, lens_class
from ._demosaic import to_channels
from ._disc_centre import measure_disc_centre
from ._positions import view_offsets_px
from ._resample import cv_flag

#: the most lenses probed (spread over the central 60 % of the grid)
PROBED_LENSES = 400
#: fewer probed lenses than this (a grid of a few lenses) decide only which views are lit at all, at nominal
MIN_PROBED = 4
#: a view is delivered where it is lit (and right) at this fraction of the probed lenses
REQUIRED_FRACTION = 0.9
#: a view is lit at a lens where its white reaches this fraction of the central view's (channel mean)
LIT_FRACTION = 0.4
#: the lit disc is decoded centred when its centre is further than this (effective pixels) off the grid's
CENTRE_TOLERANCE = 0.1
#: decode around a measured off-centre disc (its centre fitted to its edge, :mod:`._disc_centre`)
CENTRE_DECODING = True
#: the furthest (effective pixels) a view's samples are moved off their nominal position
MAX_SHIFT = 0.75
#: a view moved this share of MAX_SHIFT or further counts as not found
CONVERGED_SHARE = 0.98
#: fixed-point steps of the centroid correction
ITERATIONS = 10


@dataclass(frozen=True)
class ViewSampling:
    """What the white image says about the views (see the module docstring).

    ``delivered`` (m̂, m̂) bool; ``shift_px`` (m̂, m̂, 2) sensor px (x, y) each view's samples are read off
    nominal (the disc centre's offset included); ``centre_offset_px`` (x, y) the lit disc's centre off the
    grid's lens centres as measured; ``centred`` whether the views are read around it; ``residual`` (m̂, m̂)
    the remaining mean centroid error (effective pixels); ``lit`` (m̂, m̂) the share of probed lenses on
    which each view is lit.
    """

    delivered: np.ndarray
    shift_px: np.ndarray
    centre_offset_px: tuple
    centred: bool
    residual: np.ndarray
    lit: np.ndarray


def central_range(n: int) -> tuple[int, int]:
    """``(lo, hi)``: the central 60 % of ``n`` lens rows or columns (all of them below 10)."""
    return (int(0.2 * n), int(math.ceil(0.8 * n))) if n >= 10 else (0, n)


def probe_lenses(grid: LensGrid, count: int = PROBED_LENSES) -> list[tuple[int, int]]:
    """Up to ``count`` lens indices spread over the central 60 % of the grid (whole grid if it is small)."""
    def spread(n):
        lo, hi = central_range(n)
        per_axis = max(1, int(math.sqrt(count)))
        return sorted({int(v) for v in np.linspace(lo, hi - 1, min(per_axis, hi - lo))})
    return [(r, q) for r in spread(grid.rows) for q in spread(grid.cols)]


@dataclass(frozen=True)
class _Probe:
    """The probed lenses' patches side by side: ``tiles`` is a list of contiguous ``(L·S, S, ≤4)`` float32
    images holding, per lens, the demosaiced white, its first moments, and those of a flat image
    (channels ``6C`` in all); ``origin`` ``(L, 2)`` the lens centres in tile coordinates."""

    tiles: list
    origin: np.ndarray
    channels: int


def _planes(white, grid, cfa, demosaic_method, lenses, own_cells, soft=False) -> _Probe | None:
    """The :class:`_Probe` of ``lenses`` (those whose patch lies on the sensor)."""
    h, w = white.shape[:2]
    half = int(math.ceil(grid.pitch_px)) + 6
    size = 2 * half + 2
    tiles, origin = [], []
    for r, q in lenses:
        cx, cy = (float(v) for v in grid.lens_xy(r, q))
        x0, y0 = int(math.floor(cx)) - half & ~1, int(math.floor(cy)) - half & ~1   # even: the CFA phase stays
        xs, ys = max(0, x0), max(0, y0)
        xe, ye = min(w, x0 + size), min(h, y0 + size)
        if xe <= xs or ye <= ys:
            continue
        patch = np.zeros((size, size) + white.shape[2:], dtype=np.float64)    # black beyond the sensor
        patch[ys - y0:ye - y0, xs - x0:xe - x0] = white[ys:ye, xs:xe]
        yy, xx = np.mgrid[y0:y0 + size, x0:x0 + size].astype(np.float64)
        dx, dy = xx - cx, yy - cy
        if own_cells and soft:
            classes = cell_classes(grid, patch.shape, y0, x0)
            own = (class_weight(classes, *cell_shares(grid, patch.shape, y0, x0, classes), lens_class(r, q))
                   * (np.hypot(dx, dy) < 1.5 * grid.pitch_px))
            patch = patch * (own[..., None] if patch.ndim == 3 else own)
        elif own_cells:
            own = ((cell_classes(grid, patch.shape, y0, x0) == lens_class(r, q))
                   & (np.hypot(dx, dy) < 1.5 * grid.pitch_px))
            patch = patch * (own[..., None] if patch.ndim == 3 else own)
        if patch.ndim == 3:
            dx, dy = dx[..., None], dy[..., None]
        rx, ry = _lit_part_offsets(patch, dx, dy, cfa)      # where each pixel's lit rays are
        ones = np.ones_like(patch)
        # the white, its first moments, and the same of a flat image (the kernel's own centroid)
        planes = [to_channels(p.astype(np.float32), cfa, demosaic_method)
                  for p in (patch, patch * rx, patch * ry, ones, ones * dx, ones * dy)]
        tiles.append(np.concatenate(planes, axis=-1))
        origin.append((cx - x0, cy - y0 + len(origin) * size))
    if not tiles:
        return None
    stack = np.concatenate(tiles, axis=0)
    groups = [np.ascontiguousarray(stack[..., c0:c0 + 4]) for c0 in range(0, stack.shape[2], 4)]
    return _Probe(groups, np.array(origin), stack.shape[2] // 6)


def _lit_part_offsets(patch, dx, dy, cfa):
    """Where each pixel's lit rays are, from the lens centre: a pixel the rim of the micro image crosses is
    lit over its inner part only (lit fraction f of the full level), so its rays sit (1 − f)/2 px inwards
    of its centre along the radius. The full level is the median of the well lit pixels (above half the
    brightest) of the same Bayer phase (mono: of the patch), so that the gentle fall-off of the interior
    does not count as a rim."""
    frac = np.zeros_like(patch)
    phases = [(slice(py, None, 2), slice(px, None, 2)) for py in (0, 1) for px in (0, 1)] if (
        cfa != "none" and patch.ndim == 2) else [(slice(None), slice(None))]
    for sy, sx in phases:
        sub = patch[sy, sx]
        top = float(sub.max()) if sub.size else 0.0
        lit = sub[sub > 0.5 * top]
        ref = float(np.median(lit)) if lit.size else 0.0
        frac[sy, sx] = np.clip(sub / ref, 0.0, 1.0) if ref > 0 else 0.0
    rho = np.maximum(np.hypot(dx, dy), 1e-9)
    pull = 0.5 * (1.0 - frac)
    return dx - pull * dx / rho, dy - pull * dy / rho


def _centroids(probe: _Probe, off_x, off_y, flag):
    """Per lens: white level ``(L, m̂, m̂, C)`` and the white-weighted centroid (x, y) of the samples, all
    channels together, from the lens centre, less the kernel's own centroid plus the sample position
    (``(L, m̂, m̂)`` each; NaN where the white reads 0): a kernel that reads the sensor off the sample
    position (nearest neighbour) is not a fault of the white image."""
    import cv2

    n, m = probe.origin.shape[0], off_x.shape[0]
    map_x = (probe.origin[:, 0, None, None] + off_x[None]).astype(np.float32).reshape(n * m, m)
    map_y = (probe.origin[:, 1, None, None] + off_y[None]).astype(np.float32).reshape(n * m, m)
    got = np.concatenate([cv2.remap(t, map_x, map_y, flag, borderMode=cv2.BORDER_CONSTANT,
                                    borderValue=0).reshape(n, m, m, -1) for t in probe.tiles],
                         axis=-1).astype(np.float64)
    c = probe.channels
    lvl, total, flat = got[..., :c], got[..., :c].sum(axis=-1), got[..., 3 * c:4 * c].sum(axis=-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        own_x = got[..., 4 * c:5 * c].sum(axis=-1) / flat - off_x
        own_y = got[..., 5 * c:].sum(axis=-1) / flat - off_y
        gx = np.where(total > 0, got[..., c:2 * c].sum(axis=-1) / total - own_x, np.nan)
        gy = np.where(total > 0, got[..., 2 * c:3 * c].sum(axis=-1) / total - own_y, np.nan)
    return lvl, gx, gy


def _mean_error(planes, nom_x, nom_y, tx, ty, shift, lit, flag):
    """Mean centroid error (x, y) over the lenses where each view is lit, ``(m̂, m̂)`` each (px), and the
    share of those lenses on which the samples read light in every channel (the mean is over them)."""
    level, gx, gy = _centroids(planes, nom_x + shift[..., 0], nom_y + shift[..., 1], flag)
    ex, ey = gx - tx, gy - ty
    use = lit & np.isfinite(ex) & np.isfinite(ey) & (level.min(axis=-1) > 0)
    n = use.sum(axis=0)
    mean_x = np.where(n > 0, np.where(use, ex, 0.0).sum(axis=0) / np.maximum(n, 1), np.inf)
    mean_y = np.where(n > 0, np.where(use, ey, 0.0).sum(axis=0) / np.maximum(n, 1), np.inf)
    return mean_x, mean_y, n / np.maximum(lit.sum(axis=0), 1)


def _corrected(planes, nom_x, nom_y, tx, ty, shift, lit, flag, eff):
    """Per-view shifts moving the mean white-weighted centroid onto nominal, and the residual (eff. px)."""
    m_hat = nom_x.shape[0]
    base = shift.copy()
    best, best_err = shift.copy(), np.full((m_hat, m_hat), np.inf)
    for i in range(ITERATIONS + 1):
        ex, ey, covered = _mean_error(planes, nom_x, nom_y, tx, ty, shift, lit, flag)
        err = np.hypot(ex, ey)
        better = (err < best_err) & (covered >= REQUIRED_FRACTION)
        best[better], best_err[better] = shift[better], err[better]
        if i == ITERATIONS:
            break
        step = np.stack([np.nan_to_num(ex, posinf=0.0), np.nan_to_num(ey, posinf=0.0)], axis=-1)
        shift = shift - step
        away = np.hypot(*np.moveaxis(shift - base, -1, 0))
        shift = base + (shift - base) * np.minimum(1.0, MAX_SHIFT * eff / np.maximum(away, 1e-12))[..., None]
    return best, best_err / eff


def symmetric(views: np.ndarray) -> np.ndarray:
    """``views`` where the view and its mirror images (about either axis and the centre) all are."""
    return views & views[::-1] & views[:, ::-1] & views[::-1, ::-1]


def view_sampling(white: np.ndarray, grid: LensGrid, m_hat: int, cfa: str, demosaic_method: str,
                  interpolation: str, tolerance: float, lenses=None, probe_white=None) -> ViewSampling:
    """Delivered views and where to read them (see the module docstring); ``tolerance`` in effective pixels.

    ``probe_white``: the white that the samples' kernel weighs (rim-aware Bayer decoding reads every
    channel like a mono sensor, weighted by the phase-balanced white); the lit disc is fitted on ``white``."""
    flag = cv_flag(interpolation)
    eff = grid.pitch_px / m_hat
    c = (m_hat - 1) // 2
    probe_cfa = cfa if probe_white is None else "none"
    planes = _planes(white if probe_white is None else probe_white, grid, probe_cfa, demosaic_method,
                     probe_lenses(grid) if lenses is None else lenses, True, soft=probe_white is not None)
    nom_x, nom_y = view_offsets_px(grid, m_hat)
    if planes is None:
        return ViewSampling(np.ones((m_hat, m_hat), bool), np.zeros((m_hat, m_hat, 2)), (0.0, 0.0), False,
                            np.zeros((m_hat, m_hat)), np.ones((m_hat, m_hat)))
    if planes.origin.shape[0] < MIN_PROBED:      # too few lenses to tell a micro image from noise
        level, _, _ = _centroids(planes, nom_x, nom_y, flag)
        lit = np.all(level.min(axis=-1) > 0, axis=0)
        lit[c, c] = True
        centre = measure_disc_centre(white, grid, cfa, probe_lenses(grid) if lenses is None else lenses).offset_px
        return ViewSampling(symmetric(lit), np.zeros((m_hat, m_hat, 2)), centre, False,
                            np.zeros((m_hat, m_hat)), lit.astype(float))
    disc = measure_disc_centre(white, grid, cfa, probe_lenses(grid) if lenses is None else lenses)
    centre = disc.offset_px
    centred = CENTRE_DECODING and disc.measured and math.hypot(*centre) > max(CENTRE_TOLERANCE * eff,
                                                                              3.0 * disc.sigma_px)
    tx, ty = (nom_x + centre[0], nom_y + centre[1]) if centred else (nom_x, nom_y)
    shift = np.zeros((m_hat, m_hat, 2))
    shift[..., 0], shift[..., 1] = tx - nom_x, ty - nom_y
    level, _, _ = _centroids(planes, tx, ty, flag)
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = (level / level[:, c:c + 1, c:c + 1, :]).mean(axis=-1)        # (L, m̂, m̂), channel mean
    centre_lit = level[:, c, c, :].min(axis=-1) > 0
    lit = (np.nan_to_num(ratio, nan=0.0) >= LIT_FRACTION) & centre_lit[:, None, None]
    n_lenses = max(1, int(centre_lit.sum()))
    lit_share = lit.sum(axis=0) / n_lenses
    # per lens: is the centroid right at the nominal position?
    _, gx, gy = _centroids(planes, nom_x + shift[..., 0], nom_y + shift[..., 1], flag)
    err = np.nan_to_num(np.hypot(gx - tx, gy - ty) / eff, nan=np.inf)
    right = lit & (err <= tolerance)
    median = min(planes.origin.shape[0] - 1, n_lenses // 2)
    residual = np.sort(np.where(lit, err, np.inf), axis=0)[median]
    # the views not right at nominal are read where their mean centroid is
    fine = right.sum(axis=0) >= REQUIRED_FRACTION * np.maximum(lit.sum(axis=0), 1)
    base = shift.copy()
    moved, moved_residual = _corrected(planes, nom_x, nom_y, tx, ty, shift, lit, flag, eff)
    shift = np.where(fine[..., None], shift, moved)
    residual = np.where(fine, residual, moved_residual)
    # a correction that ran into MAX_SHIFT did not find the view's rays (its residual is what was left at
    # the limit, and the renders' parallax there was off by 0.03–0.1 in a): not delivered
    moved_by = np.hypot(*np.moveaxis(moved - base, -1, 0)) / eff
    converged = moved_by < CONVERGED_SHARE * MAX_SHIFT
    right = right | (~fine & converged & (moved_residual <= tolerance))[None] & lit
    delivered = ((lit_share >= REQUIRED_FRACTION)
                 & (right.sum(axis=0) >= REQUIRED_FRACTION * np.maximum(lit.sum(axis=0), 1)))
    delivered[c, c] = delivered[c, c] or not lit.any()
    delivered = symmetric(delivered)
    shift[~delivered] = 0.0
    return ViewSampling(delivered, shift, centre, bool(centred), residual, lit_share)


def carrying_views(signal: np.ndarray, delivered: np.ndarray) -> np.ndarray:
    """``delivered`` less the views whose samples carry signal at fewer than :data:`REQUIRED_FRACTION` of the
    central 60 % of lenses (``signal``: that share per view, ``(m̂, m̂)``); symmetric."""
    return symmetric(delivered & (np.asarray(signal) >= REQUIRED_FRACTION))


def centroid_errors(white: np.ndarray, grid: LensGrid, m_hat: int, cfa: str, demosaic_method: str,
                    interpolation: str, lenses=None, shift=None,
                    own_cells: bool = True) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per probed lens and view: the centroid error (px, all channels together), the white's level (worst channel).

    The error is the distance between the white-weighted centroid of each sample (read at nominal plus
    ``shift``, from the lens's own cell unless ``own_cells`` is false) and the view's nominal position,
    the kernel's own offset (nearest neighbour reads a pixel off the sample position) left out.
    Returns ``(errors, levels)``, each ``(lenses, m̂, m̂)``; errors are NaN where the white reads 0.
    """
    flag = cv_flag(interpolation)
    planes = _planes(white, grid, cfa, demosaic_method, probe_lenses(grid) if lenses is None else lenses, own_cells)
    nom_x, nom_y = view_offsets_px(grid, m_hat)
    off_x, off_y = view_offsets_px(grid, m_hat, shift)
    if planes is None:
        return np.full((0, m_hat, m_hat), np.nan), np.zeros((0, m_hat, m_hat))
    level, gx, gy = _centroids(planes, off_x, off_y, flag)
    return np.hypot(gx - nom_x, gy - nom_y), level.min(axis=-1)
