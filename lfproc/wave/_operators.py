"""The projection operators of a light-field microscope: the PSF of every voxel class, at the lens rate.

Polyphase form. A voxel's image depends only on its depth and on its position relative to the lens
lattice. With S voxels per lens pitch each way (the super-resolution factor) there are S × S classes per
depth; voxel (z, s) of lens j is class s of depth z, sitting at (s − (S − 1)/2)·p/S from lens j's centre
(in the sensor's orientation: image space, M times the object offset). The rectified sensor image with m̂ ×
m̂ samples per lens is a decoded light field ((m̂, m̂, Ny, Nx): view u of lens j), and the volume is Z·S²
lens-rate images ``vol[z, s](j)``, so the forward projection is a multi-input multi-output convolution
at the lens rate:

    y[u](j) = Σ_{z, s} Σ_k h[z, s, u](k) · vol[z, s](j − k)

whose kernels ``h`` are the voxels' light-field PSFs (:func:`._psf.voxel_patterns`). A rectangular lattice
with symmetric lenslets maps class s onto its mirror images and its transpose, so only the classes with
0 ≤ σy ≤ σx (σ = s − (S − 1)/2) are computed; the others are flips and transposes of them.

:class:`WaveOperators` holds the kernels and what they were made from: a plain, picklable object, built
once per optics + lattice + z list + sampling (:func:`build_operators`) and shared by every frame of a
time-lapse (and, through :mod:`lfproc.decoder_cache`, by every process that asks for the same).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import LfprocError
from ._psf import blur_radius_lenses, lens_radius, oversampling, voxel_patterns

#: the largest blur radius (in lenses) the operators model: beyond it a kernel's window outgrows memory
MAX_BLUR_LENSES = 16
#: views whose light from a uniform plane is below this share of the brightest view's are not outputs
DARK_VIEW_SHARE = 1e-3


@dataclass(frozen=True, eq=False)
class WaveOperators:
    """The light-field PSFs of every voxel class at every depth, and what they were computed for.

    Attributes
    ----------
    kernels : ndarray, float32, shape (Z, S², U, K, K)
        ``h[z, s, u, ky, kx]``: the light voxel class s of depth z sends into output view ``views[u]`` of the
        lens (ky − R, kx − R) lenses from its own (K = 2R + 1). Each (z, s) sums to 1 over every view (the
        light that reaches the sensor; views not kept hold under ``DARK_VIEW_SHARE`` of the light).
    views : ndarray, int, shape (U, 2)
        (ky, kx) of each output view (those inside the objective's NA).
    white : ndarray, float64, shape (U,)
        The light each view receives per lens from a plane of voxels of value 1 (at the depth nearest 0):
        the model's white image.
    z_um : ndarray, shape (Z,)
        The planes' depths, µm from the native object plane, positive towards the objective.
    superres : int
        S, voxels per lens pitch each way.
    m_hat : int
        Samples per lens (views per axis).
    pitch_um, lenslet_focal_um : float
        The lens pitch and the lenslet-to-sensor distance f_s at the lenslets.
    grid : str
        The lattice ("rectangular").
    oversample : int
        Sub-samples per sample and axis of the field.
    sample_shift : tuple
        (y, x) of the central view off the lens centre, in samples.
    numerical_aperture, immersion_index, objective_magnification, wavelength_nm : float
        The objective's wave optics (:class:`lfproc.camera.WaveOptics`).
    """

    kernels: np.ndarray
    views: np.ndarray
    white: np.ndarray
    z_um: np.ndarray
    superres: int
    m_hat: int
    pitch_um: float
    lenslet_focal_um: float
    grid: str
    oversample: int
    sample_shift: tuple
    numerical_aperture: float
    immersion_index: float
    objective_magnification: float
    wavelength_nm: float

    @property
    def radius(self) -> int:
        """R: kernels reach R lenses each way."""
        return (int(self.kernels.shape[-1]) - 1) // 2

    @property
    def voxel_um(self) -> tuple:
        """(dz, dy, dx) in the sample: the mean plane step (0 for one plane) and p/(S·M) laterally."""
        step = float(np.mean(np.diff(self.z_um))) if len(self.z_um) > 1 else 0.0
        lateral = self.pitch_um / (self.superres * self.objective_magnification)
        return (step, lateral, lateral)

    def __repr__(self) -> str:
        z, classes, views, k, _ = self.kernels.shape
        return (f"<WaveOperators {z} plane(s) z {float(self.z_um.min()):.4g} to {float(self.z_um.max()):.4g} um, "
                f"superres {self.superres}, {views} views, kernels {k}x{k} lenses, {self.kernels.nbytes / 1e6:.0f} MB>")


def wave_optics_of(camera, where: str = "camera"):
    """The camera's objective for wave optics, or one line refusing a camera without microscope optics."""
    optics = getattr(camera.main_optics, "wave_optics", None) if camera is not None else None
    if optics is None:
        raise LfprocError(f"{where}: deconvolution needs a camera with microscope optics (a [microscope] table: "
                          f"objective, NA, immersion); this camera has none")
    return optics


def check_superres(superres, m_hat: int) -> int:
    """S as an int, refusing what the lenslet sampling cannot give (S > m̂: finer than the samples behind a lens)."""
    if isinstance(superres, bool) or not float(superres).is_integer() or superres < 1:
        raise LfprocError(f"`superres=` must be a whole number of voxels per lens (1 or more), got {superres!r}")
    if superres > m_hat:
        raise LfprocError(f"`superres={superres}` is finer than the {m_hat} samples behind each lens: the light field "
                          f"holds at most {m_hat} voxels per lens pitch; use `superres={m_hat}` or less")
    return int(superres)


def imageable_z_um(optics, pitch_um: float, lenses: float | None = None) -> float:
    """The largest |z| the operators model: a point's blur at the lenslets at most ``MAX_BLUR_LENSES`` lenses
    in radius, and (given ``lenses``, the light field's smaller extent) at most half of the light field."""
    limit = float(MAX_BLUR_LENSES) if lenses is None else min(float(MAX_BLUR_LENSES), lenses / 2.0)
    per_um = float(blur_radius_lenses(optics, pitch_um, 1.0))
    return limit / per_um


def check_z(z_um, optics, pitch_um: float, lenses: float | None = None) -> np.ndarray:
    """The planes' depths as a sorted float array, refusing repeats and depths the optics cannot image here."""
    z = np.atleast_1d(np.asarray(z_um, dtype=np.float64))
    if z.ndim != 1 or z.size == 0 or not np.all(np.isfinite(z)):
        raise LfprocError("`z_um=` must be one depth or a non-empty sequence of finite depths in um")
    if len(np.unique(z)) != len(z):
        raise LfprocError("`z_um=` asks for the same plane twice; give each depth once")
    reach = imageable_z_um(optics, pitch_um, lenses)
    far = float(np.max(np.abs(z)))
    if far > reach:
        spread = float(blur_radius_lenses(optics, pitch_um, far))
        where = (f"half of the light field's {lenses:.0f} lenses" if lenses is not None
                 and lenses / 2.0 < MAX_BLUR_LENSES else f"the {MAX_BLUR_LENSES} lenses the operators model")
        raise LfprocError(f"`z_um=` reaches {far:g} um, where a point's light spreads over {spread:.1f} lenses in "
                          f"radius, more than {where}: these optics image z from {-reach:.4g} to {reach:.4g} um here")
    return np.sort(z)


def voxel_offsets_um(superres: int, pitch_um: float) -> np.ndarray:
    """σ·p/S for σ = s − (S − 1)/2, s = 0…S−1: the classes' offsets from their lens centre."""
    return (np.arange(superres) - (superres - 1) / 2.0) * pitch_um / superres


def build_operators(camera, z_um, superres: int, *, oversample: int | None = None, sample_shift=(0.0, 0.0),
                    lenses: float | None = None, progress=None) -> WaveOperators:
    """The light-field PSFs of every voxel class of a microscope camera at the depths ``z_um``.

    Parameters
    ----------
    camera : lfproc.Camera
        A camera with microscope optics (``camera.main_optics.wave_optics``); its lens pitch, lenslet-to-sensor
        distance ``mla.focal_length_mm`` (also the lenslets' focal length) and m̂.
    z_um : sequence of float
        Depths of the planes, µm from the native object plane, positive towards the objective.
    superres : int
        S, voxels per lens pitch each way (1 … m̂).
    oversample : int, optional
        Sub-samples of the field per rectified sample and axis (odd); default: above the field's Nyquist rate.
    sample_shift : (float, float)
        (y, x) of the central view off the lens centres, in samples (``LightField.view_centre``).
    lenses : float, optional
        The light field's smaller extent in lenses: depths whose blur covers more than half of it are refused.
    progress : callable, optional
        ``progress(done, total)`` after each plane.

    Returns
    -------
    WaveOperators

    Raises
    ------
    LfprocError
        No microscope optics, a hexagonal lattice, ``superres`` beyond m̂, depths the optics cannot image.
    """
    optics = wave_optics_of(camera, getattr(camera, "source", "") or "camera")
    if camera.grid != "rectangular":
        raise LfprocError(f"{camera.source or 'camera'}: deconvolution models rectangular lenslet grids only; this "
                          f"camera's grid is {camera.grid}")
    m_hat = int(camera.m_hat)
    superres = check_superres(superres, m_hat)
    pitch_um = camera.mla_pitch_mm * 1000.0
    focal_um = camera.mla_focal_length_mm * 1000.0
    z = check_z(z_um, optics, pitch_um, lenses)
    q = oversampling(optics, pitch_um, m_hat, focal_um) if oversample is None else int(oversample)
    if q < 1 or q % 2 == 0:
        raise LfprocError(f"oversample= must be an odd whole number, got {oversample!r}")
    shift = tuple(float(v) for v in sample_shift)
    radius = max(lens_radius(optics, pitch_um, float(v)) for v in z)
    offsets = voxel_offsets_um(superres, pitch_um)
    symmetric = shift == (0.0, 0.0)
    classes = _classes(superres, symmetric)
    order = np.argsort(np.abs(z), kind="stable")        # the plane nearest 0 first: its light picks the views
    kernels = lit = white = None
    for done, i in enumerate(order, start=1):
        r = lens_radius(optics, pitch_um, float(z[i]))
        pad = radius - r
        computed = voxel_patterns(optics, pitch_um, focal_um, m_hat, q, float(z[i]),
                                  [(offsets[a], offsets[b]) for a, b in classes], r, shift)
        if kernels is None:
            plane = sum(pattern.sum(axis=(2, 3)) for _, pattern in _expand(classes, computed, superres, symmetric))
            lit = plane >= DARK_VIEW_SHARE * plane.max()
            white = plane[lit]
            kernels = np.zeros((len(z), superres * superres, int(lit.sum()), 2 * radius + 1, 2 * radius + 1),
                               dtype=np.float32)
        for s, pattern in _expand(classes, computed, superres, symmetric):
            kernels[i, s, :, pad:pad + 2 * r + 1, pad:pad + 2 * r + 1] = pattern[lit]
        if progress is not None:
            progress(done, len(z))
    views = np.argwhere(lit)
    return WaveOperators(kernels, views, white.astype(np.float64), z, superres, m_hat, pitch_um, focal_um,
                         camera.grid, q, shift, optics.numerical_aperture, optics.immersion_index,
                         optics.objective_magnification, optics.wavelength_nm)


def _classes(superres: int, symmetric: bool) -> list:
    """The classes (a, b) to compute: every one, or those with the centre ≤ σ_a ≤ σ_b (a, b as class indices)."""
    if not symmetric:
        return [(a, b) for a in range(superres) for b in range(superres)]
    low = superres // 2      # σ ≥ 0 for a ≥ (S − 1)/2: the index of σ = 0 (odd S) or of σ = ½ (even S)
    return [(a, b) for a in range(low, superres) for b in range(a, superres)]


def _expand(classes, computed, superres: int, symmetric: bool):
    """(class index, pattern (m̂, m̂, K, K)) for every class, from the computed ones by mirror symmetry."""
    if not symmetric:
        for (a, b), pattern in zip(classes, computed):
            yield a * superres + b, pattern
        return
    table = dict(zip(classes, computed))
    for sy in range(superres):
        for sx in range(superres):
            ay, ax = _mirror(sy, superres), _mirror(sx, superres)
            pattern = table[(min(ay, ax), max(ay, ax))]
            if ay > ax:                                     # computed as (σx, σy): transpose y and x
                pattern = pattern.transpose(1, 0, 3, 2)
            if sy != ay:                                    # σy < 0: mirror the views and the lenses in y
                pattern = pattern[::-1, :, ::-1, :]
            if sx != ax:
                pattern = pattern[:, ::-1, :, ::-1]
            yield sy * superres + sx, pattern


def _mirror(s: int, superres: int) -> int:
    """The class index of |σ| for class s (σ = s − (S − 1)/2)."""
    return max(s, superres - 1 - s)


def planned_radius(camera, z_um) -> int:
    """R of the kernels for these depths (without building them)."""
    optics = wave_optics_of(camera)
    return max(lens_radius(optics, camera.mla_pitch_mm * 1000.0, float(v)) for v in np.atleast_1d(z_um))

