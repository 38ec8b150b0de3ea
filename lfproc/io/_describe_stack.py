"""``lfproc info`` on a focal z-stack that ``lfproc refocus --stack`` wrote (ImageJ hyperstack or OME-TIFF), or a
volume that ``lfproc deconvolve`` wrote (OME-TIFF: its planes, their depths and the voxel size in µm).

The stack is recognised by its slices' records, which lfproc stores as JSON (``{"slices": [...], "pixel_um",
"z_spacing_um", "evenly_spaced"}``) in the ImageJ ``Info`` or the OME image ``Description``. The x/y/z
spacing and its unit are read from the file's own structure, as Fiji (resolution tags, ``spacing``,
``unit``) and Bio-Formats (``PhysicalSize*``) read them, not from that JSON. tifffile is imported here only
for TIFFs whose description is an ImageJ or OME header.
"""

from __future__ import annotations

import json

from ..errors import LfprocError


def is_stack_header(description: str) -> bool:
    """Whether a TIFF's first ``ImageDescription`` is an ImageJ or an OME-XML header."""
    return description.startswith("ImageJ=") or ("<OME" in description[:1000])


def describe_stack(path: str) -> dict | None:
    """The stack's slice count, size, channels, x/y/z spacing and embedded records; None for an ImageJ or
    OME TIFF that lfproc did not write (described as a plain image)."""
    import logging
    import struct
    from xml.etree.ElementTree import ParseError

    import tifffile

    log = logging.getLogger("tifffile")      # it logs what it finds wrong in a file; the answer says enough
    level = log.level
    log.setLevel(logging.CRITICAL + 1)
    try:
        with tifffile.TiffFile(path) as tif:
            series = tif.series[0]
            shape, axes = tuple(int(n) for n in series.shape), series.axes
            if tif.is_imagej:
                kind, (tags, spacing) = "imagej", _imagej(tif)
            elif tif.is_ome:
                kind, (tags, spacing) = "ome", _ome(tif.ome_metadata)
            else:
                return None
    except (OSError, ValueError, KeyError, IndexError, TypeError, AttributeError, struct.error, ParseError,
            tifffile.TiffFileError) as exc:
        raise LfprocError(f"{path}: unreadable ImageJ/OME TIFF ({exc}); re-copy the file") from None
    finally:
        log.setLevel(level)
    if not isinstance(tags, dict) or not isinstance(tags.get("slices"), list):
        return None
    size = dict(zip(axes, shape))
    if _is_volume(tags):      # lfproc deconvolve's: planes of voxels, their size in µm in the sample
        return {"path": path, "format": "lfproc-output", "product": "deconvolved volume", "stack_format": kind,
                "raw_light_field": False, "width": size.get("X"), "height": size.get("Y"),
                "planes": size.get("Z", 1), "axes": axes, "voxel_um": [spacing["z"], spacing["y"], spacing["x"]],
                "z_um": [record.get("z_um") for record in tags["slices"]],
                "tags": {k: v for k, v in tags.items() if k not in ("product", "slices")}}
    return {"path": path, "format": "lfproc-output", "product": "focal stack (z-stack)", "stack_format": kind,
            "raw_light_field": False, "width": size.get("X"), "height": size.get("Y"), "slices": size.get("Z", 1),
            "channels": size.get("C", size.get("S", 1)), "axes": axes, "spacing": spacing, "tags": tags}


def _is_volume(tags: dict) -> bool:
    """A volume of ``lfproc deconvolve``: so named in its records, or (files of lfproc's first deconvolution, which
    did not name it) planes recorded by their depth and index only."""
    planes = tags["slices"]
    return tags.get("product") == "deconvolved volume" or (
        bool(planes) and all(isinstance(r, dict) and set(r) == {"z_um", "plane"} for r in planes))


def _json(text) -> dict | None:
    try:
        value = json.loads(text) if isinstance(text, str) else None
    except ValueError:
        return None
    return value if isinstance(value, dict) else None


def _imagej(tif) -> tuple[dict | None, dict]:
    """The records in ``Info`` and the spacing Fiji reads: 1 / resolution in x and y, ``spacing`` in z."""
    meta = tif.imagej_metadata or {}
    page = tif.pages[0]

    def step(tag):
        value = page.tags.get(tag)
        if value is None:
            return 1.0
        numerator, denominator = value.value
        return denominator / numerator if numerator else 1.0

    spacing = {"x": step("XResolution"), "y": step("YResolution"), "z": float(meta.get("spacing", 1.0)),
               "unit": str(meta.get("unit", "pixel"))}
    return _json(meta.get("Info")), spacing


def _ome(xml: str) -> tuple[dict | None, dict]:
    """The records in the image ``Description`` and the ``Pixels`` element's ``PhysicalSize{X,Y,Z}``."""
    from xml.etree import ElementTree

    root = ElementTree.fromstring(xml)
    namespace = root.tag[:root.tag.index("}") + 1] if root.tag.startswith("{") else ""
    image = root.find(f"{namespace}Image")
    description = image.find(f"{namespace}Description") if image is not None else None
    pixels = image.find(f"{namespace}Pixels") if image is not None else None
    attrib = pixels.attrib if pixels is not None else {}
    spacing = {axis: float(attrib.get(f"PhysicalSize{axis.upper()}", 1.0)) for axis in "xyz"}
    spacing["unit"] = attrib.get("PhysicalSizeXUnit", "µm") if "PhysicalSizeX" in attrib else "pixel"
    return _json(description.text if description is not None else None), spacing
