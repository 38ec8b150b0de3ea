"""Micro lens grid calibration: fit the lens lattice (`LensGrid`) to a white image.

A white image (a capture of a uniform, featureless scene) shows one bright micro image per micro lens.
Under the paper's telecentric model (ARCHITECTURE.md, camera file section) each micro image is centred
on its lens, so the micro image centres *are* the lens positions s_j around which Eq. 9 (shift-and-sum)
and Eq. 32 (viewpoints) index the pixels u_i. The estimate runs in five steps, each a small pure function
on numpy arrays:

1. **Monochrome.** Channels are averaged; a Bayer mosaic is low-passed by [1, 2, 1]/4 along each axis (two
   2 × 2 box averages, hence centred), which removes the period-2 colour pattern exactly. Isolated hot or
   dead pixels are replaced by their neighbours' median.
2. **Pitch guess.** The nearest peak of the autocorrelation (FFT) is a nearest-neighbour lattice vector:
   its length is a first pitch, with no assumption on the micro image shape (the rotation comes from
   step 5). The camera file's pitch is used only where the autocorrelation shows no lattice.
3. **Flattening and candidates.** The slowly varying floor (the gaps between micro images) and envelope
   (vignetting) are divided out; in the result every micro image is equally bright, and the lit points
   farthest from any dark pixel are one candidate centre per micro image.
4. **Sub-pixel centres.** Each centre moves (Gauss–Newton, all lenses at once) to the point about which
   its neighbourhood is most point-symmetric, allowing for a linear brightness slope across the micro
   image (vignetting): ``Σ m(d)·[S(c+d) − S(c−d) − (g·d)(S(c+d) + S(c−d))]² → min`` over c and g. Thin
   disks, disks clipped to their cell and blurred spots are all centred without bias; what asymmetry
   remains flags micro images cut by mechanical vignetting, noise or the image border.
5. **Robust lattice fit.** Nearest neighbours give the kind (4 → rectangular, 6 → hexagonal), pitch and
   rotation; lattice indices are assigned from the middle outwards while the fit is refined, and the
   similarity lattice ``x = O + p·R(θ)·(s, t)`` — linear in (O, p cos θ, p sin θ) — is fitted by least
   squares with iterative rejection of outliers; the RMS of the inliers' residuals is reported.

Everything heavy is vectorised over pixels or lenses (scipy.ndimage, numpy); no loop runs per lens.
Limits: tested for pitches of 7 to 150 pixels (the search spans 4 to 400); the micro images must leave
dark gaps (disks up to about 0.65 pitch clipped to a square cell, 0.55 pitch to a hexagonal one); a
non-telecentric main lens, whose micro images drift outwards, is not modelled (the fit then returns the
micro image centres). At most `MAX_REFINED_LENSES` lenses, in 9 patches across the sensor, are centred
to sub-pixel accuracy; all are counted for the grid's rows and columns.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .errors import LfprocError
from .grid import ROW_SPACING, LensGrid

#: smallest and largest lattice pitch the autocorrelation looks for, in pixels
MIN_PITCH_PX = 4.0
MAX_PITCH_PX = 400.0
#: fewest well-measured lenses a lattice fit accepts
MIN_LENSES = 6
#: relative difference between the fitted pitch and the camera file's pitch that is an error
PITCH_TOLERANCE = 0.05
#: at most this many lenses are centred to sub-pixel accuracy (spread evenly); plenty for the lattice fit
MAX_REFINED_LENSES = 6000
_SQRT3_2 = math.sqrt(3.0) / 2.0


@dataclass(frozen=True)
class GridEstimate:
    """The fitted lattice plus the measurements behind it (for plots and diagnostics).

    Attributes
    ----------
    grid : LensGrid
        The fitted lattice; ``grid.residual_rms_px`` is the RMS distance of the inlier centres from it.
    centers_xy_px : ndarray, shape (N, 2)
        Every micro image centre measured to sub-pixel accuracy (x, y), inliers and rejected ones.
    inlier : ndarray of bool, shape (N,)
        Centres used in the final least-squares fit.
    asymmetry : ndarray, shape (N,)
        Remaining point asymmetry of each micro image (0 = perfectly symmetric, ``inf`` = not measured).
    """

    grid: LensGrid
    centers_xy_px: np.ndarray
    inlier: np.ndarray
    asymmetry: np.ndarray


@dataclass(frozen=True)
class Similarity:
    """The lattice ``x = origin + s·(a, b) + t·(−b, a)`` in unit-lattice coordinates (s, t).

    ``a = p·cos θ`` and ``b = p·sin θ``; a lens of index (i, j) has (s, t) from `unit_coordinates`.
    """

    origin: np.ndarray
    a: float
    b: float

    @property
    def pitch(self) -> float:
        return math.hypot(self.a, self.b)

    @property
    def rotation_rad(self) -> float:
        return math.atan2(self.b, self.a)

    def xy(self, st: np.ndarray) -> np.ndarray:
        """Sensor positions (…, 2) of unit-lattice coordinates (…, 2)."""
        s, t = st[..., 0], st[..., 1]
        return np.stack([self.origin[0] + self.a * s - self.b * t, self.origin[1] + self.b * s + self.a * t], -1)

    def st(self, xy: np.ndarray) -> np.ndarray:
        """Fractional unit-lattice coordinates of sensor positions (the inverse of :meth:`xy`)."""
        dx, dy = xy[..., 0] - self.origin[0], xy[..., 1] - self.origin[1]
        scale = self.a * self.a + self.b * self.b
        return np.stack([(self.a * dx + self.b * dy) / scale, (-self.b * dx + self.a * dy) / scale], -1)


# ----------------------------------------------------------------------------- public API
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
        ``"none"`` or a Bayer pattern (``"RGGB"`` …): a 2-D mosaic is low-passed first (module docstring).
    source : str
        Name of the image in error messages.

    Returns
    -------
    LensGrid
        Lens (0, 0) is the first lens of the top row found; ``rows × cols`` covers every lens found whose
        cell lies on the sensor. In a rotated lattice a few grid positions at the corners of that index
        rectangle lie partly or wholly off the sensor.

    Raises
    ------
    LfprocError
        No lattice in the image (flat, black or noise), too few lenses, or a lattice kind or pitch that
        does not match the camera file.
    """
    return find_grid(white, kind, approx_pitch_px, smoothing=smoothing, cfa=cfa, source=source).grid


