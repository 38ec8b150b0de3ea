"""Runs the numba kernels over the sensor (or the lens rows) in bands, reporting progress between bands."""

from __future__ import annotations

import numpy as np

from ._scene_arrays import SceneArrays
from ._setup import _Setup, micro_image_scale

#: sensor rows (lens rows) per kernel call: enough to keep every core busy, few enough for a progress bar that moves
BAND_ROWS = 16
LENS_BAND_ROWS = 4


class Progress:
    """Adds up work done (in traced rays) and reports ``callback(fraction_done, stage)``; a no-op without callback."""

    def __init__(self, callback=None, total_rays: float = 1.0):
        self.callback = callback
        self.total = max(float(total_rays), 1.0)
        self.done = 0.0

    def advance(self, rays: float, stage: str) -> None:
        self.done += rays
        if self.callback is not None:
            self.callback(min(self.done / self.total, 1.0), stage)


def sensor_rays(setup: _Setup) -> float:
    """Rays one sensor image traces (for progress): pixels × pixel samples × aperture samples."""
    height, width = setup.shape
    return float(height * width * len(setup.pixel_offsets) * len(setup.aperture_offsets))


def ideal_rays(setup: _Setup) -> float:
    """Rays the ideal views trace (for progress): lenses × views × sub-samples × aperture samples."""
    m = setup.camera.m_hat
    return float(setup.grid.rows * setup.grid.cols * m * m * len(setup.pixel_offsets) * len(setup.aperture_offsets))


def render_sensor(setup: _Setup, arrays: SceneArrays, channels: int, progress: Progress | None = None,
                  stage: str = "sensor") -> np.ndarray:
    """Sensor irradiance float32 (H, W, channels), traced in bands of :data:`BAND_ROWS` rows."""
    from ._kernels import _sensor_kernel  # numba loads only when something is rendered

    height, width = setup.shape
    out = np.empty((height, width, channels), dtype=np.float32)
    per_row = sensor_rays(setup) / height
    for row0 in range(0, height, BAND_ROWS):
        row1 = min(row0 + BAND_ROWS, height)
        _sensor_kernel(out, row0, row1, setup.axis_px[0], setup.axis_px[1], setup.camera.pixel_pitch_mm,
                       setup.lattice, setup.inverse_scale, *setup.optics_args(), setup.pixel_offsets,
                       setup.aperture_offsets, *arrays.kernel_args())
        if progress is not None:
            progress.advance(per_row * (row1 - row0), stage)
    return out


def render_ideal(setup: _Setup, arrays: SceneArrays, channels: int,
                 progress: Progress | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Ideal views (m̂, m̂, rows, cols, channels) and their passing fractions, in bands of lens rows."""
    from ._kernels import _ideal_kernel

    camera, grid = setup.camera, setup.grid
    m = camera.m_hat
    c = camera.center_index
    p_eff_px = camera.effective_pixel_pitch_mm / camera.pixel_pitch_mm * micro_image_scale(camera)
    u, v = grid.axes
    k = np.arange(m) - c
    view_offsets = (k[None, :, None] * u + k[:, None, None] * v) * p_eff_px  # (ky, kx, 2) px
    sub = setup.pixel_offsets  # the same strata, over an effective pixel aligned with u, v
    sub_px = (sub[:, :1] * u + sub[:, 1:] * v) * p_eff_px  # effective-pixel sub-samples along u, v
    centers = np.ascontiguousarray(grid.centers_xy_px())
    lens_centers = np.ascontiguousarray(setup.lens_grid.centers_xy_px())
    views = np.empty((m, m, grid.rows, grid.cols, channels), dtype=np.float32)
    weight = np.empty((m, m, grid.rows, grid.cols), dtype=np.float32)
    per_row = ideal_rays(setup) / grid.rows
    for row0 in range(0, grid.rows, LENS_BAND_ROWS):
        row1 = min(row0 + LENS_BAND_ROWS, grid.rows)
        _ideal_kernel(views, weight, row0, row1, centers, lens_centers, np.ascontiguousarray(view_offsets),
                      np.ascontiguousarray(sub_px), setup.axis_px[0], setup.axis_px[1], camera.pixel_pitch_mm,
                      *setup.optics_args(), setup.aperture_offsets, *arrays.kernel_args())
        if progress is not None:
            progress.advance(per_row * (row1 - row0), "ideal views")
    return views, weight
