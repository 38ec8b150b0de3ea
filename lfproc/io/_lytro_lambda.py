"""Lytro's lambda as the paper's refocus parameter a and as a distance from the sensor.

A reading of the format (``lytro-format.md``), not a published specification: lambda measures
image-side defocus from the micro lens plane in units of the main lens f-number N times the micro lens
pitch p_m (the defocus at which a point's blur circle on the lenslets is one lenslet wide), positive
towards the main lens; ``infinityLambda`` = λ_∞ is where infinity is imaged, in that unit. Hence:

* the main lens images infinity λ_∞·N·p_m in front of the lenslets: ε = b_U − f_U = λ_∞·N·p_m, which
  gives the image distance b_U that the metadata otherwise lacks;
* the image plane of lambda lies x' = (λ_∞ − λ)·N·p_m behind the main lens's back focal plane, so its
  object lies x = f_U²/x' in front of the front focal plane (Newton's form, as Eq. 21);
* inverting the paper's Eq. 21 for that distance (``geometry.refocus_parameter``'s closed form with
  f_U²/x = x') gives a = −λ·N·δ / (1 − κ·λ·N·p_m), δ = p_p/f_s (Eq. 13), κ = 1/d_A (0 when
  telecentric) — independent of ε. At λ = λ_∞ this is exactly ``geometry.infinity_parameter`` of the
  camera with that b_U: lambda's infinity is the model's slice at infinity.

Results derived this way are tagged ``"distance_from": "lambda"``. ``docs/lytro.md`` gives the evidence.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..camera import MainLens
from ..errors import LfprocError

DISTANCE_FROM = "lambda"
PROVENANCE = ("derived from lambda: f_U + infinityLambda x fNumber x lensPitch (the lambda reading of "
              "docs/lytro.md; the metadata has no focus distance)")


@dataclass(frozen=True)
class LambdaMap:
    """The map lambda → a → distance of one picture's camera.

    Attributes
    ----------
    camera : Camera
        The camera from the metadata with b_U = f_U + λ_∞·N·p_m.
    f_number, lens_pitch_mm, infinity_lambda : float
        N, p_m and λ_∞ from the metadata.
    """

    camera: object
    f_number: float
    lens_pitch_mm: float
    infinity_lambda: float

    @property
    def focal_length_mm(self) -> float:
        """f_U of the camera's main lens."""
        return self.camera.main_optics.focal_length_mm

    @property
    def image_distance_mm(self) -> float:
        """b_U of the camera's main lens (where the lambda reading puts it)."""
        return self.camera.main_optics.image_distance_mm

    @property
    def unit_mm(self) -> float:
        """One lambda of image-side defocus in mm: N·p_m."""
        return self.f_number * self.lens_pitch_mm

    def a(self, lam):
        """The refocus parameter of lambda (vectorised): a = −λ·N·δ / (1 − κ·λ·N·p_m)."""
        from ..geometry import pupil_curvature

        cam = self.camera
        delta = cam.sample_pitch_mm / cam.mla_focal_length_mm
        offset = np.asarray(lam, dtype=np.float64) * self.unit_mm
        with np.errstate(divide="ignore", invalid="ignore"):
            a = -offset * delta / (self.lens_pitch_mm * (1.0 - pupil_curvature(cam) * offset))
        return float(a) if np.ndim(a) == 0 else a

    def slices(self, lambdas) -> list[dict]:
        """One record per lambda: ``lambda``, ``a``, ``distance_mm``, ``near_mm``, ``far_mm``, ``dof_mm``
        (Eqs. 21, 31 at that a) and ``distance_from``."""
        from ..geometry import slice_geometry

        lambdas = np.atleast_1d(np.asarray(lambdas, dtype=np.float64))
        records = slice_geometry(self.camera, self.a(lambdas)).records()
        return [dict(record, **{"lambda": float(lam), "distance_from": DISTANCE_FROM})
                for lam, record in zip(lambdas, records)]

    def distance_mm(self, lam) -> np.ndarray:
        """Distance from the sensor (mm) of lambda: ``inf`` at and beyond λ_∞, NaN where lambda is not finite."""
        from ..geometry import slice_distance_mm

        lam = np.asarray(lam, dtype=np.float64)
        finite = np.isfinite(lam)
        d = np.asarray(slice_distance_mm(self.camera, np.where(finite, self.a(np.where(finite, lam, 0.0)), 0.0)),
                       dtype=np.float64)
        d = np.where(finite & (lam >= self.infinity_lambda), np.inf, d)   # at and beyond infinity, exactly
        return np.where(finite, d, np.nan)


