"""File names of lfproc's outputs (contract: one image per slice or view, each with its sidecar; slices named
so that ``ls`` lists them in the order they are focused)."""

from __future__ import annotations

import os

from ..errors import LfprocError
from ..lightfield import output_stem
from ._optics_tags import named_by_position

#: output format -> file extension
FORMATS = {"tiff": ".tif", "png16": ".png", "jpeg": ".jpg", "exr": ".exr"}


def slice_name(stem: str, a: float, decimals: int = 3) -> str:
    """``STEM_a+1.500``: sign and (at least) three decimals; -0 is written as +0."""
    return f"{stem}_a{a + 0.0:+.{decimals}f}"


def slice_names(stem: str, a_values, camera=None) -> list[str]:
    """Names for every slice, whose lexical order (``ls``) is the order they are focused in.

    ``STEM_RR_a+1.500`` for a camera, ``STEM_RR_z-12.500um`` for a microscope (``camera`` given, z in µm
    from the native object plane, :func:`lfproc.geometry.slice_geometry`): ``RR`` is the slice's rank by
    increasing a, zero-padded (at least two digits), so the files list from the farthest slice to the
    nearest (a camera: from infinity towards the lens; a microscope: from low to high z) whatever the order
    of ``a_values``; the a or z that follows is for people, with as many decimals (3 to 12) as it takes to
    keep the slices apart. (A plain signed number cannot sort: ``a+…`` lists before ``a-…``, and
    ``a-0.5`` before ``a-1.0``.)

    Raises
    ------
    LfprocError
        When two values of ``a`` are equal to 12 decimals: they would be the same slice twice.
    """
    values = [float(a) for a in a_values]
    labels = _labels(values, camera)
    order = sorted(range(len(values)), key=values.__getitem__)
    rank = [0] * len(values)
    for position, index in enumerate(order):
        rank[index] = position
    width = max(2, len(str(len(values) - 1)))
    return [f"{stem}_{r:0{width}d}_{label}" for r, label in zip(rank, labels)]


def _labels(values: list[float], camera) -> list[str]:
    """``a+1.500`` (or, in signed depths from the native object plane, a microscope's ``z-12.500um``) for each
    slice, with decimals enough to tell them apart."""
    if len({round(a, 12) for a in values}) != len(values):
        raise LfprocError("two refocus parameters are equal (to 12 decimals): each slice needs its own a; "
                          "remove the duplicate from the list")
    z, space = None, None
    if named_by_position(camera):   # a microscope's z in µm: named by z, which sorts like a
        from ..geometry import slice_geometry

        z, space = [float(v) for v in (slice_geometry(camera, values).depth if values else [])], \
            camera.main_optics.object_space
    for decimals in range(3, 13):
        if z is None:
            labels = [f"a{a + 0.0:+.{decimals}f}" for a in values]
        else:
            labels = [f"{space.letter}{v + 0.0:+.{decimals}f}{space.unit}" for v in z]
        if len(set(labels)) == len(labels):
            return labels
    return labels


def view_name(stem: str, ky: int, kx: int) -> str:
    """``STEM_view_07_03`` for view (ky, kx) = (7, 3)."""
    return f"{stem}_view_{ky:02d}_{kx:02d}"


def unique_stems(paths: list[str]) -> dict[str, str]:
    """Map each input to its output stem; inputs whose names collide get their folder name prefixed."""
    stems = [output_stem(p) for p in paths]
    result = {}
    for path, stem in zip(paths, stems):
        if stems.count(stem) > 1:
            parent = os.path.basename(os.path.dirname(os.path.abspath(path))) or "root"
            stem = f"{parent}_{stem}"
        result[path] = stem
    if len(set(result.values())) != len(result):
        raise LfprocError("several inputs would write outputs of the same name; give each capture a distinct name")
    return result
