"""Wave optics of light-field microscopes: the voxels' light-field PSFs, the projections, Richardson–Lucy.

What :func:`lfproc.deconvolve` computes with (docs/deconvolution.md): the objective's field at the lenslets
(Debye, aplanatic), the lenslets as a phase mask, propagation to the sensor and the pixels
(:mod:`._psf`, Broxton et al., Opt. Express 21(21), 2013); the PSF of every voxel class at the lens rate
(:class:`WaveOperators`, :func:`build_operators`, :mod:`._operators`); the forward and back projections as
batched matrix products per frequency on overlap-save tiles (:class:`Projector`, :mod:`._projector`);
Richardson–Lucy with the depth-adaptive anti-aliasing filter of Stefanoiu et al., Opt. Express 27(22), 2019
(:func:`richardson_lucy`, :mod:`._richardson_lucy`, :mod:`._filter`); the array library behind one seam
(:func:`backend`: NumPy with SciPy's FFTs, or CuPy, :mod:`._backend`).

Computing only: no files are read or written here. Importing it loads NumPy only (SciPy on first use).
"""

from ._backend import BACKENDS, Backend, backend
from ._filter import filter_widths, lanczos_kernel
from ._operators import (WaveOperators, build_operators, check_superres, check_z, imageable_z_um, planned_radius,
                         voxel_offsets_um, wave_optics_of)
from ._projector import Projector, choose_tile
from ._psf import blur_radius_lenses, image_defocus_um, lens_radius, oversampling, voxel_patterns
from ._richardson_lucy import polyphase_to_volume, richardson_lucy, volume_to_polyphase

__all__ = ["WaveOperators", "build_operators", "Projector", "richardson_lucy", "backend", "Backend", "BACKENDS",
           "voxel_patterns", "oversampling", "lens_radius", "blur_radius_lenses", "image_defocus_um", "filter_widths",
           "lanczos_kernel", "check_superres", "check_z", "imageable_z_um", "planned_radius", "voxel_offsets_um",
           "wave_optics_of", "choose_tile", "polyphase_to_volume", "volume_to_polyphase"]
