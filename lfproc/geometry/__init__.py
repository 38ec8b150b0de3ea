"""The paper's paraxial ray model: where each refocused slice is focused, where each view looks from.

Pure, vectorised functions of a :class:`~lfproc.camera.Camera`; no images, numpy only (``lfproc
geometry`` stays light). The 2014 paper's image-side telecentric model, extended to a finite exit pupil
(Hahne et al., IJCV 2018), with the optics in front of the micro lens array as one parameter
(:attr:`Camera.main_optics <lfproc.camera.Camera.main_optics>`, a main lens, an objective + tube lens, or any
other implementation of :class:`lfproc.camera.MainOptics`): the functions ask the optics to do things (where
rays meet and back, the usable range of a, where the views look from, which views are inside the stop),
never which kind they are. Positions are in the optics' object space (``camera.main_optics.object_space``):
millimetres from the sensor for a main lens, micrometres from the native object plane for a microscope;
functions named ``_mm`` take and give millimetres from the sensor and refuse other spaces.

Private modules: ``_slices`` (distance, DOF and inverse, Eqs. 13–31), ``_planning`` (slice planning,
uncovered depths, integer gaps, evenly spaced stacks), ``_views`` (where the views look from, Eqs. 17, 33,
34), ``_exit_pupil`` (micro image drift), ``_aperture`` (the summed views as an aperture: DOF extent,
equivalent f-number or NA, synthetic apertures), ``_range`` (the usable range of a and the words of a
refusal), and the optics' own geometry: a main lens's (``_main_lens``: the lens of a camera and the plane of
its virtual cameras; ``_diffraction``: Eq. 22's Airy check; ``_triangulation``: baseline, tilt and distance of
a disparity; ``_real_rays``: the model's rays traced exactly through a prescription's surfaces, real slice
distances and virtual cameras, docs/real-lens.md; ``_ray_model``: the model's parameters without a decoder's
m̂, as PlenoptiSign's), a microscope's (``_microscope``: aplanatic per-view shifts, its z per a).
"""

from ._aperture import (aperture_limits, aperture_text, aperture_views, equivalent_f_number,
                        equivalent_numerical_aperture, summed_view_extent)
from ._diffraction import DEFAULT_WAVELENGTH_MM, DiffractionCheck, DiffractionWarning, airy_radius_mm, diffraction_check, \
    working_f_number
from ._microscope import (aplanatic_gain, microscope_slices, na_views, paraxial_depth_error, refocus_slopes,
                          refocus_summary, uses_aplanatic, z_per_a_um)
from ._exit_pupil import exit_pupil_from_scale, micro_image_scale, pupil_curvature
from ._main_lens import chief_ray_heights, main_lens_of, virtual_camera_plane_mm
from ._range import (check_usable_a, check_usable_distances, format_a, front_focal_plane_mm, slice_positions,
                     usable_a_range, usable_range_text)
from ._ray_model import RayModel
from ._real_rays import RealRaySlices, RealRayViews, real_ray_lens, real_ray_slices, real_ray_views, \
    traces_real_rays
from ._planning import (FINE_STEP_FACTOR, MAX_SLICES, SlicePlan, integer_slice_gaps, plan_depth_range, plan_slices,
                        step_advice, uncovered_depths)
from ._slices import (SliceGeometry, infinity_parameter, position_parameter, refocus_parameter, require_space,
                      slice_distance_mm, slice_geometry)
from ..camera import RayTransfer, main_optics_transfer, prescription_transfer
from ._triangulation import Triangulation, triangulate
from ._views import (ViewGeometry, baseline_mm, place_views, view_geometry, view_offsets, view_positions_mm,
                     view_slopes, view_tilts_deg, views_inside_aperture)

# the public API (docs/api.md); the other names above serve lfproc's own stages and commands
__all__ = ["slice_geometry", "SliceGeometry", "refocus_parameter", "position_parameter", "view_geometry",
           "ViewGeometry", "summed_view_extent", "triangulate", "Triangulation", "real_ray_slices",
           "RealRaySlices", "real_ray_views", "RealRayViews"]
