"""Defaults from what was measured rather than from the camera file's nominal numbers.

**m̂ from the measured micro image pitch.** Decoding resamples every micro image to m̂ × m̂ samples, m̂ the
largest odd integer not above the micro image pitch in pixels. Without ``[decode] micro_image_px`` the
camera file can only give the *nominal* pitch, ``mla.pitch_mm / sensor.pixel_pitch_mm`` (over the relay
of a microscope); the micro images a white image shows are spaced by the lens pitch times the exit pupil's
scale ``(d_A + f_s)/d_A``, and a real rig's pixel size or relay is seldom exactly its nominal value (a
microscope radiometry frame: nominal 16.89 px, measured 17.20 px). Where a grid is known (calibrated from a
white image, or read from GRID.json) and the camera file does not state m̂, m̂ is the largest odd integer not
above the grid's *measured* pitch: a nominal 46.5 px with micro images 48.2 px apart gives 47, not 45, and no
ring of views the sensor holds is dropped. A stated m̂ is always kept.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass


@dataclass(frozen=True)
class MeasuredMHat:
    """The m̂ decoding uses and why: ``camera`` carries it; ``note`` is one line (None where the camera's
    own m̂ stands unchanged)."""

    camera: object          # lfproc.Camera
    note: str | None


def measured_m_hat(camera, pitch_px: float, source: str = "the grid") -> MeasuredMHat:
    """``camera`` with m̂ from the measured micro image pitch ``pitch_px`` (module docstring), unless the
    camera states m̂ (`Camera.micro_image_px_given`) or the measured pitch gives the same m̂."""
    from ..camera import largest_odd_at_most

    if camera.micro_image_px_given or not pitch_px > 1.0:
        return MeasuredMHat(camera, None)
    m_hat = largest_odd_at_most(float(pitch_px))
    if m_hat == camera.m_hat:
        return MeasuredMHat(camera, None)
    nominal = camera.mla_pitch_mm / camera.lenslet_pixel_pitch_mm
    note = (f"decoding {m_hat} x {m_hat} views (m_hat {m_hat}, the largest odd integer <= the micro image pitch "
            f"{pitch_px:.3f} px measured by {source}; the camera file's nominal {nominal:.3f} px gives {camera.m_hat}); "
            f"set [decode] micro_image_px in the camera file to choose")
    return MeasuredMHat(dataclasses.replace(camera, micro_image_px=m_hat), note)
