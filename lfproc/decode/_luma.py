"""Views read from the Bayer mosaic as it is: their luminance where their rays are, their colour from nearby.

At the rim of a micro image, red and blue pixels are two pixels apart and demosaicing inside the own cell
only reaches the ones further in: the outer views of a Bayer capture cannot be read where their rays are,
however far out they are read (their red centroid stays half an effective pixel inwards). Read from the
mosaic as it is, as a mono sensor's pixels would be, every pixel counts for its own rays, whatever its
colour: ``K·capture / K·white`` over the raw pixels is the scene's brightness (each colour weighted by its
share ``s`` of the white there), with a kernel that reaches the rim like a mono sensor's
(:func:`lfproc.decode._view_mask.view_sampling` picks these views and where to read them).

Their colour comes from the same view read at its nominal position, demosaiced, averaged over
:data:`CHROMA_LENSES` × :data:`CHROMA_LENSES` lenses; their brightness from the mosaic reading split by
the colour of the pixels it reads, each part divided by the view's mean colour (:func:`with_colour`).
(The colour cannot be measured on the view's own rays: with an even pitch in pixels, neighbouring
lenses see the same Bayer colours at the rim, and some colours not at all.)
"""

from __future__ import annotations

import numpy as np

from ._hexagonal import hex_rows_read, hex_rows_to_rect

#: lenses per side over which a mosaic-read view's colour is averaged
CHROMA_LENSES = 3


class ColourPlanes:
    """A Bayer mosaic ``(H, W)`` seen as ``(H, W, 3)``: each pixel in the plane of its colour, 0 in the others
    (rows are sliced from the mosaic's own row 0, so the pattern's phase is kept)."""

    def __init__(self, mosaic: np.ndarray, cfa: str):
        self.mosaic, self.cfa = mosaic, cfa
        self.shape, self.ndim, self.dtype = tuple(mosaic.shape) + (3,), 3, np.dtype(np.float32)

    def __getitem__(self, rows: slice) -> np.ndarray:
        start = rows.start or 0
        strip = np.asarray(self.mosaic[rows], dtype=np.float32)
        out = np.zeros(strip.shape + (3,), dtype=np.float32)
        for (py, px), colour in zip(((0, 0), (0, 1), (1, 0), (1, 1)), self.cfa):
            sy = (py - start) % 2
            out[sy::2, px::2, "RGB".index(colour)] = strip[sy::2, px::2]
        return out


def luminance_views(sensor: np.ndarray, decoder, read_band, band_rows: int) -> np.ndarray:
    """``(n, Ny, Nx, 3)`` mosaic readings of the decoder's ``luma_views`` (row-major order), devignetted by
    the white's mosaic reading and split by the colour of the pixels they read (their sum is the reading)."""
    grid, out_grid, m = decoder.grid, decoder.output_grid, decoder.m_hat
    runs = _runs(decoder.luma_views)
    out = np.zeros((len(runs), out_grid.rows, out_grid.cols, 3), dtype=np.float32)
    planes = ColourPlanes(sensor, decoder.cfa)
    for r0 in range(0, out_grid.rows, band_rows):
        out_rows = range(r0, min(r0 + band_rows, out_grid.rows))
        rows = hex_rows_read(out_rows, grid.rows) if grid.kind == "hexagonal" else out_rows
        views = read_band(planes, grid, m, rows, "none", decoder.demosaic_method, decoder.interpolation,
                          decoder.luma_shift_px, decoder.cells, runs)
        for i, (ky, kx, _) in enumerate(runs):
            run = views[ky:ky + 1, kx:kx + 1]
            run *= decoder.inverse_luma[i, rows.start:rows.stop]
            dst = out[None, i:i + 1, out_rows.start:out_rows.stop]
            if grid.kind == "hexagonal":
                hex_rows_to_rect(run, rows.start, out_rows, dst)
            else:
                dst[...] = run
    return out


def _runs(luma) -> list[tuple[int, int, int]]:
    """One run per view of ``luma``, row-major (the order of the decoder's compact arrays)."""
    return [(int(ky), int(kx), int(kx) + 1) for ky, kx in np.argwhere(luma)]


def _box(values: np.ndarray) -> np.ndarray:
    """Mean over :data:`CHROMA_LENSES` × :data:`CHROMA_LENSES` lenses of ``(n, Ny, Nx, C)`` (zero beyond)."""
    from scipy import ndimage

    return ndimage.uniform_filter(values, size=(1, CHROMA_LENSES, CHROMA_LENSES, 1), mode="constant")


def with_colour(parts: np.ndarray, nominal: np.ndarray) -> np.ndarray:
    """``(n, Ny, Nx, 3)`` views from their mosaic readings split by colour (``parts``, :func:`luminance_views`)
    and their demosaiced readings at nominal ``nominal``, all devignetted, 0 where a sample carries no signal.

    A sample's part of colour c is the white's share of that colour there times ``ρ_c·T``, the scene's
    colour and brightness at the view's rays. With the view's mean colour g (of its nominal readings, channel
    mean 1), ``T = Σ_c part_c / g_c`` is the brightness whatever colours the sample's pixels have (a red
    pixel on a red surface reads bright, a blue one dark: without this a coloured scene would print the
    Bayer pattern into these views), and the sample is ``C · T`` with C the local colour: the nominal
    readings over :data:`CHROMA_LENSES` × :data:`CHROMA_LENSES` lenses, channel mean 1. Neither colour
    changes the sample's brightness (channel mean): the nominal readings' channels are read at centroids up
    to half an effective pixel apart, and their texture must not enter it (it moved refocus sweeps by
    −0.016 in a). Where no colour is known it is neutral; where the mosaic reading carries no signal the
    nominal reading stays.
    """
    known = np.all(nominal != 0, axis=-1, keepdims=True)
    lit = np.where(known, nominal, np.float32(0.0))
    view = lit.sum(axis=(1, 2), keepdims=True)
    view_ok = np.all(view > 0, axis=-1, keepdims=True)
    mean_colour = np.where(view_ok, view / np.where(view_ok, view.mean(axis=-1, keepdims=True), 1.0), 1.0)
    brightness = np.sum(parts / mean_colour, axis=-1, keepdims=True)
    local = _box(lit)
    local_ok = np.all(local > 0, axis=-1, keepdims=True)
    colour = np.where(local_ok, local / np.where(local_ok, local.mean(axis=-1, keepdims=True), 1.0), 1.0)
    total = parts.sum(axis=-1, keepdims=True)
    return np.where(total != 0, colour * brightness, nominal).astype(np.float32)
