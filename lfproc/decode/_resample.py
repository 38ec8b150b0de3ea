"""Reading an ``(H, W, C)`` image at the view sample positions with ``cv2.remap``."""

from __future__ import annotations

import numpy as np

from ..errors import LfprocError
from ..grid import LensGrid
from ._positions import remap_maps

INTERPOLATIONS = ("nearest", "linear", "cubic", "lanczos")
#: how far (pixels) beyond a sample position each interpolation reads
INTERPOLATION_REACH_PX = {"nearest": 1, "linear": 1, "cubic": 2, "lanczos": 4}
CV_MAX_SIZE = 32000  # cv2.remap requires every image side below SHRT_MAX


def check_interpolation(interpolation: str) -> None:
    if interpolation not in INTERPOLATIONS:
        raise LfprocError(f"unknown interpolation {interpolation!r}; use one of {', '.join(INTERPOLATIONS)}")


def cv_flag(interpolation: str) -> int:
    import cv2

    check_interpolation(interpolation)
    return {"nearest": cv2.INTER_NEAREST, "linear": cv2.INTER_LINEAR, "cubic": cv2.INTER_CUBIC,
            "lanczos": cv2.INTER_LANCZOS4}[interpolation]


def remap_into(dst: np.ndarray, image: np.ndarray, map_x: np.ndarray, map_y: np.ndarray, flag: int,
               scale: float | None = None, offset: float = 0.0, border: float = 0) -> None:
    """``dst[i, j, :] = image`` read at ``(map_x[i, j], map_y[i, j])``, 0 outside; blocks of rows and of
    4 channels (OpenCV's limits: sides below 32767, at most 4 channels per call). With ``scale``, ``dst``
    (float32) receives ``value · scale + offset``: the conversion of a quantized image's samples, which
    reads ``border`` outside (the value that stands for 0)."""
    import cv2

    channels = image.shape[2]
    for r0 in range(0, map_x.shape[0], CV_MAX_SIZE - 1):
        r1 = min(r0 + CV_MAX_SIZE - 1, map_x.shape[0])
        for ch0 in range(0, channels, 4):
            ch1 = min(ch0 + 4, channels)
            plane = np.ascontiguousarray(image[:, :, ch0:ch1] if channels > 1 else image[:, :, 0])
            res = cv2.remap(plane, map_x[r0:r1], map_y[r0:r1], flag, borderMode=cv2.BORDER_CONSTANT,
                            borderValue=(border,) * 4)
            block = dst[r0:r1, :, ch0:ch1]
            res = res.reshape(block.shape)
            if scale is None:
                block[...] = res
            else:
                np.multiply(res, np.float32(scale), out=block)
                if offset:
                    block += np.float32(offset)


def check_remap_size(height: int, width: int, cols: int) -> None:
    if max(height, width, cols) >= CV_MAX_SIZE:
        raise LfprocError(f"sensor image {width}x{height} ({cols} lens columns) is beyond OpenCV's remap limit of "
                          f"{CV_MAX_SIZE} px")


def resample_views(image: np.ndarray, grid: LensGrid, m_hat: int, interpolation: str = "linear",
                   maps: list | None = None) -> np.ndarray:
    """Read an ``(H, W, C)`` image at the sample positions: ``(m̂, m̂, rows, cols, C)`` float32.

    Positions outside the image read 0. One ``cv2.remap`` per view row (and block of map rows).
    """
    flag = cv_flag(interpolation)
    h, w, channels = image.shape
    check_remap_size(h, w, grid.cols)
    maps = maps if maps is not None else remap_maps(grid, m_hat)
    out = np.empty((m_hat, m_hat, grid.rows, grid.cols, channels), dtype=np.float32)
    src = np.ascontiguousarray(image, dtype=np.float32)
    flat = out.reshape(m_hat, m_hat * grid.rows, grid.cols, channels)  # rows (kx, r) of view row ky
    for ky, (map_x, map_y) in enumerate(maps):
        remap_into(flat[ky], src, map_x, map_y, flag)
    return out
