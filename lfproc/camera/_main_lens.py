"""A photographic main lens in front of the micro lens array (the camera file's ``[main_lens]``).

The paper's optics (Table 1; Hahne et al. 2018 for a finite exit pupil): f_U, principal planes H1U/H2U,
b_U from H2U to the MLA, an f-number and the exit pupil d_A, optionally its surfaces (a
:class:`~._lens.LensPrescription`). Positions are millimetres from the sensor (Eqs. 21 and 31); views are
virtual cameras at positions F_i in the entrance pupil (Eqs. 17, 33, 34). With ε = b_U − f_U, δ = p_p/f_s
(the slope step between views), κ = 1/d_A (0 when telecentric) and L = f_s + H1sH2s + b_U + H1UH2U:

* slice a sits at d = L + f_U + f_U²·N/(a·p_m + N·ε), N = δ − a·p_m·κ (Newton's form of Eq. 21);
* the slice at infinity is a_∞ = −δ·ε/(p_m·(1 − κε)); the slices approach the front focal plane L + f_U
  as a → ∞ (telecentric) or at a = δ/(p_m·κ) (a finite exit pupil);
* view i looks from F_i = m_i·f_U/(1 − κε) with tilt Φ_i = arctan(m_i·ε/f_U), m_i = −i·δ; neighbours are
  ΔB = δ·f_U/|1 − κε| apart.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ..errors import LfprocError
from ._lens import PRESCRIPTION_TOLERANCE, LensPrescription, surfaces_to_toml
from ._main_optics import UsableRange, ViewPlacement, ViewPupil, pupil_curvature, slope_step
from ._optics import image_distance_for_focus
from ._space import SENSOR_MM
from ._transfer import RayTransfer, gap, lens, prescription_transfer
from ._validation import require_finite, require_positive


@dataclass(frozen=True)
class MainLens:
    """A photographic main lens in front of the micro lens array (the camera file's ``[main_lens]``).

    Parameters
    ----------
    focal_length_mm : float
        f_U.
    image_distance_mm : float
        b_U, H2U to the MLA's H1s; at least f_U.
    principal_plane_gap_mm : float
        H1U–H2U (negative where the planes are interchanged).
    f_number : float or None
        For the Airy limit (Eq. 22) and aperture checks.
    exit_pupil_distance_mm : float
        d_A; ``inf`` (image-side telecentric) is the 2014 paper's model.
    prescription : LensPrescription or None
        The lens's surfaces, where given: f_U, H1U–H2U and d_A are then its cardinal points.
    """

    focal_length_mm: float
    image_distance_mm: float
    principal_plane_gap_mm: float = 0.0
    f_number: float | None = None
    exit_pupil_distance_mm: float = math.inf
    prescription: LensPrescription | None = None

    object_space = SENSOR_MM
    relay_magnification = 1.0
    #: no wave-optics model of a photographic main lens (deconvolution needs a microscope's)
    wave_optics = None

    def validate(self, where: str) -> None:
        """Raise `LfprocError` naming the ``main_lens.`` key of an impossible value (``where``: the file)."""
        require_positive(self.focal_length_mm, "main_lens.focal_length_mm", where)
        require_finite(self.image_distance_mm, "main_lens.image_distance_mm", where)
        require_finite(self.principal_plane_gap_mm, "main_lens.principal_plane_gap_mm", where)
        d_a = self.exit_pupil_distance_mm
        if isinstance(d_a, bool) or not isinstance(d_a, (int, float)) or math.isnan(d_a) or d_a <= 0:
            raise LfprocError(f"{where}: main_lens.exit_pupil_distance_mm must be a positive distance or inf, "
                              f"got {d_a!r}")
        if self.f_number is not None:
            require_positive(self.f_number, "main_lens.f_number", where)
        if self.image_distance_mm < self.focal_length_mm:
            raise LfprocError(
                f"{where}: main_lens.image_distance_mm = {self.image_distance_mm} is below the main lens focal length "
                f"{self.focal_length_mm}, so the main lens would focus beyond infinity; "
                f"set image_distance_mm >= focal_length_mm (or give focus_distance_mm)")
        if self.prescription is not None:
            self._validate_prescription(where)

    def _validate_prescription(self, where: str) -> None:
        """f_U, H1U–H2U and d_A of a lens with a prescription are the prescription's own (within 0.1 %)."""
        lens_ = self.prescription
        if not isinstance(lens_, LensPrescription):
            raise LfprocError(f"{where}: main_lens prescription must be a LensPrescription, got {lens_!r}")
        if lens_.object_index != 1.0:
            raise LfprocError(f"{where}: a main lens looks at objects in air; its prescription's object_index is "
                              f"{lens_.object_index} (an immersion objective belongs in [microscope])")
        for key, value, lens_value in (
                ("focal_length_mm", self.focal_length_mm, lens_.focal_length_mm),
                ("principal_plane_gap_mm", self.principal_plane_gap_mm, lens_.principal_plane_gap_mm),
                ("exit_pupil_distance_mm", self.exit_pupil_distance_mm,
                 lens_.exit_pupil_distance_mm(self.image_distance_mm))):
            same = (value == lens_value if math.isinf(value) or math.isinf(lens_value)
                    else abs(value - lens_value) <= PRESCRIPTION_TOLERANCE * max(abs(lens_value), 1e-3))
            if not same:
                raise LfprocError(f"{where}: main_lens.{key} = {value} disagrees with the prescription's "
                                  f"{lens_value:.6g} (more than 0.1 %); use MainLens.with_prescription or fix the "
                                  f"value")

    # ----------------------------------------------------------------- where rays meet, and back
    @property
    def image_aperture_sine(self) -> float | None:
        """1/(2N) for the f-number N (paraxial), ``None`` without one."""
        return None if self.f_number is None else 1.0 / (2.0 * self.f_number)

    def transfer(self) -> RayTransfer:
        """S from H1U to the MLA: T(b_U)·L(f_U), or the prescription's own surfaces (``camera._transfer``)."""
        if self.prescription is not None:
            return prescription_transfer(self.prescription, self.image_distance_mm)
        return gap(self.image_distance_mm) @ lens(self.focal_length_mm)

    def object_position(self, shift, pitch_mm: float, slope_gap, mla_path_mm: float):
        """Distance from the sensor where two rays meet in front of the lens (Eqs. 18–21).

        Rays g = ``shift``·``pitch_mm`` apart at the MLA with image-side slopes differing by N = ``slope_gap``
        meet w = g/N behind the MLA; in Newton's form its conjugate is x = f_U²·N/(g + N·ε) from the front focal
        plane (ε = b_U − f_U), so d = L + f_U + x with L = f_s + H1sH2s + b_U + H1UH2U: the transfer's
        s = n·(B + w·D)/(A + w·C) without cancellation at infinity (the tests check they agree).
        ``inf`` where the conjugate lies behind H1U or at infinity; never negative, never NaN.
        """
        f_u = self.focal_length_mm
        g = np.asarray(shift, dtype=np.float64) * pitch_mm
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            z = f_u + f_u * f_u * slope_gap / (g + slope_gap * (self.image_distance_mm - f_u))
        z = np.where((z > 0) & np.isfinite(z), z, np.inf)
        return self.sensor_path_mm(mla_path_mm) + z

    def sensor_path_mm(self, mla_path_mm: float) -> float:
        """L = f_s + H1sH2s + b_U + H1UH2U: the sensor to H1U (Eqs. 21, 31)."""
        return mla_path_mm + self.image_distance_mm + self.principal_plane_gap_mm

    def front_focal_plane_mm(self, mla_path_mm: float) -> float:
        """L + f_U: the front focal plane, in mm from the sensor (no real image nearer)."""
        return self.sensor_path_mm(mla_path_mm) + self.focal_length_mm

    def refocus_parameter(self, camera, position):
        """The ``a`` whose slice is centred at ``position`` mm from the sensor (Eq. 21 inverted).

        a = δ·(f_U²/x − ε) / (p_m·(1 − κε + κ·f_U²/x)) with x = d − L − f_U, the distance from the front
        focal plane. `LfprocError` for a distance at or behind the main lens (d ≤ L), or NaN.
        """
        d = np.asarray(position, dtype=np.float64)
        inside = self.sensor_path_mm(camera.mla_path_mm)
        if np.any(np.isnan(d)) or np.any(d <= inside):
            bad = d[np.isnan(d) | (d <= inside)].ravel()[0]
            raise LfprocError(f"distance {bad} mm is not in front of the main lens (it must exceed {inside:.3f} mm "
                              f"from the sensor); give a larger distance")
        f_u = self.focal_length_mm
        eps = self.image_distance_mm - f_u
        kappa = pupil_curvature(self.exit_pupil_distance_mm)
        x = d - inside - f_u
        with np.errstate(divide="ignore"):
            inv_x = np.where(np.isinf(d), 0.0, 1.0 / x)
        with np.errstate(invalid="ignore"):
            pupil = 1.0 - kappa * eps + kappa * (f_u * f_u * inv_x) if kappa else 1.0
        a = slope_step(camera) * (f_u * f_u * inv_x - eps) / (camera.mla_pitch_mm * pupil)
        return float(a) if np.ndim(a) == 0 else a

    def usable_range(self, camera) -> UsableRange:
        """From the slice at infinity, a_∞ = −δ·ε/(p_m·(1 − κε)), to the front focal plane, reached as a → ∞
        (telecentric) or at a = δ/(p_m·κ) (the image-side slopes of the pair become parallel)."""
        eps = self.image_distance_mm - self.focal_length_mm
        kappa = pupil_curvature(self.exit_pupil_distance_mm)
        low = float(-slope_step(camera) * eps / (camera.mla_pitch_mm * (1.0 - kappa * eps)))
        high = math.inf
        if kappa > 0:
            high = camera.sample_pitch_mm / camera.mla_focal_length_mm / (camera.mla_pitch_mm * kappa)
        return UsableRange(low, max(high, low), math.inf, self.front_focal_plane_mm(camera.mla_path_mm),
                           "the main lens's front focal plane")

    def refusal(self, camera, a: float) -> str:
        """Below a_∞ the rays diverge (beyond infinity), or, further down, meet between the lens and its front
        focal plane; above the range they meet nearer than the front focal plane."""
        kappa = pupil_curvature(self.exit_pupil_distance_mm)
        slope_gap = slope_step(camera) - a * camera.mla_pitch_mm * kappa
        d = float(self.object_position(a, camera.mla_pitch_mm, slope_gap, camera.mla_path_mm))
        front = self.front_focal_plane_mm(camera.mla_path_mm)
        if a < self.usable_range(camera).low and not (math.isfinite(d) and d <= front):
            return "focuses beyond infinity (its rays diverge: no object is imaged there)"
        where = f"{d:.1f} mm from the sensor, " if math.isfinite(d) else ""
        return (f"focuses {where}nearer than the main lens's front focal plane ({front:.1f} mm), where no object "
                f"forms a real image")

    # ----------------------------------------------------------------- views and apertures
    def lit_view_extent(self, sample_pitch_mm: float, mla_focal_length_mm: float, center_index) -> float:
        """c, the full micro image (the paper's DOF: a main lens matched to the lenslets fills it)."""
        return float(center_index)

    def wave_depth_of_field(self) -> float:
        """0: a camera's diffraction limit is the Airy check of Eq. 22, not a DOF term."""
        return 0.0

    def place_views(self, camera, offsets) -> ViewPlacement:
        """Virtual cameras (Eqs. 17, 33, 34): F_i = m_i·f_U/(1 − κε) in the entrance pupil (the front focal plane
        when telecentric), tilt Φ_i = arctan(m_i·ε/f_U), neighbours δ·f_U/|1 − κε| apart, m_i = −i·δ."""
        f_u = self.focal_length_mm
        eps = self.image_distance_mm - f_u
        factor = 1.0 - pupil_curvature(self.exit_pupil_distance_mm) * eps
        i = np.asarray(offsets, dtype=np.float64)
        slopes = -i * slope_step(camera) + 0.0        # + 0.0: the central view at 0.0, not -0.0
        tilt = np.degrees(np.arctan(slopes * eps / f_u)) + 0.0
        return ViewPlacement(i, slopes * f_u / factor, tilt, float(slope_step(camera) * f_u / abs(factor)))

    def inside_aperture(self, camera) -> np.ndarray:
        """Views whose virtual centre lies inside the entrance pupil, a disc of diameter f_U/N (all without N)."""
        m = camera.m_hat
        if self.f_number is None:
            return np.ones((m, m), dtype=bool)
        c = camera.center_index
        pos = self.place_views(camera, np.arange(-c, c + 1)).position_mm
        radius = self.focal_length_mm / (2.0 * self.f_number)
        r2 = pos[:, None] ** 2 + pos[None, :] ** 2
        return r2 <= radius * radius * (1.0 + 1e-12)

    def view_pupil(self, camera) -> ViewPupil:
        """The virtual cameras in the entrance pupil, one baseline wide each; f/F is a disc f_U/F wide."""
        c = camera.center_index
        views = self.place_views(camera, np.arange(-c, c + 1))
        return ViewPupil(views.position_mm, views.baseline_mm, self.focal_length_mm, self.f_number)

    def lateral_sampling_um(self, camera) -> None:
        """``None``: a lens's views are perspective, the object-space size of a lens grows with distance."""
        return None

    def virtual_camera_plane_mm(self, mla_path_mm: float) -> float:
        """Distance from the sensor of the plane holding every view's virtual optical centre (Eq. 17 generalised):
        z_V = f_U·(1 − b_U/d_A)/(1 − ε/d_A) from H1U, the front focal plane when telecentric, the entrance pupil
        otherwise; ``inf`` (object-side telecentric views) when d_A = ε."""
        kappa = pupil_curvature(self.exit_pupil_distance_mm)
        f_u, b_u = self.focal_length_mm, self.image_distance_mm
        denom = 1.0 - kappa * (b_u - f_u)
        if denom == 0.0:
            return math.inf
        return self.sensor_path_mm(mla_path_mm) + f_u * (1.0 - kappa * b_u) / denom

    # ----------------------------------------------------------------- words, file, variants
    def summary(self, camera) -> dict:
        """The numbers the geometry rests on (``lfproc geometry --json``'s ``camera``; ``inf`` becomes null)."""
        return dict(m_hat=camera.m_hat, effective_pixel_pitch_mm=camera.effective_pixel_pitch_mm,
                    sample_pitch_mm=camera.sample_pitch_mm, image_distance_mm=self.image_distance_mm,
                    exit_pupil_distance_mm=self.exit_pupil_distance_mm, telecentric=camera.telecentric,
                    micro_image_scale=camera.micro_image_scale,
                    virtual_camera_plane_mm=self.virtual_camera_plane_mm(camera.mla_path_mm),
                    infinity_a=self.usable_range(camera).low)

    def describe(self) -> str:
        stop = "" if self.f_number is None else f"f/{self.f_number:g} "
        return f"{stop}main lens, f_U {self.focal_length_mm:g} mm"

    def toml_lines(self) -> list:
        """``[main_lens]`` (b_U as ``image_distance_mm``; the surfaces inline, so the file stands alone)."""
        lines = ["[main_lens]", f"focal_length_mm = {self.focal_length_mm!r}",
                 f"principal_plane_gap_mm = {self.principal_plane_gap_mm!r}",
                 f"image_distance_mm = {self.image_distance_mm!r}"]
        if self.f_number is not None:
            lines.append(f"f_number = {self.f_number!r}")
        if not math.isinf(self.exit_pupil_distance_mm):
            lines.append(f"exit_pupil_distance_mm = {self.exit_pupil_distance_mm!r}")
        if self.prescription is not None:      # indices at the lens's wavelength
            lines.append(f"wavelength_nm = {float(self.prescription.wavelength_nm)!r}")
            lines += surfaces_to_toml(self.prescription)
        return lines

    def focused_at(self, focus_distance_mm: float, mla_path_mm: float, where: str = "camera") -> "MainLens":
        """This lens with the b_U that focuses it at ``focus_distance_mm`` from the sensor (``mla_path_mm``:
        f_s + H1sH2s of the camera); a prescription's exit pupil moves with it."""
        b_u = image_distance_for_focus(self.focal_length_mm, focus_distance_mm,
                                       mla_path_mm + self.principal_plane_gap_mm, where)
        d_a = (self.exit_pupil_distance_mm if self.prescription is None
               else self.prescription.exit_pupil_distance_mm(b_u))
        return replace(self, image_distance_mm=b_u, exit_pupil_distance_mm=d_a)

    def with_prescription(self, prescription: LensPrescription, image_distance_mm: float | None = None) -> "MainLens":
        """This lens as ``prescription``: f_U, H1U–H2U and d_A become its cardinal points (b_U from its rear
        principal plane: ``image_distance_mm``, default this lens's)."""
        b_u = self.image_distance_mm if image_distance_mm is None else float(image_distance_mm)
        return replace(self, focal_length_mm=prescription.focal_length_mm,
                       principal_plane_gap_mm=prescription.principal_plane_gap_mm, image_distance_mm=b_u,
                       exit_pupil_distance_mm=prescription.exit_pupil_distance_mm(b_u), prescription=prescription)