def find_grid(white, kind: str | None = None, approx_pitch_px: float | None = None, *,
              smoothing: float = 0.08, cfa: str = "none", source: str = "white image") -> GridEstimate:
    """Like :func:`estimate_grid`, but also return the measured centres, inliers and asymmetries."""
    if kind is not None and kind not in ROW_SPACING:
        raise LfprocError(f"unknown grid kind {kind!r}; use rectangular or hexagonal")
    if approx_pitch_px is not None and not (math.isfinite(approx_pitch_px) and approx_pitch_px > 0):
        raise LfprocError(f"approximate pitch must be a positive number of pixels, got {approx_pitch_px!r}")
    if not (math.isfinite(smoothing) and smoothing >= 0):
        raise LfprocError(f"smoothing must be a non-negative fraction of the pitch, got {smoothing!r}")
    image = repair_outlier_pixels(white_to_mono(white, cfa, source))
    guess = lattice_guess_from_autocorrelation(image)
    if guess is None and approx_pitch_px is None:
        raise LfprocError(_no_grid(source))
    pitch0 = guess[0] if guess is not None else float(approx_pitch_px)
    return _fit_at_pitch(image, pitch0, kind, approx_pitch_px, smoothing, source, retry=True)


def _no_grid(source: str) -> str:
    return (f"{source}: no micro lens grid found (the image is flat, black or noise); use a white image, "
            f"a capture of a uniform bright surface through the camera")


# ----------------------------------------------------------------------------- 1. monochrome
def white_to_mono(white, cfa: str = "none", source: str = "white image") -> np.ndarray:
    """A float64 2-D image: channels averaged, a Bayer mosaic low-passed by [1, 2, 1]/4 ⊗ [1, 2, 1]/4.

    The kernel is two 2 × 2 box averages in a row: centred (no half-pixel shift), with a zero at the
    Nyquist frequency, so a white image's period-2 colour pattern vanishes while the much coarser micro
    images keep their centres.
    """
    arr = np.asarray(white)
    if not (np.issubdtype(arr.dtype, np.number) and not np.iscomplexobj(arr)) or arr.dtype == np.bool_:
        raise LfprocError(f"{source}: pixel type {arr.dtype} is not a real number type; pass an image")
    if arr.ndim == 3:
        arr = arr.astype(np.float64).mean(axis=2)
    if arr.ndim != 2 or min(arr.shape) < 8:
        raise LfprocError(f"{source}: expected a 2-D image (or channels-last colour image) of at least 8x8 "
                          f"pixels, got shape {np.shape(white)}; pass the white image itself")
    image = arr.astype(np.float64)
    if not np.all(np.isfinite(image)):
        raise LfprocError(f"{source}: the image has NaN or infinite pixels; re-export the white image")
    if cfa not in (None, "", "none"):
        from scipy import ndimage
        kernel = np.array([0.25, 0.5, 0.25])
        image = ndimage.correlate1d(image, kernel, axis=0, mode="mirror")
        image = ndimage.correlate1d(image, kernel, axis=1, mode="mirror")
    return image


