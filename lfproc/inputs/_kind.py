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
    refused; below it the texture ratio says nothing (0.02–0.04 holds only simulated white images).
  - **lens-to-lens contrast** (`lens_scene_contrast`): the brightness at the centre of every micro image
    (`lens_brightness`, a Gaussian of σ = 0.15 pitch, the Bayer colours weighted equally) is, in a white
    image, the main lens's smooth vignetting times each lenslet's own transmission, and in a capture the scene
    as the central view sees it: a picture, whose neighbouring lenses agree. Its variation about a local
    quadratic fit over 13 × 13 lenses (the lens itself left out; hexagonal rows in lattice coordinates) is
    split by pairs of neighbouring lenses: what neighbours share (their covariance, from the robust spreads of
    their sums and differences) is the contrast; noise and lenslets that pass light unevenly vary each lens on
    its own and cancel. It warns where that contrast is above `SCENE_CONTRAST_LIMIT` (0.5 %) and the
    neighbours' correlation beyond noise above `SCENE_CORRELATION_LIMIT` (0.3). Real white images: the sea
    urchin's radiometry frame (1.7 % lens to lens, all of it lens by lens: contrast 0.00 %, correlation −0.31),
    the HyLFM flat 0.00 %, two more microscopes' and a photographic SPC's 0.19–0.24 % (correlation ≤ 0.52);
    simulated whites 0.00–0.09 %, 0.34 % with dust specks, 0.64 % and correlation 0.03 through lenslets 4 %
    uneven. Low-texture captures: 0.71 % (±5 %, 3 m; correlation 0.79) to 0.95 % (±10 %, 800 mm), 0.87 %
    under 300-photon shot noise (0.63). Their values on every real file: docs/real-data.md.
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

from ..calibrate import TEXTURE_LIMIT
from ..errors import LfprocError, warn

#: fewest lenses per side of a light field judged by `lens_flatness` (a crop of a few lenses may be uniform)
MIN_LENSES_PER_SIDE = 20
#: lens-to-lens brightness shared with the neighbouring lenses above which a white image is warned about (never
#: refused)
SCENE_CONTRAST_LIMIT = 0.005
#: ... when that brightness is also this correlated between neighbours (a picture; uneven lenslets vary lens by lens)
SCENE_CORRELATION_LIMIT = 0.3
#: fewest pairs of neighbouring lenses that tell (fewer: no doubt is raised)
MIN_NEIGHBOUR_PAIRS = 100
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
    contrast, correlation : float
        The lens-to-lens contrast shared with neighbouring lenses, relative to the level, and the correlation of
        the lens brightness between neighbours beyond noise (`lens_scene_contrast`).
    """

    texture: float
    contrast: float
    correlation: float

    @property
    def is_scene(self) -> bool:
        """A definite contradiction: the texture ratio is above `TEXTURE_LIMIT`."""
        return self.texture > TEXTURE_LIMIT

    @property
    def doubts(self) -> tuple:
        """The reasons (plain text, ``()`` when none) to doubt, short of refusing, that this is a white image."""
        reasons = []
        if self.contrast > SCENE_CONTRAST_LIMIT and self.correlation > SCENE_CORRELATION_LIMIT:
            reasons.append(f"the brightness of its micro images varies from lens to lens like a picture (lens-to-lens "
                           f"contrast {100 * self.contrast:.1f} % shared with neighbouring lenses, neighbour "
                           f"correlation {self.correlation:.2f}; a white image's lenslets vary each on its own: "
                           f"correlation < {SCENE_CORRELATION_LIMIT})")
        return tuple(reasons)


def white_evidence(image, cfa: str, grid, texture: float | None = None) -> WhiteEvidence:
    """Both measures of the module docstring for ``image`` on ``grid``; ``texture`` when known already
    (`lfproc.calibrate.GridEstimate.texture`, the same number)."""
    from ..calibrate import white_texture

    texture = white_texture(image, cfa, grid) if texture is None else float(texture)
    return WhiteEvidence(texture, *lens_scene_contrast(image, cfa, grid))


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
                          f"their neighbours (texture ratio {evidence.texture:.3f}; real white images give < 0.01, "
                          f"refused above {TEXTURE_LIMIT}); give a white image (a uniform bright surface, e.g. through "
                          f"a diffuser) as `white=`, or pass `white_is_white=True` if this is one")
    if evidence.doubts:
        warn(f"{source}: may be a capture of a scene, not a white image: {'; and '.join(evidence.doubts)}; "
             f"if it is a white image, say so with `white_is_white=True`")
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
    """``(contrast, correlation)``: how much the brightness at the micro images' centres (`lens_brightness`)
    varies from lens to lens *together with the neighbouring lenses*, relative to the local level, and the
    correlation of neighbours beyond noise.

    On up to `SCENE_TILES`² tiles of `SCENE_TILE_LENSES`² lenses spread over the grid, over the well-lit
    lenses (at least half the 99th percentile of all tiles, two lenses in from the edge of that region),
    ``r`` = brightness / trend − 1, the trend a local quadratic fit over `SCENE_TREND_LENSES`² lenses
    (`local_quadratic_trend`). For the pairs of neighbouring lenses (along both lattice axes) the robust
    spreads (1.4826 × MAD) of their sum and difference, ``s₊`` and ``s₋``, give the covariance of neighbours
    ``(s₊² − s₋²) / 4``: independent variations (noise; lenslets that pass light unevenly, each on its own)
    add equally to both and cancel, a picture's (the scene as the central view sees it) does not.
    ``contrast = sqrt(max(covariance, 0))``; ``correlation = (s₊² − s₋²) / (s₊² + s₋² − 4 n²)``, ``n`` the
    noise measured from two interleaved halves of the same pixels. ``(0, 0)`` where fewer than
    `MIN_NEIGHBOUR_PAIRS` pairs tell, or where the noise accounts for all the variation.
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
        return 0.0, 0.0
    floor = 0.5 * float(np.percentile(pooled, 99))
    sums, differences, noise = [], [], []
    for t, v in zip(tiles, valid):
        level = np.where(v, t[0], 0.0)
        inner = ndimage.binary_erosion(v & (level >= floor), iterations=2)
        trend = local_quadratic_trend(level, inner, SCENE_TREND_LENSES, grid.kind == "hexagonal")
        inner &= np.isfinite(trend) & (trend > 0)
        safe = np.where(inner, trend, 1.0)
        ratio = np.where(inner, level / safe - 1.0, 0.0)
        noise.append((0.5 * (t[1] - t[2]) / safe)[inner])
        for first, second, both in ((ratio[:, :-1], ratio[:, 1:], inner[:, :-1] & inner[:, 1:]),
                                    (ratio[:-1], ratio[1:], inner[:-1] & inner[1:])):
            sums.append((first + second)[both])
            differences.append((first - second)[both])
    sums, differences, noise = (np.concatenate(x) for x in (sums, differences, noise))
    if sums.size < MIN_NEIGHBOUR_PAIRS:
        return 0.0, 0.0
    mad = lambda x: 1.4826 * float(np.median(np.abs(x - np.median(x))))   # noqa: E731
    plus, minus, n = mad(sums) ** 2, mad(differences) ** 2, mad(noise) ** 2
    signal = plus + minus - 4.0 * n
    if signal <= 0.0:
        return 0.0, 0.0
    return float(np.sqrt(max(0.25 * (plus - minus), 0.0))), float(np.clip((plus - minus) / signal, -1.0, 1.0))


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
                          f">= {100 * WHITE_FLATNESS:.1f} %); pass the capture as `capture=` and the white image as "
                          f"`white=`")
