"""Inputs that belong together: what a grid was made from, and checks of camera, grid, white image, dark
frame and capture against each other, before anything is decoded (issues 20, 21 and 23).

Public names: `ImageFacts` and `probe_image` (header facts of any input, with the diagnosis ``lfproc info``
gives), `file_hash`; `made_from` (what a lens grid was fitted from: its calibration's record);
`check_grid_fits_camera`, `check_same_sensor`, `check_fits_grid_extent`, `reference_facts` (mismatches
refused in one line naming both files); `read_dark`, `subtract_dark` (``--dark``); `check_white_is_white`,
`check_capture_is_not_white`, `lens_scene_contrast`, `white_evidence` (swapped white image and capture;
``white_is_white=True`` skips the white image's check); `measured_m_hat` (m̂ from the measured pitch).
See docs/inputs.md.

Internal package: not lfproc's API (docs/api.md lists that); its names serve lfproc's own stages, commands and
tests, and may change without notice.
"""

from ._dark import read_dark, subtract_dark
from ._defaults import measured_m_hat
from ._facts import ImageFacts, file_hash, probe_image, same_file_content
from ._kind import (SCENE_CONTRAST_LIMIT, SCENE_CORRELATION_LIMIT, TEXTURE_LIMIT, WHITE_FLATNESS,
                    check_capture_is_not_white, check_white_is_white, lens_flatness, white_evidence)
from ._match import camera_name, check_fits_grid_extent, check_grid_fits_camera, check_same_sensor, reference_facts
from ._provenance import made_from
