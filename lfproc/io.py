"""Reading raw captures and images; writing images, GIFs and sidecars with lfproc's metadata.

Reading
    `read_capture` turns a sensor capture into a linear float32 `Capture`: camera raws (DNG, CR2,
    NEF, ARW, RAF, ORF, RW2, …) through LibRaw (rawpy), which carries its own black and white
    levels and CFA pattern; TIFF, PNG, EXR and every other format through OpenImageIO, with the
    levels and CFA of the camera file. `read_image` reads any image as stored, for general use.

Writing
    `write_image` writes float32 linear images as float TIFF (the default for outputs), 16-bit
    linear PNG, float EXR or 8-bit sRGB JPEG (for viewing only), and uint16 sensor data exactly.
    lfproc's metadata dict travels inside the file: as JSON in ``ImageDescription`` and, where the
    format keeps them, as one ``lfproc:<key>`` attribute per scalar. What OpenImageIO 3.x keeps::

        format  ImageDescription (JSON)  lfproc:<key> attributes
        tiff    yes                      no (TIFF has no free-form tags)
        png16   yes (text chunk)         yes, as strings ("313.066", "inf")
        exr     yes (header)             yes, typed (float, int, string "inf")
        jpeg    yes (comment and EXIF)   no
        uint16  as png16 / tiff by the extension

    The JSON sidecar (`write_sidecar`, contract: ``NAME.EXT`` -> ``NAME.json``) holds the same dict
    for every format. All writers are atomic: a failed write leaves neither the file nor a
    temporary file behind.

OpenImageIO, rawpy and Pillow are imported inside the functions that use them, so importing this
module is cheap.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass
from typing import Mapping, Sequence

import numpy as np

from .atomic import atomic_path, json_safe, python_scalar, write_json_atomic
from .errors import LfprocError

#: extensions tried with LibRaw (rawpy) first; everything else goes to OpenImageIO first
RAW_EXTENSIONS = frozenset({
    ".3fr", ".ari", ".arw", ".bay", ".cap", ".cr2", ".cr3", ".crw", ".dcr", ".dcs", ".dng", ".drf",
    ".eip", ".erf", ".fff", ".gpr", ".iiq", ".k25", ".kdc", ".mdc", ".mef", ".mos", ".mrw", ".nef",
    ".nrw", ".orf", ".pef", ".ptx", ".pxn", ".r3d", ".raf", ".raw", ".rw2", ".rwl", ".rwz", ".sr2",
    ".srf", ".srw", ".x3f",
})
BAYER_PATTERNS = ("RGGB", "BGGR", "GRBG", "GBRG")
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


@dataclass(frozen=True, eq=False)
class Capture:
    """A sensor capture, linear and normalised.

    Attributes
    ----------
    data : numpy.ndarray
        float32, ``(H, W)`` for a mosaic or monochrome sensor, ``(H, W, C)`` for files that are
        already RGB. Black level subtracted and scaled so that the white level is 1.0; not clipped
        (noise below black stays negative, highlights above white stay above 1).
    cfa : str
        ``"none"`` or the Bayer pattern of ``data``'s top-left 2×2 block: ``"RGGB"``, ``"BGGR"``,
        ``"GRBG"`` or ``"GBRG"``.
    source : str
        The path the capture was read from.
    """

    data: np.ndarray
    cfa: str
    source: str

    @property
    def is_mosaic(self) -> bool:
        """True for a Bayer mosaic that still needs demosaicing."""
        return self.cfa != "none"


# ===================================================================== reading

class _NotThisFormat(Exception):
    """A reader does not recognise the file (another reader may); the message says why."""


def read_capture(path: str | os.PathLike, camera=None) -> Capture:
    """Read a sensor capture as a linear float32 `Capture`.

    Camera raws go through LibRaw: the visible raw mosaic, the per-channel black levels of the
    file subtracted, divided by (white level − black); the camera file's levels are ignored for
    them (the contract: LibRaw raws carry their own). Other files go through OpenImageIO: 8/16-bit
    integer data keeps its digital numbers, from which ``camera.black_level`` is subtracted and the
    result divided by ``camera.white_level − camera.black_level`` (0 and the type's maximum without
    a camera); float files (EXR, float TIFF) are taken as already linear (black 0, white 1).
    Single-channel files take their CFA from ``camera.cfa`` ("none" without a camera); files with
    colour channels give ``(H, W, 3)`` data (alpha dropped) and CFA "none".

    The reader is chosen by extension and falls back to the other one when the first does not
    recognise the content, except for ``.dng``: OpenImageIO would read a DNG as a plain TIFF
    without its levels and CFA, so a DNG LibRaw rejects is an error. No brightening, gamma or
    demosaicing happens here.

    Parameters
    ----------
    path : str or os.PathLike
    camera : lfproc.camera.Camera, optional
        Supplies ``cfa``, ``black_level`` and ``white_level`` for non-raw files.

    Raises
    ------
    LfprocError
        Missing, empty, truncated, unreadable or unsupported files (X-Trans and other non-Bayer
        CFAs), zero-size images, NaN/inf in float files, impossible levels.
    """
    path = _existing_file(path)
    extension = os.path.splitext(path)[1].lower()
    readers = (_read_libraw_capture, _read_oiio_capture)
    if extension == ".dng":
        # a DNG is also a TIFF: OpenImageIO would read it without its levels and CFA, silently wrong
        readers = (_read_libraw_capture,)
    elif extension not in RAW_EXTENSIONS:
        readers = readers[::-1]
    reasons = []
    for reader in readers:
        try:
            return reader(path, camera)
        except _NotThisFormat as exc:
            reasons.append(str(exc))
    raise LfprocError(f"{path}: not a readable image or camera raw ({'; '.join(reasons)}); "
                      f"pass a camera raw (DNG, CR2, NEF, …), TIFF, PNG or EXR file")


def read_image(path: str | os.PathLike) -> np.ndarray:
    """Read any image OpenImageIO knows as float32 ``(H, W, C)``, all channels, no level handling.

    Float files come back as stored; integer files are divided by their type's maximum (as
    OpenImageIO does), so a 16-bit PNG written by `write_image` reads back as the image written.

    Raises
    ------
    LfprocError
        Missing, empty, truncated or unreadable files, zero-size images, NaN/inf values.
    """
    path = _existing_file(path)
    try:
        pixels, _ = _oiio_pixels(path)
    except _NotThisFormat as exc:
        raise LfprocError(f"{path}: not a readable image ({exc}); pass a TIFF, PNG, EXR or JPEG file "
                          f"(camera raws: use read_capture)") from None
    if np.issubdtype(pixels.dtype, np.integer):
        return pixels.astype(np.float32) / np.float32(np.iinfo(pixels.dtype).max)
    _require_finite_pixels(pixels, path)
    return pixels.astype(np.float32)


def _existing_file(path) -> str:
    path = os.fspath(path)
    if not os.path.exists(path):
        raise LfprocError(f"{path}: file not found; check the path")
    if not os.path.isfile(path):
        raise LfprocError(f"{path}: is not a regular file; pass an image file")
    if os.path.getsize(path) == 0:
        raise LfprocError(f"{path}: file is empty; re-copy or re-export the capture")
    if not os.access(path, os.R_OK):
        raise LfprocError(f"{path}: file is not readable; check its permissions")
    return path


# --------------------------------------------------------------------- LibRaw

def _read_libraw_capture(path: str, camera=None) -> Capture:
    """Read a camera raw through rawpy: visible mosaic, per-channel black and white levels, CFA."""
    import rawpy

    try:
        raw_file = rawpy.imread(path)
    except rawpy.LibRawFileUnsupportedError:
        raise _NotThisFormat("LibRaw: not a supported camera raw") from None
    except rawpy.LibRawError as exc:
        raise LfprocError(f"{path}: truncated or corrupt camera raw ({_libraw_message(exc)}); "
                          f"re-copy the file from the camera") from None
    try:
        with raw_file as raw:
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
            data = np.empty(mosaic.shape, np.float32)
            for dy in range(2):
                for dx in range(2):
                    black = np.float32(cell_black[dy, dx])
                    data[dy::2, dx::2] = (mosaic[dy::2, dx::2].astype(np.float32) - black) / np.float32(white - black)
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


# --------------------------------------------------------------------- OpenImageIO

def _oiio_pixels(path: str) -> tuple[np.ndarray, "object"]:
    """Pixels of the first subimage in the file's own type, ``(H, W, C)``, and the ImageSpec."""
    import OpenImageIO as oiio

    config = oiio.ImageSpec()
    config.attribute("oiio:UnassociatedAlpha", 1)      # colour as stored, not multiplied by alpha
    inp = oiio.ImageInput.open(path, config)
    if inp is None:
        raise _NotThisFormat(_one_line(oiio.geterror()) or "OpenImageIO: unknown format")
    try:
        spec = inp.spec()
        if spec.width <= 0 or spec.height <= 0 or spec.nchannels <= 0:
            raise LfprocError(f"{path}: the image has zero size; pass a real capture")
        if spec.depth > 1:
            raise LfprocError(f"{path}: volume images are not supported; pass a 2-D image")
        pixels = inp.read_image(0, 0, 0, spec.nchannels, oiio.UNKNOWN)
        failed = pixels is None or inp.has_error
        message = _one_line(inp.geterror()) if failed else ""
    finally:
        inp.close()
    if failed:
        raise LfprocError(f"{path}: truncated or corrupt image ({message or 'read failed'}); re-export the file")
    pixels = np.asarray(pixels)
    if pixels.ndim == 2:
        pixels = pixels[:, :, None]
    return pixels, spec


