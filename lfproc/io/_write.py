"""Writing images with lfproc's metadata embedded, and reading that metadata back.

lfproc's metadata dict travels inside the file: as JSON in ``ImageDescription`` and, where the
format keeps them, as one ``lfproc:<key>`` attribute per scalar. What OpenImageIO 3.x keeps::

    format  ImageDescription (JSON)  lfproc:<key> attributes
    tiff    yes                      no (TIFF has no free-form tags)
    png16   yes (text chunk)         yes, as strings ("313.066", "inf")
    exr     yes (header)             yes, typed (float, int, string "inf")
    jpeg    yes (comment and EXIF)   no
    uint16  as png16 / tiff by the extension

All writers are atomic: a failed write leaves neither the file nor a temporary file behind.
OpenImageIO is imported inside the functions that use it.
"""

from __future__ import annotations

import json
import math
import os
from typing import Mapping

import numpy as np

from ..atomic import atomic_path, json_safe, python_scalar
from ..errors import LfprocError
from ._checks import existing_file, library_error
from ._native import libraries_quiet

#: output formats of `write_image`
FORMATS = ("tiff", "png16", "jpeg", "exr", "uint16")
_FORMAT_BY_EXTENSION = {".tif": "tiff", ".tiff": "tiff", ".png": "png16", ".jpg": "jpeg", ".jpeg": "jpeg",
                        ".exr": "exr"}
_EXTENSIONS_BY_FORMAT = {"tiff": (".tif", ".tiff"), "png16": (".png",), "jpeg": (".jpg", ".jpeg"),
                         "exr": (".exr",), "uint16": (".png", ".tif", ".tiff")}
#: OpenImageIO colour space names (OIIO 3.x): linear data gets a gAMA 1.0 chunk in PNG
_LINEAR_SPACE, _SRGB_SPACE, _RAW_SPACE = "lin_rec709_scene", "srgb_rec709_scene", "Raw"
_JPEG_QUALITY = 95
_METADATA_PREFIX = "lfproc:"


def srgb_encode(linear: np.ndarray) -> np.ndarray:
    """The sRGB transfer function (IEC 61966-2-1) of linear values clipped to [0, 1], as float32."""
    x = np.clip(np.asarray(linear, dtype=np.float64), 0.0, 1.0)
    encoded = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1.0 / 2.4) - 0.055)
    return encoded.astype(np.float32)


def srgb_decode(encoded: np.ndarray) -> np.ndarray:
    """The inverse sRGB transfer function (IEC 61966-2-1): encoded values in [0, 1] to linear, float32."""
    x = np.clip(np.asarray(encoded, dtype=np.float64), 0.0, 1.0)
    return np.where(x <= 0.04045, x / 12.92, np.power((x + 0.055) / 1.055, 2.4)).astype(np.float32)


