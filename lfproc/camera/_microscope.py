"""The main optics of a light-field microscope: an infinity-corrected objective and its tube lens.

The camera file's ``[microscope]`` table (ARCHITECTURE.md, "Microscope camera file") replaces
``[main_lens]``. The objective (focal length f_obj = f_tube / M) and the tube lens form an afocal,
doubly telecentric relay: the aperture stop sits in the objective's back focal plane, which is the
tube lens's front focal plane, so every micro image is centred under its own lenslet (the paper's
telecentric case) and the native object plane is imaged onto the micro lens array with lateral
magnification M and axial magnification M²/n (n the immersion index).

Views are directions (object-side telecentric): view i samples the image-side direction sine
u/|(u, f_s)|, u = i·p_p under its lens, which the Abbe sine condition n·sin θ = M·sin θ' turns into the
object-space angle θ_i; its rays cross the objective's back focal plane (its pupil) at −f_tube·sin θ'.

The objective may be given by its surfaces (``objective``, a :class:`~._lens.LensPrescription` whose
object side is the immersion medium): its focal length, NA (the stop's marginal ray from the front focal
point) and native object plane (the front focal plane) are then those of its paraxial trace
(docs/microscope.md, "An objective by its surfaces").
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import LfprocError
from ._lens import PRESCRIPTION_TOLERANCE, LensPrescription, surfaces_to_toml
from ._main_optics import UsableRange, ViewPlacement, ViewPupil, slope_step
from ._space import NATIVE_PLANE_UM
from ._transfer import RayTransfer, gap, lens

#: λ where the camera file gives no microscope.wavelength_nm
DEFAULT_WAVELENGTH_NM = 550.0
#: camera-file key of each Microscope field (error messages)
MICROSCOPE_KEYS = ("objective_magnification", "numerical_aperture", "immersion_index",
                   "tube_lens_focal_length_mm", "relay_magnification", "wavelength_nm", "aplanatic")


@dataclass(frozen=True)
class WaveOptics:
    """What a wave-optics model of a light-field microscope needs of its objective (Broxton et al., Opt.
    Express 21(21), 2013): an aplanatic objective with its tube lens, infinity corrected and telecentric.

    Attributes
    ----------
    numerical_aperture : float
        NA = n·sin α.
    immersion_index : float
        n between sample and objective.
    objective_magnification : float
        M, with its tube lens.
    objective_focal_length_mm, tube_lens_focal_length_mm : float
        f_obj = f_tube / M and f_tube.
    wavelength_nm : float
        λ in vacuum (the camera file's ``microscope.wavelength_nm``; 550 where it gives none).
    """

    numerical_aperture: float
    immersion_index: float
    objective_magnification: float
    objective_focal_length_mm: float
    tube_lens_focal_length_mm: float
    wavelength_nm: float

    def describe(self) -> str:
        return (f"{self.objective_magnification:g}x/{self.numerical_aperture:g} (n {self.immersion_index:g}), "
                f"{self.wavelength_nm:g} nm")


@dataclass(frozen=True)
class Microscope:
    """Objective, tube lens and relay of a light-field microscope (Levoy et al., SIGGRAPH 2006).

    Parameters
    ----------
    objective_magnification : float
        M, the objective's nominal lateral magnification with its tube lens.
    numerical_aperture : float
        NA = n·sin θ_max of the objective; must be below ``immersion_index``.
    immersion_index : float
        n, the refractive index between sample and objective (1.0 air, 1.33 water, 1.515 oil).
    tube_lens_focal_length_mm : float
        f_tube; the objective's focal length is f_tube / M.
    relay_magnification : float
        Lateral magnification from the lenslets' focal plane to the sensor (1 without a relay): the
        pixel at the lenslet focal plane is ``pixel_pitch_mm / relay_magnification``.
    wavelength_nm : float or None
        λ for the diffraction term of the depth of field; ``None`` uses 550 nm.
    aplanatic : bool or None
        Refocus with per-view shifts from the sine condition (True), paraxial shifts a·(c − k)
        (False), or decide from the camera (None, the default; see ``lfproc.geometry``).
    objective : LensPrescription or None
        The objective's surfaces, sample side first (its ``object_index`` is ``immersion_index``); M, NA
        and the native object plane are then its paraxial trace's (:meth:`prescribed`), and
        :meth:`transfer` traces its surfaces.
    """

    objective_magnification: float
    numerical_aperture: float
    immersion_index: float = 1.0
    tube_lens_focal_length_mm: float = 200.0
    relay_magnification: float = 1.0
    wavelength_nm: float | None = None
    aplanatic: bool | None = None
    objective: LensPrescription | None = None

    @classmethod
    def prescribed(cls, objective: LensPrescription, tube_lens_focal_length_mm: float = 200.0,
                   **settings) -> "Microscope":
        """The microscope of an objective given by its surfaces: M = f_tube/f_obj from its focal length,
        NA from its stop (:attr:`LensPrescription.numerical_aperture`), n its object-side index.
        ``settings``: ``relay_magnification``, ``wavelength_nm``, ``aplanatic``."""
        return cls(tube_lens_focal_length_mm / objective.focal_length_mm, objective.numerical_aperture,
                   objective.object_index, tube_lens_focal_length_mm, objective=objective, **settings)

    def validate(self, where: str) -> None:
        """Raise `LfprocError` with one line naming the ``microscope.`` key for an impossible value."""
        for key in ("objective_magnification", "numerical_aperture", "immersion_index",
                    "tube_lens_focal_length_mm", "relay_magnification"):
            _positive(getattr(self, key), key, where)
        if self.wavelength_nm is not None:
            _positive(self.wavelength_nm, "wavelength_nm", where)
        if self.immersion_index < 1.0:
            raise LfprocError(f"{where}: microscope.immersion_index must be at least 1 (air), "
                              f"got {self.immersion_index!r}")
        if self.numerical_aperture >= self.immersion_index:
            raise LfprocError(f"{where}: microscope.numerical_aperture {self.numerical_aperture!r} must be below "
                              f"microscope.immersion_index {self.immersion_index!r} (NA = n·sin θ); check both")
        if self.aplanatic is not None and not isinstance(self.aplanatic, bool):
            raise LfprocError(f"{where}: microscope.aplanatic must be true or false, got {self.aplanatic!r}")
        if self.objective is not None:
            self._validate_objective(where)

    def _validate_objective(self, where: str) -> None:
        """M, NA and n of a prescribed objective are its trace's (within 0.1 %)."""
        objective = self.objective
        if not isinstance(objective, LensPrescription):
            raise LfprocError(f"{where}: microscope objective must be a LensPrescription, got {objective!r}")
        for key, value, traced in (
                ("objective_magnification", self.objective_magnification,
                 self.tube_lens_focal_length_mm / objective.focal_length_mm),
                ("numerical_aperture", self.numerical_aperture, objective.numerical_aperture),
                ("immersion_index", self.immersion_index, objective.object_index)):
            if abs(value - traced) > PRESCRIPTION_TOLERANCE * abs(traced):
                raise LfprocError(f"{where}: microscope.{key} = {value} disagrees with the objective's surfaces "
                                  f"({traced:.6g}, more than 0.1 %); remove it or fix the surfaces")

    @property
    def objective_focal_length_mm(self) -> float:
        """f_obj = f_tube / M."""
        return self.tube_lens_focal_length_mm / self.objective_magnification

    @property
    def axial_magnification(self) -> float:
        """M² / n: an object-space depth step dz moves the image behind the tube lens by dz·M²/n."""
        return self.objective_magnification ** 2 / self.immersion_index

    @property
    def image_numerical_aperture(self) -> float:
        """NA / M, the sine of the marginal ray's angle at the micro lens array (Abbe sine condition)."""
        return self.numerical_aperture / self.objective_magnification

    @property
    def wavelength_mm(self) -> float:
        """λ in millimetres (550 nm where the camera file gives none)."""
        return (DEFAULT_WAVELENGTH_NM if self.wavelength_nm is None else self.wavelength_nm) * 1e-6

    # ----------------------------------------------------------------- the main-optics interface (._main_optics)
    object_space = NATIVE_PLANE_UM
    #: the aperture stop in the objective's back focal plane: image-side telecentric, no exit pupil to place
    exit_pupil_distance_mm = math.inf

    @property
    def image_aperture_sine(self) -> float:
        """NA / M (:attr:`image_numerical_aperture`)."""
        return self.image_numerical_aperture

    def transfer(self) -> RayTransfer:
        """S from the native object plane (in immersion n) to the MLA, built from its lenses:
        T(f_tube)·L(f_tube)·T(f_obj + f_tube)·L(f_obj)·T(f_obj) = [[−M, 0], [0, −1/M]] (``._transfer``).
        A prescribed objective: its surfaces from its front focal plane to its back focal plane, the tube
        lens f_tube behind that (afocal and imaging paraxially, whatever the surfaces)."""
        f_tube = self.tube_lens_focal_length_mm
        if self.objective is not None:
            o = self.objective
            a, b, c, d = o.matrix()
            to_first = gap((o.vertex_mm(0) - o.front_focal_plane_mm) / o.object_index)
            to_back_focus = gap(o.rear_principal_plane_mm + o.focal_length_mm - o.length_mm)
            s = gap(f_tube) @ lens(f_tube) @ gap(f_tube) @ to_back_focus @ RayTransfer(a, b, c, d) @ to_first
        else:
            f_obj = self.objective_focal_length_mm
            s = gap(f_tube) @ lens(f_tube) @ gap(f_obj + f_tube) @ lens(f_obj) @ gap(f_obj)
        return RayTransfer(s.A, s.B, s.C, s.D, float(self.immersion_index))

    def object_position(self, shift, pitch_mm: float, slope_gap, mla_path_mm: float = 0.0):
        """z in µm where two rays meet: the image point w = ``shift``·``pitch_mm`` / ``slope_gap`` behind the MLA
        maps to n·w/M² through :meth:`transfer`, positive towards the objective (``mla_path_mm`` does not
        enter: z is from the native object plane). Linear in ``shift``: z = shift · z(1), exactly, so that
        z → a → z round-trips as z / z(1) · z(1)."""
        with np.errstate(divide="ignore", invalid="ignore"):
            per_shift = np.asarray(self.transfer().object_offset_mm(pitch_mm / np.asarray(slope_gap)),
                                   dtype=np.float64) * 1000.0
        z = np.asarray(shift, dtype=np.float64) * per_shift + 0.0   # + 0.0: never −0
        return float(z) if z.ndim == 0 else z

    def z_per_a_um(self, camera) -> float:
        """dz/da = m̂·f_s·n/M² in µm: slice a's ray pair (a lenses apart, slopes one view step δ apart) meets at
        a·z(1), exactly (:meth:`object_position` is linear in the shift)."""
        return float(self.object_position(1.0, camera.mla_pitch_mm, slope_step(camera)))

    def refocus_parameter(self, camera, position):
        """a = z / z(1): the slice at ``position`` µm from the native object plane."""
        z = np.asarray(position, dtype=np.float64)
        if not np.all(np.isfinite(z)):
            raise LfprocError(f"depth {position} um is not a finite number of micrometres")
        a = z / self.z_per_a_um(camera)
        return float(a) if a.ndim == 0 else a

    def usable_range(self, camera) -> UsableRange:
        """Every ``a``: an afocal objective images every depth, of either sign (no slice at infinity, no front
        focal plane)."""
        return UsableRange(-math.inf, math.inf, -math.inf, math.inf)

    def refusal(self, camera, a: float) -> str:
        return "focuses at no depth of the sample"

    def na_view_extent(self, sample_pitch_mm: float, mla_focal_length_mm: float, center_index: int) -> int:
        """c_NA: the largest view offset |i| ≤ c whose image-side ray sine, i·p_p/|(i·p_p, f_s)|, is within NA/M."""
        i = np.arange(int(center_index) + 1)
        u = i * sample_pitch_mm
        sines = u / np.hypot(u, mla_focal_length_mm)
        return int(i[sines <= self.image_numerical_aperture * (1.0 + 1e-12)][-1])

    def lit_view_extent(self, sample_pitch_mm: float, mla_focal_length_mm: float, center_index) -> float:
        """The views inside the NA (c_NA, at least 1 and at most c): the DOF of a microscope's slices."""
        return float(min(max(self.na_view_extent(sample_pitch_mm, mla_focal_length_mm, center_index), 1),
                         center_index))

    def wave_depth_of_field(self) -> float:
        """λ·n/NA² in µm, the wave term of a microscope's DOF (Inoué and Spring; Levoy et al. 2006)."""
        return self.wavelength_mm * 1000.0 * self.immersion_index / self.numerical_aperture ** 2

    # ----------------------------------------------------------------- views: directions (sine condition)
    def image_sines(self, camera, offsets) -> np.ndarray:
        """Image-side direction sines u/|(u, f_s)| of view offsets i, sampled at u = i·p_p under their lens."""
        u = np.asarray(offsets, dtype=np.float64) * camera.sample_pitch_mm
        return u / np.hypot(u, camera.mla_focal_length_mm)

    def place_views(self, camera, offsets) -> ViewPlacement:
        """Orthographic views: view i at the object-space angle θ_i, sin θ_i = −M·sin θ'_i/n (Abbe sine condition;
        m_i = −i·p_p/f_s; NaN beyond 90°), crossing the objective's pupil at f_obj·n·sin θ_i = −f_tube·sin θ'_i."""
        image = self.image_sines(camera, offsets)
        sines = -self.objective_magnification * image / self.immersion_index
        with np.errstate(invalid="ignore"):
            angle = np.degrees(np.arcsin(np.where(np.abs(sines) <= 1.0, sines, np.nan))) + 0.0
        return ViewPlacement(np.asarray(offsets, dtype=np.float64), -self.tube_lens_focal_length_mm * image + 0.0,
                             angle, None)

    def inside_aperture(self, camera) -> np.ndarray:
        """``(m̂, m̂)``: views whose image-side ray sine, |(u_x, u_y)|/|(u_x, u_y, f_s)|, is within NA/M."""
        c = camera.center_index
        k = np.arange(-c, c + 1, dtype=np.float64) * camera.sample_pitch_mm
        ux, uy = np.meshgrid(k, k)
        rho = np.sqrt(ux * ux + uy * uy + camera.mla_focal_length_mm ** 2)
        return (ux * ux + uy * uy) <= (self.image_numerical_aperture * rho) ** 2 * (1.0 + 1e-12)

    def view_pupil(self, camera) -> ViewPupil:
        """Directions have no position in a pupil: the views are image-side slopes i·δ under the lenslets, f/F
        a disc 1/F wide in slope, the widest the image-side working f-number M/(2·NA)."""
        step = slope_step(camera)
        coords = (np.arange(camera.m_hat) - camera.center_index) * step
        return ViewPupil(coords, step, 1.0, 1.0 / (2.0 * self.image_aperture_sine))

    def lateral_sampling_um(self, camera) -> float:
        """p_m/M in µm: every lens covers the same patch of the sample, at every depth (Levoy et al. 2006)."""
        return camera.mla_pitch_mm / self.objective_magnification * 1000.0

    # ----------------------------------------------------------------- words and file
    def summary(self, camera) -> dict:
        """The derived numbers of a microscope camera (``lfproc geometry --json``'s ``camera``)."""
        return dict(m_hat=camera.m_hat, effective_pixel_pitch_mm=camera.effective_pixel_pitch_mm,
                    pitch_px=camera.pitch_px, telecentric=True, objective_magnification=self.objective_magnification,
                    numerical_aperture=self.numerical_aperture, immersion_index=self.immersion_index,
                    objective_focal_length_mm=self.objective_focal_length_mm,
                    axial_magnification=self.axial_magnification, z_per_a_um=self.z_per_a_um(camera),
                    lateral_sampling_um=self.lateral_sampling_um(camera),
                    na_views=self.na_view_extent(camera.sample_pitch_mm, camera.mla_focal_length_mm,
                                                 camera.center_index),
                    wavelength_nm=self.wavelength_mm * 1e6)
    @property
    def wave_optics(self) -> WaveOptics:
        """The objective's parameters for wave optics (deconvolution, :mod:`lfproc.wave`)."""
        return WaveOptics(self.numerical_aperture, self.immersion_index, self.objective_magnification,
                          self.objective_focal_length_mm, self.tube_lens_focal_length_mm,
                          DEFAULT_WAVELENGTH_NM if self.wavelength_nm is None else float(self.wavelength_nm))

    def describe(self) -> str:
        return f"{self.objective_magnification:g}x/{self.numerical_aperture:g} objective"

    def toml_lines(self) -> list:
        """``[microscope]`` (a prescribed objective's surfaces inline, as ``[[microscope.surfaces]]``)."""
        lines = ["[microscope]"]
        for key in MICROSCOPE_KEYS:
            value = getattr(self, key)
            if isinstance(value, bool):
                lines.append(f"{key} = {'true' if value else 'false'}")
            elif value is not None:
                lines.append(f"{key} = {float(value)!r}")
        if self.objective is not None:      # indices at wavelength_nm (550 nm where not given)
            lines += surfaces_to_toml(self.objective, "microscope")
        return lines


def _positive(value, key: str, where: str) -> None:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
        raise LfprocError(f"{where}: microscope.{key} must be a finite positive number, got {value!r}")
