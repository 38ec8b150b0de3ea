"""An independent white-image generator for the calibration tests (deliberately not lfproc.simulate).

A white image of a Standard Plenoptic Camera shows one bright micro image per micro lens: the image
of the main lens's aperture, a disk centred exactly on the lens centre, clipped to the lens's cell
(the set of sensor points nearer to that lens than to any other). This module renders that picture
by brute force and nothing cleverer:

* every pixel is area-integrated by averaging ``supersample`` × ``supersample`` point samples;
* a sample is lit when its distance to the *nearest* lattice point is at most ``disk_radius_px``
  (nearest point = the cell clip), the nearest point found by trying the lattice points around it;
* a radial vignetting factor ``1 - vignetting·(r/r_corner)²`` darkens the border, and an optional
  sharp cut beyond ``cut_radius_px`` (mechanical vignetting) leaves border lenses dark or cut in part;
* Gaussian noise and hot pixels are added, and the result is quantised to 16 bits.

The true lens centres are ``grid.lens_xy(...)`` of the ``LensGrid`` passed in: the lattice convention
of ``lfproc/grid.py`` is the one thing shared with the code under test.
"""

from __future__ import annotations

import math

import numpy as np

from lfproc.grid import LensGrid


def nearest_lattice_distance(x: np.ndarray, y: np.ndarray, grid: LensGrid) -> np.ndarray:
    """Distance from each point (x, y) to the nearest point of the (infinite) lattice of ``grid``."""
    u, v = grid.axes
    dx, dy = x - grid.origin_xy_px[0], y - grid.origin_xy_px[1]
    along_v = (dx * v[0] + dy * v[1]) / grid.row_spacing_px
    best = np.full(np.shape(x), np.inf)
    base_row = np.floor(along_v)
    for row_step in (-1.0, 0.0, 1.0, 2.0):
        row = base_row + row_step
        centre_col = grid.lens_xy(row, 0.0)  # lens (row, 0) of every candidate row
        along_u = ((x - centre_col[..., 0]) * u[0] + (y - centre_col[..., 1]) * u[1]) / grid.pitch_px
        base_col = np.floor(along_u)
        for col_step in (0.0, 1.0):
            # lens_xy adds the half-pitch shift of odd rows itself, so base_col counts from that row's lens 0
            centre = grid.lens_xy(row, base_col + col_step)
            dist = np.hypot(x - centre[..., 0], y - centre[..., 1])
            best = np.minimum(best, dist)
    return best


def white_image(shape, grid: LensGrid, disk_radius_px: float, *, vignetting: float = 0.0,
                cut_radius_px: float | None = None, noise_sigma: float = 0.0, hot_pixels: int = 0,
                peak: float = 50000.0, black: float = 0.0, supersample: int = 4, seed: int = 0) -> np.ndarray:
    """Render a 16-bit white image (uint16, shape ``shape``) of the lattice ``grid``.

    Parameters
    ----------
    shape : (int, int)
        Image rows and columns.
    grid : LensGrid
        The true lattice; every lattice point (also those outside ``grid.rows × grid.cols``) carries a lens.
    disk_radius_px : float
        Radius of each micro image disk; disks larger than half the pitch are clipped to their cell.
    vignetting : float
        Relative brightness lost at the image corners (quadratic radial falloff).
    cut_radius_px : float or None
        Beyond this distance from the image centre the sensor is dark (cuts border micro images).
    noise_sigma : float
        Standard deviation of additive Gaussian noise, as a fraction of ``peak``.
    hot_pixels : int
        Number of pixels set to the maximum 65535.
    peak, black : float
        Digital value of a fully lit pixel at the centre, and of a dark pixel.
    supersample : int
        Point samples per pixel along each axis (area integration).
    seed : int
        Seed of the noise and hot pixel positions.
    """
    rows, cols = shape
    yy, xx = np.meshgrid(np.arange(rows, dtype=np.float64), np.arange(cols, dtype=np.float64), indexing="ij")
    cy, cx = (rows - 1) / 2.0, (cols - 1) / 2.0
    corner = math.hypot(cy, cx)
    lit = np.zeros(shape)
    steps = (np.arange(supersample) + 0.5) / supersample - 0.5
    for sy in steps:
        for sx in steps:
            x, y = xx + sx, yy + sy
            on = nearest_lattice_distance(x, y, grid) <= disk_radius_px
            r = np.hypot(x - cx, y - cy)
            gain = 1.0 - vignetting * (r / corner) ** 2
            if cut_radius_px is not None:
                gain = np.where(r <= cut_radius_px, gain, 0.0)
            lit += on * gain
    lit /= supersample * supersample
    rng = np.random.default_rng(seed)
    image = black + peak * lit + rng.normal(0.0, noise_sigma * peak, size=shape)
    if hot_pixels:
        flat = image.reshape(-1)
        flat[rng.choice(flat.size, size=hot_pixels, replace=False)] = 65535.0
    return np.clip(np.rint(image), 0, 65535).astype(np.uint16)


