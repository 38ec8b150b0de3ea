"""The main optics in front of the micro lens array: one parameter of the ray model, one small interface.

The paper's ray model (Eqs. 13–31) follows chief-ray pairs from the sensor through the micro lens array
to the point w behind the MLA where they meet (:mod:`lfproc.geometry`). Everything in front of the MLA
enters only through the *main optics*, which are asked to do things, never what kind they are: where the
object point conjugate to an image point lies, and back (in their own unit, from their own origin:
:class:`~._space.ObjectSpace`), which slices image real objects and why the others do not, how the views
are placed (virtual cameras at positions, or directions), which views lie inside their stop, how many views
their aperture fills, the diffraction term of the depth of field, and how the camera file writes them.

Two kinds are built in: :class:`~._main_lens.MainLens` (``[main_lens]``, distances in mm from the sensor)
and :class:`~._microscope.Microscope` (``[microscope]``, depths in µm from the native object plane). Any
other class with the members of :class:`MainOptics` works the same (``tests/test_third_optics.py`` writes
one); nothing outside :mod:`lfproc.camera` and the optics' own geometry modules asks which kind it is.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

from ._space import ObjectSpace
from ._transfer import RayTransfer


@dataclass(frozen=True)
class UsableRange:
    """The refocus parameters of real slices and where their ends focus.

    Attributes
    ----------
    low, high : float
        The lowest and highest ``a`` whose slice images a real object (``-inf``/``inf`` where unbounded).
    low_position, high_position : float
        Where the slices at ``low`` and ``high`` focus, in the optics' object space (the limits as ``a``
        tends to an unbounded end).
    high_name : str
        What the near end is, for messages (``"the main lens's front focal plane"``); empty where it is only a
        position.
    """

    low: float
    high: float
    low_position: float
    high_position: float
    high_name: str = ""

    def near_end(self, space) -> str:
        """The near end in words: ``"the main lens's front focal plane (100.4 mm)"``, or its position."""
        where = space.text(self.high_position)
        return f"{self.high_name} ({where})" if self.high_name else where


@dataclass(frozen=True, eq=False)
class ViewPlacement:
    """Where the views along one axis look from, or along.

    Attributes
    ----------
    offset : ndarray
        View offsets i (in view steps from the central view; fractional where the decoder read the views
        off the lens centres).
    position_mm : ndarray
        Where each view's rays cross the optics' pupil: a virtual camera's optical centre F_i (Eq. 17), or
        for orthographic views the height in the objective's back focal plane.
    tilt_deg : ndarray
        The view's axis to the optical axis: Φ_i (Eq. 33), or an orthographic view's object-space angle
        (NaN where no ray has that direction).
    baseline_mm : float or None
        ΔB between neighbouring views (Eq. 34); ``None`` for orthographic views, which are directions:
        every view sees every point from the same place.
    """

    offset: np.ndarray
    position_mm: np.ndarray
    tilt_deg: np.ndarray
    baseline_mm: float | None

    @property
    def orthographic(self) -> bool:
        """Whether the views are directions (no baseline, no virtual camera positions)."""
        return self.baseline_mm is None


@dataclass(frozen=True, eq=False)
class ViewPupil:
    """The views as cells of a pupil, for synthetic apertures (:mod:`lfproc.geometry`'s ``_aperture``).

    Attributes
    ----------
    coordinates : ndarray (m̂,)
        Each view offset's coordinate in the pupil along an axis.
    cell : float
        The width of one view's cell, in the same unit.
    length : float
        An aperture f/F is a disc of diameter ``length / F`` in those coordinates.
    widest : float or None
        The optics' own f-number (the widest synthetic aperture), ``None`` where the camera file gives none.
    """

    coordinates: np.ndarray
    cell: float
    length: float
    widest: float | None


@runtime_checkable
class MainOptics(Protocol):
    """What the ray model, the outputs and the commands ask of the optics in front of the micro lens array.

    Methods that take ``camera`` read the micro lens array and sensor behind the optics from it (pitches,
    f_s, m̂: the :class:`~lfproc.camera.Camera` the optics sit in). ``wave_optics`` (the objective's wave
    description for deconvolution, ``None`` without an objective) belongs here too.

    Attributes
    ----------
    object_space : ObjectSpace
        The unit, origin and direction of its positions (mm from the sensor for a main lens, µm from the native
        object plane for a microscope).
    wave_optics : WaveOptics or None
        The objective's wave description (deconvolution), ``None`` without an objective.
    """

    @property
    def object_space(self) -> ObjectSpace:
        """Unit, origin and direction of the positions :meth:`object_position` returns."""

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

    def validate(self, where: str) -> None:
        """Raise `LfprocError` (one line naming the camera-file key, ``where`` the file) for impossible values."""

    def transfer(self) -> RayTransfer:
        """The paraxial transfer from the object-side reference plane to the MLA (reduced angles)."""

    def object_position(self, shift, pitch_mm: float, slope_gap, mla_path_mm: float):
        """Where two rays meet in object space, in :attr:`object_space` units: rays ``shift`` lens pitches
        (``pitch_mm``) apart at the MLA whose image-side slopes differ by ``slope_gap`` meet
        w = shift·pitch / slope_gap behind it, and the object point is that image point's conjugate
        (``mla_path_mm`` = f_s + H1s–H2s, the sensor to the MLA's H1s)."""

    def refocus_parameter(self, camera, position):
        """The ``a`` whose slice (the central ray pair, Eqs. 13–21) is centred at ``position``, in
        :attr:`object_space` units; `LfprocError` for a position no slice can focus on."""

    def usable_range(self, camera) -> UsableRange:
        """The ``a`` of the slices that image real objects, and where those ends focus."""

    def refusal(self, camera, a: float) -> str:
        """Why slice ``a`` (outside :meth:`usable_range`) images no real object, in words."""

    def lit_view_extent(self, sample_pitch_mm: float, mla_focal_length_mm: float, center_index) -> float:
        """r, the half-extent in view steps of the views the optics fill: the DOF's views when none are named."""

    def wave_depth_of_field(self) -> float:
        """The diffraction term added to every slice's geometric DOF, in :attr:`object_space` units."""

    def place_views(self, camera, offsets) -> ViewPlacement:
        """The views at ``offsets`` (view steps from the central one) along one axis."""

    def inside_aperture(self, camera) -> np.ndarray:
        """``(m̂, m̂)`` booleans: the views inside the optics' stop (all where the camera file gives none)."""

    def view_pupil(self, camera) -> ViewPupil:
        """The views as cells of a pupil, for synthetic apertures."""

    def lateral_sampling_um(self, camera) -> float | None:
        """The object-space size of one lens in µm where it is one for every depth (object-side telecentric
        optics); ``None`` where it changes with depth (perspective views)."""

    def summary(self, camera) -> dict:
        """The numbers that describe the optics in this camera, JSON-ready (``lfproc geometry --json``)."""

    @property
    def wave_optics(self):
        """The objective's parameters for a wave-optics model (:class:`~._microscope.WaveOptics`: NA, immersion,
        magnification, focal lengths, wavelength), or ``None`` where the optics have none (a main lens)."""

    def describe(self) -> str:
        """A short human description (``f/4 main lens, f_U 100 mm`` / ``20x/0.5 objective``)."""

    def toml_lines(self) -> list:
        """The optics' table of the camera file (``[main_lens]`` …), full precision."""


def slope_step(camera) -> float:
    """δ = p_p / f_s: the image-side slope step between neighbouring views (Eq. 13 for Δu = 1)."""
    return camera.sample_pitch_mm / camera.mla_focal_length_mm


def pupil_curvature(exit_pupil_distance_mm: float) -> float:
    """κ = 1/d_A in 1/mm; exactly 0.0 for image-side telecentric optics (d_A = ∞)."""
    return 0.0 if np.isinf(exit_pupil_distance_mm) else 1.0 / exit_pupil_distance_mm
