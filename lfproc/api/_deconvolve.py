"""3-D deconvolution of a light-field microscope capture into a volume in micrometres: :func:`deconvolve`.

The measurement the wave-optics model predicts (docs/deconvolution.md): the decoder divides each capture by the
white image (which takes out the lens-to-lens gains, dust and the pixels' vignetting of the real instrument)
and the model's own white image puts the optics' light distribution back, view by view, so the data are
``views[u] · white_model[u]`` in the model's units: a uniform plane of voxels of value 1 reproduces a capture
equal to the white image. Views outside the objective's NA (or dark in the white image: the light field's view
mask) are not measurements (weight 0); every sample of the other views is, a sample the decoder left at 0
because the white image is dark there (a lenslet under dust so thick that it passes under a tenth of the light)
included: it reads as "no light" there.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass

import numpy as np

from ..errors import LfprocError

#: voxels per lens pitch when neither superres= nor operators= say (the commands' --superres default)
DEFAULT_SUPERRES = 3
#: the background's estimate: this percentile of the measured samples (devignetted: the white image's level is 1)
BACKGROUND_PERCENTILE = 1.0
#: the sidecar keys of a volume (contract: z_um, voxel_um, iterations, superres, the optics, provenance)
VOLUME_UNIT = "relative emission: a plane of voxels of 1 gives the white image's light"


@dataclass(frozen=True, eq=False, repr=False)
class Volume:
    """A deconvolved volume and its tags.

    Attributes
    ----------
    data : ndarray, float32, shape (Z, Y, X)
        Emission per voxel (:data:`VOLUME_UNIT`), planes in the order of ``z_um``, rows and columns in the
        sensor's orientation (voxel (jy·S + sy, jx·S + sx) is class (sy, sx) of lens (jy, jx), as the refocused
        slices of the same capture).
    z_um : ndarray, shape (Z,)
        Each plane's depth, µm from the native object plane, positive towards the objective.
    voxel_um : tuple of float
        (dz, dy, dx) in the sample: the plane step, and the lens pitch / (S·M) laterally.
    optics : dict
        The wave optics and lenslets the model used (NA, immersion index, magnification, focal lengths,
        wavelength, lens pitch, f_s, m̂, grid, the field's oversampling).
    iterations : int
        Richardson–Lucy updates run.
    residuals : ndarray, shape (iterations,)
        The relative misfit ‖w·(H·x + b − y)‖/‖w·y‖ after each update.
    superres : int
        S, voxels per lens pitch.
    background : float
        The background b subtracted by the model, in the devignetted light field's units (white image = 1).
    filtered : bool
        Whether the depth-adaptive anti-aliasing filter ran.
    source : str or None
        The capture (or saved light field), as an absolute path.
    provenance : dict
        The files that shaped the volume (:mod:`lfproc.provenance`).
    """

    data: np.ndarray
    z_um: np.ndarray
    voxel_um: tuple
    optics: dict
    iterations: int
    residuals: np.ndarray
    superres: int
    background: float
    filtered: bool
    source: str | None
    provenance: dict

    def records(self) -> dict:
        """The sidecar ``STEM_volume.json`` as a dict (the contract's keys and the rest of the tags)."""
        z, y, x = self.data.shape
        return {"source": self.source, "z_um": [float(v) for v in self.z_um], "voxel_um": list(self.voxel_um),
                "shape_zyx": [z, y, x], "axes": "ZYX", "unit": VOLUME_UNIT, "iterations": int(self.iterations),
                "residuals": [float(v) for v in self.residuals], "superres": int(self.superres),
                "background": float(self.background), "antialiasing_filter": bool(self.filtered),
                "optics": dict(self.optics), "provenance": self.provenance}

    def save(self, outdir, stem: str | None = None) -> list[str]:
        """Write what ``lfproc deconvolve`` writes: ``OUTDIR/STEM_volume.ome.tif`` (OME-TIFF, ZYX, µm spacing)
        and ``OUTDIR/STEM_volume.json``, together (both or neither). Returns their paths."""
        from ..camera import NATIVE_PLANE_UM
        from ..outputs import write_volume
        from ._focal import _stem

        return write_volume(os.fspath(outdir), _stem(stem, self.source), self.data, self.voxel_um, self.records(),
                            NATIVE_PLANE_UM)

    def to_xarray(self):
        """The volume as an ``xarray.DataArray`` (dims z, y, x; coordinates in µm; the tags in ``attrs``). Needs
        xarray (not a dependency of lfproc)."""
        try:
            import xarray
        except ImportError:
            raise LfprocError("to_xarray needs the xarray package; install it (pip install xarray)") from None
        z, y, x = self.data.shape
        coords = {"z": ("z", self.z_um), "y": ("y", np.arange(y) * self.voxel_um[1]),
                  "x": ("x", np.arange(x) * self.voxel_um[2])}
        attrs = {key: json.dumps(value) if isinstance(value, (dict, list)) else value
                 for key, value in self.records().items() if value is not None}
        return xarray.DataArray(self.data, dims=("z", "y", "x"), coords=coords, attrs=attrs)

    def __repr__(self) -> str:
        z, y, x = self.data.shape
        where = f"z {float(self.z_um.min()):.4g} to {float(self.z_um.max()):.4g} um" if z > 1 else \
            f"z {float(self.z_um[0]):.4g} um"
        misfit = f", misfit {self.residuals[-1]:.3g}" if len(self.residuals) else ""
        return (f"<Volume {z}x{y}x{x} voxels of {self.voxel_um[2]:.3g} um ({where}), superres {self.superres}, "
                f"{self.iterations} iteration(s){misfit}>")


def deconvolve(lf, camera=None, white=None, grid=None, dark=None, *, z_um=None, iterations: int = 8,
               superres: int | None = None, background="auto", tolerance: float | None = None, antialias: bool = True,
               operators=None, cache: bool = False, backend: str = "numpy", memory_mb: float = 512,
               oversample: int | None = None, progress=None) -> Volume:
    """Deconvolve a light-field microscope capture into a volume (Richardson–Lucy with a wave-optics model).

    Parameters
    ----------
    lf : LightField, str, os.PathLike or ndarray
        A decoded light field (:func:`lfproc.read_light_field`), or anything ``read_light_field`` reads (then
        ``camera``, ``white``, ``grid`` and ``dark`` are passed to it).
    camera, white, grid, dark : optional
        As :func:`lfproc.read_light_field`'s, for a capture that is not yet decoded.
    z_um : sequence of float
        The planes' depths, µm from the native object plane, positive towards the objective (or the depths of
        ``operators``).
    iterations : int
        The most Richardson–Lucy updates (default 8).
    superres : int, optional
        S, voxels per lens pitch each way (1 … m̂); default: that of ``operators``, else 3.
    background : "auto" or float
        The background per sample in the devignetted light field's units (the white image's level is 1):
        ``"auto"`` takes the 1st percentile of the measured samples, 0 assumes none.
    tolerance : float, optional
        Stop early once an update lowers the misfit by less than this fraction.
    antialias : bool
        Run the depth-adaptive anti-aliasing filter (Stefanoiu et al. 2019) after each update (default True).
    operators : lfproc.wave.WaveOperators, optional
        Operators built before (:func:`lfproc.wave.build_operators`, e.g. once for every frame of a time-lapse);
        they must be for this camera's optics, m̂ and ``superres``.
    cache : bool
        Keep the operators in lfproc's cache on disk and reuse them from there (docs/cache.md). Default False.
    backend : {"numpy", "cupy"}
        Where the arithmetic runs (CuPy needs a GPU; never required).
    memory_mb : float
        Budget of the projections' per-frequency matrices, in MB (larger: fewer, larger tiles).
    oversample : int, optional
        Field sub-samples per pixel and axis of the operators (odd; default: above the field's Nyquist rate;
        1 samples the field once per pixel, as pyolaf does).
    progress : callable, optional
        ``progress(stage, done, total)`` with stage "operators" (per plane) or "iterations".

    Returns
    -------
    Volume

    Raises
    ------
    LfprocError
        A camera without microscope optics, a z range the optics cannot image here (the message says the range
        they can), ``superres`` beyond m̂, operators made for other optics, bad arguments.
    """
    from .. import wave
    from ..provenance import provenance as provenance_of

    lf = _light_field(lf, camera, white, grid, dark, cache)
    if isinstance(iterations, bool) or not float(iterations).is_integer() or iterations < 1:
        raise LfprocError(f"`iterations=` must be a whole number of at least 1, got {iterations!r}")
    if tolerance is not None and not (isinstance(tolerance, (int, float)) and 0 < tolerance < 1):
        raise LfprocError(f"`tolerance=` must be a fraction between 0 and 1, got {tolerance!r}")
    background_level = _background_argument(background)
    if superres is None:
        superres = DEFAULT_SUPERRES if operators is None else operators.superres
    if z_um is None:
        if operators is None:
            raise LfprocError("deconvolve needs `z_um=` (the planes' depths in um), e.g. `z_um=[-20, 0, 20]`")
        z_um = operators.z_um
    z, superres, shift, lenses = _sampling(lf, z_um, superres)
    optics = wave.wave_optics_of(lf.camera)
    if operators is None:
        operators = _operators(lf.camera, z, superres, shift, lenses, cache, progress, oversample)
    else:
        _check_operators(operators, lf.camera, z, superres, shift)
    views, weights, data, level = _measurement(lf, operators, background_level)
    projector = wave.Projector(operators, lf.lens_shape, views, backend=backend, memory=int(memory_mb * 2 ** 20))
    white_model = operators.white[views]
    callback = None if progress is None else (lambda done, total, misfit: progress("iterations", done, total))
    volume, misfits = wave.richardson_lucy(projector, data, weights, level * white_model, int(iterations),
                                           superres=superres, widths=wave.filter_widths(operators) if antialias
                                           else None, tolerance=tolerance, callback=callback)
    source = None if lf.source is None else os.path.abspath(lf.source)
    return Volume(volume, np.asarray(operators.z_um, dtype=np.float64), operators.voxel_um,
                  _optics_record(operators, optics), len(misfits), np.array(misfits), superres, float(level),
                  bool(antialias), source, provenance_of(lf.inputs))


def prepare_deconvolution(lf, z_um, superres: int = DEFAULT_SUPERRES, *, cache: bool = False,
                          oversample: int | None = None, progress=None):
    """The operators :func:`deconvolve` builds for a light field, built once for many frames of one rig.

    A time-lapse (``lfproc batch``) builds them here, once, and gives them to every frame's
    ``deconvolve(frame, operators=...)``; they pickle (a Dask worker or a local process receives them whole).

    Parameters
    ----------
    lf : LightField
        A frame of the rig (its camera, its view centre and its extent in lenses shape the operators).
    z_um : sequence of float
        The planes' depths, µm from the native object plane, positive towards the objective.
    superres : int
        S, voxels per lens pitch each way (1 … m̂; default 3).
    cache, oversample, progress
        As :func:`deconvolve`'s.

    Returns
    -------
    WaveOperators
        The projection operators, picklable: pass them to every frame's ``lfproc.deconvolve(frame,
        operators=...)``.

    Raises
    ------
    LfprocError
        As :func:`deconvolve`: no microscope optics, a z range the optics cannot image here, ``superres`` beyond m̂.
    """
    lf = _light_field(lf)
    z, superres, shift, lenses = _sampling(lf, z_um, superres)
    return _operators(lf.camera, z, superres, shift, lenses, cache, progress, oversample)


def _light_field(lf, camera=None, white=None, grid=None, dark=None, cache=False):
    """A LightField with its camera (decoded with :func:`read_light_field` unless it is one); refuses a camera
    without microscope optics."""
    from .. import wave
    from ..lightfield import LightField
    from ._read import read_light_field

    if not isinstance(lf, LightField):
        lf = read_light_field(lf, camera, white, grid, dark, cache=cache)
    if lf.camera is None:
        raise LfprocError("deconvolve needs a LightField with its camera (lfproc.read_light_field, or "
                          "LightField.from_views(views, camera))")
    wave.wave_optics_of(lf.camera, lf.camera.source or "camera")
    return lf


def _sampling(lf, z_um, superres) -> tuple:
    """(depths checked against the optics and the light field's extent, S checked against m̂, the view centre,
    the smaller extent in lenses) of a light field."""
    from .. import wave

    camera = lf.camera
    superres = wave.check_superres(superres, camera.m_hat)
    lenses = float(min(lf.lens_shape))
    z = wave.check_z(z_um, wave.wave_optics_of(camera), camera.mla_pitch_mm * 1000.0, lenses)
    return z, superres, lf.view_centre or (0.0, 0.0), lenses


def _background_argument(background):
    if isinstance(background, str):
        if background != "auto":
            raise LfprocError(f"`background=` must be 'auto' or a number (the white image's level is 1), got "
                              f"{background!r}")
        return None
    try:
        value = float(background)
    except (TypeError, ValueError):
        value = float("nan")
    if not (np.isfinite(value) and value >= 0):
        raise LfprocError(f"`background=` must be 'auto' or a finite number >= 0, got {background!r}")
    return value


def _operators(camera, z, superres, shift, lenses, cache, progress, oversample):
    """The operators for this camera, from the cache on disk when ``cache`` (built and stored there otherwise)."""
    from .. import wave

    def build():
        step = None if progress is None else (lambda done, total: progress("operators", done, total))
        return wave.build_operators(camera, z, superres, sample_shift=shift, lenses=lenses, progress=step,
                                    oversample=oversample)

    if not cache:
        return build()
    from ..decoder_cache import cached_entry, operators_key

    return cached_entry(operators_key(camera, z, superres, shift, oversample), build, wave.WaveOperators)


def _check_operators(operators, camera, z, superres, shift) -> None:
    from .. import wave

    optics = wave.wave_optics_of(camera)
    made = (operators.m_hat, operators.superres, round(operators.pitch_um, 9), round(operators.lenslet_focal_um, 9),
            operators.numerical_aperture, operators.immersion_index, operators.objective_magnification,
            operators.wavelength_nm, tuple(operators.sample_shift))
    wanted = (camera.m_hat, superres, round(camera.mla_pitch_mm * 1000.0, 9),
              round(camera.mla_focal_length_mm * 1000.0, 9), optics.numerical_aperture, optics.immersion_index,
              optics.objective_magnification, optics.wavelength_nm, tuple(float(v) for v in shift))
    if made != wanted:
        raise LfprocError(f"operators= were built for other optics or sampling ({operators!r}); build them with "
                          f"lfproc.wave.build_operators for this camera and `superres={superres}`")
    if len(operators.z_um) != len(z) or not np.allclose(np.sort(operators.z_um), z):
        raise LfprocError("operators= were built for other depths than `z_um=`; give their depths (or none)")


def _measurement(lf, operators, background_level):
    """(views used (U,) bool, weights (U', Ny, Nx), data (U', Ny, Nx), background level) of a light field."""
    mask = np.ones((lf.m_hat, lf.m_hat), bool) if lf.view_mask is None else lf.view_mask
    views = mask[operators.views[:, 0], operators.views[:, 1]]
    if not views.any():
        raise LfprocError("the light field carries no light in the views inside the objective's NA; check the white "
                          "image and the camera's NA")
    picked = operators.views[views]
    samples = lf.views[picked[:, 0], picked[:, 1]].mean(axis=-1, dtype=np.float64)          # (U', Ny, Nx)
    finite = np.isfinite(samples)
    samples = np.where(finite, samples, 0.0)
    weights = finite.astype(np.float32)
    if background_level is None:
        measured = samples[weights > 0]
        background_level = max(float(np.percentile(measured, BACKGROUND_PERCENTILE)), 0.0) if measured.size else 0.0
    data = (np.clip(samples, 0.0, None) * operators.white[views][:, None, None]).astype(np.float32)
    return views, weights, data, background_level


def _optics_record(operators, optics) -> dict:
    return {"numerical_aperture": optics.numerical_aperture, "immersion_index": optics.immersion_index,
            "objective_magnification": optics.objective_magnification,
            "objective_focal_length_mm": optics.objective_focal_length_mm,
            "tube_lens_focal_length_mm": optics.tube_lens_focal_length_mm, "wavelength_nm": optics.wavelength_nm,
            "lens_pitch_um": operators.pitch_um, "lenslet_focal_length_um": operators.lenslet_focal_um,
            "micro_image_px": operators.m_hat, "grid": operators.grid, "field_oversampling": operators.oversample,
            "views": int(len(operators.views))}
