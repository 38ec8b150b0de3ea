"""A contract camera from Lytro metadata, with the provenance of every number.

What the metadata gives (SI units there, millimetres here): pixel pitch, micro lens pitch and tiling,
the MLA-to-sensor distance (the micro lens focal length f_s of a Standard Plenoptic Camera), the main
lens focal length f_U and f-number at the capture's zoom, the exit pupil distance, levels and CFA.
What it does not give: the main lens's focus (image) distance and the principal plane gaps. Those
come from ``focus_distance_mm`` or stay documented defaults (focused at infinity, b_U = f_U; thin
lenses), each named in ``provenance`` so that ``lfproc geometry`` can say where numbers came from.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..camera import Camera, MainLens
from ..errors import LfprocError
from ._lytro_metadata import LytroMetadata

DEFAULT_FOCUS = ("default: focused at infinity, b_U = f_U (the metadata has no focus distance); "
                 "pass --focus-distance MM")


@dataclass(frozen=True)
class LytroCamera:
    """A `Camera` built from metadata, where each key came from, and notes for the camera file.

    Attributes
    ----------
    camera : Camera
    provenance : tuple of (str, str)
        ``(dotted camera-file key, "metadata: <key>" or "default: …" or "flag: …")``.
    notes : tuple of str
        Facts from the metadata that the camera file has no key for (written as comments).
    """

    camera: Camera
    provenance: tuple
    notes: tuple

    def to_toml(self) -> str:
        """The camera file: notes as comments, then the contract tables with ``[provenance]`` last."""
        text = self.camera.to_toml()
        if self.camera.telecentric:   # said explicitly: the metadata's "effectively infinite" offset
            text = text.replace("[decode]", "exit_pupil_distance_mm = inf\n[decode]", 1)
        return "\n".join(f"# {note}" for note in self.notes) + "\n" + text


def lytro_camera(meta: LytroMetadata, focus_distance_mm: float | None = None) -> LytroCamera:
    """Build the camera of a Lytro capture from its metadata.

    Parameters
    ----------
    meta : LytroMetadata
    focus_distance_mm : float, optional
        Distance from the sensor the main lens was focused at (``inf`` allowed); without it the main
        lens is taken as focused at infinity (b_U = f_U), and the provenance says so.

    Raises
    ------
    LfprocError
        When the metadata lacks a number the model cannot do without (pixel pitch, lens pitch,
        MLA-to-sensor distance, focal length).
    """
    where = meta.source
    need = {"devices.sensor.pixelPitch": meta.pixel_pitch_m, "devices.mla.lensPitch": meta.lens_pitch_m,
            "devices.mla.sensorOffset.z": meta.sensor_offset_m[2] if meta.sensor_offset_m else None,
            "devices.lens.focalLength": meta.focal_length_m}
    for key, value in need.items():
        if value is None or value <= 0:
            raise LfprocError(f"{where}: the metadata lacks {key} (or it is not positive); write the camera file "
                              f"by hand (see the README's camera file format)")
    provenance = [
        ("sensor.pixel_pitch_mm", "metadata: devices.sensor.pixelPitch"),
        ("sensor.cfa", f"metadata: {meta.raw_details_key}.mosaic.upperLeftPixel"),
        ("mla.pitch_mm", "metadata: devices.mla.lensPitch"),
        ("mla.focal_length_mm", "metadata: devices.mla.sensorOffset.z (MLA-to-sensor distance)"),
        ("mla.grid", "metadata: devices.mla.tiling"),
        ("mla.principal_plane_gap_mm", "default: 0, thin micro lenses (the metadata has no principal planes)"),
        ("main_lens.focal_length_mm", "metadata: devices.lens.focalLength"),
        ("main_lens.principal_plane_gap_mm", "default: 0, thin main lens (the metadata has no principal planes)"),
    ]
    black, white = meta.levels()
    levels = {}
    if black.min() == black.max() and white.min() == white.max():
        levels = dict(black_level=float(black[0, 0]), white_level=float(white[0, 0]))
        provenance += [("sensor.black_level", f"metadata: {meta.raw_details_key}.pixelFormat.black"),
                       ("sensor.white_level", f"metadata: {meta.raw_details_key}.pixelFormat.white")]
    if meta.f_number is not None:
        provenance.append(("main_lens.f_number", "metadata: devices.lens.fNumber"))
    if meta.exit_pupil_at_infinity:
        exit_pupil = math.inf
        text = ("metadata: devices.lens.exitPupilOffset.z" + (f" = {meta.exit_pupil_offset_m:g} m, effectively "
                f"infinite (telecentric)" if meta.exit_pupil_offset_m is not None else " absent: telecentric"))
    else:
        exit_pupil = metres_to_mm(meta.exit_pupil_offset_m)
        text = "metadata: devices.lens.exitPupilOffset.z"
    provenance.append(("main_lens.exit_pupil_distance_mm", text))
    f_u = metres_to_mm(meta.focal_length_m)
    fields = dict(
        pixel_pitch_mm=metres_to_mm(meta.pixel_pitch_m), mla_pitch_mm=metres_to_mm(meta.lens_pitch_m),
        mla_focal_length_mm=metres_to_mm(meta.sensor_offset_m[2]),
        main_optics=MainLens(f_u, f_u, f_number=meta.f_number, exit_pupil_distance_mm=exit_pupil),
        grid="hexagonal" if "hex" in (meta.tiling or "").lower() else "rectangular",
        cfa=meta.cfa, name=" ".join(p for p in ("Lytro", meta.model, meta.serial or "") if p), source=where, **levels)
    if focus_distance_mm is None:
        provenance.append(("main_lens.image_distance_mm", DEFAULT_FOCUS))
    else:
        fields["main_optics"] = fields["main_optics"].focused_at(float(focus_distance_mm),
                                                                 fields["mla_focal_length_mm"], where)
        provenance.append(("main_lens.image_distance_mm",
                           f"flag: --focus-distance {focus_distance_mm:g} mm (thin-lens equation)"))
    provenance.append(("decode.micro_image_px", "not stated: the largest odd integer not above the measured micro "
                                                "image pitch (the white image's calibration), else pitch / pixel pitch"))
    return LytroCamera(camera=Camera(**fields, provenance=tuple(provenance)), provenance=tuple(provenance),
                       notes=tuple(_notes(meta)))


def metres_to_mm(metres: float) -> float:
    """The metadata's number in millimetres without binary noise: its decimal (the shortest that reads back
    as it) shifted by three places, so 3e-05 m is 0.03 mm, not 0.030000000000000002 as 3e-05 * 1e3 is; every
    digit the metadata has is kept (1.3999999737279722e-06 m is 0.0013999999737279722 mm)."""
    from decimal import Decimal

    value = float(metres)
    return float(Decimal(repr(value)).scaleb(3)) if math.isfinite(value) else value * 1e3


def _notes(meta: LytroMetadata) -> list[str]:
    notes = [f"camera file written by 'lfproc camera' from {meta.source} (Lytro {meta.model}"
             f"{', serial ' + meta.serial if meta.serial else ''})"]
    if meta.rotation_rad is not None:
        notes.append(f"metadata: devices.mla.rotation = {math.degrees(meta.rotation_rad):.6f} deg "
                     f"(lfproc calibrate measures the lattice rotation from the white image)")
    if meta.scale_factor is not None:
        notes.append(f"metadata: devices.mla.scaleFactor = {meta.scale_factor[0]:.6f}, {meta.scale_factor[1]:.6f}")
    if meta.zoom_step is not None or meta.focus_step is not None:
        notes.append(f"metadata: devices.lens.zoomStep = {meta.zoom_step:g}, focusStep = {meta.focus_step:g}, "
                     f"infinityLambda = {_number(meta.infinity_lambda)}")
    black, white = meta.levels()
    if not (black.min() == black.max() and white.min() == white.max()):
        notes.append(f"levels per 2x2 position: black {black.tolist()}, white {white.tolist()} "
                     f"(Lytro files carry their own levels; the camera file's are not used for them)")
    return notes


def _number(value) -> str:
    """A metadata number for reading: 7 significant digits at most (the metadata's floats are float32)."""
    return str(value) if value is None or isinstance(value, int) else f"{float(value):.7g}"
