"""`Capture`: a sensor capture as every reader returns it, linear float32 with its CFA."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


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


def normalise_mosaic(mosaic: np.ndarray, black: np.ndarray, white: np.ndarray) -> np.ndarray:
    """float32 ``(mosaic − black) / (white − black)`` with levels per 2×2 CFA position.

    Parameters
    ----------
    mosaic : numpy.ndarray
        Integer raw data ``(H, W)``.
    black, white : numpy.ndarray
        ``(2, 2)`` levels of the pixels at (row % 2, column % 2).
    """
    data = np.empty(mosaic.shape, np.float32)
    for dy in range(2):
        for dx in range(2):
            level = np.float32(black[dy, dx])
            data[dy::2, dx::2] = (mosaic[dy::2, dx::2].astype(np.float32) - level) / np.float32(white[dy, dx] - level)
    return data
