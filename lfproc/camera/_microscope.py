"""The main optics of a light-field microscope: an infinity-corrected objective and its tube lens.

The camera file's ``[microscope]`` table (ARCHITECTURE.md, "Microscope camera file") replaces
``[main_lens]``. The objective (focal length f_obj = f_tube / M) and the tube lens form an afocal,
doubly telecentric relay: the aperture stop sits in the objective's back focal plane, which is the
tube lens's front focal plane, so every micro image is centred under its own lenslet (the paper's
telecentric case) and the native object plane is imaged onto the micro lens array with lateral
magnification M and axial magnification M²/n (n the immersion index).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import LfprocError
from ._main_optics import NATIVE_PLANE_UM
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
    """

    objective_magnification: float
    numerical_aperture: float
    immersion_index: float = 1.0
    tube_lens_focal_length_mm: float = 200.0
    relay_magnification: float = 1.0
    wavelength_nm: float | None = None
    aplanatic: bool | None = None

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
    #: object-side telecentric too: a view is one direction through every lens
    views_are_orthographic = True

    @property
    def image_aperture_sine(self) -> float:
        """NA / M (:attr:`image_numerical_aperture`)."""
        return self.image_numerical_aperture

    def transfer(self) -> RayTransfer:
        """S from the native object plane (in immersion n) to the MLA, built from its lenses:
        T(f_tube)·L(f_tube)·T(f_obj + f_tube)·L(f_obj)·T(f_obj) = [[−M, 0], [0, −1/M]] (``._transfer``)."""
        f_obj, f_tube = self.objective_focal_length_mm, self.tube_lens_focal_length_mm
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

    @property
    def wave_optics(self) -> WaveOptics:
        """The objective's parameters for wave optics (deconvolution, :mod:`lfproc.wave`)."""
        return WaveOptics(self.numerical_aperture, self.immersion_index, self.objective_magnification,
                          self.objective_focal_length_mm, self.tube_lens_focal_length_mm,
                          DEFAULT_WAVELENGTH_NM if self.wavelength_nm is None else float(self.wavelength_nm))

    def describe(self) -> str:
        return f"{self.objective_magnification:g}x/{self.numerical_aperture:g} objective"


def _positive(value, key: str, where: str) -> None:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
        raise LfprocError(f"{where}: microscope.{key} must be a finite positive number, got {value!r}")
