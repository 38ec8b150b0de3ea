"""The paper's paraxial ray model: where each refocused slice is focused, where each view looks from.

Pure, vectorised functions of a :class:`~lfproc.camera.Camera`; no images, numpy only (``lfproc
geometry`` stays light). The 2014 paper's image-side telecentric model, extended to a finite exit pupil
(Hahne et al., IJCV 2018), with the optics in front of the micro lens array as one parameter
(:attr:`Camera.main_optics <lfproc.camera.Camera.main_optics>`, a main lens or an objective + tube lens):
the functions ask the optics' interface (:class:`lfproc.camera.MainOptics`: where rays meet, the object
space's unit and origin, whether views are orthographic, the aperture as a sine at the MLA), not which
kind they are. Positions are in the camera's object space (:attr:`Camera.object_space
<lfproc.camera.Camera.object_space>`): millimetres from the sensor for a main lens, micrometres from the
native object plane for a microscope; functions named ``_mm`` take and give millimetres from the sensor.

Private modules: ``_slices`` (distance, DOF and inverse, Eqs. 13–31), ``_planning`` (slice planning,
uncovered depths, integer gaps), ``_views`` (virtual cameras, Eqs. 17, 33, 34), ``_triangulation``
(baseline, tilt and distance of a disparity), ``_exit_pupil`` (micro image drift),
``_aperture`` (the summed views as an aperture: DOF extent, equivalent f-number, synthetic apertures),
``_diffraction`` (Eq. 22), ``_range`` (the usable range of a: infinity to the front focal plane),
``_ray_model`` (the model's parameters without a decoder's m̂),
``_real_rays`` (the model's rays traced exactly through a prescription's
surfaces: real slice distances and virtual cameras, docs/real-lens.md),
``_microscope`` (a light-field microscope's slices in µm, view angles, aplanatic per-view shifts).
"""

from ._aperture import (aperture_limits, aperture_text, aperture_views, equivalent_f_number,
                        equivalent_numerical_aperture, summed_view_extent)
from ._diffraction import DEFAULT_WAVELENGTH_MM, DiffractionCheck, DiffractionWarning, airy_radius_mm, diffraction_check, \
    working_f_number
from ._microscope import (MicroscopeViews, aplanatic_gain, lateral_sampling_um, microscope_slices, microscope_views,
                          na_views, plan_z_range, paraxial_depth_error, refocus_parameter_z, refocus_slopes, uses_aplanatic,
                          views_inside_na, z_per_a_um, pupil_positions_mm, z_step_advice, FINE_STEP_FACTOR)
from ._exit_pupil import exit_pupil_from_scale, micro_image_scale, pupil_curvature, virtual_camera_plane_mm
from ._range import (check_usable_a, check_usable_distances, format_a, front_focal_plane_mm, usable_a_range,
                     usable_range_text)
from ._ray_model import RayModel
from ._real_rays import RealRaySlices, RealRayViews, real_ray_slices, real_ray_views
from ._planning import MAX_SLICES, SlicePlan, integer_slice_gaps, plan_depth_range, plan_slices, uncovered_depths
from ._slices import SliceGeometry, infinity_parameter, refocus_parameter, slice_distance_mm, slice_geometry
from ..camera import RayTransfer, main_optics_transfer, prescription_transfer
from ._triangulation import Triangulation, triangulate
from ._views import (ViewGeometry, baseline_mm, view_geometry, view_offsets, view_positions_mm, view_slopes,
                     view_tilts_deg, views_inside_aperture)

__all__ = [
    "aperture_limits", "aperture_views", "equivalent_f_number", "summed_view_extent", "aperture_text",
    "equivalent_numerical_aperture",
    "DEFAULT_WAVELENGTH_MM", "DiffractionCheck", "DiffractionWarning", "airy_radius_mm", "diffraction_check",
    "working_f_number", "exit_pupil_from_scale", "micro_image_scale", "pupil_curvature", "virtual_camera_plane_mm",
    "check_usable_a", "check_usable_distances", "format_a", "front_focal_plane_mm", "usable_a_range",
    "usable_range_text", "RayModel", "MAX_SLICES", "SlicePlan", "integer_slice_gaps", "plan_depth_range", "plan_slices", "uncovered_depths",
    "SliceGeometry", "infinity_parameter", "refocus_parameter", "slice_distance_mm", "slice_geometry",
    "Triangulation", "triangulate", "RayTransfer", "main_optics_transfer", "prescription_transfer",
    "RealRaySlices", "RealRayViews", "real_ray_slices", "real_ray_views",
    "MicroscopeViews", "aplanatic_gain", "lateral_sampling_um", "microscope_slices", "microscope_views", "na_views",
    "plan_z_range",    "paraxial_depth_error", "refocus_parameter_z", "refocus_slopes", "uses_aplanatic", "views_inside_na",
    "pupil_positions_mm",
    "z_per_a_um", "z_step_advice", "FINE_STEP_FACTOR",
    "ViewGeometry", "baseline_mm", "view_geometry", "view_offsets", "view_positions_mm", "view_slopes",
    "view_tilts_deg", "views_inside_aperture",
]
