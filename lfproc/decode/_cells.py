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


#: width (px) over which a pixel on the border between two cells passes from one lens to the other
SHARE_WIDTH_PX = 1.0


def _neighbour_offsets(grid: LensGrid, odd_row: bool) -> list[tuple[int, int, np.ndarray]]:
    """``(dr, dq, offset_xy)`` of a lens's neighbours (rigid lattice; a smooth deviation barely changes them)."""
    u, v = (np.asarray(a, dtype=np.float64) for a in grid.axes)
    spacing = ROW_SPACING[grid.kind] * grid.pitch_px
    if grid.kind == "hexagonal":
        side = (0, 1) if odd_row else (-1, 0)
        steps = [(0, -1), (0, 1)] + [(dr, dq) for dr in (-1, 1) for dq in side]
    else:
        steps = [(dr, dq) for dr in (-1, 0, 1) for dq in (-1, 0, 1) if (dr, dq) != (0, 0)]
    out = []
    for dr, dq in steps:
        along_u = dq + (0.5 * (1 if not odd_row else -1) if grid.kind == "hexagonal" and dr else 0.0)
        out.append((dr, dq, along_u * grid.pitch_px * u + dr * spacing * v))
    return out


def cell_shares(grid: LensGrid, sensor_shape, y0: int = 0, x0: int = 0,
                classes: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """``(second, share)``: per pixel, the class of the lens across the nearest cell border (``uint8``) and
    the pixel's share in its own (nearest) lens, 0.5 … 1 as ``uint8`` 128 … 255.

    A pixel on the border between two cells sees both micro images; a hard border would hand it from
    one lens to the other as the grid moves by a hundredth of a pixel, and a sample that reads it would
    jump. Here it passes over :data:`SHARE_WIDTH_PX`: the share is ``0.5 + t / width`` (at most 1), t the
    pixel's distance from the perpendicular bisector to the nearest neighbour's centre. ``classes``: the
    :func:`cell_classes` map of the same pixels, when already at hand.
    """
    height, width = sensor_shape[:2]
    second = np.empty((height, width), dtype=np.uint8)
    share = np.empty((height, width), dtype=np.uint8)
    offsets = {odd: _neighbour_offsets(grid, odd) for odd in (False, True)}
    if grid.deviation is None and type(grid).lens_xy is LensGrid.lens_xy:    # rigid: the compiled kernel
        from ._rim_kernel import cell_shares_rigid

        u, v = grid.axes
        lattice = np.array([grid.origin_xy_px[0], grid.origin_xy_px[1], u[0], u[1], v[0], v[1], grid.pitch_px,
                            grid.row_spacing_px, 1.0 if grid.kind == "hexagonal" else 0.0])
        steps = [np.array([[dr, dq, off[0], off[1]] for dr, dq, off in offsets[odd]]) for odd in (False, True)]
        classes = cell_classes(grid, sensor_shape, y0, x0) if classes is None else classes
        cell_shares_rigid(classes, y0, x0, lattice, steps[0], steps[1], SHARE_WIDTH_PX, second, share)
        return second, share
    xs = np.arange(x0, x0 + width, dtype=np.float64)
    for r0 in range(0, height, _CHUNK_ROWS):
        r1 = min(r0 + _CHUNK_ROWS, height)
        yy, xx = np.meshgrid(np.arange(y0 + r0, y0 + r1, dtype=np.float64), xs, indexing="ij")
        r, q = nearest_lens(grid, xx, yy)
        centre = grid.lens_xy(r, q)
        dx, dy = xx - centre[..., 0], yy - centre[..., 1]
        best = np.full(r.shape, np.inf)
        best_cls = np.zeros(r.shape, dtype=np.uint8)
        odd = (r % 2 == 1) if grid.kind == "hexagonal" else np.zeros(r.shape, bool)
        for parity in (False, True):
            rows = odd == parity
            if not rows.any():
                continue
            for dr, dq, off in offsets[parity]:
                length = float(np.hypot(*off))
                t = 0.5 * length - (dx * off[0] + dy * off[1]) / length
                closer = rows & (t < best)
                best = np.where(closer, t, best)
                best_cls = np.where(closer, lens_class(r + dr, q + dq), best_cls).astype(np.uint8)
        second[r0:r1] = best_cls
        frac = np.clip(0.5 + np.maximum(best, 0.0) / SHARE_WIDTH_PX, 0.5, 1.0)
        share[r0:r1] = np.rint(frac * 255).astype(np.uint8)
    return second, share


def class_weight(classes: np.ndarray, second: np.ndarray, share: np.ndarray, cls: int) -> np.ndarray:
    """Each pixel's weight (float32, 0 … 1) in the lenses of class ``cls``: its share where it is their cell,
    the rest where it borders it (:func:`cell_shares`)."""
    own = share.astype(np.float32) * np.float32(1 / 255)
    return np.where(classes == cls, own, np.where(second == cls, np.float32(1.0) - own, np.float32(0.0)))
