"""Demosaicing of linear Bayer mosaics (OpenCV) and the conversion of any sensor image to ``(H, W, C)``."""

from __future__ import annotations

import numpy as np

from ..errors import LfprocError

DEMOSAIC_METHODS = ("fast", "careful")
#: OpenCV's Bayer codes are named after the second row's pixels: our top-left 2x2 -> their name
_CV_BAYER = {"RGGB": "BayerBG", "BGGR": "BayerRG", "GRBG": "BayerGB", "GBRG": "BayerGR"}
#: how far (pixels) each method reads around a pixel: bilinear reads the 3x3 neighbourhood; OpenCV's
#: edge-aware variant reads up to two pixels away
DEMOSAIC_REACH_PX = {"fast": 1, "careful": 2}


def check_cfa(cfa: str) -> None:
    """LfprocError unless ``cfa`` is ``"none"`` or a Bayer pattern lfproc knows."""
    if cfa != "none" and cfa not in _CV_BAYER:
        raise LfprocError(f"unknown Bayer pattern {cfa!r}; use one of {', '.join(_CV_BAYER)}")


def check_method(method: str) -> None:
    if method not in DEMOSAIC_METHODS:
        raise LfprocError(f"unknown demosaic method {method!r}; use one of {', '.join(DEMOSAIC_METHODS)}")


def quantize_levels(mosaic: np.ndarray) -> tuple[float, float]:
    """``(low, scale)`` of :func:`quantize` for ``mosaic``: its minimum (at most 0) and 65535 / its range."""
    data = np.asarray(mosaic)
    low = min(float(data.min()), 0.0) if data.size else 0.0
    top = float(data.max()) - low if data.size else 0.0
    return low, (65535.0 / top if top > 0 else 1.0)


def quantize(mosaic: np.ndarray, levels: tuple | None = None) -> tuple[np.ndarray, float, float]:
    """A linear mosaic as OpenCV's demosaicing needs it: ``(uint16 data, low, scale)`` with
    ``linear = data / scale + low`` (the data shifted by the minimum, so negative values survive, and
    scaled to 16 bits). ``levels``, ``(low, scale)`` of the whole image (:func:`quantize_levels`) when
    ``mosaic`` is a part of it: every part is then quantized alike (the edge-aware demosaicing's choice
    of direction turns on single 16-bit units, so a part's own levels would change its output).

    Raises
    ------
    LfprocError
        NaN or infinite pixels (the 16-bit conversion would turn them into silent zeros).
    """
    data = np.asarray(mosaic, dtype=np.float32)
    if not np.all(np.isfinite(data)):
        raise LfprocError("the Bayer mosaic contains NaN or infinite pixels; replace them "
                          "(e.g. numpy.nan_to_num) before decoding")
    low, scale = quantize_levels(data) if levels is None else levels
    return np.clip((data - low) * scale + 0.5, 0, 65535).astype(np.uint16), low, scale


def quantized_zero(low: float, scale: float) -> int:
    """The 16-bit value :func:`quantize` gives a linear 0."""
    return int(min(max((0.0 - low) * scale + 0.5, 0), 65535))


def demosaic_u16(as_u16: np.ndarray, cfa: str, method: str = "fast", dst: np.ndarray | None = None) -> np.ndarray:
    """OpenCV's demosaicing of a mosaic that :func:`quantize` made, left in its 16-bit units: ``(H, W, 3)``
    uint16 RGB (written into ``dst``, a C-contiguous array of that shape, when given)."""
    import cv2

    code = getattr(cv2, f"COLOR_{_CV_BAYER[cfa]}2RGB" + ("_EA" if method == "careful" else ""))
    return cv2.cvtColor(as_u16, code, dst=dst)


def demosaic_quantized(as_u16: np.ndarray, low: float, scale: float, cfa: str, method: str = "fast") -> np.ndarray:
    """:func:`demosaic` of a mosaic that :func:`quantize` made: ``(H, W, 3)`` RGB float32, linear."""
    rgb = demosaic_u16(as_u16, cfa, method).astype(np.float32)
    rgb *= np.float32(1.0 / scale)
    rgb += np.float32(low)
    return rgb


def demosaic(mosaic: np.ndarray, cfa: str, method: str = "fast", levels: tuple | None = None) -> np.ndarray:
    """Demosaic a linear Bayer mosaic ``(H, W)`` to ``(H, W, 3)`` RGB float32 with OpenCV.

    ``"fast"`` is bilinear interpolation (linear, so a ratio of two demosaiced images stays an exact
    weighted average); ``"careful"`` is OpenCV's edge-aware (EA) variant. The data are shifted and
    scaled into 16 bits for OpenCV (its demosaicing works on integers; :func:`quantize`) and back, so
    linear values keep 1/65535 of their range as precision; negative values (noise below the black
    level) are kept: bilinear weights sum to 1, so adding the offset back afterwards is exact. ``levels``:
    the quantization of the whole image when ``mosaic`` is a part of it (:func:`quantize`).
    """
    if cfa not in _CV_BAYER:
        raise LfprocError(f"unknown Bayer pattern {cfa!r}; use one of {', '.join(_CV_BAYER)}")
    check_method(method)
    return demosaic_quantized(*quantize(mosaic, levels), cfa, method)


def to_channels(image: np.ndarray, cfa: str, method: str, levels: tuple | None = None) -> np.ndarray:
    """A sensor image as ``(H, W, C)`` float32: demosaiced if it is a Bayer mosaic (``levels``: see
    :func:`demosaic`)."""
    data = np.asarray(image)
    if data.ndim == 2:
        if cfa != "none":
            return demosaic(data, cfa, method, levels)
        return data.astype(np.float32, copy=False)[:, :, None]
    if data.ndim == 3:
        return data.astype(np.float32, copy=False)
    raise LfprocError(f"a sensor image must be 2-D or (H, W, C), got shape {data.shape}")


def channel_count(image: np.ndarray, cfa: str) -> int:
    """How many channels :func:`to_channels` gives for ``image``."""
    if image.ndim == 2:
        return 3 if cfa != "none" else 1
    if image.ndim == 3:
        return int(image.shape[2])
    raise LfprocError(f"a sensor image must be 2-D or (H, W, C), got shape {image.shape}")
