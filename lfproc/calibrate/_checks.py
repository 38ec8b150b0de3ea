"""Plausibility checks of a calibration, each reduced to one number and, past a limit, a one-line warning.

* **Scene texture** (a capture given as the white image, or a white image of a textured surface): in a
  white image every micro image repeats its neighbour, so the flattened image S satisfies
  S(x + a/2) ≈ S(x − a/2) for a lattice vector a. The texture ratio
  ``Σ (S(x + a/2) − S(x − a/2))² / Σ [(S(x + a/2) − S̄)² + (S(x − a/2) − S̄)²]`` is 0 for a perfect
  lattice and 1 for micro images unrelated to their neighbours. The one number lfproc reports under
  that name (GRID.json's ``texture_ratio``, every warning and refusal) is `white_texture`: the largest
  ratio over up to 4 × 4 tiles of well-lit micro images (`lattice_texture`). `texture_ratio` is the same
  ratio over calibration's windows, for diagnostics only. Measured (docs/real-data.md): real white
  images 0.0016–0.0063, simulated ones 0.0005–0.008 (0.039 for a tiny white dark beyond its 9 × 12
  lenses); real captures 0.13 (an 8-bit microscope capture of a sea urchin), 0.62 (fluorescent beads),
  simulated ones 0.067–0.19. Above `TEXTURE_LIMIT` (0.04, six times the largest real white's) the image is
  refused as a capture (`lfproc.inputs.check_white_is_white`); below it nothing is said (between 0.02 and 0.04
  lie only simulated white images: dusty, 30 DN, uneven lenslets; a tiny one dark beyond its lenses).
* **Residual**: the lattice fit's inlier RMS beyond `TRUST_RMS_PX` (or 1 % of the pitch, whichever is
  larger), or more than a quarter of the indexed centres rejected, means the micro image centres are
  not where a lattice puts them (a textured or overexposed white image, strong mechanical vignetting).
* **Exit pupil** (given a camera): micro image centres form the lens lattice scaled by
  ``(d_A + f_s)/d_A`` about the optical axis, so the fitted pitch over the camera file's lens pitch
  implies the exit pupil distance ``d_A = f_s / (scale − 1)``.
* **Microscope pitch**: a light-field microscope is telecentric (the objective's stop sits in the tube
  lens's front focal plane), so its micro images sit exactly under their lenslets and a pitch that
  differs from the camera file's is no exit pupil: it is the pixel size at the lenslets' focal plane,
  ``sensor.pixel_pitch_mm / microscope.relay_magnification``, that is off. The measured pitch implies
  the relay magnification to write into the camera file (the sensor's pixel is what its maker states; a
  nominally 1:1 relay, or none, is what is rarely exact). Decoding takes m̂ from the measured pitch anyway, and
  the geometry depends on the pixel only through m̂ (docs/microscope.md).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: texture ratio (`white_texture`) above which a "white image" is a capture of a scene: real whites give <= 0.0063
TEXTURE_LIMIT = 0.04
#: inlier RMS (px) above which the grid is reported as not trustworthy (or 1 % of the pitch if larger)
TRUST_RMS_PX = 0.1
#: relative tolerance of the camera file's nominal pitches (MLA and pixel) when checking the exit pupil
NOMINAL_PITCH_TOLERANCE = 1e-4


def texture_ratio(measured, model, kind: str, tile_pitches: float = 16.0, max_samples: int = 40_000) -> float:
    """The texture ratio (module docstring) over the windows ``measured`` (`_measure.Measured`).

    Each window's core is cut into tiles of about ``tile_pitches`` lenses, each compared with itself
    shifted by its own local lattice vector (from ``model``), so a drifting lattice stays periodic.
    """
    num = den = 0.0
    pitch = model.rigid.pitch
    for m in measured:
        cy0, cy1, cx0, cx1 = m.window.core
        ny = max(1, int(round((cy1 - cy0) / (tile_pitches * pitch))))
        nx = max(1, int(round((cx1 - cx0) / (tile_pitches * pitch))))
        ys, xs = np.linspace(cy0, cy1, ny + 1).astype(int), np.linspace(cx0, cx1, nx + 1).astype(int)
        per_tile = max(1, max_samples // (ny * nx))
        for ty in range(ny):
            for tx in range(nx):
                n, d = _tile_terms(m, model, (ys[ty], ys[ty + 1], xs[tx], xs[tx + 1]), per_tile)
                num, den = num + n, den + d
    return num / den if den > 0 else 0.0


def _tile_terms(m, model, tile, max_samples: int) -> tuple[float, float]:
    """Numerator and denominator of the texture ratio over one tile of a window."""
    flat, win = m.flat, m.window
    ty0, ty1, tx0, tx1 = tile
    centre = np.array([0.5 * (tx0 + tx1), 0.5 * (ty0 + ty1)])
    st = model.st(centre)
    a = model.xy(st + np.array([1.0, 0.0])) - model.xy(st)
    reach = int(math.ceil(0.5 * float(np.hypot(*a)))) + 2
    ys = np.arange(max(ty0, win.y0 + reach), min(ty1, win.y1 - reach)) - win.y0
    xs = np.arange(max(tx0, win.x0 + reach), min(tx1, win.x1 - reach)) - win.x0
    if len(ys) == 0 or len(xs) == 0:
        return 0.0, 0.0
    stride = max(1, int(math.sqrt(len(ys) * len(xs) / max_samples)))
    yy, xx = np.meshgrid(ys[::stride], xs[::stride], indexing="ij")
    return _half_vector_terms(flat, yy, xx, a)


def _half_vector_terms(flat, yy, xx, a) -> tuple[float, float]:
    """Numerator and denominator of the texture ratio: ``flat`` at (yy, xx) ± a/2 compared."""
    from scipy import ndimage
    plus = ndimage.map_coordinates(flat, [yy + 0.5 * a[1], xx + 0.5 * a[0]], order=1, mode="nearest")
    minus = ndimage.map_coordinates(flat, [yy - 0.5 * a[1], xx - 0.5 * a[0]], order=1, mode="nearest")
    mean = 0.5 * (plus.mean() + minus.mean())
    return float(np.sum((plus - minus) ** 2)), float(np.sum((plus - mean) ** 2 + (minus - mean) ** 2))


def white_texture(image, cfa: str, grid) -> float:
    """The texture ratio of a white image (module docstring): the largest of `lattice_texture`'s tiles, 0.0
    where no tile holds lit micro images. The one number reported under that name."""
    return float(max([0.0, *(float(t) for t in lattice_texture(image, cfa, grid))]))


def trust_warning(source: str, residual_px: float, pitch_px: float, inliers: int, indexed: int) -> str | None:
    limit = max(TRUST_RMS_PX, 0.01 * pitch_px)
    if residual_px <= limit and inliers >= 0.75 * indexed:
        return None
    return (f"{source}: warning: the lattice fit leaves {residual_px:.3f} px RMS residual over {inliers} of "
            f"{indexed} micro images (a trustworthy fit leaves < {limit:.2f} px and keeps 3/4): the grid may be "
            f"off; use a well exposed white image of a uniform surface taken with the capture's zoom and focus")


@dataclass(frozen=True)
class ExitPupilEstimate:
    """What the fitted pitch says about the exit pupil (module docstring).

    Attributes
    ----------
    scale : float
        Fitted micro image pitch over the camera file's lens pitch, ``(d_A + f_s)/d_A``.
    scale_sigma : float
        Its standard error from the fit.
    distance_mm : float
        Implied exit pupil distance d_A; ``inf`` when the scale is within `allowance` of 1 (the fit
        cannot tell it from a telecentric lens).
    range_mm : tuple of float
        d_A for the scale ± `allowance` (the upper end ``inf`` when that reaches 1).
    expected_scale : float
        The scale the camera file's ``exit_pupil_distance_mm`` predicts (1.0 when telecentric).
    """

    scale: float
    scale_sigma: float
    distance_mm: float
    range_mm: tuple
    expected_scale: float

    @property
    def allowance(self) -> float:
        """3 standard errors of the fit plus the nominal pitches' tolerance (`NOMINAL_PITCH_TOLERANCE`)."""
        return 3.0 * self.scale_sigma + NOMINAL_PITCH_TOLERANCE * self.expected_scale

    @property
    def contradicts_camera(self) -> bool:
        """Whether the scale differs from the camera file's by more than the `allowance`."""
        return abs(self.scale - self.expected_scale) > self.allowance

    def describe(self) -> str:
        """``"46.0 mm (40.2-53.8)"`` or ``"telecentric within the fit (>= 2400 mm)"``, for messages."""
        low, high = self.range_mm
        if math.isinf(self.distance_mm):
            return "telecentric within the fit" + ("" if math.isinf(low) else f" (>= {low:.0f} mm)")
        return f"{self.distance_mm:.1f} mm ({low:.1f}-{high:.1f})"


