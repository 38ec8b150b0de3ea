"""Views read from the Bayer mosaic as it is: their luminance where their rays are, their colour from nearby.

At the rim of a micro image, red and blue pixels are two pixels apart and demosaicing inside the own cell
only reaches the ones further in: the outer views of a Bayer capture cannot be read where their rays are,
however far out they are read (their red centroid stays half an effective pixel inwards). Read from the
mosaic as it is, as a mono sensor's pixels would be, every pixel counts for its own rays, whatever its
colour: ``K·capture / K·white`` over the raw pixels is the scene's brightness, with a kernel that reaches
the rim like a mono sensor's (:func:`lfproc.decode._view_mask.view_sampling` picks these views and where
to read them).

Their brightness is the mosaic's reading with each pixel divided by its colour's gain, the scene's
mean colour in the central view (:func:`luminance_views`): a red pixel on a red surface reads bright, a blue one dark, and
without the gains a coloured scene would print the Bayer pattern into these views. Their colour comes
from the same view read at its nominal position, demosaiced, averaged over :data:`CHROMA_LENSES` ×
:data:`CHROMA_LENSES` lenses and scaled to channel mean 1, so that it does not change the brightness
(:func:`with_colour`): the nominal reading's channels are read at centroids up to half an effective
pixel apart, and their texture must not enter it (it moved refocus sweeps by −0.016 in a). The colour
cannot be measured on the view's own rays: with an even pitch in pixels neighbouring lenses see the
same Bayer colours at the rim, and some colours not at all.
"""

from __future__ import annotations

import numpy as np

from ._cells import MIN_OWN_WEIGHT, lens_class
from ._hexagonal import hex_rows_to_rect
from ._positions import lens_centers, lens_offsets_px

#: lenses per side over which a mosaic-read view's colour is averaged
CHROMA_LENSES = 3
#: lenses per side over which the colour that makes its brightness is averaged (wider: the nominal readings'
#: channels are read at centroids up to half an effective pixel apart, and their texture must stay out)
GAIN_LENSES = 7


def _read(image: np.ndarray, colours: np.ndarray, grid, m_hat: int, cells: np.ndarray, luma,
          shift) -> tuple[np.ndarray, np.ndarray]:
    """The ``luma`` views (row-major) of every lens read from the mosaic ``image`` as it is (bilinear), from
    the lens's own cell only: ``(C, n, rows, cols)`` weighted sums of the pixels of each colour
    (``colours`` ``(2, 2)``: the index of each Bayer position's colour, C = its maximum + 1) and ``(n, rows,
    cols)`` the kernel's weight on the own cell. A direct gather: the few views read this way cost in
    proportion to their samples, not to the sensor."""
    rows = range(grid.rows)
    ky, kx = np.nonzero(luma)
    off_x, off_y = (np.broadcast_to(v, (m_hat, m_hat, grid.rows, grid.cols))[ky, kx]
                    for v in lens_offsets_px(grid, m_hat, rows, shift))
    centres = lens_centers(grid, rows)
    x, y = centres[None, ..., 0] + off_x, centres[None, ..., 1] + off_y
    r, q = np.meshgrid(np.arange(grid.rows), np.arange(grid.cols), indexing="ij")
    own_class = lens_class(r, q)[None]
    x0, y0 = np.floor(x).astype(np.int64), np.floor(y).astype(np.int64)
    fx, fy = x - x0, y - y0
    height, width = image.shape
    n_colours, size = int(colours.max()) + 1, x.size
    total, weight = np.zeros(n_colours * size), np.zeros(x.shape)
    slot = np.arange(size).reshape(x.shape)
    for dy, dx, w in ((0, 0, (1 - fx) * (1 - fy)), (0, 1, fx * (1 - fy)), (1, 0, (1 - fx) * fy), (1, 1, fx * fy)):
        xi, yi = x0 + dx, y0 + dy
        inside = (xi >= 0) & (xi < width) & (yi >= 0) & (yi < height)
        xi, yi = np.clip(xi, 0, width - 1), np.clip(yi, 0, height - 1)
        w = np.where(inside & (cells[yi, xi] == own_class), w, 0.0)
        total += np.bincount((colours[yi % 2, xi % 2] * size + slot).ravel(), weights=(w * image[yi, xi]).ravel(),
                             minlength=n_colours * size)
        weight += w
    return total.reshape((n_colours,) + x.shape), weight


