"""Images through OpenImageIO: TIFF, PNG, EXR, JPEG, … as captures (with the camera's levels) or as stored.

OpenImageIO is imported inside the functions that use it, so importing this module is cheap.
"""

from __future__ import annotations

import math
import os

import numpy as np

from ..errors import LfprocError
from ._capture import Capture
from ._native import libraries_quiet
from ._checks import (_NotThisFormat, check_declared_size, existing_file, library_error, one_line,
                      require_finite_pixels)


def read_image(path: str | os.PathLike) -> np.ndarray:
    """Read any image OpenImageIO knows as float32 ``(H, W, C)``, all channels, no level handling.

    Float files come back as stored; integer files are divided by their type's maximum (as
    OpenImageIO does), so a 16-bit PNG written by `write_image` reads back as the image written.

    Raises
    ------
    LfprocError
        Missing, empty, truncated or unreadable files, zero-size images, NaN/inf values.
    """
    path = existing_file(path)
    try:
        pixels, _ = oiio_pixels(path)
    except _NotThisFormat as exc:
        raise LfprocError(f"{path}: not a readable image ({exc}); pass a TIFF, PNG, EXR or JPEG file "
                          f"(camera raws: use read_capture)") from None
    if np.issubdtype(pixels.dtype, np.integer):
        return pixels.astype(np.float32) / np.float32(np.iinfo(pixels.dtype).max)
    require_finite_pixels(pixels, path)
    return pixels.astype(np.float32)


def oiio_pixels(path: str) -> tuple[np.ndarray, "object"]:
    """Pixels of the first subimage in the file's own type, ``(H, W, C)``, and the ImageSpec."""
    import OpenImageIO as oiio

    config = oiio.ImageSpec()
    config.attribute("oiio:UnassociatedAlpha", 1)      # colour as stored, not multiplied by alpha
    with libraries_quiet() as native:                  # libtiff, libpng & co. print their own errors to fd 2
        inp = oiio.ImageInput.open(path, config)
    if inp is None:
        raise _NotThisFormat(library_error(oiio.geterror) or one_line(native.text()) or "OpenImageIO: unknown format")
    try:
        spec = inp.spec()
        if spec.width <= 0 or spec.height <= 0 or spec.nchannels <= 0:
            raise LfprocError(f"{path}: the image has zero size; pass a real capture")
        if spec.depth > 1:
            raise LfprocError(f"{path}: volume images are not supported; pass a 2-D image")
        check_declared_size(path, spec.width * spec.height * spec.nchannels * max(1, spec.channel_bytes()),
                            f"{spec.width} x {spec.height} x {spec.nchannels}")
        with libraries_quiet() as native:
            pixels = inp.read_image(0, 0, 0, spec.nchannels, oiio.UNKNOWN)
        failed = pixels is None or inp.has_error
        message = (library_error(inp.geterror) or one_line(native.text())) if failed else ""
    finally:
        inp.close()
    if failed:
        raise LfprocError(f"{path}: truncated or corrupt image ({message or 'read failed'}); re-export the file")
    pixels = np.asarray(pixels)
    if pixels.ndim == 2:
        pixels = pixels[:, :, None]
    return pixels, spec


def read_oiio_capture(path: str, camera=None) -> Capture:
    """Read a TIFF/PNG/EXR/... capture and apply the camera's levels to integer data."""
    pixels, spec = oiio_pixels(path)
    pixels = _colour_channels(pixels, spec, path)
    if np.issubdtype(pixels.dtype, np.integer):
        type_max = float(np.iinfo(pixels.dtype).max)
        black, white = camera.raw_levels(type_max) if camera is not None else (0.0, type_max)
        if white > type_max:
            bits, sensor_bits = 8 * pixels.dtype.itemsize, math.ceil(math.log2(white + 1.0))
            named, article = " ".join(["the camera", camera.source or camera.name]).strip(), "an" if bits == 8 else "a"
            raise LfprocError(f"{path}: {article} {bits}-bit file (at most {type_max:g}), but {named} saturates at "
                              f"{white:g} (sensor.white_level, a {sensor_bits}-bit sensor): it describes another "
                              f"camera; pass `camera=` the camera of the instrument that took this file (or, if it is "
                              f"that camera, set its sensor.white_level to {type_max:g})")
        if black >= white:
            raise LfprocError(f"{path}: the camera's sensor.black_level {black:g} is not below this file's white level "
                              f"{white:g}; set sensor.black_level (and white_level) for this file in the camera file")
        data = pixels.astype(np.float32)        # in place from here: one full-size float image, not three
        data -= np.float32(black)
        data /= np.float32(white - black)
    else:
        require_finite_pixels(pixels, path)
        data = pixels.astype(np.float32)
    if data.shape[2] == 1:
        return Capture(data=data[:, :, 0], cfa=camera.cfa if camera is not None else "none", source=path)
    return Capture(data=data, cfa="none", source=path)


def _colour_channels(pixels: np.ndarray, spec, path: str) -> np.ndarray:
    """Drop alpha; keep 1 (mono) or 3 (RGB) channels."""
    names = list(spec.channelnames)
    keep = [i for i in range(pixels.shape[2]) if i != spec.alpha_channel]
    if spec.alpha_channel < 0 and len(keep) in (2, 4) and names and names[-1].upper() in ("A", "ALPHA"):
        keep = keep[:-1]
    if len(keep) in (1, 3):
        return pixels if keep == list(range(pixels.shape[2])) else pixels[:, :, keep]
    upper = [n.upper() for n in names]
    if all(c in upper for c in ("R", "G", "B")):
        return pixels[:, :, [upper.index(c) for c in ("R", "G", "B")]]
    raise LfprocError(f"{path}: {pixels.shape[2]} channels ({', '.join(names)}) is neither mono nor RGB; "
                      f"save the capture with 1 or 3 channels")