def micro_image_scale(camera) -> float:
    """``(d_A + f_s)/d_A`` of a camera (1.0 when telecentric); from `lfproc.geometry` where it exists."""
    try:
        from ..geometry import micro_image_scale as scale
    except ImportError:
        return float(camera.micro_image_scale)
    return float(scale(camera))


def exit_pupil_from_scale(scale: float, camera) -> float:
    """d_A = f_s / (scale − 1), ``inf`` for scale ≤ 1; from `lfproc.geometry` where it exists."""
    try:
        from ..geometry import exit_pupil_from_scale as from_scale
    except ImportError:
        return camera.mla_focal_length_mm / (scale - 1.0) if scale > 1.0 else math.inf
    return float(from_scale(scale, camera))


def implied_exit_pupil(pitch_px: float, pitch_sigma_px: float, camera) -> ExitPupilEstimate:
    """The exit pupil distance the fitted pitch implies, for ``camera`` (`lfproc.Camera`)."""
    lens_pitch_px = camera.pitch_px
    scale = pitch_px / lens_pitch_px
    expected = micro_image_scale(camera)
    sigma = pitch_sigma_px / lens_pitch_px
    allowance = 3.0 * sigma + NOMINAL_PITCH_TOLERANCE * expected
    if _afocal(camera):     # telecentric by construction: no exit pupil to imply
        return ExitPupilEstimate(scale=scale, scale_sigma=sigma, distance_mm=math.inf, range_mm=(math.inf, math.inf),
                                 expected_scale=expected)
    distance = exit_pupil_from_scale(scale, camera) if scale - allowance > 1.0 else math.inf
    span = (exit_pupil_from_scale(scale + allowance, camera), exit_pupil_from_scale(scale - allowance, camera))
    return ExitPupilEstimate(scale=scale, scale_sigma=sigma, distance_mm=distance, range_mm=span,
                             expected_scale=expected)


