"""Ground truth of a render that needs the scene: what the central view sees at each lens."""

from __future__ import annotations

import numpy as np


def central_view_truth(setup, arrays) -> tuple[np.ndarray, np.ndarray]:
    """What the central view's chief ray meets at each lens of ``setup.grid``: ``(plane_label, depth_mm)``.

    The rays leave the lenses of ``setup.lens_grid`` (the same lens indices as ``setup.grid``).

    The chief ray leaves the lens centre towards the centre of the exit pupil (slope 0 when
    telecentric) and continues through the main lens (Eqs. 16-19). ``plane_label`` (rows, cols) int
    is the index into the scene's planes of the nearest plane it meets, −1 for the background;
    ``depth_mm`` (rows, cols) float64 is the distance from the sensor of the point it meets (the
    plane's depth there, Eq. 21's convention), NaN on the background.
    """
    from ._kernels import _central_hits_kernel  # numba loads only when something is rendered

    centers = setup.lens_grid.centers_xy_px()
    if arrays.order.size == 0:
        return np.full(centers.shape[:2], -1, dtype=np.int64), np.full(centers.shape[:2], np.nan)
    camera = setup.camera
    s_mm = (centers - np.array(setup.axis_px)) * camera.pixel_pitch_mm
    inv_d_a = 0.0 if camera.telecentric else 1.0 / camera.main_optics.exit_pupil_distance_mm
    labels, hit_z = _central_hits_kernel(np.ascontiguousarray(s_mm), inv_d_a, camera.main_optics.image_distance_mm,
                                         camera.main_optics.focal_length_mm, *arrays.kernel_args()[:3])
    labels = np.where(labels >= 0, arrays.order[np.maximum(labels, 0)], -1).astype(np.int64)
    return labels, hit_z + camera.main_optics.sensor_path_mm(camera.mla_path_mm)
