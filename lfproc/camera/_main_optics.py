"""The main optics in front of the micro lens array: one parameter of the ray model, one small interface.

The paper's ray model (Eqs. 13–31) follows chief-ray pairs from the sensor through the micro lens array
to the point w behind the MLA where they meet (:mod:`lfproc.geometry`). Everything in front of the MLA
enters only through the *main optics*: where the object point conjugate to that image point lies, in which
unit and from which origin it is reported, and the optics' aperture. Two kinds implement the interface:

* :class:`MainLens`, a photographic main lens: f_U, H1U–H2U, b_U, f-number and exit pupil (the
  ``[main_lens]`` table), optionally its surfaces (a :class:`~._lens.LensPrescription`). Distances are
  millimetres from the sensor (the paper's Eq. 21 and 31).
* :class:`~._microscope.Microscope`, an objective + tube lens (+ relay) of a light-field microscope (the
  ``[microscope]`` table). Depths are micrometres from the native object plane, positive towards the
  objective.

The interface (:class:`MainOptics`) is what the geometry, the outputs and the commands may ask; nothing
outside :mod:`lfproc.camera` and the optics' own geometry module branches on which kind it is.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

from ._lens import LensPrescription
from ._transfer import RayTransfer, gap, lens, prescription_transfer


@dataclass(frozen=True)
class ObjectSpace:
    """The unit and origin in which the main optics report object-space positions of slices and depths.

    Attributes
    ----------
    unit : {"mm", "um"}
    origin : str
        Where 0 is, and which way is positive (words for labels and sidecars).
    keys : tuple of str
        The contract's record keys of (position, near limit, far limit, depth of field), in this unit.
    per_mm : float
        Units per millimetre (1 or 1000).
    """

    unit: str
    origin: str
    keys: tuple
    per_mm: float

    @property
    def position_key(self) -> str:
        """The record key of a slice's (or a depth's) position: ``distance_mm`` or ``z_um``."""
        return self.keys[0]

    @property
    def from_sensor(self) -> bool:
        """True for distances from the sensor (positive, ``inf`` at infinity); False for signed depths."""
        return self.unit == "mm"


def _in_space(unit: str, name: str, doc: str) -> property:
    """A contract name that reads the field ``name`` where the result is in ``unit``, else ``None``."""
    return property(lambda self: getattr(self, name) if self.space.unit == unit else None, doc=doc)


class PositionNames:
    """The contract's names of a result's one set of positions ``depth``, ``near``, ``far`` in its ``space``:
    ``distance_mm``, ``near_mm``, ``far_mm`` (mm from the sensor) and ``z_um``, ``z_near_um``, ``z_far_um``
    (µm from the native object plane), each ``None`` in the other space. Read-only; a mixin for the frozen
    results (depth maps)."""

    distance_mm = _in_space("mm", "depth", "distance from the sensor in mm (Eq. 21); None for a microscope")
    near_mm = _in_space("mm", "near", "the nearer limit in mm from the sensor (Eq. 31); None for a microscope")
    far_mm = _in_space("mm", "far", "the farther limit in mm from the sensor (Eq. 31); None for a microscope")
    z_um = _in_space("um", "depth", "z in µm from the native object plane; None for a camera")
    z_near_um = _in_space("um", "near", "the limit nearer the objective (larger z), µm; None for a camera")
    z_far_um = _in_space("um", "far", "the limit farther from the objective (smaller z), µm; None for a camera")


class SliceNames(PositionNames):
    """:class:`PositionNames` and the depth of field ``dof`` as ``dof_mm`` / ``dof_um`` (slices, focal stacks)."""

    dof_mm = _in_space("mm", "dof", "the depth of field in mm (Eq. 23); None for a microscope")
    dof_um = _in_space("um", "dof", "the depth of field in µm; None for a camera")


#: a photographic camera's object space: millimetres from the sensor (the paper's Eqs. 21, 31)
SENSOR_MM = ObjectSpace("mm", "from the sensor", ("distance_mm", "near_mm", "far_mm", "dof_mm"), 1.0)
#: a microscope's object space: micrometres from the native object plane, positive towards the objective
NATIVE_PLANE_UM = ObjectSpace("um", "from the native object plane, positive towards the objective",
                              ("z_um", "z_near_um", "z_far_um", "dof_um"), 1000.0)


@runtime_checkable
class MainOptics(Protocol):
    """What the ray model and the outputs ask of the optics in front of the micro lens array."""

    @property
    def object_space(self) -> ObjectSpace:
        """Unit and origin of the positions :meth:`object_position` returns."""

    @property
    def exit_pupil_distance_mm(self) -> float:
        """d_A from the MLA towards the object; ``inf`` for image-side telecentric optics."""

    @property
    def relay_magnification(self) -> float:
        """Lateral magnification from the lenslets' focal plane to the sensor (1 without a relay)."""

    @property
    def image_aperture_sine(self) -> float | None:
        """The sine of the marginal ray's angle at the MLA (1/(2N) of a lens, NA/M of an objective); ``None``
        when the camera file does not say."""

    @property
    def views_are_orthographic(self) -> bool:
        """True where every view looks along one direction from all lenses (an object-side telecentric
        objective: views have angles); False where each view is a pinhole camera at a position on the lens."""

    def transfer(self) -> RayTransfer:
        """The paraxial transfer from the object-side reference plane to the MLA (reduced angles)."""

    def object_position(self, shift, pitch_mm: float, slope_gap, mla_path_mm: float):
        """Where two rays meet in object space, in :attr:`object_space` units: rays ``shift`` lens pitches
        (``pitch_mm``) apart at the MLA whose image-side slopes differ by ``slope_gap`` meet
        w = shift·pitch / slope_gap behind it, and the object point is that image point's conjugate
        (``mla_path_mm`` = f_s + H1s–H2s, the sensor to the MLA's H1s)."""

    def lit_view_extent(self, sample_pitch_mm: float, mla_focal_length_mm: float, center_index) -> float:
        """r, the half-extent in view steps of the views the optics fill: the DOF's views when none are named."""

    def wave_depth_of_field(self) -> float:
        """The diffraction term added to every slice's geometric DOF, in :attr:`object_space` units."""

    @property
    def wave_optics(self):
        """The objective's parameters for a wave-optics model (:class:`~._microscope.WaveOptics`: NA, immersion,
        magnification, focal lengths, wavelength), or ``None`` where the optics have none (a main lens)."""

    def describe(self) -> str:
        """A short human description (``f/4 main lens, f_U 100 mm`` / ``20x/0.5 objective``)."""


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
    views_are_orthographic = False
    #: no wave-optics model of a photographic main lens (deconvolution needs a microscope's)
    wave_optics = None

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

    def lit_view_extent(self, sample_pitch_mm: float, mla_focal_length_mm: float, center_index) -> float:
        """c, the full micro image (the paper's DOF: a main lens matched to the lenslets fills it)."""
        return float(center_index)

    def wave_depth_of_field(self) -> float:
        """0: a camera's diffraction limit is the Airy check of Eq. 22, not a DOF term."""
        return 0.0

    def describe(self) -> str:
        stop = "" if self.f_number is None else f"f/{self.f_number:g} "
        return f"{stop}main lens, f_U {self.focal_length_mm:g} mm"