def _afocal(camera) -> bool:
    """Whether ``camera`` (or a bare exit pupil distance) has doubly telecentric main optics: orthographic views
    (object-side telecentric) through a stop at infinity on the image side, as an objective + tube lens. Their
    micro images sit under their lenslets whatever the camera file says, so a pitch off the file's is the pixel
    size at the lenslets, not an exit pupil."""
    optics = getattr(camera, "main_optics", None)    # object-side telecentric: one lateral scale for every depth
    return (optics is not None and optics.lateral_sampling_um(camera) is not None
            and math.isinf(optics.exit_pupil_distance_mm))


def microscope_pitch_warning(source: str, estimate: ExitPupilEstimate, camera) -> str | None:
    """For a microscope camera: the measured pitch in pixels, and the relay magnification or pixel pitch it
    implies (module docstring), when it contradicts the camera file; ``None`` otherwise."""
    if not estimate.contradicts_camera:
        return None
    ratio = estimate.scale
    relay = camera.main_optics.relay_magnification
    m_hat = (f"decoding uses the camera file's m̂ {camera.m_hat}" if camera.micro_image_px_given else
             "decoding takes m̂ from the measured pitch")
    return (f"{source}: warning: the micro images are {ratio * camera.pitch_px:.4f} px apart but the camera file "
            f"predicts {camera.pitch_px:.4f} px ({100 * (ratio - 1):+.2f} %): a microscope is telecentric, so the "
            f"lenslets' focal plane reaches the sensor magnified {relay * ratio:.5g}, not {relay:g}; {m_hat} and "
            f"nothing else depends on the pixel size; for numbers made without a grid, set "
            f"microscope.relay_magnification = {relay * ratio:.5g} (sensor.pixel_pitch_mm stays the camera's pixel)")


def exit_pupil_warning(source: str, estimate: ExitPupilEstimate, camera_distance_mm) -> str | None:
    """The exit pupil the pitch implies, when it contradicts the camera file. ``camera_distance_mm`` is the
    camera file's exit pupil distance, or the camera itself: a microscope camera gets
    :func:`microscope_pitch_warning` (no exit pupil to blame)."""
    if _afocal(camera_distance_mm):
        return microscope_pitch_warning(source, estimate, camera_distance_mm)
    if hasattr(camera_distance_mm, "main_optics"):
        camera_distance_mm = camera_distance_mm.main_optics.exit_pupil_distance_mm
    if not estimate.contradicts_camera:
        return None
    given = "infinite (telecentric)" if math.isinf(camera_distance_mm) else f"{camera_distance_mm:.1f} mm"
    return (f"{source}: warning: the micro image pitch implies an exit pupil distance of {estimate.describe()} (scale "
            f"{estimate.scale:.6f} +- {estimate.scale_sigma:.6f}) but the camera file says {given} "
            f"(scale {estimate.expected_scale:.6f}); set main_lens.exit_pupil_distance_mm, or check mla.pitch_mm "
            f"and sensor.pixel_pitch_mm")


#: tiles per side of the sensor that `lattice_texture` samples (at most, fewer on small sensors)
TEXTURE_TILES = 4
#: tile size in lens pitches
TEXTURE_TILE_PITCHES = 12.0
#: `lattice_texture` compares micro images where the local white level is at least this share of the brightest
FULLY_LIT = 0.5