def inverse_mosaic_white(white: np.ndarray, grid, m_hat: int, cells: np.ndarray, luma, shift,
                         dark_fraction: float) -> np.ndarray:
    """``(n, rows, cols, 1)`` 1 / the white's mosaic readings of the ``luma`` views (row-major), 0 where a
    sample carries no signal: less than ``MIN_OWN_WEIGHT`` of its kernel on its own cell, or a white below
    ``dark_fraction`` of the readings' bright level (99th percentile) per unit of that weight."""
    total, weight = _read(white, np.zeros((2, 2), dtype=np.int64), grid, m_hat, cells, luma, shift)
    level = total[0]
    bright = float(np.percentile(level, 99)) if level.size else 0.0
    signal = (weight > MIN_OWN_WEIGHT) & (level > dark_fraction * bright * weight) & (level > 0)
    inverse = np.where(signal, 1.0 / np.where(signal, level, 1.0), 0.0)
    return inverse[..., None].astype(np.float32)


def luminance_views(sensor: np.ndarray, decoder) -> np.ndarray:
    """``(n, Ny, Nx, 3)`` mosaic readings of the decoder's ``luma_views`` (row-major order), devignetted by the
    white's mosaic reading and split by the colour of the pixels they read (their sum is the reading)."""
    grid, out_grid = decoder.grid, decoder.output_grid
    colours = np.empty((2, 2), dtype=np.int64)
    for (py, px), colour in zip(((0, 0), (0, 1), (1, 0), (1, 1)), decoder.cfa):
        colours[py, px] = "RGB".index(colour)
    total, _ = _read(sensor, colours, grid, decoder.m_hat, decoder.cells, decoder.luma_views, decoder.luma_shift_px)
    views = np.moveaxis(total.astype(np.float32), 0, -1) * decoder.inverse_luma
    if grid.kind != "hexagonal":
        return views
    out = np.zeros((views.shape[0], out_grid.rows, out_grid.cols, 3), dtype=np.float32)
    hex_rows_to_rect(views[None], 0, range(out_grid.rows), out[None])
    return out


def _box(values: np.ndarray, lenses: int) -> np.ndarray:
    """Mean over ``lenses`` × ``lenses`` lenses of ``(n, Ny, Nx, C)`` (zero beyond)."""
    from scipy import ndimage

    return ndimage.uniform_filter(values, size=(1, lenses, lenses, 1), mode="constant")


def _channel_mean_one(values: np.ndarray) -> np.ndarray:
    """``values`` ``(..., 3)`` scaled to channel mean 1 where every channel is positive, else 1 (neutral)."""
    with np.errstate(invalid="ignore", divide="ignore"):
        out = values / values.mean(axis=-1, keepdims=True)
    out[~np.all(values > 0, axis=-1)] = 1.0
    return out


def with_colour(parts: np.ndarray, nominal: np.ndarray) -> np.ndarray:
    """``(n, Ny, Nx, 3)`` views from their mosaic readings split by colour (``parts``, :func:`luminance_views`)
    and their demosaiced readings at nominal ``nominal``, all devignetted, 0 where a sample carries no signal.

    The brightness of a sample is ``T = Σ_c part_c / g_c``, each colour's part divided by the scene's
    colour g there (the nominal readings over :data:`GAIN_LENSES` × :data:`GAIN_LENSES` lenses, channel
    mean 1): a red pixel on a red surface reads bright, a blue one dark, and without g a coloured scene
    would print the Bayer pattern into these views. The sample is ``C · T`` with C the local colour (over
    :data:`CHROMA_LENSES` × :data:`CHROMA_LENSES` lenses, channel mean 1, so that it does not change the
    brightness). Where no colour is known it is neutral; where the mosaic reading carries no signal the
    nominal reading stays.
    """
    known = np.all(nominal != 0, axis=-1, keepdims=True)
    lit = np.where(known, nominal, np.float32(0.0))
    gains = _channel_mean_one(_box(lit, GAIN_LENSES))
    brightness = np.sum(parts / gains, axis=-1, keepdims=True)
    colour = _channel_mean_one(_box(lit, CHROMA_LENSES))
    return np.where(np.any(parts != 0, axis=-1, keepdims=True), colour * brightness, nominal).astype(np.float32)