def write_image(path: str | os.PathLike, image: np.ndarray, metadata: Mapping | None = None,
                format: str | None = None, *, allow_nonfinite: bool = False) -> None:
    """Write an image atomically, with ``metadata`` embedded in the file.

    Parameters
    ----------
    path : str or os.PathLike
        Destination; its extension picks the file format (``.tif``/``.tiff``, ``.png``, ``.exr``,
        ``.jpg``/``.jpeg``) and must agree with ``format`` when both are given.
    image : numpy.ndarray
        float32 linear ``(H, W, C)`` or ``(H, W)``; for ``"uint16"`` a uint16 array.
    metadata : dict, optional
        JSON-able dict (e.g. ``source``, ``a``, ``distance_mm``, ``near_mm``, ``far_mm``,
        ``dof_mm``): stored as strict JSON in ``ImageDescription`` (infinity as ``null``) and each
        scalar as an ``lfproc:<key>`` attribute (numbers as float/int, infinity as the string
        ``"inf"``; ``None`` skipped), as far as the format keeps them (module docstring).
    format : {"tiff", "png16", "jpeg", "exr", "uint16"}, optional
        ``"tiff"``: float32 linear TIFF (default for outputs). ``"png16"``: 16-bit linear PNG,
        clipped to [0, 1] and rounded. ``"jpeg"``: 8-bit sRGB-encoded for viewing only (clipped,
        not linear, lossy). ``"exr"``: 32-bit float OpenEXR. ``"uint16"``: a uint16 array written
        exactly as 16-bit PNG or TIFF, for simulated sensor captures. Default: from the extension,
        ``"uint16"`` for uint16 arrays.
    allow_nonfinite : bool
        Keep NaN and ±inf in a float TIFF or EXR (a data product such as a depth map, NaN = unknown);
        pictures refuse them (the default).

    Raises
    ------
    LfprocError
        Unknown format or extension, NaN/inf pixels, bad shape, unwritable destination. Nothing is
        left behind on failure.
    """
    import OpenImageIO as oiio

    path = os.fspath(path)
    fmt = _output_format(path, image, format)
    pixels, pixel_type, colour_space = _encode_pixels(image, fmt, path, allow_nonfinite)
    height, width, channels = pixels.shape
    spec = oiio.ImageSpec(width, height, channels, pixel_type)
    spec.attribute("oiio:ColorSpace", colour_space)
    spec.attribute("oiio:UnassociatedAlpha", 1)      # store a 4th channel's colour as given, never ÷ alpha
    spec.attribute("Software", "lfproc")
    spec.attribute("DateTime", "")  # TIFF/EXR would stamp the write time: same inputs, same bytes
    if fmt == "jpeg":
        spec.attribute("Compression", f"jpeg:{_JPEG_QUALITY}")
        spec.attribute("jpeg:subsampling", "4:4:4")
    extension = os.path.splitext(path)[1].lower()
    if extension in (".tif", ".tiff"):
        # uncompressed: every TIFF reader opens it (OpenImageIO's default zip + floating-point predictor needs
        # imagecodecs in tifffile), and it writes at disk speed (zip of float noise runs at ~6 MB/s)
        spec.attribute("Compression", "none")
    _attach_metadata(spec, metadata, strings_only=extension == ".png")
    try:
        with atomic_path(path) as tmp:
            out = oiio.ImageOutput.create(tmp)
            if out is None:
                raise LfprocError(f"{path}: OpenImageIO cannot write this format ({library_error(oiio.geterror)}); "
                                  f"use .tif, .png, .exr or .jpg")
            if not out.open(tmp, spec):
                raise LfprocError(f"{path}: cannot write ({library_error(out.geterror)}); "
                                  f"check that the folder exists and is writable")
            written = out.write_image(pixels)
            closed = out.close()
            if not (written and closed):
                raise LfprocError(f"{path}: writing failed ({library_error(out.geterror)}); "
                                  f"check the free disk space and permissions")
    except OSError as exc:
        raise LfprocError(f"{path}: cannot write ({exc.strerror or exc}); check the folder and permissions") from None


def _output_format(path: str, image, fmt: str | None) -> str:
    extension = os.path.splitext(path)[1].lower()
    if fmt is None:
        if isinstance(image, np.ndarray) and image.dtype == np.uint16 and extension in _EXTENSIONS_BY_FORMAT["uint16"]:
            return "uint16"
        if extension not in _FORMAT_BY_EXTENSION:
            raise LfprocError(f"{path}: unknown image extension {extension!r}; use .tif, .png, .exr or .jpg")
        return _FORMAT_BY_EXTENSION[extension]
    if fmt not in FORMATS:
        raise LfprocError(f"{path}: unknown image format {fmt!r}; use one of {', '.join(FORMATS)}")
    if extension not in _EXTENSIONS_BY_FORMAT[fmt]:
        raise LfprocError(f"{path}: format {fmt!r} needs the extension {' or '.join(_EXTENSIONS_BY_FORMAT[fmt])}; "
                          f"rename the output")
    return fmt


