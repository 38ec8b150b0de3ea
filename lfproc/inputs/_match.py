"""Do camera, grid, white image, dark frame and capture belong together? One-line refusals naming both files.

Checked before anything is decoded (every decoding goes through `lfproc.prepare_decoding`, which calls these):

* **lattice kind and Bayer pattern**: the grid's ``grid`` equals the camera file's ``mla.grid``, and the
  camera file's ``sensor.cfa`` is the one the grid was calibrated with (where recorded);
* **micro image pitch**: the grid's ``pitch_px`` against the camera's prediction, the lens pitch in pixels
  (``mla.pitch_mm / sensor.pixel_pitch_mm``) times the micro image scale ``(d_A + f_s)/d_A`` of a finite
  exit pupil (`lfproc.geometry.micro_image_scale`). Accepted within ``3σ + 1e-4`` of the calibration's own
  pitch uncertainty σ, but never tighter than `PITCH_MATCH_FLOOR` (nominal pitches and zoom-dependent
  exit pupils are not exact); also accepted when the camera is, in these numbers, the one the grid was
  calibrated with (whatever that calibration warned about, it accepted). Grid files without a record of
  their camera get `PITCH_TOLERANCE_WITHOUT_RECORD`, what ``lfproc calibrate`` itself accepts;
* **sensor size and Bayer pattern**: the white image, the dark frame and every capture have the size
  (and, where the header tells, the CFA) of the white image the grid was calibrated on; a grid file
  without that record is checked against the extent of its own lenses.
"""

from __future__ import annotations

import math

from ..errors import LfprocError

#: relative pitch difference that is always accepted (nominal pitches, exit pupils that move with zoom)
PITCH_MATCH_FLOOR = 0.01
#: relative pitch difference accepted for grid files that do not record their camera (lfproc calibrate's own)
PITCH_TOLERANCE_WITHOUT_RECORD = 0.05
#: relative tolerance within which two cameras' lens pitch in pixels and micro image scale count as the same
SAME_CAMERA_TOLERANCE = 1e-4


def camera_name(camera, fallback: str = "the camera") -> str:
    return str(camera.source) if getattr(camera, "source", "") else fallback


def expected_pitch_px(camera) -> float:
    """The micro image pitch in pixels a camera predicts: lens pitch in pixels × (d_A + f_s)/d_A."""
    from ..geometry import micro_image_scale

    return float(camera.pitch_px) * float(micro_image_scale(camera))


def check_grid_fits_camera(camera, grid) -> None:
    """Refuse a `LensGrid` made for another camera: lattice kind and micro image pitch (module docstring)."""
    from ..grid import MAKE_GRID

    cam, name = camera_name(camera), grid.source or "the grid"
    if grid.kind != camera.grid:
        raise LfprocError(f"{name}: holds a {grid.kind} lens grid but {cam} says mla.grid = "
                          f"\"{camera.grid}\"; use the camera file the grid was calibrated with, or fit the grid "
                          f"again with {MAKE_GRID}")
    expected = expected_pitch_px(camera)
    deviation = grid.pitch_px / expected - 1.0
    tolerance, recorded = pitch_tolerance(grid)
    if abs(deviation) <= tolerance or _same_camera(camera, recorded):
        recorded_cfa = (recorded or {}).get("cfa")
        if recorded_cfa is not None and recorded_cfa != camera.cfa:
            raise LfprocError(f"{name}: was calibrated with sensor.cfa = \"{recorded_cfa}\" but {cam} says "
                              f"\"{camera.cfa}\"; use the camera file the grid was calibrated with, or calibrate again")
        return
    made_for = "" if recorded is None else \
        f", and it was calibrated for {recorded.get('lens_pitch_px', float('nan')):.3f} px per lens"
    raise LfprocError(f"{name}: its micro image pitch is {grid.pitch_px:.3f} px but {cam} predicts "
                      f"{expected:.3f} px (mla.pitch_mm / sensor.pixel_pitch_mm x the exit pupil's scale; "
                      f"{100 * deviation:+.1f} %, more than the {100 * tolerance:.1f} % accepted{made_for}): the grid "
                      f"belongs to another camera; pass the camera file it was made for, or calibrate again")


def pitch_tolerance(grid) -> tuple[float, dict | None]:
    """The accepted relative pitch difference of a `LensGrid`, and the camera facts its calibration recorded
    (or None)."""
    calibration = grid.calibration
    recorded = None if calibration is None else calibration.camera_facts
    if recorded is None:
        return PITCH_TOLERANCE_WITHOUT_RECORD, None
    sigma = calibration.pitch_sigma_px
    own = 3.0 * sigma / grid.pitch_px + 1e-4 if sigma is not None and math.isfinite(sigma) else 0.0
    return max(own, PITCH_MATCH_FLOOR), recorded


def _same_camera(camera, recorded: dict | None) -> bool:
    from ..geometry import micro_image_scale

    if recorded is None or recorded.get("grid", camera.grid) != camera.grid:
        return False
    return (abs(camera.pitch_px / recorded["lens_pitch_px"] - 1.0) <= SAME_CAMERA_TOLERANCE
            and abs(micro_image_scale(camera) / recorded["micro_image_scale"] - 1.0) <= SAME_CAMERA_TOLERANCE)


def reference_facts(grid, white_facts=None):
    """What every sensor image must match: the given white image's facts, else those the grid's calibration
    recorded of its white image (None where neither is known)."""
    from ._facts import ImageFacts

    if white_facts is not None:
        return white_facts
    facts = grid.calibration.white_facts if grid is not None and grid.calibration is not None else None
    if facts:
        return ImageFacts(facts.get("path") or grid.source or "the grid", facts["height"], facts["width"],
                          facts.get("cfa"), int(facts.get("channels") or 1))
    return None


def check_same_sensor(facts, reference, what: str = "capture", reference_what: str = "white image") -> None:
    """Refuse an image (`ImageFacts`) whose size, channels or Bayer pattern differ from ``reference``'s."""
    if reference is None:
        return
    if (facts.height, facts.width) != (reference.height, reference.width):
        raise LfprocError(f"{facts.path}: this {what} is {facts.size} pixels but the {reference_what} "
                          f"{reference.path} is {reference.size}; they come from different sensors or crops: "
                          f"pass files of the same camera and mode")
    if facts.cfa is not None and reference.cfa is not None and facts.cfa != reference.cfa:
        raise LfprocError(f"{facts.path}: this {what} has colour filter {facts.cfa} but the {reference_what} "
                          f"{reference.path} has {reference.cfa}; set sensor.cfa in the camera file, or pass files "
                          f"of the same camera")
    if facts.channels != reference.channels:
        raise LfprocError(f"{facts.path}: this {what} has {facts.channels} channel(s) but the {reference_what} "
                          f"{reference.path} has {reference.channels}; save both the same way (raw mosaic or RGB)")


def check_fits_grid_extent(facts, grid, what: str = "capture") -> None:
    """For grids without a record of their white image: the lenses must lie on this sensor."""
    import numpy as np

    xy = grid.centers_xy_px().reshape(-1, 2)
    margin = grid.pitch_px
    if xy[:, 0].max() > facts.width - 1 + margin or xy[:, 1].max() > facts.height - 1 + margin \
            or xy.min() < -margin or not np.isfinite(xy).all():
        raise LfprocError(f"{facts.path}: this {what} is {facts.size} pixels but the lenses of {grid.source or 'the grid'} reach "
                          f"to x = {xy[:, 0].max():.0f}, y = {xy[:, 1].max():.0f}: the grid was calibrated on "
                          f"another sensor; calibrate again with this camera's white image")
