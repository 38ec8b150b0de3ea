"""Swapped inputs: a capture given as the white image, a white image given as the capture.

* **A capture given as the white image** (``lfproc calibrate``, ``--white``): a refusal only where the
  contradiction is definite, a warning where a heuristic is not sure, and ``--white-is-white``
  (``white_is_white=True``) to say "this is my white image" and skip both. Two measures, each under one name
  with one number everywhere (`WhiteEvidence`; their values on every real and simulated file are tabulated in
  docs/real-data.md by scripts/real_data_report.py):

  - **texture ratio** (`lfproc.calibrate.white_texture`, the largest over up to 4 × 4 tiles of well-lit
    micro images): in a white image every micro image repeats its neighbour. Real white images measure
    0.0016–0.0063 (a light-field microscope's 8-bit radiometry frame, a 16-bit flat), simulated ones
    0.0005–0.008 (noise, hot pixels, vignetting with a sharp rim cut, 8-bit quantisation), up to 0.022 with
    dust, 30 DN and uneven lenslets together, 0.039 for a tiny 9 × 12-lens white dark beyond its lenses; real captures 0.13 and 0.62, the bundled sample's 0.11, the Lytro sample's 0.067, a
    faint far grating 0.19. Above `TEXTURE_LIMIT` (0.04, six times the largest real white's) the image is
    refused; above `TEXTURE_WARN` (0.02) one line warns.
  - **lens-to-lens contrast** (`lens_scene_contrast`): the brightness at the centre of every micro image
    (`lens_brightness`, a Gaussian of σ = 0.15 pitch, the Bayer colours weighted equally) is, in a white
    image through identical lenslets, the main lens's smooth vignetting, and in a capture the scene as the
    central view sees it. Its robust spread about a local quadratic fit over 13 × 13 lenses (the lens itself
    left out; hexagonal rows in lattice coordinates), beyond the noise measured from two interleaved halves
    of the same pixels (on up to 3 × 3 tiles of 40 × 40 lenses). It cannot tell uneven lenslets from a
    low-texture scene far from the focus (both vary the micro images' brightness, not their content): a
    real microscope radiometry frame measures 1.6 %, more than low-texture captures (0.81 % at ±5 %, 3 m;
    1.04 % at ±10 %, 800 mm). It therefore only warns, above `SCENE_CONTRAST_LIMIT` (0.6 %) and
    `NOISE_MULTIPLE` (2) × its noise. Simulated whites (renders at 16 and 8 bits, strong vignetting,
    hexagonal with a rim cut, the Lytro sample's) measure 0.00–0.03 %, 0.5 % with 300-photon shot noise.
* **A white image given as the capture**: decoded (and devignetted), a white image is a smooth field with
  no scene in it. Each view is a pinhole image of the scene, sharp at every depth, so a capture shows its
  scene in every view at lens resolution. For the central view and the four views halfway to the rim, the
  99th percentile of |V / median5x5(V) − 1| over the interior lenses is taken (`lens_flatness`); where
  the median of these stays below `WHITE_FLATNESS` (0.5 %) the capture shows no scene and is refused.
  Measured on renders of the sample's camera: a white image given as the capture 0.00 % (devignetted by
  itself) and 0.13 % (an 8-bit copy, heavy shot noise); captures 1.4 % (a faint distant grating, ±10 %),
  2.5 % (a ±10 % low-contrast texture), 9.8–14 % (noisy or textured planes), 57 % (the bundled sample).
  Not recognised: a *different*, very noisy frame of a white image (8.9 %: its noise reads as a scene).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from ..calibrate import TEXTURE_LIMIT, TEXTURE_WARN
from ..errors import LfprocError, LfprocWarning

#: fewest lenses per side of a light field judged by `lens_flatness` (a crop of a few lenses may be uniform)
MIN_LENSES_PER_SIDE = 20
#: spread of the lens-level brightness beyond noise above which a white image is warned about (never refused)
SCENE_CONTRAST_LIMIT = 0.006
#: ... and it must exceed the noise of the lens brightness by this factor (a noisy white's estimate scatters)
NOISE_MULTIPLE = 2.0
#: lens-level trend window (lenses): wider than a scene's detail, far narrower than the vignetting
SCENE_TREND_LENSES = 13
#: 99th percentile of the lens-to-neighbourhood brightness difference below which a capture is a white image
WHITE_FLATNESS = 0.005


@dataclass(frozen=True)
class WhiteEvidence:
    """What says a "white image" may be a capture of a scene (module docstring): each number under one name.

    Attributes
    ----------
    texture : float
        The texture ratio (`lfproc.calibrate.white_texture`).
    contrast, noise : float
        The lens-to-lens contrast beyond noise and that noise (`lens_scene_contrast`), relative to the level.
    """

    texture: float
    contrast: float
    noise: float

    @property
    def is_scene(self) -> bool:
        """A definite contradiction: the texture ratio is above `TEXTURE_LIMIT`."""
        return self.texture > TEXTURE_LIMIT

    @property
    def doubts(self) -> tuple:
        """The reasons (plain text, ``()`` when none) to doubt, short of refusing, that this is a white image."""
        reasons = []
        if TEXTURE_WARN < self.texture <= TEXTURE_LIMIT:
            reasons.append(f"its micro images differ a little from their neighbours (texture ratio {self.texture:.3f}; "
                           f"white images give < {TEXTURE_WARN}, captures of scenes > {TEXTURE_LIMIT})")
        if self.contrast > SCENE_CONTRAST_LIMIT and self.contrast > NOISE_MULTIPLE * self.noise:
            reasons.append(f"the brightness of its micro images varies from lens to lens (lens-to-lens contrast "
                           f"{100 * self.contrast:.1f} % beyond noise; identical lenslets under uniform light give "
                           f"< {100 * SCENE_CONTRAST_LIMIT:.1f} %, uneven lenslets and low-texture scenes more)")
        return tuple(reasons)


def white_evidence(image, cfa: str, grid, texture: float | None = None) -> WhiteEvidence:
    """Both measures of the module docstring for ``image`` on ``grid``; ``texture`` when known already
    (`lfproc.calibrate.GridEstimate.texture`, the same number)."""
    from ..calibrate import white_texture

    texture = white_texture(image, cfa, grid) if texture is None else float(texture)
    contrast, noise = lens_scene_contrast(image, cfa, grid)
    return WhiteEvidence(texture, contrast, noise)


def check_white_is_white(source: str, image, cfa: str, grid, *, white_is_white: bool = False,
                         texture: float | None = None) -> WhiteEvidence | None:
    """Refuse a white image that is definitely a capture of a scene, warn (`warnings.warn`, one line) where a
    measure doubts it (module docstring); nothing is measured with ``white_is_white``.

    Returns
    -------
    WhiteEvidence or None
        The measures (None with ``white_is_white``).

    Raises
    ------
    LfprocError
        One line naming ``source`` when its texture ratio is above `TEXTURE_LIMIT`.
    """
    if white_is_white:
        return None
    evidence = white_evidence(image, cfa, grid, texture)
    if evidence.is_scene:
        raise LfprocError(f"{source}: this is a capture of a scene, not a white image: its micro images differ from "
                          f"their neighbours (texture ratio {evidence.texture:.3f}; white images give < {TEXTURE_WARN}, "
                          f"refused above {TEXTURE_LIMIT}); give a white image (a uniform bright surface, e.g. through "
                          f"a diffuser) as white=, or pass white_is_white=True if this is one")
    if evidence.doubts:
        warnings.warn(f"{source}: may be a capture of a scene, not a white image: {'; and '.join(evidence.doubts)}; "
                      f"if it is a white image, say so with white_is_white=True", LfprocWarning,
                      stacklevel=2)
    return evidence


def lens_brightness(image, cfa: str, grid, rows, cols) -> np.ndarray:
    """``(3, len(rows), len(cols))``: the brightness at the centre of the micro images of lenses ``rows`` ×
    ``cols`` of ``grid``, from all pixels and from each of two halves of them; NaN where the stencil leaves
    the sensor.

    A Gaussian of σ = 0.15 pitch around the lens centre (`grid.lens_xy`, sub-pixel); on a Bayer mosaic each
    colour is averaged on its own and the three means averaged, so the colour mix does not change with the
    Bayer phase under a lens. The halves are the 2 × 2 cells of even and of odd parity (a checkerboard of
    whole cells, so both hold every colour): two estimates whose difference is noise.
    """
    arr = np.asarray(image)
    if arr.ndim == 3:
        arr, cfa = arr.mean(axis=2, dtype=np.float32), "none"
    h, w = arr.shape
    sigma = 0.15 * float(grid.pitch_px)
    r = max(1, int(np.ceil(2.0 * sigma)))
    off = np.arange(-r, r + 1)
    rr, cc = np.meshgrid(np.asarray(rows), np.asarray(cols), indexing="ij")
    xy = grid.lens_xy(rr, cc)
    cx, cy = np.rint(xy[..., 0]).astype(int), np.rint(xy[..., 1]).astype(int)
    inside = (cx - r >= 0) & (cx + r < w) & (cy - r >= 0) & (cy + r < h)
    py = np.clip(cy, r, h - 1 - r)[..., None, None] + off[:, None]
    px = np.clip(cx, r, w - 1 - r)[..., None, None] + off[None, :]
    weight = np.exp(-0.5 * ((py - xy[..., 1, None, None]) ** 2 + (px - xy[..., 0, None, None]) ** 2)
                    / sigma ** 2).astype(np.float32)
    values = arr[py, px].astype(np.float32)
    parity = (py // 2 + px // 2) % 2
    channels = (np.array(["RGB".index(ch) for ch in cfa])[(py % 2) * 2 + (px % 2)]
                if cfa not in (None, "", "none") else np.zeros_like(parity))
    out = np.empty((3,) + rr.shape)
    present = np.unique(channels)
    for k, part in enumerate((None, 0, 1)):
        wk = weight if part is None else weight * (parity == part)
        means = []
        for ch in present:
            wc = wk * (channels == ch)
            means.append((values * wc).sum(axis=(-2, -1)) / np.maximum(wc.sum(axis=(-2, -1)), 1e-12))
        out[k] = np.where(inside, np.mean(means, axis=0), np.nan)
    return out


def local_quadratic_trend(values: np.ndarray, use: np.ndarray, size: int, hexagonal: bool = False) -> np.ndarray:
    """Per lens, the value at it of the quadratic surface fitted (least squares) to the ``use`` lenses of the
    ``size`` × ``size`` lenses around it, itself left out: the vignetting's smooth curvature is followed, a
    scene's lens-to-lens detail is not. On a hexagonal lattice odd rows sit half a pitch to the right
    (`LensGrid.lens_xy`): the fit is in lattice coordinates (an affine map of the sensor's, under which a
    quadratic stays a quadratic), with kernels for even and for odd centre rows. NaN where the fit is
    undetermined."""
    from scipy import ndimage

    h = size // 2
    u = np.arange(-h, h + 1, dtype=np.float64)
    uy, ux = np.meshgrid(u, u, indexing="ij")
    w = use.astype(np.float64)
    wv = w * np.where(use, values, 0.0)
    trend = np.full(values.shape, np.nan)
    parities = (0, 1) if hexagonal else (0,)
    for parity in parities:
        # x of the neighbour (row + uy) relative to the centre (row of this parity), in pitches
        dx = ux + (0.5 * (np.mod(parity + uy, 2) - parity) if hexagonal else 0.0)
        basis = [np.ones_like(ux), dx, uy, dx * dx, dx * uy, uy * uy]
        normal = np.empty(values.shape + (6, 6))
        rhs = np.empty(values.shape + (6,))
        for i in range(6):
            kernel = basis[i].copy()
            kernel[h, h] = 0.0                                 # leave the lens itself out
            rhs[..., i] = ndimage.correlate(wv, kernel, mode="constant")
            for j in range(i, 6):
                k2 = basis[i] * basis[j]
                k2[h, h] = 0.0
                normal[..., i, j] = normal[..., j, i] = ndimage.correlate(w, k2, mode="constant")
        rows = (np.arange(values.shape[0]) % 2 == parity)[:, None] if hexagonal else np.ones((values.shape[0], 1), bool)
        ok = rows & (normal[..., 0, 0] >= 12)
        if ok.any():
            a, b = normal[ok], rhs[ok]
            good = np.linalg.cond(a) < 1e8
            coeffs = np.full(b.shape, np.nan)
            coeffs[good] = np.linalg.solve(a[good], b[good][..., None])[..., 0]
            trend[ok] = coeffs[:, 0]
    return trend


#: lens-level test: tiles of this many lenses a side, at most ``SCENE_TILES`` × ``SCENE_TILES`` of them spread
#: over the sensor (a sample of the lenses: cheap on a 40-megapixel sensor)
SCENE_TILE_LENSES = 40
SCENE_TILES = 3


def lens_scene_contrast(image, cfa: str, grid) -> tuple[float, float]:
    """``(contrast, noise)``: how much the brightness at the micro images' centres (`lens_brightness`) varies
    from lens to lens beyond noise, and that noise, both relative to the local level.

    On up to `SCENE_TILES`² tiles of `SCENE_TILE_LENSES`² lenses spread over the grid, over the well-lit
    lenses (at least half the 99th percentile of all tiles, two lenses in from the edge of that region): the
    robust spread (1.4826 × MAD) of brightness / trend − 1 is ``s``, the trend a local quadratic fit over
    `SCENE_TREND_LENSES`² lenses (`local_quadratic_trend`); the robust spread of half the difference of
    the two halves' estimates is the noise ``n``; ``contrast = sqrt(max(s² − n², 0))``. ``(0, inf)``
    where fewer than 25 lenses tell.
    """
    from scipy import ndimage

    def starts(count):
        size = min(SCENE_TILE_LENSES, count)
        n = max(1, min(SCENE_TILES, count // size))
        return [int(round(v)) // 2 * 2 for v in np.linspace(0, count - size, n)], size   # even: hexagonal parity

    (row_starts, ny), (col_starts, nx) = starts(grid.rows), starts(grid.cols)
    tiles = [lens_brightness(image, cfa, grid, np.arange(r0, r0 + ny), np.arange(c0, c0 + nx))
             for r0 in row_starts for c0 in col_starts]
    valid = [np.isfinite(t).all(axis=0) for t in tiles]
    pooled = np.concatenate([t[0][v] for t, v in zip(tiles, valid)])
    if pooled.size < 25:
        return 0.0, float("inf")
    floor = 0.5 * float(np.percentile(pooled, 99))
    ratios, diffs = [], []
    for t, v in zip(tiles, valid):
        level = np.where(v, t[0], 0.0)
        inner = ndimage.binary_erosion(v & (level >= floor), iterations=2)
        trend = local_quadratic_trend(level, inner, SCENE_TREND_LENSES, grid.kind == "hexagonal")
        inner &= np.isfinite(trend) & (trend > 0)
        ratios.append(level[inner] / trend[inner] - 1.0)
        diffs.append(0.5 * (t[1][inner] - t[2][inner]) / trend[inner])
    ratios, diffs = np.concatenate(ratios), np.concatenate(diffs)
    if ratios.size < 25:
        return 0.0, float("inf")
    mad = lambda x: 1.4826 * float(np.median(np.abs(x - np.median(x))))   # noqa: E731
    spread, noise = mad(ratios), mad(diffs)
    return float(np.sqrt(max(spread * spread - noise * noise, 0.0))), noise


#: most interior lenses per view `lens_flatness` judges: a larger light field is judged on a regular subsample
#: (every s-th lens along both axes), which keeps its 99th percentile and costs a fraction of the whole
FLATNESS_SAMPLE_LENSES = 20_000


def lens_flatness(views: np.ndarray, view_mask=None) -> float:
    """How much a decoded light field's views vary from lens to lens (module docstring).

    For the central view and the four views halfway to the rim (those that carry light), the 99th
    percentile of |V / median5x5(V) − 1| over the interior lit lenses (channels averaged); the median of
    these. Each view is a pinhole image of the scene, sharp at every depth, so scene detail shows at lens
    resolution however far the scene is from the focus plane. ``inf`` where too few lenses tell (fewer than
    `MIN_LENSES_PER_SIDE` per side). Over `FLATNESS_SAMPLE_LENSES` interior lenses, every s-th lens along
    both axes is judged (the fewest s that keep it under that; the median of each judged lens's full 5 × 5
    neighbourhood): an Illum-sized light field takes a fifth of the time of all its lenses.
    """
    views = np.asarray(views)
    m = views.shape[0]
    mask = np.ones((m, m), bool) if view_mask is None else np.asarray(view_mask, bool)
    c, h = (m - 1) // 2, max(1, (m - 1) // 4)
    chosen = [(ky, kx) for ky, kx in ((c, c), (c - h, c), (c + h, c), (c, c - h), (c, c + h)) if mask[ky, kx]]
    ny, nx = views.shape[2:4]
    if not chosen or min(ny, nx) < MIN_LENSES_PER_SIDE:
        return float("inf")
    step = int(np.ceil(np.sqrt((ny - 4) * (nx - 4) / FLATNESS_SAMPLE_LENSES)))
    rows, cols = np.arange(2, ny - 2, step), np.arange(2, nx - 2, step)
    stack = np.stack([views[ky, kx].mean(axis=-1) for ky, kx in chosen]).astype(np.float32)   # (V, Ny, Nx)
    near = np.arange(-2, 3)
    around = stack[:, (rows[:, None] + near)[:, None, :, None], (cols[:, None] + near)[None, :, None, :]]
    trend = np.median(around.reshape(*around.shape[:3], 25), axis=-1)       # (V, rows, cols): median of 5 x 5
    inner = stack[:, rows[:, None], cols[None, :]]
    values = []
    for view, level in zip(inner, trend):
        top = float(np.percentile(level, 95))
        lit = level > 0.05 * top
        if top > 0 and lit.sum() >= 25:
            values.append(float(np.percentile(np.abs(view[lit] / level[lit] - 1.0), 99)))
    return float(np.median(values)) if values else float("inf")


def check_capture_is_not_white(source: str, views: np.ndarray, view_mask=None) -> None:
    """Refuse a decoded "capture" that is a white image (module docstring)."""
    flatness = lens_flatness(views, view_mask)
    if flatness < WHITE_FLATNESS:
        raise LfprocError(f"{source}: this looks like a white image, not a capture: decoded, its lenses show a smooth "
                          f"field with no scene ({100 * flatness:.2f} % lens-to-lens variation, captures show "
                          f">= {100 * WHITE_FLATNESS:.1f} %); pass the capture as capture= and the white image as "
                          f"white=")
