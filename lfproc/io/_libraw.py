"""Camera raws (DNG, CR2, NEF, …) through LibRaw (rawpy): the visible mosaic, per-channel levels, CFA.

rawpy is imported inside the reader, so importing this module is cheap.
"""

from __future__ import annotations

import numpy as np

from ..errors import LfprocError
from ._capture import Capture, normalise_mosaic
from ._checks import _NotThisFormat
from ._native import libraries_quiet

BAYER_PATTERNS = ("RGGB", "BGGR", "GRBG", "GBRG")


def read_libraw_capture(path: str, camera=None, fallback: bool = False) -> Capture:
    """Read a camera raw through rawpy: visible mosaic, per-channel black and white levels, CFA.

    ``fallback``: LibRaw is only tried because the reader the extension chose did not recognise the file
    (a ``.tif`` that is no TIFF); then a file LibRaw cannot open is not a camera raw either, and the
    caller says "not an image" rather than "corrupt camera raw" (the reader that fails decides).
    """
    import rawpy

    try:
        with libraries_quiet():              # LibRaw prints its own errors ("Unexpected end of file") to fd 2
            raw_file = rawpy.imread(path)
    except rawpy.LibRawFileUnsupportedError:
        raise _NotThisFormat("LibRaw: not a supported camera raw") from None
    except rawpy.LibRawError as exc:
        if fallback:
            raise _NotThisFormat(f"LibRaw: {_libraw_message(exc)}") from None
        raise LfprocError(f"{path}: truncated or corrupt camera raw ({_libraw_message(exc)}); "
                          f"re-copy the file from the camera") from None
    try:
        with raw_file as raw, libraries_quiet():
            if raw.raw_type != rawpy.RawType.Flat:
                raise LfprocError(f"{path}: camera raw with several values per pixel (Foveon or linear DNG) is "
                                  f"not supported; convert it to a linear TIFF first")
            mosaic = np.asarray(raw.raw_image_visible)
            colors = np.asarray(raw.raw_colors_visible)
            black_per_channel = np.asarray(raw.black_level_per_channel, dtype=np.float64)
            white = float(raw.white_level)
            color_desc = raw.color_desc.decode("ascii", "replace")
            num_colors = int(raw.num_colors)
            if mosaic.size == 0 or mosaic.ndim != 2:
                raise LfprocError(f"{path}: the raw file holds no image data; re-copy or re-export the capture")
            cfa = bayer_pattern_from_colors(colors[:12, :12], color_desc, num_colors, path)
            # black level of each 2x2 position (one for all pixels of a monochrome sensor)
            cell_black = black_per_channel[colors[:2, :2]] if cfa != "none" else np.full((2, 2), black_per_channel[0])
            if not np.all(white > cell_black):
                raise LfprocError(f"{path}: the raw file's white level {white:g} is not above its black level "
                                  f"{float(cell_black.max()):g}; the file's metadata is corrupt, re-export it")
            data = normalise_mosaic(mosaic, cell_black, np.full((2, 2), white))
    except rawpy.LibRawError as exc:
        raise LfprocError(f"{path}: truncated or corrupt camera raw ({_libraw_message(exc)}); "
                          f"re-copy the file from the camera") from None
    return Capture(data=data, cfa=cfa, source=path)


def bayer_pattern_from_colors(colors: np.ndarray, color_desc: str, num_colors: int = 3,
                              path: str = "raw") -> str:
    """The Bayer pattern string of a LibRaw colour-index block, or "none" for a monochrome sensor.

    Parameters
    ----------
    colors : numpy.ndarray
        Colour indices of the top-left pixels (``raw_colors_visible``), at least 2×2; a block
        larger than 2×2 is checked to repeat with period 2 (X-Trans's 6×6 layout does not).
    color_desc : str
        LibRaw's colour letters by index, e.g. ``"RGBG"`` (the second G counts as G).
    num_colors : int
        LibRaw's number of colours; 1 means a monochrome sensor.

    Raises
    ------
    LfprocError
        For X-Trans and other non-Bayer colour filter arrays.
    """
    if num_colors == 1:
        return "none"
    colors = np.asarray(colors)
    if colors.ndim != 2 or colors.shape[0] < 2 or colors.shape[1] < 2:
        raise LfprocError(f"{path}: the raw image is smaller than one 2x2 colour filter cell; pass a real capture")
    periodic = np.array_equal(colors[2:, :], colors[:-2, :]) and np.array_equal(colors[:, 2:], colors[:, :-2])
    try:
        letters = "".join(color_desc[int(c)] for c in colors[:2, :2].ravel())
    except IndexError:
        letters = "?"
    if not periodic or letters not in BAYER_PATTERNS:
        raise LfprocError(f"{path}: unsupported colour filter array (not a 2x2 Bayer pattern: X-Trans or "
                          f"similar); convert the raw to a demosaiced linear TIFF first")
    return letters


def _libraw_message(exc: Exception) -> str:
    text = exc.args[0] if exc.args else str(exc)
    if isinstance(text, bytes):
        text = text.decode("utf-8", "replace")
    return str(text) or type(exc).__name__