def _read_oiio_capture(path: str, camera=None) -> Capture:
    """Read a TIFF/PNG/EXR/... capture and apply the camera's levels to integer data."""
    pixels, spec = _oiio_pixels(path)
    pixels = _colour_channels(pixels, spec, path)
    if np.issubdtype(pixels.dtype, np.integer):
        type_max = float(np.iinfo(pixels.dtype).max)
        black, white = camera.raw_levels(type_max) if camera is not None else (0.0, type_max)
        if white > type_max:
            raise LfprocError(f"{path}: the camera's sensor.white_level {white:g} exceeds this "
                              f"{8 * pixels.dtype.itemsize}-bit file's maximum {type_max:g}; "
                              f"set sensor.white_level (and black_level) for this file in the camera file")
        data = (pixels.astype(np.float32) - np.float32(black)) / np.float32(white - black)
    else:
        _require_finite_pixels(pixels, path)
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
        return pixels[:, :, keep]
    upper = [n.upper() for n in names]
    if all(c in upper for c in ("R", "G", "B")):
        return pixels[:, :, [upper.index(c) for c in ("R", "G", "B")]]
    raise LfprocError(f"{path}: {pixels.shape[2]} channels ({', '.join(names)}) is neither mono nor RGB; "
                      f"save the capture with 1 or 3 channels")