def lattice_texture(image, cfa: str, grid, tiles: int = TEXTURE_TILES) -> np.ndarray:
    """Texture ratios (module docstring) of up to ``tiles`` × ``tiles`` tiles spread over the sensor.

    Unlike `texture_ratio` this needs no calibration run: the lattice vector of each tile comes from a known
    ``grid`` (`lfproc.LensGrid`), and only the tiles (``TEXTURE_TILE_PITCHES`` lenses wide, plus a margin)
    are flattened, so it is cheap enough to run on every capture before decoding it.

    Returns
    -------
    numpy.ndarray
        One ratio per tile that holds lit micro images (dark tiles, e.g. outside the main lens's image
        circle, are left out); empty when no tile does.
    """
    from scipy import ndimage

    from ._flatten import flatten, smooth_large
    from ._monochrome import white_to_mono

    arr = np.asarray(image)
    h, w = arr.shape[:2]
    pitch = float(grid.pitch_px)
    core = int(round(TEXTURE_TILE_PITCHES * pitch))
    margin = int(math.ceil(3 * pitch))
    ny = max(1, min(tiles, h // max(core, 1)))
    nx = max(1, min(tiles, w // max(core, 1)))
    sigma = max(0.08 * pitch, 0.7)
    ratios = []
    for cy in (np.arange(ny) + 0.5) * h / ny:
        for cx in (np.arange(nx) + 0.5) * w / nx:
            y0 = max(0, int(cy - core / 2 - margin)) // 2 * 2
            x0 = max(0, int(cx - core / 2 - margin)) // 2 * 2
            y1, x1 = min(h, int(cy + core / 2 + margin)), min(w, int(cx + core / 2 + margin))
            mono = white_to_mono(arr[y0:y1, x0:x1], cfa if arr.ndim == 2 else "none")
            flattened = flatten(mono, pitch)
            if flattened.valid.mean() < 0.5:
                continue
            flat = ndimage.gaussian_filter(flattened.flat, sigma)
            envelope = smooth_large(flattened.above_floor, pitch)
            # well lit only: micro images cut by a vignetting edge differ from their neighbours in any image
            inside = ndimage.binary_erosion(envelope >= FULLY_LIT * float(np.percentile(envelope, 99)),
                                            iterations=max(1, int(round(pitch))))
            ratio = _grid_tile_ratio(flat, inside, grid, (cx - x0, cy - y0), (x0, y0), margin)
            if ratio is not None:
                ratios.append(ratio)
    return np.asarray(ratios, dtype=float)


def _grid_tile_ratio(flat, valid, grid, centre, origin, margin: int, max_samples: int = 20_000):
    """The texture ratio of one flattened crop (``origin`` its top-left (x, y) on the sensor, ``centre`` the
    tile's centre in the crop), comparing it with itself half a lattice vector each way where both ends are
    lit (``valid``: beyond a mechanical vignetting cut there is nothing to compare)."""
    rows, cols = np.meshgrid(np.arange(grid.rows), np.arange(grid.cols), indexing="ij")
    xy = grid.lens_xy(rows, cols)            # the lattice vector of the lens nearest the tile's centre
    r, q = np.unravel_index(np.argmin(np.hypot(xy[..., 0] - origin[0] - centre[0],
                                               xy[..., 1] - origin[1] - centre[1])), rows.shape)
    q2 = q + 1 if q + 1 < grid.cols else q - 1
    a = (xy[r, q2] - xy[r, q]) * (1 if q2 > q else -1)
    reach = int(math.ceil(0.5 * float(np.hypot(*a)))) + 2
    h, w = flat.shape
    lo = max(reach, margin // 2)
    ys, xs = np.arange(lo, h - lo), np.arange(lo, w - lo)
    if len(ys) < 2 or len(xs) < 2:
        return None
    stride = max(1, int(math.sqrt(len(ys) * len(xs) / max_samples)))
    yy, xx = np.meshgrid(ys[::stride], xs[::stride], indexing="ij")
    lit = (valid[np.clip(np.rint(yy + 0.5 * a[1]).astype(int), 0, h - 1), np.clip(np.rint(xx + 0.5 * a[0]).astype(int), 0, w - 1)]
           & valid[np.clip(np.rint(yy - 0.5 * a[1]).astype(int), 0, h - 1), np.clip(np.rint(xx - 0.5 * a[0]).astype(int), 0, w - 1)])
    if lit.sum() < 100:
        return None
    num, den = _half_vector_terms(flat, yy[lit], xx[lit], a)
    return num / den if den > 0 else None
