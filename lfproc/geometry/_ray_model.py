"""The camera as the ray model sees it: sample pitch, lens pitch, focal lengths, spacings, exit pupil.

Every geometry function takes a :class:`~lfproc.camera.Camera`, whose sample pitch is the micro
image pitch over the odd m̂ of the decoder. :class:`RayModel` is the same set of numbers without
that tie: any sample pitch and any real micro image size M, as PlenoptiSign and the paper's
raw-sensor examples use them. The geometry functions accept either (they read the same attributes).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..camera import MainLens
from ..errors import LfprocError


@dataclass(frozen=True)
class RayModel:
    """Parameters of the paraxial ray model (all lengths in mm, distances as in :class:`Camera`).

    Parameters
    ----------
    sample_pitch_mm : float
        p_p, the spacing of the samples under each micro lens.
    mla_pitch_mm, mla_focal_length_mm, main_focal_length_mm, image_distance_mm : float
        p_m, f_s, f_U, b_U.
    micro_image_px : float
        M, samples per micro image (real; c = (M − 1)/2 sets the extreme samples of the DOF).
    mla_principal_plane_gap_mm, main_principal_plane_gap_mm : float
        H1s–H2s and H1U–H2U.
    exit_pupil_distance_mm : float
        d_A from the micro lens array; ``inf`` = telecentric.
    f_number : float or None
    """

    sample_pitch_mm: float
    mla_pitch_mm: float
    mla_focal_length_mm: float
    main_focal_length_mm: float
    image_distance_mm: float
    micro_image_px: float
    mla_principal_plane_gap_mm: float = 0.0
    main_principal_plane_gap_mm: float = 0.0
    exit_pupil_distance_mm: float = math.inf
    f_number: float | None = None

    def __post_init__(self):
        for key in ("sample_pitch_mm", "mla_pitch_mm", "mla_focal_length_mm", "main_focal_length_mm",
                    "micro_image_px", "exit_pupil_distance_mm"):
            value = getattr(self, key)
            if not (isinstance(value, (int, float)) and value > 0):
                raise LfprocError(f"ray model: {key} must be a positive number, got {value!r}")
        if not self.image_distance_mm >= self.main_focal_length_mm:
            raise LfprocError(f"ray model: image_distance_mm {self.image_distance_mm} is below the focal length "
                              f"{self.main_focal_length_mm}")

    @property
    def m_hat(self) -> float:
        return self.micro_image_px

    @property
    def center_index(self) -> float:
        return (self.micro_image_px - 1.0) / 2.0

    @property
    def telecentric(self) -> bool:
        return math.isinf(self.exit_pupil_distance_mm)

    @property
    def micro_image_scale(self) -> float:
        d_a = self.exit_pupil_distance_mm
        return 1.0 if self.telecentric else (d_a + self.mla_focal_length_mm) / d_a

    @property
    def main_optics(self) -> MainLens:
        """The main lens as the one main-optics interface (:class:`~lfproc.camera.MainLens`)."""
        return MainLens(self.main_focal_length_mm, self.image_distance_mm, self.main_principal_plane_gap_mm,
                        self.f_number, self.exit_pupil_distance_mm)

    #: error messages name the model
    source = "ray model"

    @property
    def mla_path_mm(self) -> float:
        return self.mla_focal_length_mm + self.mla_principal_plane_gap_mm
