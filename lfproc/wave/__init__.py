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

Internal package: not lfproc's API (docs/api.md lists that); its names serve lfproc's own stages, commands and
tests, and may change without notice.
"""

from ._backend import Backend, backend
from ._filter import filter_widths
from ._operators import WaveOperators, build_operators, check_superres, check_z, wave_optics_of
from ._projector import Projector
from ._psf import blur_radius_lenses, image_defocus_um, lens_radius, oversampling, voxel_patterns
from ._richardson_lucy import richardson_lucy