def lambda_map(meta) -> LambdaMap:
    """The lambda map of a picture's `LytroMetadata` (camera as ``lytro_camera`` builds it, b_U from λ_∞).

    Raises
    ------
    LfprocError
        When the metadata lacks the camera, ``fNumber``, ``lensPitch`` or ``infinityLambda``, or when
        λ_∞ is negative (infinity imaged behind the lenslets: the reading does not hold).
    """
    from ._lytro_camera import lytro_camera

    where = meta.source
    for key, value in (("devices.lens.fNumber", meta.f_number), ("devices.lens.infinityLambda", meta.infinity_lambda)):
        if value is None:
            raise LfprocError(f"{where}: the metadata lacks {key}, so lambda cannot be turned into distances")
    if meta.f_number <= 0 or meta.infinity_lambda < 0:
        raise LfprocError(f"{where}: fNumber {meta.f_number:g} / infinityLambda {meta.infinity_lambda:g} do not fit "
                          f"the lambda reading (both must be positive); distances are not derived")
    built = lytro_camera(meta).camera
    pitch = built.mla_pitch_mm
    lens = built.main_optics                    # a Lytro camera's main lens (lytro_camera builds it)
    image_distance = lens.focal_length_mm + meta.infinity_lambda * meta.f_number * pitch
    provenance = tuple(p for p in built.provenance if p[0] != "main_lens.image_distance_mm") + \
        (("main_lens.image_distance_mm", PROVENANCE),)
    camera = replace(built, main_optics=replace(lens, image_distance_mm=image_distance), provenance=provenance)
    return LambdaMap(camera=camera, f_number=meta.f_number, lens_pitch_mm=pitch, infinity_lambda=meta.infinity_lambda)


CAMERA_PROVENANCE = "infinityLambda = (b_U - f_U) / (f_number x pitch_mm) of the camera file (the lambda reading)"


def camera_lambda_map(camera, source: str) -> LambdaMap:
    """The lambda map of a picture whose camera comes from a camera file (pictures without camera metadata).

    The reading needs N and p_m (a(λ) = −λ·N·δ / (1 − κ·λ·N·p_m) does not depend on b_U) and takes the
    camera's b_U as where the main lens focused: λ_∞ = (b_U − f_U) / (N·p_m).

    Raises
    ------
    LfprocError
        A microscope camera, or one without ``f_number``.
    """
    lens = camera.main_optics
    if not isinstance(lens, MainLens):     # lambda is a main lens's focus unit (a Lytro camera's)
        raise LfprocError(f"{source}: describes a {lens.describe()}, not a Lytro camera; pass a camera file with a "
                          f"[main_lens] (e.g. from `lfproc.read_camera(path) of a Lytro file of the same camera`)")
    if lens.f_number is None or lens.f_number <= 0:
        raise LfprocError(f"{source}: [main_lens] has no f_number, which turns lambda into distances; add "
                          f"f_number (the Lytro F01 is f/1.91; `lfproc.read_camera(path) reads it from a Lytro "
                          f"file's metadata`)")
    pitch = camera.mla_pitch_mm
    infinity = (lens.image_distance_mm - lens.focal_length_mm) / (lens.f_number * pitch)
    return LambdaMap(camera=camera, f_number=lens.f_number, lens_pitch_mm=pitch, infinity_lambda=infinity)


def refocused_map(mapping: LambdaMap, focus_distance_mm: float) -> LambdaMap:
    """The lambda map with the main lens focused at ``focus_distance_mm`` from the sensor (b_U from the
    thin-lens equation, λ_∞ = (b_U − f_U) / (N·p_m)); a(λ) is unchanged."""
    camera = focused_at(mapping.camera, float(focus_distance_mm))
    camera = replace(camera, provenance=camera.provenance + (
        ("main_lens.image_distance_mm", f"flag: --focus-distance {focus_distance_mm:g} mm (thin-lens equation)"),))
    lens = camera.main_optics
    infinity = (lens.image_distance_mm - lens.focal_length_mm) / mapping.unit_mm
    return replace(mapping, camera=camera, infinity_lambda=infinity)


def focused_at(camera, focus_distance_mm: float):
    """The camera with its main lens focused at another distance (no Lytro file records where it focused).

    b_U follows from the thin-lens equation (``MainLens.focused_at``); the provenance of b_U (or of a focus
    distance) no longer holds and is dropped. Every slice distance moves with it (Eq. 21).

    Parameters
    ----------
    camera : Camera
        With a main lens (a photographic camera).
    focus_distance_mm : float
        The distance from the sensor the main lens was focused at, mm (``inf`` allowed).

    Returns
    -------
    Camera
        The same camera, its main lens focused there.

    Raises
    ------
    LfprocError
        A camera without a main lens, or a distance the lens cannot focus at.
    """
    stale = ("main_lens.image_distance_mm", "main_lens.focus_distance_mm")
    if not isinstance(camera.main_optics, MainLens):
        raise LfprocError(f"{camera.source or 'camera'}: a focus distance needs a main lens ([main_lens]); this "
                          f"camera's optics are a {camera.main_optics.describe()}")
    lens = camera.main_optics.focused_at(focus_distance_mm, camera.mla_path_mm, camera.source or "camera")
    return replace(camera, main_optics=lens, provenance=tuple(p for p in camera.provenance if p[0] not in stale))
