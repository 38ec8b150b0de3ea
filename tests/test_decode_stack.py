"""The own-cell band reader (one remap over the four lens classes' strips, stacked) against the plain
reading it stands for: each class masked to its cells, demosaiced in float, remapped over the whole
sensor, its lenses kept. Within the 16-bit quantization of the demosaicing (2 units of the range)."""

import cv2
import numpy as np
import pytest

from lfproc.decode._cells import CLASSES, cell_classes, lens_class
from lfproc.decode._band import read_band
from lfproc.decode._demosaic import to_channels
from lfproc.decode._positions import remap_maps, sample_positions
from lfproc.decode._plan import MAP_STEP, plan_reading
from lfproc.decode._resample import cv_flag
from lfproc.grid import LensGrid


def plain_reading(sensor, grid, m, cfa, interpolation, cells):
    rows, cols = grid.rows, grid.cols
    lens_cls = lens_class(*np.meshgrid(np.arange(rows), np.arange(cols), indexing="ij"))
    out = np.zeros((m, m, rows, cols, 3), np.float32)
    for cls in range(CLASSES):
        image = to_channels(np.where(cells == cls, sensor, 0.0), cfa, "fast")
        for ky, (map_x, map_y) in enumerate(remap_maps(grid, m)):
            # the decoder reads rows at MAP_STEP px (band-size invariance, lfproc.decode._plan); on this
            # white noise (±1000 a pixel) float32's own rounding of the rows would show
            y = sample_positions(grid, m)[1][ky].reshape(map_y.shape)
            map_y = (np.rint(y / MAP_STEP) * MAP_STEP).astype(np.float32)
            views = cv2.remap(image, map_x, map_y, cv_flag(interpolation), borderMode=cv2.BORDER_CONSTANT,
                              borderValue=0).reshape(m, rows, cols, 3)
            out[ky][:, lens_cls == cls] = views[:, lens_cls == cls]
    return out


@pytest.mark.parametrize("kind, interpolation", [("hexagonal", "linear"), ("rectangular", "linear"),
                                                 ("hexagonal", "nearest"), ("hexagonal", "cubic")])
def test_stacked_classes_read_as_each_class_alone(kind, interpolation):
    # lenses on the top and left border: their outer samples reach past the sensor (read 0), in the first band
    grid = LensGrid(kind, 9.4, 1.5, (2.0, 1.5), 12, 13)
    sensor = np.random.default_rng(3).uniform(-20.0, 1000.0, (110, 125))   # noise below black: low < 0
    cells = cell_classes(grid, sensor.shape)
    m = 7
    want = plain_reading(sensor, grid, m, "GRBG", interpolation, cells)
    plan = plan_reading(grid, m, sensor.shape, "GRBG", "fast", interpolation, 3, cells=cells, rows_per_band=5)
    got = np.concatenate([read_band(plan, band, sensor) for band in plan.bands], axis=2)
    unit = (sensor.max() - sensor.min()) / 65535
    assert np.abs(want).max() > 900
    np.testing.assert_allclose(got, want, rtol=0, atol=2 * unit)
