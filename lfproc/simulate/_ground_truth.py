"""Ground truth of a render that needs the scene: what the central view sees at each lens."""

from __future__ import annotations

import numpy as np


def central_plane_labels(setup, arrays) -> np.ndarray:
    """Index of the plane the central view's chief ray (through each lens centre, m = 0) meets; −1 = background."""
    from ._kernels import _plane_labels_kernel

    centers = setup.grid.centers_xy_px()
    if arrays.order.size == 0:
        return np.full(centers.shape[:2], -1, dtype=np.int64)
    s_mm = (centers - np.array(setup.axis_px)) * setup.camera.pixel_pitch_mm
    labels = _plane_labels_kernel(np.ascontiguousarray(s_mm), setup.camera.main_focal_length_mm,
                                 *arrays.kernel_args())
    return np.where(labels >= 0, arrays.order[np.maximum(labels, 0)], -1).astype(np.int64)
