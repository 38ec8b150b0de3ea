"""A main lens described by its surfaces (a prescription) and its paraxial cardinal points.

A prescription lists the refracting surfaces of the main lens (or of a microscope objective), object side
first: each surface's radius of curvature (``inf`` for a plane; positive when the centre of curvature lies
behind the vertex, towards the image), its thickness to the next surface, the refractive index of the
medium after it (at the camera's ``wavelength_nm``), an optional semi-diameter, and which surface is the
aperture stop. Image space is air (n = 1); object space is air for a main lens and the immersion medium
(``object_index``: water 1.33, oil 1.515) for an objective.

Cardinal points come from a paraxial y-nu trace (Welford, *Aberrations of Optical Systems*, ch. 3):
refraction at surface k changes the reduced angle nu = n·u by −y·(n' − n)·c_k, a gap t changes the
height by t·nu/n. Written as 2×2 matrices on (y, nu) this is the system matrix M = [[A, B], [C, D]]
from the first vertex to the last, with power φ = −C and

* f_U = 1/φ (the image-side focal length; the object-side one is n₀/φ in a medium of index n₀),
* the front principal plane H1U at n₀·(1 − D)/φ behind the first vertex, the front focal point F1 at
  −n₀·D/φ (a point there leaves the lens collimated),
* the rear principal plane H2U at (A − 1)/φ behind the last vertex,
* the exit pupil: the image of the stop centre through the stop surface and every surface after it,
* the numerical aperture n₀·sin u ≈ nu of the marginal ray from F1 that just fills the stop (paraxial).

Positions along the axis ("lens coordinates") are in mm from the first vertex, positive towards the
image. The paper's Table 1 quantities are f_U and H1U–H2U = z(H2U) − z(H1U) (negative where the
principal planes are interchanged, as in a Double Gauss).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

from ..errors import LfprocError

#: the camera file's default wavelength (the helium d line, nm), the design wavelength of most catalogues
DEFAULT_LENS_WAVELENGTH_NM = 587.6
#: hand-written cardinal points must agree with the prescription's within this relative difference (0.1 %)
PRESCRIPTION_TOLERANCE = 1e-3


@dataclass(frozen=True)
class Surface:
    """One refracting surface: radius (``inf`` = plane), thickness to the next, index after it, stop flag."""

    radius_mm: float
    thickness_mm: float
    index: float = 1.0
    semi_diameter_mm: float | None = None
    stop: bool = False

    @property
    def curvature(self) -> float:
        """c = 1/R (0 for a plane)."""
        return 0.0 if math.isinf(self.radius_mm) else 1.0 / self.radius_mm


@dataclass(frozen=True)
class LensPrescription:
    """The main lens as its surfaces (object side first), at ``wavelength_nm``.

    Attributes
    ----------
    surfaces : tuple of Surface
        The refracting surfaces; the last one's thickness is not used (the camera's b_U places the MLA).
    wavelength_nm : float
        The wavelength the indices hold for.
    source : str
        Where the prescription came from (a ``.zmx`` file or the camera file's inline table).
    object_index : float
        n₀ of the medium in front of the first surface: 1 (air) for a main lens, the immersion medium of an
        objective.
    """

    surfaces: tuple
    wavelength_nm: float = DEFAULT_LENS_WAVELENGTH_NM
    source: str = field(default="", compare=False)
    object_index: float = 1.0

    def __post_init__(self):
        where = self.source or "prescription"
        if not self.surfaces:
            raise LfprocError(f"{where}: the main lens prescription has no surfaces; list them object side first")
        stops = [k for k, s in enumerate(self.surfaces) if s.stop]
        if len(stops) != 1:
            raise LfprocError(f"{where}: exactly one surface must be the aperture stop (stop = true), "
                              f"found {len(stops)}; mark the stop surface")
        for k, s in enumerate(self.surfaces):
            for name, value in (("radius_mm", s.radius_mm), ("thickness_mm", s.thickness_mm), ("index", s.index)):
                if isinstance(value, bool) or not isinstance(value, (int, float)) or math.isnan(value):
                    raise LfprocError(f"{where}: surface {k + 1} {name} must be a number, got {value!r}")
            if s.radius_mm == 0.0 or not math.isfinite(s.thickness_mm) or not (math.isfinite(s.index) and s.index > 0):
                raise LfprocError(f"{where}: surface {k + 1} needs a nonzero radius (inf for a plane), a finite "
                                  f"thickness and a positive index; got {s.radius_mm}, {s.thickness_mm}, {s.index}")
        if isinstance(self.object_index, bool) or not isinstance(self.object_index, (int, float)) \
                or not (math.isfinite(self.object_index) and self.object_index >= 1.0):
            raise LfprocError(f"{where}: the object-side index must be a number of at least 1 (air), got "
                              f"{self.object_index!r}")
        if self.surfaces[-1].index != 1.0:
            raise LfprocError(f"{where}: the last surface must leave the light in air (index 1.0), got "
                              f"{self.surfaces[-1].index}; the image side of the main lens is air")
        if self.power <= 0.0:
            raise LfprocError(f"{where}: the lens has no positive focal length (power {self.power:.3g} 1/mm); "
                              f"check the signs of the radii (object side first)")

    # ----------------------------------------------------------------- paraxial matrices
    @property
    def stop_index(self) -> int:
        return next(k for k, s in enumerate(self.surfaces) if s.stop)

    def vertex_mm(self, k: int) -> float:
        """z of surface k's vertex (0 for the first)."""
        return float(sum(s.thickness_mm for s in self.surfaces[:k]))

    @property
    def length_mm(self) -> float:
        """First vertex to last vertex."""
        return self.vertex_mm(len(self.surfaces) - 1)

    def indices_before(self) -> list[float]:
        """The index of the medium in front of each surface (object space: ``object_index``)."""
        return [float(self.object_index)] + [s.index for s in self.surfaces[:-1]]

    def matrix(self, first: int = 0, last: int | None = None) -> tuple:
        """(A, B, C, D) on (y, nu) from just before surface ``first`` to just after surface ``last``."""
        last = len(self.surfaces) - 1 if last is None else last
        n_before = self.indices_before()
        a, b, c, d = 1.0, 0.0, 0.0, 1.0
        for k in range(first, last + 1):
            s = self.surfaces[k]
            if k > first:   # the gap from surface k − 1 to k, in the medium after k − 1
                t = self.surfaces[k - 1].thickness_mm / n_before[k]
                a, b = a + t * c, b + t * d
            phi = (s.index - n_before[k]) * s.curvature
            c, d = c - phi * a, d - phi * b
        return a, b, c, d

    @property
    def power(self) -> float:
        """φ = −C of the system matrix (1/mm)."""
        return -self.matrix()[2]

    # ----------------------------------------------------------------- cardinal points
    @property
    def focal_length_mm(self) -> float:
        """f_U = 1/φ."""
        return 1.0 / self.power

    @property
    def front_principal_plane_mm(self) -> float:
        """z(H1U) = n₀·(1 − D)/φ from the first vertex."""
        a, b, c, d = self.matrix()
        return self.object_index * (1.0 - d) / self.power

    @property
    def rear_principal_plane_mm(self) -> float:
        """z(H2U) = last vertex + (A − 1)/φ."""
        a, b, c, d = self.matrix()
        return self.length_mm + (a - 1.0) / self.power

    @property
    def principal_plane_gap_mm(self) -> float:
        """H1U–H2U = z(H2U) − z(H1U) (the paper's Table 1; negative where the planes are interchanged)."""
        return self.rear_principal_plane_mm - self.front_principal_plane_mm

    @property
    def front_focal_plane_mm(self) -> float:
        """z(F1U) = z(H1U) − n₀·f_U (a microscope objective's native object plane)."""
        return self.front_principal_plane_mm - self.object_index * self.focal_length_mm

    @property
    def numerical_aperture(self) -> float:
        """n₀·sin u of the paraxial marginal ray from the front focal point through the stop's rim: the ray
        (y = 0, nu = 1) from F1, D/φ (reduced) in front of the first vertex, reaches the stop at height h, so
        the ray that fills a stop of semi-diameter r has nu = r/|h|."""
        stop = self.surfaces[self.stop_index]
        if stop.semi_diameter_mm is None:
            raise LfprocError(f"{self.source or 'prescription'}: the stop (surface {self.stop_index + 1}) needs "
                              f"semi_diameter_mm: the numerical aperture comes from it")
        a, b, c, d = self.matrix()
        to_first = d / self.power                      # reduced distance F1 → first vertex
        a_s, b_s, _, _ = self.matrix(0, self.stop_index)
        return float(stop.semi_diameter_mm) / abs(a_s * to_first + b_s)

    @property
    def exit_pupil_mm(self) -> float:
        """z of the exit pupil (the stop's image in image space); ``inf`` when it is at infinity.

        The stop centre's ray (y = 0, nu = 1) through the stop surface and the surfaces after it leaves
        the last vertex at (y_e, nu_e); the pupil is where that ray, extended, crosses the axis.
        """
        a, b, c, d = self.matrix(self.stop_index)
        y_e, nu_e = b, d
        if abs(nu_e) * 1e12 <= abs(y_e) / self.focal_length_mm:
            return math.inf
        return self.length_mm - y_e / nu_e

    def exit_pupil_distance_mm(self, image_distance_mm: float) -> float:
        """d_A: from the MLA (b_U behind H2U) to the exit pupil, towards the object; ``inf`` when telecentric."""
        z_xp = self.exit_pupil_mm
        if math.isinf(z_xp):
            return math.inf
        return self.rear_principal_plane_mm + image_distance_mm - z_xp

    # ----------------------------------------------------------------- variants
    def with_stop_at_front_focal_plane(self) -> "LensPrescription":
        """The same lens with its stop moved to the front focal plane (image-side telecentric, d_A = ∞).

        The paper's experiment chose its rays by Eq. 13's angles, i.e. as if the exit pupil were at
        infinity; this variant is the lens that makes that true. A plane surface in air is added in
        front (at F1U) as the stop; the lens's own stop flag is cleared.
        """
        gap = -self.front_focal_plane_mm
        if gap <= 0.0:
            raise LfprocError(f"{self.source or 'prescription'}: the front focal plane lies behind the first "
                              f"vertex; a stop there cannot be added in front")
        surfaces = [Surface(math.inf, gap, 1.0, None, True)]
        surfaces += [replace(s, stop=False) for s in self.surfaces]
        return LensPrescription(tuple(surfaces), self.wavelength_nm, self.source + " (stop at F1U)", self.object_index)


def surfaces_from_table(rows, source: str, wavelength_nm: float, table: str = "main_lens",
                        object_index: float = 1.0) -> LensPrescription:
    """The camera file's ``[[main_lens.surfaces]]`` (or ``[[microscope.surfaces]]``) array of tables as a
    :class:`LensPrescription` (``object_index``: the medium in front of the first surface)."""
    if not isinstance(rows, list) or not rows or not all(isinstance(r, dict) for r in rows):
        raise LfprocError(f"{source}: {table}.surfaces must be an array of tables [[{table}.surfaces]], "
                          f"one per surface, object side first")
    known = {"radius_mm", "thickness_mm", "index", "semi_diameter_mm", "stop"}
    surfaces = []
    for k, row in enumerate(rows):
        unknown = sorted(set(row) - known)
        if unknown:
            raise LfprocError(f"{source}: unknown key {unknown[0]!r} in surface {k + 1} of [[{table}.surfaces]]; "
                              f"the keys there are {', '.join(sorted(known))}")
        for key in ("radius_mm", "thickness_mm"):
            if key not in row:
                raise LfprocError(f"{source}: surface {k + 1} of [[{table}.surfaces]] needs {key}; add it")
        vals = {}
        for key in ("radius_mm", "thickness_mm", "index", "semi_diameter_mm"):
            value = row.get(key)
            if value is None:
                continue
            if isinstance(value, str) and value.strip().lower() in ("inf", "infinity") and key == "radius_mm":
                value = math.inf
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise LfprocError(f"{source}: surface {k + 1} {key} must be a number, got {value!r}")
            vals[key] = float(value)
        stop = row.get("stop", False)
        if not isinstance(stop, bool):
            raise LfprocError(f"{source}: surface {k + 1} stop must be true or false, got {stop!r}")
        surfaces.append(Surface(vals["radius_mm"], vals["thickness_mm"], vals.get("index", 1.0),
                                vals.get("semi_diameter_mm"), stop))
    return LensPrescription(tuple(surfaces), wavelength_nm, source, object_index)


def surfaces_to_toml(prescription: LensPrescription, table: str = "main_lens") -> list[str]:
    """``[[main_lens.surfaces]]`` (``table``) lines of a prescription (indices at its wavelength; full precision)."""
    lines = []
    for s in prescription.surfaces:
        radius = "inf" if math.isinf(s.radius_mm) else repr(float(s.radius_mm))
        lines += [f"[[{table}.surfaces]]", f"radius_mm = {radius}", f"thickness_mm = {float(s.thickness_mm)!r}",
                  f"index = {float(s.index)!r}"]
        if s.semi_diameter_mm is not None:
            lines.append(f"semi_diameter_mm = {float(s.semi_diameter_mm)!r}")
        lines.append(f"stop = {'true' if s.stop else 'false'}")
    return lines