def covering_grid(shape, kind: str, pitch_px: float, rotation_deg: float, offset_xy_px=(0.0, 0.0)) -> LensGrid:
    """A lattice with lens (0, 0) near the top-left and enough rows and columns to cover ``shape``.

    ``offset_xy_px`` moves the whole lattice (sub-pixel offsets).
    """
    rows_px, cols_px = shape
    spacing = pitch_px * (math.sqrt(3.0) / 2.0 if kind == "hexagonal" else 1.0)
    margin = 3
    n_rows = int(math.ceil(max(rows_px, cols_px) * 1.2 / spacing)) + 2 * margin
    n_cols = int(math.ceil(max(rows_px, cols_px) * 1.2 / pitch_px)) + 2 * margin
    centre = np.array([(cols_px - 1) / 2.0, (rows_px - 1) / 2.0]) + np.asarray(offset_xy_px, dtype=float)
    probe = LensGrid(kind, pitch_px, rotation_deg, (0.0, 0.0), n_rows, n_cols)
    middle = probe.lens_xy(2 * (n_rows // 4), n_cols // 2)  # an even row keeps the parity convention
    origin = centre - middle
    return LensGrid(kind, pitch_px, rotation_deg, tuple(origin), n_rows, n_cols)


def true_centres_inside(grid: LensGrid, shape, margin_px: float) -> np.ndarray:
    """True lens centres (N, 2) at least ``margin_px`` inside the image."""
    xy = grid.centers_xy_px().reshape(-1, 2)
    rows, cols = shape
    keep = ((xy[:, 0] >= margin_px) & (xy[:, 0] <= cols - 1 - margin_px)
            & (xy[:, 1] >= margin_px) & (xy[:, 1] <= rows - 1 - margin_px))
    return xy[keep]


# ----------------------------------------------------------------------------- non-rigid lattices and spots
def drifting_centres(shape, pitch_from: float, pitch_to: float, rotation_deg: float = 0.0, offset=(0.0, 0.0),
                     jitter_px: float = 0.0, seed: int = 0):
    """True centres of a rectangular lattice whose pitch drifts linearly from ``pitch_from`` to ``pitch_to``.

    In the lattice frame (a, b) (the sensor frame rotated by ``rotation_deg`` about the image centre,
    moved by ``offset``) lens i of a row sits at ``X(i) = p0·i + k·i²/2`` with the local pitch
    p0 + k·i running from ``pitch_from`` at one edge to ``pitch_to`` at the other (PlenoptiCam's white
    image *d*); rows alike. ``jitter_px`` adds independent random offsets to every centre (a lattice that
    no smooth model describes). Returns ``(centres (J, I, 2) in sensor (x, y), X(i) coefficients)``.
    """
    rows, cols = shape
    half = 0.5 * max(rows, cols) * 1.5
    p0 = 0.5 * (pitch_from + pitch_to)
    k = (pitch_to - pitch_from) / (2.0 * half / p0)  # pitch change per lens
    n = int(half / min(pitch_from, pitch_to)) + 3
    i = np.arange(-n, n + 1, dtype=np.float64)
    along = p0 * i + 0.5 * k * i * i
    a, b = np.meshgrid(along, along)  # (J, I): a along rows (x), b along columns (y)
    rng = np.random.default_rng(seed)
    a = a + rng.normal(0.0, jitter_px / math.sqrt(2.0), a.shape) if jitter_px else a
    b = b + rng.normal(0.0, jitter_px / math.sqrt(2.0), b.shape) if jitter_px else b
    t = math.radians(rotation_deg)
    cx, cy = (cols - 1) / 2.0 + offset[0], (rows - 1) / 2.0 + offset[1]
    x = cx + a * math.cos(t) - b * math.sin(t)
    y = cy + a * math.sin(t) + b * math.cos(t)
    return np.stack([x, y], -1), (p0, k, n, cx, cy, t)


def drifting_white(shape, pitch_from: float, pitch_to: float, *, rotation_deg: float = 0.0, offset=(0.0, 0.0),
                   disk_fraction: float = 0.45, jitter_px: float = 0.0, noise_sigma: float = 0.01,
                   supersample: int = 4, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """A uint16 white image of disks (radius ``disk_fraction`` × local pitch) on a drifting lattice.

    Returns the image and the true centres (N, 2) (see :func:`drifting_centres`); each sample point is
    lit when it lies within the radius of the nearest of the 3 × 3 lenses around its approximate index.
    """
    centres, (p0, k, n, cx, cy, t) = drifting_centres(shape, pitch_from, pitch_to, rotation_deg, offset,
                                                      jitter_px, seed)
    rows, cols = shape
    yy, xx = np.meshgrid(np.arange(rows, dtype=np.float64), np.arange(cols, dtype=np.float64), indexing="ij")
    steps = (np.arange(supersample) + 0.5) / supersample - 0.5
    lit = np.zeros(shape)

    def approx_index(along):  # inverse of p0·i + k·i²/2
        if abs(k) < 1e-12:
            return np.rint(along / p0)
        return np.rint((-p0 + np.sqrt(np.maximum(p0 * p0 + 2.0 * k * along, 0.0))) / k)

    for sy in steps:
        for sx in steps:
            x, y = xx + sx, yy + sy
            a = (x - cx) * math.cos(t) + (y - cy) * math.sin(t)
            b = -(x - cx) * math.sin(t) + (y - cy) * math.cos(t)
            i0, j0 = approx_index(a).astype(int) + n, approx_index(b).astype(int) + n
            best = np.full(shape, np.inf)
            radius = np.zeros(shape)
            for dj in (-1, 0, 1):
                for di in (-1, 0, 1):
                    jj = np.clip(j0 + dj, 0, centres.shape[0] - 1)
                    ii = np.clip(i0 + di, 0, centres.shape[1] - 1)
                    c = centres[jj, ii]
                    dist = np.hypot(x - c[..., 0], y - c[..., 1])
                    local = disk_fraction * (p0 + k * (ii - n))
                    closer = dist < best
                    best = np.where(closer, dist, best)
                    radius = np.where(closer, local, radius)
            lit += best <= radius
    lit /= supersample * supersample
    rng = np.random.default_rng(seed + 1)
    image = 50000.0 * lit + rng.normal(0.0, noise_sigma * 50000.0, shape)
    return np.clip(np.rint(image), 0, 65535).astype(np.uint16), centres.reshape(-1, 2)


def spot_white(shape, grid: LensGrid, spot_sigma_px: float, *, noise_sigma: float = 0.02, square: bool = False,
               seed: int = 0) -> np.ndarray:
    """Blurred spots instead of disks (PlenoptiCam's synthetic *a*, *b*, *c*): a Gaussian of ``spot_sigma_px``
    at every lens, or with ``square`` a square of side 0.6 pitch blurred by it; plus Gaussian noise."""
    from scipy import ndimage
    rows, cols = shape
    image = np.zeros(shape)
    yy, xx = np.meshgrid(np.arange(rows, dtype=np.float64), np.arange(cols, dtype=np.float64), indexing="ij")
    u, v = grid.axes
    for c in grid.centers_xy_px().reshape(-1, 2):
        if not (-3 * grid.pitch_px < c[0] < cols + 3 * grid.pitch_px and -3 * grid.pitch_px < c[1] < rows + 3 * grid.pitch_px):
            continue
        r = int(3 * spot_sigma_px + grid.pitch_px)
        y0, y1 = max(0, int(c[1]) - r), min(rows, int(c[1]) + r + 1)
        x0, x1 = max(0, int(c[0]) - r), min(cols, int(c[0]) + r + 1)
        if y0 >= y1 or x0 >= x1:
            continue
        dx, dy = xx[y0:y1, x0:x1] - c[0], yy[y0:y1, x0:x1] - c[1]
        if square:
            du, dv = dx * u[0] + dy * u[1], dx * v[0] + dy * v[1]
            half = 0.3 * grid.pitch_px
            # a square's area integral per pixel, approximated by 8 x 8 point samples
            s = (np.arange(8) + 0.5) / 8 - 0.5
            inside = np.zeros(du.shape)
            for oy in s:
                for ox in s:
                    pu, pv = du + ox * u[0] + oy * u[1], dv + ox * v[0] + oy * v[1]
                    inside += (np.abs(pu) <= half) & (np.abs(pv) <= half)
            image[y0:y1, x0:x1] += inside / 64.0
        else:
            image[y0:y1, x0:x1] += np.exp(-(dx * dx + dy * dy) / (2 * spot_sigma_px ** 2))
    if square:
        image = ndimage.gaussian_filter(image, spot_sigma_px)
    image /= image.max()
    image += np.random.default_rng(seed).normal(0.0, noise_sigma, shape)
    return np.clip(np.rint(image * 200 + 20), 0, 255).astype(np.uint8)