def repair_outlier_pixels(image: np.ndarray, threshold: float = 5.0) -> np.ndarray:
    """Replace hot and dead pixels by the median of their 3 × 3 neighbourhood.

    A pixel is an outlier when it exceeds the largest of its 8 neighbours (or falls below the smallest)
    by more than ``threshold`` robust noise deviations and 5 % of the image's range: micro images are
    larger than a pixel, so no real pixel stands alone like that.
    """
    from scipy import ndimage
    ring = np.ones((3, 3), bool)
    ring[1, 1] = False
    # noise from differences of vertical neighbours (every few columns): their lower quartile, as edges
    # between micro images may well make up half of all pairs; |N(0, 2σ²)| has its quartile at 0.3186·√2·σ
    step = np.diff(image[:, ::max(1, image.shape[1] // 512)], axis=0)
    noise = float(np.percentile(np.abs(step), 25)) / (0.3186 * math.sqrt(2.0))
    lo, hi = np.percentile(image, [0.1, 99.9])
    margin = max(threshold * noise, 0.05 * float(hi - lo), np.finfo(float).tiny)
    bad = (image - ndimage.maximum_filter(image, footprint=ring, mode="nearest") > margin) | \
          (ndimage.minimum_filter(image, footprint=ring, mode="nearest") - image > margin)
    if not bad.any():
        return image
    iy, ix = np.nonzero(bad)
    padded = np.pad(image, 1, mode="reflect")
    patches = np.stack([padded[iy + dy, ix + dx] for dy in range(3) for dx in range(3)], -1)
    repaired = image.copy()
    repaired[iy, ix] = np.median(patches, axis=-1)
    return repaired


# ----------------------------------------------------------------------------- 2. lattice guess
def lattice_guess_from_autocorrelation(image: np.ndarray, crop: int = 1024,
                                       min_peak: float = 0.3) -> tuple[float, float] | None:
    """Pitch and rotation (radians) of the lattice from the nearest autocorrelation peak, or ``None``.

    The autocorrelation of a lattice pattern peaks at every lattice vector; its nearest peak beyond
    `MIN_PITCH_PX` that reaches ``min_peak`` of the zero-lag value is a nearest-neighbour vector. A central
    ``crop`` × ``crop`` window is used, Hann-tapered, with periods above 2 × `MAX_PITCH_PX` removed.
    """
    from scipy import ndimage
    h, w = image.shape
    ch, cw = min(h, crop), min(w, crop)
    y0, x0 = (h - ch) // 2, (w - cw) // 2
    patch = ndimage.gaussian_filter(image[y0:y0 + ch, x0:x0 + cw], 0.7)
    patch = (patch - patch.mean()) * np.outer(np.hanning(ch), np.hanning(cw))
    power = np.abs(np.fft.rfft2(patch, s=(2 * ch, 2 * cw))) ** 2  # zero padded: no wrap-around
    fy = np.fft.fftfreq(2 * ch)[:, None]
    fx = np.fft.rfftfreq(2 * cw)[None, :]
    power[np.hypot(fx, fy) < 1.0 / (2.0 * MAX_PITCH_PX)] = 0.0
    acf = np.fft.fftshift(np.fft.irfft2(power, s=(2 * ch, 2 * cw)))
    zero = acf[ch, cw]
    if not (np.isfinite(zero) and zero > 0):
        return None
    acf /= zero
    ly = np.arange(2 * ch)[:, None] - ch
    lx = np.arange(2 * cw)[None, :] - cw
    lag = np.hypot(lx, ly)
    peaks = (acf == ndimage.maximum_filter(acf, size=3)) & (acf >= min_peak)
    peaks &= (lag >= MIN_PITCH_PX) & (lag <= min(MAX_PITCH_PX, min(ch, cw) / 2.0))
    if not peaks.any():
        return None
    iy, ix = np.nonzero(peaks)
    k = int(np.argmin(lag[iy, ix]))
    py, px = iy[k], ix[k]
    dy = _parabola_vertex(acf[py - 1, px], acf[py, px], acf[py + 1, px])
    dx = _parabola_vertex(acf[py, px - 1], acf[py, px], acf[py, px + 1])
    vy, vx = ly[py, 0] + dy, lx[0, px] + dx
    return float(math.hypot(vx, vy)), float(math.atan2(vy, vx))


def _parabola_vertex(left: float, centre: float, right: float) -> float:
    """Offset of the vertex of the parabola through three equally spaced samples (within ±0.5)."""
    denom = left - 2.0 * centre + right
    if denom >= 0:
        return 0.0
    return float(np.clip(0.5 * (left - right) / denom, -0.5, 0.5))


# ----------------------------------------------------------------------------- 3. flattening, candidates
@dataclass(frozen=True)
class Flattened:
    """Results of :func:`flatten`.

    Attributes
    ----------
    flat : ndarray
        (image − floor) / envelope where ``valid``, else 0: micro images of equal brightness.
    valid : ndarray of bool
        Pixels whose envelope reaches a tenth of its 99th percentile (not vignetted to black).
    above_floor : ndarray
        (image − floor) / 99th percentile of the envelope: the micro images with their vignetting.
    """

    flat: np.ndarray
    valid: np.ndarray
    above_floor: np.ndarray


def flatten(image: np.ndarray, pitch: float, valid_fraction: float = 0.1) -> Flattened:
    """Remove the floor and divide out the envelope of a white image.

    floor = Gaussian(σ = pitch) of the local minimum over 1.3 pitches (every such window holds a gap
    between micro images); envelope = Gaussian(σ = pitch) of image − floor, the local mean (σ = pitch damps
    the lattice's ripple by exp(−2π²) ≈ 3e-9).
    """
    from scipy import ndimage
    denoised = ndimage.gaussian_filter(image, 1.0)  # light: narrow gaps between fat micro images survive
    floor = smooth_large(ndimage.minimum_filter(denoised, size=_odd(1.3 * pitch)), pitch)
    above = image - floor
    envelope = smooth_large(above, pitch)
    reference = float(np.percentile(envelope, 99))
    scale = float(np.percentile(np.abs(image), 99.9))
    if not reference > 1e-6 * max(scale, np.finfo(float).tiny):
        return Flattened(np.zeros_like(image), np.zeros(image.shape, bool), np.zeros_like(image))
    valid = envelope >= valid_fraction * reference
    flat = np.where(valid, above / np.where(valid, envelope, 1.0), 0.0)
    return Flattened(flat, valid, above / reference)


def smooth_large(image: np.ndarray, sigma: float) -> np.ndarray:
    """Gaussian smoothing for large σ, computed on a block-averaged copy and interpolated back.

    Blocks of k ≈ σ/4 pixels leave the result smooth on the scale of a pixel (the error of the linear
    interpolation is of order (k/σ)²/8 of the curvature) while the cost no longer grows with σ.
    """
    from scipy import ndimage
    k = int(sigma // 4)
    if k < 2:
        return ndimage.gaussian_filter(image, sigma, mode="reflect")
    h, w = image.shape
    hb, wb = -(-h // k), -(-w // k)
    padded = np.pad(image, ((0, hb * k - h), (0, wb * k - w)), mode="reflect")
    blocks = padded.reshape(hb, k, wb, k).mean(axis=(1, 3))
    sigma_blocks = math.sqrt(max(sigma * sigma - k * k / 12.0, 0.0)) / k  # the block mean blurs by k²/12
    low = ndimage.gaussian_filter(blocks, sigma_blocks, mode="reflect")
    return _interpolate_blocks(_interpolate_blocks(low, k, h, axis=0), k, w, axis=1)


def _interpolate_blocks(low: np.ndarray, k: int, n: int, axis: int) -> np.ndarray:
    """Linear interpolation along ``axis`` from block centres ((b + 1/2)·k − 1/2) back to ``n`` pixels."""
    pos = np.clip((np.arange(n) - (k - 1) / 2.0) / k, 0.0, low.shape[axis] - 1.0)
    i0 = np.minimum(np.floor(pos).astype(int), low.shape[axis] - 1)
    i1 = np.minimum(i0 + 1, low.shape[axis] - 1)
    frac = pos - i0
    shape = [1, 1]
    shape[axis] = n
    frac = frac.reshape(shape)
    return np.take(low, i0, axis=axis) * (1.0 - frac) + np.take(low, i1, axis=axis) * frac


def candidate_centres(flat: np.ndarray, valid: np.ndarray, pitch: float) -> np.ndarray:
    """Approximate (x, y) of the lit points farthest from any dark pixel: one per micro image.

    ``flat`` is thresholded at half its 90th percentile; the maxima of the distance to the nearest dark
    pixel are the centres of thin disks and of cells dark only at their corners alike. Maxima nearer than
    0.15 pitch to the dark are specks and dropped; a plateau of equal maxima counts once (its centroid).
    """
    from scipy import ndimage
    smooth = ndimage.gaussian_filter(flat, 1.0)
    level = 0.5 * float(np.percentile(smooth[valid], 90)) if valid.any() else 0.0
    lit = (smooth > level) & valid
    if not lit.any() or lit.all():
        return np.zeros((0, 2))
    distance = ndimage.distance_transform_edt(lit)
    peaks = (distance == ndimage.maximum_filter(distance, size=_odd(0.6 * pitch), mode="nearest"))
    peaks &= distance >= 0.15 * pitch
    labels, count = ndimage.label(peaks, structure=np.ones((3, 3)))
    if count == 0:
        return np.zeros((0, 2))
    centres = np.array(ndimage.center_of_mass(peaks, labels, np.arange(1, count + 1)))
    return centres[:, ::-1].astype(np.float64)


def _odd(size: float) -> int:
    n = max(int(round(size)), 3)
    return n if n % 2 else n + 1


# ----------------------------------------------------------------------------- 4. sub-pixel centres
def symmetric_offsets(pitch: float, radius: float = 0.8, full: float = 0.62,
                      max_per_axis: int = 12) -> tuple[np.ndarray, np.ndarray]:
    """Half-plane offsets d (K, 2) within ``radius``·pitch and their weights m(|d|).

    The weight is 1 up to ``full``·pitch and falls as cos² to 0 at ``radius``·pitch (the corners of a
    cell, where fat micro images leave their only gaps, lie at 0.58–0.71 pitch). The spacing is 1 px or
    coarser, so at most about 2·max_per_axis² pairs are used whatever the pitch.
    """
    r_max = radius * pitch
    step = max(1.0, r_max / max_per_axis)
    n = int(math.floor(r_max / step))
    g = np.arange(-n, n + 1) * step
    dx, dy = np.meshgrid(g, g)
    dist = np.hypot(dx, dy)
    keep = (dist <= r_max) & ((dy > 0) | ((dy == 0) & (dx > 0)))
    rel = (dist[keep] - full * pitch) / ((radius - full) * pitch)
    weight = np.where(rel <= 0, 1.0, np.cos(0.5 * math.pi * np.clip(rel, 0.0, 1.0)) ** 2)
    return np.stack([dx[keep], dy[keep]], -1), weight


def refine_centres(smooth: np.ndarray, xy: np.ndarray, pitch: float, blur_variance: float = 0.0,
                   iterations: int = 12, max_shift: float | None = None,
                   offsets: tuple[np.ndarray, np.ndarray] | None = None,
                   chunk_samples: int = 4_000_000) -> tuple[np.ndarray, np.ndarray]:
    """Move each centre to the point of best point symmetry of ``smooth`` (Gauss–Newton, vectorised).

    A micro image P that is point-symmetric about c but lies under a brightness slope g (vignetting)
    satisfies ``S(c + d) − S(c − d) = (g·d)·(S(c + d) + S(c − d))``. For every lens at once this solves

        min over c, g of  Σ_k m_k [S(c + d_k) − S(c − d_k) − (g·d_k)(S(c + d_k) + S(c − d_k))]²,

    so a linear slope across the micro image does not move its centre. Smoothing (variance
    ``blur_variance``: σ² of the Gaussian plus 1/12 for the pixel's area) turns a sloped micro image into a
    symmetric one displaced by −σ²·g, because G∗(x·P) = x·(G∗P) + σ²·∇(G∗P); that displacement is added
    back. ``S`` is sampled with cubic splines, its gradient bilinearly; a pair (c + d, c − d) with either
    point off the image is left out as a pair.

    Returns
    -------
    xy : ndarray (N, 2)
        The centres.
    asymmetry : ndarray (N,)
        ``Σ m r² / Σ m (S(c+d)² + S(c−d)²)`` at the solution: about 0 for a symmetric micro image, of order
        1 for half a disk; ``inf`` where a centre moved more than ``max_shift`` (default a quarter pitch)
        from its start, towards another point of symmetry of the lattice such as the midpoint of two lenses.
    """
    from scipy import ndimage
    d, m = offsets if offsets is not None else symmetric_offsets(pitch)
    coeffs = ndimage.spline_filter(smooth, order=3, mode="mirror")
    gradients = np.gradient(smooth)[::-1]  # (d/dx, d/dy)
    start_xy = np.array(xy, dtype=np.float64).reshape(-1, 2)
    out = start_xy.copy()
    asym = np.full(len(out), np.inf)
    max_step = 0.1 * pitch
    max_shift = 0.25 * pitch if max_shift is None else max_shift
    max_slope = 0.5 / float(np.max(np.hypot(d[:, 0], d[:, 1]))) if len(d) else 0.0
    per_chunk = max(1, chunk_samples // max(len(d), 1))
    for first in range(0, len(out), per_chunk):
        c = out[first:first + per_chunk].copy()
        g = np.zeros_like(c)
        for _ in range(iterations):
            r, jac, w, _ = _symmetry_terms(coeffs, gradients, c, g, d, m)
            normal = np.einsum("nk,nki,nkj->nij", w, jac, jac)
            rhs = np.einsum("nk,nki,nk->ni", w, jac, r)
            trace = np.trace(normal, axis1=1, axis2=2)
            blank = ~(trace > 0)  # no texture at all (or off the image): the lens stays where it is
            normal[blank] = np.eye(4)
            rhs[blank] = 0.0
            normal += (1e-9 * np.where(blank, 1.0, trace))[:, None, None] * np.eye(4)
            delta = -_solve_batched(normal, rhs)
            step = delta[:, :2]
            norm = np.hypot(step[:, 0], step[:, 1])
            step *= np.minimum(1.0, max_step / np.maximum(norm, 1e-300))[:, None]
            c += step
            g = np.clip(g + delta[:, 2:], -max_slope, max_slope)
            if float(np.max(np.abs(step), initial=0.0)) < 1e-5:
                break
        r, _, w, energy = _symmetry_terms(coeffs, None, c, g, d, m)
        with np.errstate(divide="ignore", invalid="ignore"):
            asym[first:first + per_chunk] = np.where(energy > 0, (w * r * r).sum(1) / energy, np.inf)
        out[first:first + per_chunk] = c + blur_variance * g
    moved = np.hypot(*(out - start_xy).T)
    asym[~(moved <= max_shift)] = np.inf
    return out, asym


def _solve_batched(normal: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """Solve the stacked normal equations; a degenerate system gives a zero step."""
    try:
        delta = np.linalg.solve(normal, rhs[..., None])[..., 0]
    except np.linalg.LinAlgError:
        delta = np.einsum("nij,nj->ni", np.linalg.pinv(normal), rhs)
    delta[~np.isfinite(delta).all(1)] = 0.0
    return delta


def _symmetry_terms(coeffs, gradients, c, g, d, m):
    """Residuals of the symmetry model, Jacobian in (cx, cy, gx, gy) (if ``gradients``), weights, energy."""
    h, w = coeffs.shape
    plus, minus = c[:, None, :] + d, c[:, None, :] - d
    on_image = ((plus[..., 0] >= 0) & (plus[..., 0] <= w - 1) & (plus[..., 1] >= 0) & (plus[..., 1] <= h - 1)
                & (minus[..., 0] >= 0) & (minus[..., 0] <= w - 1) & (minus[..., 1] >= 0) & (minus[..., 1] <= h - 1))
    weight = m * on_image
    s_plus, s_minus = _sample(coeffs, plus, order=3), _sample(coeffs, minus, order=3)
    slope = g[:, None, 0] * d[:, 0] + g[:, None, 1] * d[:, 1]  # g·d, shape (n, K)
    total = s_plus + s_minus
    residual = s_plus - s_minus - slope * total
    energy = (weight * (s_plus ** 2 + s_minus ** 2)).sum(1)
    jac = None
    if gradients is not None:
        jac = np.empty(residual.shape + (4,))
        for axis, grad in enumerate(gradients):
            g_plus, g_minus = _sample(grad, plus, order=1), _sample(grad, minus, order=1)
            jac[..., axis] = g_plus - g_minus - slope * (g_plus + g_minus)
            jac[..., 2 + axis] = -d[:, axis] * total
    return residual, jac, weight, energy


def _sample(image: np.ndarray, xy: np.ndarray, order: int) -> np.ndarray:
    """``image`` at points (…, 2) given as (x, y); order 3 expects spline coefficients."""
    from scipy import ndimage
    coords = np.stack([xy[..., 1].reshape(-1), xy[..., 0].reshape(-1)])
    out = ndimage.map_coordinates(image, coords, order=order, mode="mirror", prefilter=False)
    return out.reshape(xy.shape[:-1])


# ----------------------------------------------------------------------------- 5. lattice fit
def neighbour_lattice(xy: np.ndarray) -> tuple[str, float, float, int] | None:
    """Kind, pitch, rotation (radians, axis nearest +x) and support from nearest-neighbour vectors.

    Neighbours within ±20 % of the median nearest distance count; a lens with 5 or 6 of them is in a
    hexagonal lattice, with 4 in a rectangular one (diagonals lie at √2 pitch). The rotation is the
    circular mean of the neighbour directions folded by the lattice's symmetry (×4 or ×6). ``support``
    is the number of lenses with 3 or more such neighbours; ``None`` when fewer than 3 have.
    """
    from scipy.spatial import cKDTree
    if len(xy) < 4:
        return None
    dist, idx = cKDTree(xy).query(xy, k=min(7, len(xy)))
    dist, idx = dist[:, 1:], idx[:, 1:]
    nearest = float(np.median(dist[:, 0]))
    band = (dist > 0.8 * nearest) & (dist < 1.2 * nearest)
    counts = band.sum(1)
    well = counts >= 3
    if well.sum() < 3:
        return None
    kind = "hexagonal" if float(np.median(counts[well])) >= 5 else "rectangular"
    sel = band & well[:, None]
    vec = xy[idx] - xy[:, None, :]
    fold = 6 if kind == "hexagonal" else 4
    angle = np.arctan2(vec[..., 1][sel], vec[..., 0][sel])
    rotation = float(np.angle(np.exp(1j * fold * angle).sum())) / fold
    return kind, float(np.median(dist[sel])), rotation, int(well.sum())


def unit_coordinates(kind: str, index: np.ndarray) -> np.ndarray:
    """Unit-lattice coordinates (s, t) of lattice indices (i, j): rectangular (i, j), hexagonal (i + j/2, j·√3/2)."""
    i, j = index[..., 0].astype(np.float64), index[..., 1].astype(np.float64)
    if kind == "hexagonal":
        return np.stack([i + 0.5 * j, _SQRT3_2 * j], -1)
    return np.stack([i, j], -1)


def lattice_index(kind: str, st: np.ndarray) -> np.ndarray:
    """Nearest lattice indices (i, j) (as floats) of fractional unit-lattice coordinates (s, t)."""
    if kind == "hexagonal":
        j = np.rint(st[..., 1] / _SQRT3_2)
        return np.stack([np.rint(st[..., 0] - 0.5 * j), j], -1)
    return np.rint(st)


def fit_similarity(xy: np.ndarray, st: np.ndarray) -> Similarity:
    """Least squares ``x = O + s·(a, b) + t·(−b, a)``: linear in the 4 unknowns (Ox, Oy, a, b)."""
    n = len(xy)
    design = np.zeros((2 * n, 4))
    design[0::2, 0] = 1.0
    design[1::2, 1] = 1.0
    design[0::2, 2], design[0::2, 3] = st[:, 0], -st[:, 1]
    design[1::2, 2], design[1::2, 3] = st[:, 1], st[:, 0]
    sol = np.linalg.lstsq(design, xy.reshape(-1), rcond=None)[0]
    return Similarity(np.array(sol[:2]), float(sol[2]), float(sol[3]))


def robust_fit(xy: np.ndarray, st: np.ndarray, usable: np.ndarray, reject_sigma: float = 4.0,
               floor_px: float = 0.01, max_rounds: int = 20) -> tuple[Similarity, np.ndarray]:
    """Fit, drop centres beyond ``reject_sigma`` robust deviations, refit until the inlier set settles.

    The per-axis deviation comes from the median residual distance (a Rayleigh median is 1.1774 σ); the
    limit is at least ``floor_px`` and at most a quarter pitch.
    """
    inlier = usable.copy()
    model = fit_similarity(xy[inlier], st[inlier])
    for _ in range(max_rounds):
        residual = np.hypot(*(xy - model.xy(st)).T)
        sigma = float(np.median(residual[inlier])) / 1.1774
        limit = min(max(reject_sigma * sigma, floor_px), 0.25 * model.pitch)
        new = usable & (residual <= limit)
        if new.sum() < 3 or np.array_equal(new, inlier):
            break
        inlier = new
        model = fit_similarity(xy[inlier], st[inlier])
    return model, inlier


class _NoLattice(Exception):
    """Too few centres line up with any lattice."""


def assign_and_fit(xy: np.ndarray, usable: np.ndarray, kind: str, pitch: float,
                   rotation: float) -> tuple[Similarity, np.ndarray, np.ndarray, np.ndarray]:
    """Index the centres and fit the lattice, growing the indexed region outwards from the middle lens.

    Within a radius of 3, 9, 27, … lenses, each centre takes the index of the nearest lattice point of the
    current fit (if within 0.3 pitch of it), and the fit is redone; so a small error of the first pitch
    or rotation never misnumbers distant lenses. Returns the fit, the indices (N, 2), their unit-lattice
    coordinates and the inlier mask.
    """
    middle = np.median(xy[usable], axis=0)
    candidates = np.flatnonzero(usable)
    ref = candidates[np.argmin(np.hypot(*(xy[candidates] - middle).T))]
    model = Similarity(xy[ref].copy(), pitch * math.cos(rotation), pitch * math.sin(rotation))
    radius = 3.0
    while True:
        index = lattice_index(kind, model.st(xy))
        st = unit_coordinates(kind, index)
        close = np.hypot(*(xy - model.xy(st)).T) < 0.3 * model.pitch
        near = np.max(np.abs(index), axis=1) <= radius
        sel = usable & close & near
        if sel.sum() < 3:
            raise _NoLattice
        model, inlier = robust_fit(xy, st, sel)
        if np.all(np.max(np.abs(index[usable & close]), axis=1) <= radius):
            index = lattice_index(kind, model.st(xy))
            st = unit_coordinates(kind, index)
            close = np.hypot(*(xy - model.xy(st)).T) < 0.3 * model.pitch
            model, inlier = robust_fit(xy, st, usable & close)
            return model, index, st, inlier
        radius *= 3.0


# ----------------------------------------------------------------------------- the pipeline
def _fit_at_pitch(image, pitch0, kind, approx_pitch_px, smoothing, source, retry) -> GridEstimate:
    from scipy import ndimage
    h, w = image.shape
    flattened = flatten(image, pitch0)
    candidates = candidate_centres(flattened.flat, flattened.valid, pitch0)
    if len(candidates) < MIN_LENSES:
        raise LfprocError(_no_grid(source))
    # sub-pixel centres of the micro images whose symmetric neighbourhood (0.8 pitch) lies on the sensor
    reach = 0.8 * pitch0 + 2.0
    inside = ((candidates[:, 0] >= reach) & (candidates[:, 0] <= w - 1 - reach)
              & (candidates[:, 1] >= reach) & (candidates[:, 1] <= h - 1 - reach))
    chosen = spread_patches(candidates, np.flatnonzero(inside), (h, w), MAX_REFINED_LENSES)
    sigma = max(smoothing * pitch0, 0.7)
    smooth = ndimage.gaussian_filter(flattened.above_floor, sigma)
    xy, asym = refine_centres(smooth, candidates[chosen], pitch0, blur_variance=sigma * sigma + 1.0 / 12.0)
    xy, asym = _merge_duplicates(xy, asym, 0.3 * pitch0)
    usable = np.isfinite(asym) & (asym <= _asymmetry_limit(asym))
    neighbours = neighbour_lattice(xy[usable])
    if neighbours is None:
        raise LfprocError(_no_grid(source))
    seen_kind, pitch1, rotation1, support = neighbours
    if retry and abs(pitch1 - pitch0) > 0.1 * pitch0:
        return _fit_at_pitch(image, pitch1, kind, approx_pitch_px, smoothing, source, retry=False)
    if kind is not None and seen_kind != kind and support >= 2 * MIN_LENSES:
        raise LfprocError(f"{source}: the camera file says mla.grid = {kind!r} but the white image shows a "
                          f"{seen_kind} lattice; set mla.grid = \"{seen_kind}\" in the camera file")
    fit_kind = kind or seen_kind
    try:
        model, index, st, inlier = assign_and_fit(xy, usable, fit_kind, pitch1, rotation1)
    except _NoLattice:
        raise LfprocError(_no_grid(source)) from None
    if inlier.sum() < MIN_LENSES or len(np.unique(index[inlier, 0])) < 2 or len(np.unique(index[inlier, 1])) < 2:
        raise LfprocError(f"{source}: only {int(inlier.sum())} micro lenses could be measured and a grid fit "
                          f"needs {MIN_LENSES} in 2 rows and columns; use a larger or brighter white image")
    rms = float(np.sqrt(np.mean(np.sum((xy[inlier] - model.xy(st[inlier])) ** 2, axis=1))))
    if rms > 0.1 * model.pitch:
        raise LfprocError(_no_grid(source))
    if approx_pitch_px is not None and abs(model.pitch - approx_pitch_px) > PITCH_TOLERANCE * approx_pitch_px:
        raise LfprocError(f"{source}: the camera file's micro lens pitch ({approx_pitch_px:.3f} px = mla.pitch_mm "
                          f"/ sensor.pixel_pitch_mm) does not match the white image ({model.pitch:.3f} px); "
                          f"check both pitches in the camera file, or the white image")
    all_index = lattice_index(fit_kind, model.st(candidates))
    found = np.hypot(*(candidates - model.xy(unit_coordinates(fit_kind, all_index))).T) < 0.25 * model.pitch
    grid = grid_from_fit(fit_kind, model, all_index[found], (h, w), rms)
    return GridEstimate(grid=grid, centers_xy_px=xy, inlier=inlier, asymmetry=asym)


def spread_patches(xy: np.ndarray, chosen: np.ndarray, shape, limit: int, patches: int = 3) -> np.ndarray:
    """At most ``limit`` of the lenses ``chosen``: compact patches around a 3 × 3 grid of points spanning the image.

    Patches keep every lens's neighbours (for `neighbour_lattice`) and their spread keeps the lever arm
    that pins down pitch and rotation.
    """
    if len(chosen) <= limit:
        return chosen
    h, w = shape
    fractions = (np.arange(patches) + 0.5) / patches
    centres = np.stack(np.meshgrid(fractions * w, fractions * h), -1).reshape(-1, 2)
    per_patch = limit // len(centres)
    picked = []
    for centre in centres:  # 9 patches, each a vectorised selection
        dist = np.hypot(*(xy[chosen] - centre).T)
        picked.append(chosen[np.argpartition(dist, per_patch)[:per_patch]])
    return np.unique(np.concatenate(picked))


def _asymmetry_limit(values: np.ndarray) -> float:
    """Asymmetry above which a micro image is not used: far above that of the typical (median) lens."""
    values = values[np.isfinite(values)]
    if values.size == 0:
        return 0.0
    med = float(np.median(values))
    mad = float(np.median(np.abs(values - med)))
    return max(med + 10.0 * 1.4826 * mad, 3.0 * med, 1e-4)


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


def grid_from_fit(kind: str, model: Similarity, index: np.ndarray, shape, rms: float) -> LensGrid:
    """The `LensGrid` (lfproc/grid.py convention) covering the lenses ``index`` whose cell is on the sensor.

    In unit-lattice coordinates grid row R lies at t = (row0 + R)·row_spacing and its lens Q at
    s = s0 + Q + (R mod 2)/2 (hexagonal) or s = s0 + Q (rectangular). Every hexagonal row j has its s values
    at j/2 modulo 1, so any lattice point of row ``row0`` as origin satisfies the half-pitch convention;
    ``row0`` and ``s0`` are chosen so the lenses have R, Q ≥ 0 starting at 0.
    """
    h, w = shape
    st = unit_coordinates(kind, index)
    xy = model.xy(st)
    margin = 0.5 * model.pitch
    on_sensor = ((xy[:, 0] >= margin - 0.5) & (xy[:, 0] <= w - 0.5 - margin)
                 & (xy[:, 1] >= margin - 0.5) & (xy[:, 1] <= h - 0.5 - margin))
    if on_sensor.any():
        index, st = index[on_sensor], st[on_sensor]
    row0 = float(index[:, 1].min())
    rows_from_top = index[:, 1] - row0
    s_row0 = 0.5 * row0 if kind == "hexagonal" else 0.0  # s of lattice index (0, row0)
    q = st[:, 0] - s_row0
    if kind == "hexagonal":
        q = q - 0.5 * np.mod(rows_from_top, 2.0)
    q = np.rint(q)
    q0 = float(q.min())
    origin = model.xy(np.array([s_row0 + q0, row0 * ROW_SPACING[kind]]))
    return LensGrid(kind=kind, pitch_px=model.pitch, rotation_deg=math.degrees(model.rotation_rad),
                    origin_xy_px=(float(origin[0]), float(origin[1])), rows=int(rows_from_top.max()) + 1,
                    cols=int(q.max() - q0) + 1, residual_rms_px=rms)