def _require_finite_pixels(pixels: np.ndarray, path: str) -> None:
    if not np.all(np.isfinite(pixels)):
        raise LfprocError(f"{path}: the image contains NaN or infinite values; re-export it with finite pixels")


def _one_line(text: str) -> str:
    return " ".join(str(text or "").split())


# ===================================================================== writing

def srgb_encode(linear: np.ndarray) -> np.ndarray:
    """The sRGB transfer function (IEC 61966-2-1) of linear values clipped to [0, 1], as float32."""
    x = np.clip(np.asarray(linear, dtype=np.float64), 0.0, 1.0)
    encoded = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1.0 / 2.4) - 0.055)
    return encoded.astype(np.float32)


def write_image(path: str | os.PathLike, image: np.ndarray, metadata: Mapping | None = None,
                format: str | None = None) -> None:
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

    Raises
    ------
    LfprocError
        Unknown format or extension, NaN/inf pixels, bad shape, unwritable destination. Nothing is
        left behind on failure.
    """
    import OpenImageIO as oiio

    path = os.fspath(path)
    fmt = _output_format(path, image, format)
    pixels, pixel_type, colour_space = _encode_pixels(image, fmt, path)
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
                raise LfprocError(f"{path}: OpenImageIO cannot write this format ({_one_line(oiio.geterror())}); "
                                  f"use .tif, .png, .exr or .jpg")
            if not out.open(tmp, spec):
                raise LfprocError(f"{path}: cannot write ({_one_line(out.geterror())}); "
                                  f"check that the folder exists and is writable")
            written = out.write_image(pixels)
            closed = out.close()
            if not (written and closed):
                raise LfprocError(f"{path}: writing failed ({_one_line(out.geterror())}); "
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


def _encode_pixels(image, fmt: str, path: str) -> tuple[np.ndarray, str, str]:
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
    if not np.all(np.isfinite(image)):
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

    path = _existing_file(path)
    inp = oiio.ImageInput.open(path)
    if inp is None:
        raise LfprocError(f"{path}: not a readable image ({_one_line(oiio.geterror())}); pass a TIFF, PNG, EXR "
                          f"or JPEG written by lfproc")
    try:
        description = inp.spec().get_string_attribute("ImageDescription")
    finally:
        inp.close()
    try:
        metadata = json.loads(description) if description else {}
    except json.JSONDecodeError:
        return {}
    return metadata if isinstance(metadata, dict) else {}


# ===================================================================== GIF and sidecars

def write_gif(path: str | os.PathLike, frames: Sequence[np.ndarray] | np.ndarray, duration_ms: float) -> None:
    """Write an animated, endlessly looping GIF of float32 linear frames, atomically (Pillow).

    Frames (each ``(H, W)``, ``(H, W, 1)`` or ``(H, W, 3)``, all the same shape) are clipped to
    [0, 1], sRGB-encoded and rounded to 8 bits; colour frames are reduced to a 256-colour palette
    by Pillow, grey frames are exact. ``duration_ms`` is the display time of each frame (GIF
    stores hundredths of a second).
    """
    from PIL import Image

    path = os.fspath(path)
    if not (isinstance(duration_ms, (int, float)) and math.isfinite(duration_ms) and duration_ms > 0):
        raise LfprocError(f"{path}: GIF frame duration {duration_ms!r} ms must be a positive number")
    stack = [np.asarray(frame) for frame in frames]
    if not stack:
        raise LfprocError(f"{path}: no frames to write; pass at least one image")
    shape = stack[0].shape
    if any(frame.shape != shape for frame in stack):
        raise LfprocError(f"{path}: GIF frames differ in shape; pass frames of one size")
    if not (len(shape) == 2 or (len(shape) == 3 and shape[2] in (1, 3))) or 0 in shape:
        raise LfprocError(f"{path}: GIF frames of shape {shape} are not (H, W), (H, W, 1) or (H, W, 3)")
    if not all(np.all(np.isfinite(frame)) for frame in stack):
        raise LfprocError(f"{path}: a GIF frame contains NaN or infinite values; fix the computation first")
    images = []
    for frame in stack:
        pixels = np.round(srgb_encode(frame) * 255.0).astype(np.uint8)
        if pixels.ndim == 3 and pixels.shape[2] == 1:
            pixels = pixels[:, :, 0]
        images.append(Image.fromarray(pixels))  # uint8 (H, W) -> "L", (H, W, 3) -> "RGB"
    try:
        with atomic_path(path, suffix=".gif") as tmp:
            images[0].save(tmp, format="GIF", save_all=True, append_images=images[1:],
                           duration=int(round(duration_ms)), loop=0)
    except OSError as exc:
        raise LfprocError(f"{path}: cannot write GIF ({exc.strerror or exc}); check the folder and permissions") from None


def sidecar_path(image_path: str | os.PathLike) -> str:
    """The contract's sidecar of ``OUTDIR/NAME.EXT``: ``OUTDIR/NAME.json``."""
    stem, extension = os.path.splitext(os.fspath(image_path))
    if extension.lower() == ".json":
        raise LfprocError(f"{image_path}: an image named .json would be its own sidecar; use an image extension")
    return stem + ".json"


def write_sidecar(image_path: str | os.PathLike, metadata: Mapping) -> str:
    """Write ``metadata`` as strict JSON (infinity as ``null``) next to the image, atomically.

    Returns
    -------
    str
        The sidecar's path (`sidecar_path`).
    """
    target = sidecar_path(image_path)
    try:
        write_json_atomic(target, metadata)
    except OSError as exc:
        raise LfprocError(f"{target}: cannot write sidecar ({exc.strerror or exc}); check the folder") from None
    return target
