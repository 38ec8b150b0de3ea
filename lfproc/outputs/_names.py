"""File names of lfproc's outputs (contract: one image per slice or view, each with its sidecar)."""

from __future__ import annotations

from ..errors import LfprocError

#: output format -> file extension
FORMATS = {"tiff": ".tif", "png16": ".png", "jpeg": ".jpg", "exr": ".exr"}


def slice_name(stem: str, a: float, decimals: int = 3) -> str:
    """``STEM_a+1.500``: sign and (at least) three decimals; -0 is written as +0."""
    return f"{stem}_a{a + 0.0:+.{decimals}f}"


def slice_names(stem: str, a_values) -> list[str]:
    """Names for every slice, with as many decimals (3 to 12) as it takes to keep them apart.

    Raises
    ------
    LfprocError
        When two values of ``a`` are equal to 12 decimals: they would overwrite each other's file.
    """
    values = [float(a) for a in a_values]
    for decimals in range(3, 13):
        names = [slice_name(stem, a, decimals) for a in values]
        if len(set(names)) == len(names):
            return names
    raise LfprocError("two refocus parameters are equal (to 12 decimals): each slice needs its own a; "
                      "remove the duplicate from the list")


def view_name(stem: str, ky: int, kx: int) -> str:
    """``STEM_view_07_03`` for view (ky, kx) = (7, 3)."""
    return f"{stem}_view_{ky:02d}_{kx:02d}"
