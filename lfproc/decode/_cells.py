"""Each micro image on its own: the lens cells of the sensor, so that no sample reads another lens's light.

A decoded sample mixes the sensor pixels within its kernel's reach (demosaicing and interpolation,
about ±2 px). At the edge of a micro image that touches its neighbour (an f-number matched camera)
the kernel reaches into the neighbouring micro image, whose rays come from the other side of the
main lens: crosstalk. The decoder therefore reads every lens from its own *cell* only (the pixels
nearer to its centre than to any other lens centre): the sensor image is masked to the cells of one
*class* of lenses at a time, demosaiced (so that Bayer interpolation stays inside the micro image
too) and only that class's samples are read from it. Four classes, ``2·(r mod 2) + (q mod 2)``,
suffice on rectangular and hexagonal lattices: two lenses of a class are at least two rows or two
columns apart, so their cells lie far beyond any kernel's reach of each other.

The class map depends only on the grid and the sensor size, so a decoder computes it once.
"""

from __future__ import annotations

import numpy as np

from ..grid import ROW_SPACING, LensGrid

#: lens classes whose cells are read separately (see the module docstring)
CLASSES = 4
#: sensor rows converted at a time (bounded float64 temporaries)
_CHUNK_ROWS = 256


def lens_class(r, q):
    """Class of lens (r, q): ``2·(r mod 2) + (q mod 2)``."""
    return 2 * (np.asarray(r) % 2) + np.asarray(q) % 2


def nearest_lens(grid: LensGrid, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Row and column ``(r, q)`` of the lens whose centre is nearest to each sensor position (x, y).

    A smooth lattice deviation is followed to first order (the position is moved back by the
    deviation there), which is exact wherever the deviation varies little over a lens.
    """
    x = np.asarray(x, dtype=np.float64)
    y = np.asarray(y, dtype=np.float64)
    if grid.deviation is not None:
        d = grid.deviation.offsets_at(np.stack([x, y], axis=-1))
        x, y = x - d[..., 0], y - d[..., 1]
    u, v = grid.axes
    dx, dy = x - grid.origin_xy_px[0], y - grid.origin_xy_px[1]
    spacing = ROW_SPACING[grid.kind] * grid.pitch_px
    a = (dx * u[0] + dy * u[1]) / grid.pitch_px     # along u, in pitches
    b = (dx * v[0] + dy * v[1]) / spacing           # along v, in rows
    if grid.kind != "hexagonal":
        return np.rint(b).astype(np.int64), np.rint(a).astype(np.int64)
    best_r = best_q = best_d = None
    for r in (np.floor(b), np.floor(b) + 1):
        half = 0.5 * np.mod(r, 2)
        q = np.rint(a - half)
        dist = ((a - q - half) * grid.pitch_px) ** 2 + ((b - r) * spacing) ** 2
        if best_d is None:
            best_r, best_q, best_d = r, q, dist
        else:
            closer = dist < best_d
            best_r, best_q, best_d = np.where(closer, r, best_r), np.where(closer, q, best_q), np.minimum(dist, best_d)
    return best_r.astype(np.int64), best_q.astype(np.int64)


def cell_classes(grid: LensGrid, sensor_shape, y0: int = 0, x0: int = 0) -> np.ndarray:
    """``uint8`` map ``sensor_shape[:2]`` (offset by ``(x0, y0)``) of the class of each pixel's nearest lens."""
    height, width = sensor_shape[:2]
    out = np.empty((height, width), dtype=np.uint8)
    xs = np.arange(x0, x0 + width, dtype=np.float64)
    for r0 in range(0, height, _CHUNK_ROWS):
        r1 = min(r0 + _CHUNK_ROWS, height)
        yy, xx = np.meshgrid(np.arange(y0 + r0, y0 + r1, dtype=np.float64), xs, indexing="ij")
        r, q = nearest_lens(grid, xx, yy)
        out[r0:r1] = lens_class(r, q)
    return out


def masked(image: np.ndarray, classes: np.ndarray, cls: int, fill=0) -> np.ndarray:
    """``image`` with every pixel outside the cells of lens class ``cls`` set to ``fill`` (0; for a
    quantized mosaic the value that stands for 0)."""
    keep = classes == cls
    if image.ndim == 3:
        keep = keep[:, :, None]
    return np.where(keep, image, np.asarray(fill, dtype=image.dtype))
