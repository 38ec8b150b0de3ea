"""Micro lens grid calibration: fit the micro image lattice (`LensGrid`) to a white image.

A white image (a capture of a uniform, featureless scene) shows one bright micro image per micro lens;
their centres are the positions s_j around which Eq. 9 (shift-and-sum) and Eq. 32 (viewpoints) of the
paper index the pixels u_i. With a finite exit pupil they sit outwards of the lenses, on the lens
lattice scaled by (d_A + f_s)/d_A: calibration finds what the white image shows, and reports the exit
pupil distance that scale implies (`implied_exit_pupil`).

Public functions: :func:`estimate_grid` (the `LensGrid`), :func:`find_grid` (plus the measured centres,
inliers, asymmetries, texture ratio and warnings), :func:`implied_exit_pupil`, and the steps' building
blocks used by plots and tests. Implementation modules, one step each: ``_monochrome`` (1),
``_lattice_guess`` (2), ``_flatten`` (3), ``_symmetry_centres`` (4), ``_measure`` (3–4 in windows),
``_lattice``, ``_assign`` and ``_smooth_fit`` (5: rigid and non-rigid fits), ``_grid_extent`` (listed
lenses), ``_checks`` (warnings, exit pupil), ``_estimate`` (the pipeline). See docs/calibration.md.

Internal package: not lfproc's API (docs/api.md lists that); its names serve lfproc's own stages, commands and
tests, and may change without notice.
"""

from ._checks import (TEXTURE_LIMIT, exit_pupil_warning, implied_exit_pupil, lattice_texture, micro_image_scale,
                      texture_ratio, white_texture)
from ._estimate import GridEstimate, estimate_grid, find_grid
from ._flatten import smooth_large
from ._grid_extent import grid_from_fit
from ._lattice import Similarity, lattice_index, unit_coordinates
from ._monochrome import repair_outlier_pixels, white_to_mono
from ._symmetry_centres import refine_centres