def _encode_pixels(image, fmt: str, path: str, allow_nonfinite: bool = False) -> tuple[np.ndarray, str, str]:
    """(H, W, C) pixels ready for OpenImageIO, their type name and colour space."""
    image = np.asarray(image)
    if image.ndim == 2:
        image = image[:, :, None]
    if image.ndim != 3 or image.shape[0] == 0 or image.shape[1] == 0 or not 1 <= image.shape[2] <= 4:
        raise LfprocError(f"{path}: image of shape {image.shape} cannot be written; "
                          f"pass (H, W) or (H, W, C) with 1 to 4 channels")
    if fmt == "uint16":
        if image.dtype != np.uint16:
            raise LfprocError(f"{path}: format 'uint16' writes uint16 sensor data exactly, got {image.dtype}; "
                              f"convert with np.round(...).astype(np.uint16) first")
        return np.ascontiguousarray(image), "uint16", _RAW_SPACE
    if not (np.issubdtype(image.dtype, np.floating) or np.issubdtype(image.dtype, np.integer)):
        raise LfprocError(f"{path}: image dtype {image.dtype} is not numeric; pass a float32 image")
    if allow_nonfinite and fmt not in ("tiff", "exr"):
        raise LfprocError(f"{path}: only float TIFF and EXR files hold NaN or infinity; write .tif or .exr")
    if not allow_nonfinite and not np.all(np.isfinite(image)):
        raise LfprocError(f"{path}: the image contains NaN or infinite values; fix the computation before writing")
    if fmt == "png16":
        return np.round(np.clip(image, 0.0, 1.0) * 65535.0).astype(np.uint16), "uint16", _LINEAR_SPACE
    if fmt == "jpeg":
        if image.shape[2] not in (1, 3):
            raise LfprocError(f"{path}: JPEG holds 1 or 3 channels, got {image.shape[2]}; write TIFF or EXR instead")
        return np.round(srgb_encode(image) * 255.0).astype(np.uint8), "uint8", _SRGB_SPACE
    return np.ascontiguousarray(image, dtype=np.float32), "float", _LINEAR_SPACE


def _attach_metadata(spec, metadata: Mapping | None, strings_only: bool) -> None:
    """Put the dict as JSON in ImageDescription and each scalar as ``lfproc:<key>``."""
    if metadata is None:
        return
    safe = json_safe(metadata)
    if not isinstance(safe, dict):
        raise LfprocError(f"metadata must be a dict, got {type(metadata).__name__}")
    spec.attribute("ImageDescription", json.dumps(safe, allow_nan=False))
    for key, value in metadata.items():
        name = _METADATA_PREFIX + str(key)
        value = python_scalar(value)
        if value is None or isinstance(value, (list, tuple, dict)):
            continue
        if isinstance(value, bool):
            spec.attribute(name, "true" if value else "false")
        elif isinstance(value, float) and math.isinf(value):
            spec.attribute(name, "inf" if value > 0 else "-inf")
        elif isinstance(value, (int, float)) and not strings_only:
            spec.attribute(name, value)
        else:
            spec.attribute(name, repr(value) if isinstance(value, float) else str(value))


def read_metadata(path: str | os.PathLike) -> dict:
    """The metadata dict that `write_image` embedded (the JSON in ``ImageDescription``).

    Infinite distances come back as ``None`` (strict JSON). An image without lfproc metadata gives
    an empty dict.

    Raises
    ------
    LfprocError
        Missing or unreadable files.
    """
    import OpenImageIO as oiio

    path = existing_file(path)
    with libraries_quiet():
        inp = oiio.ImageInput.open(path)
    if inp is None:
        raise LfprocError(f"{path}: not a readable image ({library_error(oiio.geterror)}); pass a TIFF, PNG, EXR "
                          f"or JPEG written by lfproc")
    try:
        description = inp.spec().get_string_attribute("ImageDescription")
    except UnicodeDecodeError:  # not lfproc's (UTF-8 JSON) description
        description = ""
    finally:
        inp.close()
    try:
        metadata = json.loads(description) if description else {}
    except json.JSONDecodeError:
        return {}
    return metadata if isinstance(metadata, dict) else {}
