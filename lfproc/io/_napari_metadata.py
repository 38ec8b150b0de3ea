"""napari-LF's ``metadata.txt`` (JSON) as a microscope camera file (ARCHITECTURE.md, "Microscope camera file").

napari-LF (the LFAnalyze/LFDisplay lineage of Levoy's light-field microscope tools) keeps a rig's optics
in the ``"calibrate"`` table of its settings file. The documented mapping (``docs/microscope.md``):

=========================  ==================================  ==========================================
napari-LF key (unit)       camera file key                     reading
=========================  ==================================  ==========================================
``pixel_size`` (µm)        ``sensor.pixel_pitch_mm``           the pixel at the lenslets (no relay):
                                                               ``microscope.relay_magnification`` = 1
``ulens_pitch`` (µm)       ``mla.pitch_mm``
``ulens_focal_distance``   ``mla.focal_length_mm``             the lenslet-to-sensor distance, the f_s the
(µm)                                                           views are formed with (``ulens_focal_length``,
                                                               the lenslets' nominal focal length, is a comment)
``objective_magnification````microscope.objective_magnification``
``objective_na``           ``microscope.numerical_aperture``
``medium_index``           ``microscope.immersion_index``
``tubelens_focal_length``  ``microscope.tube_lens_focal_length_mm``
(mm)
``center_wavelength`` (nm) ``microscope.wavelength_nm``
=========================  ==================================  ==========================================

The lenslet grid is rectangular (napari-LF's model). Each number's source goes into ``[provenance]``.
"""

from __future__ import annotations

import json
import math
import os

from ..errors import LfprocError

#: (napari-LF key, camera-file key, scale to the camera file's unit)
MAPPING = (
    ("pixel_size", "sensor.pixel_pitch_mm", 1e-3),
    ("ulens_pitch", "mla.pitch_mm", 1e-3),
    ("ulens_focal_distance", "mla.focal_length_mm", 1e-3),
    ("objective_magnification", "microscope.objective_magnification", 1.0),
    ("objective_na", "microscope.numerical_aperture", 1.0),
    ("medium_index", "microscope.immersion_index", 1.0),
    ("tubelens_focal_length", "microscope.tube_lens_focal_length_mm", 1.0),
    ("center_wavelength", "microscope.wavelength_nm", 1.0),
)
_UNITS = {"pixel_size": "um", "ulens_pitch": "um", "ulens_focal_distance": "um", "tubelens_focal_length": "mm",
          "center_wavelength": "nm"}


def is_napari_metadata(path: str) -> bool:
    """A JSON file (any name) with napari-LF's ``"calibrate"`` table holding ``ulens_pitch``."""
    try:
        if os.path.getsize(path) > 1 << 20:
            return False
        with open(path, encoding="utf-8") as fh:
            document = json.load(fh)
    except (OSError, ValueError, UnicodeDecodeError):
        return False
    return isinstance(document, dict) and isinstance(document.get("calibrate"), dict) and \
        "ulens_pitch" in document["calibrate"]


def napari_camera(path: str):
    """``(Camera, notes)``: the microscope camera napari-LF's metadata file describes, with its provenance.

    Raises
    ------
    LfprocError
        A key of the mapping missing or not a positive number (one line naming the key and the file).
    """
    from ..camera import Camera, Microscope

    with open(path, encoding="utf-8") as fh:
        table = json.load(fh)["calibrate"]
    values, provenance = {}, []
    for key, target, scale in MAPPING:
        value = table.get(key)
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
            raise LfprocError(f"{path}: napari-LF metadata 'calibrate.{key}' must be a positive number, got "
                              f"{value!r}; fix the metadata file or write the camera file by hand (docs/microscope.md)")
        values[target] = _scaled(value, scale)
        unit = f" ({_UNITS[key]})" if key in _UNITS else ""
        provenance.append((target, f"napari-LF metadata: calibrate.{key}{unit}"))
    provenance.append(("microscope.relay_magnification",
                       "napari-LF metadata: calibrate.pixel_size is the pixel at the lenslets (no relay): 1"))
    provenance.append(("mla.grid", "default: rectangular (napari-LF's lenslet model)"))
    provenance.append(("decode.micro_image_px", "not stated: the largest odd integer not above the measured micro "
                                                "image pitch (the white image's calibration), else pitch / pixel pitch"))
    scope = Microscope(objective_magnification=values["microscope.objective_magnification"],
                       numerical_aperture=values["microscope.numerical_aperture"],
                       immersion_index=values["microscope.immersion_index"],
                       tube_lens_focal_length_mm=values["microscope.tube_lens_focal_length_mm"],
                       relay_magnification=1.0, wavelength_nm=values["microscope.wavelength_nm"])
    scope.validate(path)
    camera = Camera(pixel_pitch_mm=values["sensor.pixel_pitch_mm"], mla_pitch_mm=values["mla.pitch_mm"],
                    mla_focal_length_mm=values["mla.focal_length_mm"], grid="rectangular", main_optics=scope,
                    name=_rig_name(path), source=path,
                    provenance=tuple(provenance))
    notes = [f"camera file written by 'lfproc camera' from napari-LF metadata {path}"]
    nominal = table.get("ulens_focal_length")
    if isinstance(nominal, (int, float)) and not isinstance(nominal, bool):
        notes.append(f"napari-LF metadata: calibrate.ulens_focal_length = {nominal:g} um, the lenslets' nominal focal "
                     f"length (not used: mla.focal_length_mm is ulens_focal_distance, the lenslet-to-sensor distance)")
    return camera, notes


def _scaled(value: float, scale: float) -> float:
    """``value * scale`` without binary noise for powers of ten (7.4 um is 0.0074 mm, not 0.0074000000000000003)."""
    from decimal import Decimal

    if scale == 1.0:
        return float(value)
    return float(Decimal(repr(float(value))).scaleb(round(math.log10(scale))))


def _rig_name(path: str) -> str:
    """The file's stem, or its folder's name for napari-LF's usual ``metadata.txt``."""
    stem = os.path.splitext(os.path.basename(path))[0]
    if stem.lower() == "metadata":
        stem = os.path.basename(os.path.dirname(os.path.abspath(path))) or stem
    return f"{stem} (napari-LF)"
