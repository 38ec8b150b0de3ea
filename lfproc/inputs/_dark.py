"""Dark frames (``--dark FILE``): read like a capture, subtracted per pixel from captures and white images.

Units: the dark frame goes through the same reader and the same level mapping as the image it is taken
from (``(DN − black_level) / (white_level − black_level)`` with the camera file's or the raw file's own
levels), and is subtracted in those normalised units. The black level therefore cancels: the result is
``(DN − dark DN) / (white_level − black_level)``, i.e. the dark frame replaces the black level pixel by
pixel. Negative values (noise below the dark level) are kept, as the readers keep noise below black.
"""

from __future__ import annotations

import numpy as np

from ..errors import LfprocError


def read_dark(path: str, camera=None):
    """The dark frame at ``path`` as an `lfproc.io.Capture` (same reader and levels as captures)."""
    from ..io import read_capture

    return read_capture(path, camera)


def subtract_dark(image, dark, what: str = "capture"):
    """``image − dark`` per pixel (`lfproc.io.Capture` objects, same units: module docstring).

    Raises
    ------
    LfprocError
        One line naming both files when their sizes or channels differ, or when the dark frame is brighter on
        average than the white image it is subtracted from (``what="white image"``): the two are swapped.
    """
    from ..io import Capture

    if dark is None:
        return image
    if image.data.shape != dark.data.shape:
        def size(c):
            shape = c.data.shape
            return f"{shape[1]}x{shape[0]}" + ("" if c.data.ndim == 2 else f"x{shape[2]}")
        raise LfprocError(f"{dark.source}: this dark frame is {size(dark)} pixels but the {what} {image.source} is "
                          f"{size(image)}; take the dark frame with the same camera and mode")
    if image.cfa != dark.cfa and image.cfa != "none" and dark.cfa != "none":
        raise LfprocError(f"{dark.source}: this dark frame has colour filter {dark.cfa} but the {what} "
                          f"{image.source} has {image.cfa}; take the dark frame with the same camera")
    if what == "white image" and float(np.mean(dark.data, dtype=np.float64)) > float(np.mean(image.data, dtype=np.float64)):
        raise LfprocError(f"{image.source} and {dark.source} look swapped: the dark frame {dark.source} is brighter "
                          f"on average than the white image {image.source}; pass the white image as `white=` "
                          f"and the dark frame (lens cap on) as `dark=`")
    data = np.subtract(image.data, dark.data, dtype=np.float32)
    return Capture(data=data, cfa=image.cfa, source=image.source)
