"""The main optics as a paraxial ray transfer (ABCD): where an image-side meeting point lies in object space.

Every slice and DOF limit of the ray model is a pair of chief rays that meet at a distance w behind the
micro lens array (w = A·p_m/N for the pair (A, C) of :mod:`._slices`, positive towards the sensor).
Which object point that is depends only on the optics in front of the MLA, written as the transfer
matrix S (reduced angles n·u, det S = 1) from an object-side reference plane to the MLA plane. The
object point conjugate to the image point lies at s along the axis from the reference plane (s > 0
in the direction of the light, towards the optics), where the total matrix T(w)·S·T(−s/n) images,
i.e. its B element vanishes:

    s = n·(B + w·D) / (A + w·C).

Three instances (each main optics' ``transfer()``, :mod:`._main_optics`):

* the paper's thick main lens (f_U, principal planes H1U/H2U, b_U from H2U to the MLA), reference
  plane H1U: S = T(b_U)·L(f_U), so s = −f_U·(b_U + w)/(b_U + w − f_U), the thin-lens equation. The
  ray model evaluates it in Newton's form x = f_U²/(ε + w) (:meth:`MainLens.object_position`), which
  is the same number without cancellation at infinity; the tests check the two agree.
* a main lens given by its surfaces (a prescription, :class:`~lfproc.camera.LensPrescription`), the
  same reference plane H1U: S = T(b_U + z(H2U) − z_last)·M·T(z_first − z(H1U)), with M the surfaces'
  own y-nu matrix. Its cardinal points are where the camera's f_U and H1U–H2U come from, so S equals
  the thick lens's T(b_U)·L(f_U) (a property the tests check to 1e-9).
* a light-field microscope (Levoy et al. 2006): object plane in immersion n, objective f_obj = f_tube/M,
  aperture stop in its back focal plane = the tube lens's front focal plane, MLA in the tube lens's
  back focal plane: S = T(f_tube)·L(f_tube)·T(f_obj + f_tube)·L(f_obj)·T(f_obj) = [[−M, 0], [0, −1/M]],
  afocal (C = 0) and imaging (B = 0), so s = n·w/M²: lateral magnification −M, axial M²/n.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class RayTransfer:
    """A paraxial ray transfer [[A, B], [C, D]] (reduced angles) from an object-side plane to the MLA.

    Attributes
    ----------
    A, B, C, D : float
        The matrix elements (lengths in mm).
    index : float
        Refractive index n on the object side (1 in air, the immersion index of a microscope).
    """

    A: float
    B: float
    C: float
    D: float
    index: float = 1.0

    def __matmul__(self, other: "RayTransfer") -> "RayTransfer":
        """``self @ other``: first ``other``, then ``self`` (keeps the object side's index of ``other``)."""
        return RayTransfer(self.A * other.A + self.B * other.C, self.A * other.B + self.B * other.D,
                           self.C * other.A + self.D * other.C, self.C * other.B + self.D * other.D, other.index)

    def object_offset_mm(self, w_mm):
        """s = n·(B + w·D)/(A + w·C): the object point conjugate to the image point w behind the MLA.

        s is measured from the reference plane in the direction of the light (towards the optics);
        ``inf`` where the conjugate is at infinity (A + w·C = 0).
        """
        w = np.asarray(w_mm, dtype=np.float64)
        with np.errstate(divide="ignore", invalid="ignore"):
            s = self.index * (self.B + w * self.D) / (self.A + w * self.C)
        s = np.where(np.isfinite(w), s, self.index * self.D / self.C if self.C else np.inf)
        return float(s) if s.ndim == 0 else s

    @property
    def lateral_magnification(self) -> float:
        """A: the image height at the MLA per object height (for an imaging transfer, B = 0)."""
        return self.A


def gap(length_mm: float) -> RayTransfer:
    """T(t): free propagation over a reduced length t = physical length / n."""
    return RayTransfer(1.0, float(length_mm), 0.0, 1.0)


def lens(focal_length_mm: float) -> RayTransfer:
    """L(f): a thin lens (or a thick one between its principal planes) of focal length f."""
    return RayTransfer(1.0, 0.0, -1.0 / float(focal_length_mm), 1.0)


def prescription_transfer(prescription, image_distance_mm: float) -> RayTransfer:
    """S of a lens prescription from its front principal plane H1U to the MLA, b_U behind H2U."""
    a, b, c, d = prescription.matrix()
    surfaces = RayTransfer(a, b, c, d)
    to_mla = prescription.rear_principal_plane_mm + image_distance_mm - prescription.length_mm
    return gap(to_mla) @ surfaces @ gap(-prescription.front_principal_plane_mm)


def main_optics_transfer(camera) -> RayTransfer:
    """S for ``camera``: its main optics' transfer from their object-side reference plane to the MLA
    (H1U of a main lens, its surfaces where it has a prescription; the native object plane of a microscope,
    built from objective, stop and tube lens so that the afocal, imaging result is a property the tests check).
    """
    return camera.main_optics.transfer()
