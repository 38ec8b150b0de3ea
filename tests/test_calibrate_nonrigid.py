"""Non-rigid lattices (issue 14): a smooth deviation where the pitch drifts, rigid where it does not.

White images come from tests/whitegen.py with every true centre known: a rectangular lattice whose pitch
drifts linearly across the image (as PlenoptiCam's public synthetic white image *d*: 7.4 → 8.0 px), at
the issue's smallest pitches (5 px), and blurred spots (PlenoptiCam's *a*, *b*, *c*). The accuracy is
the RMS distance from each true centre at least a pitch inside the image to the nearest centre of the
fitted grid (extended by 3 lenses on every side, so trimmed border lenses still count).
"""

import json

import numpy as np
import pytest
from scipy.spatial import cKDTree
from whitegen import covering_grid, drifting_white, spot_white, true_centres_inside

from lfproc.calibrate import find_grid
from lfproc.grid import LensGrid, SmoothDeviation


def fitted_centres(grid: LensGrid, pad: int = 3) -> np.ndarray:
    rows, cols = np.meshgrid(np.arange(-pad, grid.rows + pad), np.arange(-pad, grid.cols + pad), indexing="ij")
    return grid.lens_xy(rows, cols).reshape(-1, 2)


def centre_rms(grid: LensGrid, truth: np.ndarray, shape, margin: float, remove_offset: bool = False) -> float:
    rows, cols = shape
    inside = truth[(truth[:, 0] >= margin) & (truth[:, 0] <= cols - 1 - margin)
                   & (truth[:, 1] >= margin) & (truth[:, 1] <= rows - 1 - margin)]
    fitted = fitted_centres(grid)
    _, idx = cKDTree(fitted).query(inside)
    diff = fitted[idx] - inside
    if remove_offset:
        diff = diff - diff.mean(0)
    return float(np.sqrt(np.mean(np.sum(diff ** 2, axis=1))))


@pytest.mark.parametrize("pitch_from, pitch_to, shape, rotation", [
    (7.4, 8.0, (400, 400), -2.0),   # PlenoptiCam's d: 7.7 px lenses drifting by +-4 %
    (4.8, 5.2, (300, 320), 0.7),    # the smallest pitch the issue asks for
])
def test_a_drifting_pitch_is_fitted_by_a_smooth_lattice(pitch_from, pitch_to, shape, rotation):
    image, truth = drifting_white(shape, pitch_from, pitch_to, rotation_deg=rotation, offset=(0.3, -0.2))
    estimate = find_grid(image)
    grid = estimate.grid
    assert grid.model == "smooth" and isinstance(grid.deviation, SmoothDeviation)
    assert centre_rms(grid, truth, shape, pitch_to + 1.0) <= 0.03
    assert not estimate.warnings
    # the rigid part alone misses by far more: the deviation carries the drift
    rigid = LensGrid(grid.kind, grid.pitch_px, grid.rotation_deg, grid.origin_xy_px, grid.rows, grid.cols)
    assert centre_rms(rigid, truth, shape, pitch_to + 1.0) > 0.3


def test_a_rigid_lattice_stays_rigid_at_5_px():
    shape = (240, 300)
    true = covering_grid(shape, "hexagonal", 5.0, 0.4, (0.2, 0.1))
    from whitegen import white_image
    image = white_image(shape, true, 0.42 * 5.0, noise_sigma=0.01, seed=4)
    grid = find_grid(image).grid
    assert grid.model == "rigid" and grid.deviation is None
    truth = true_centres_inside(true, shape, 5.0)
    assert centre_rms(grid, truth, shape, 5.0) <= 0.03
    assert abs(grid.pitch_px - 5.0) <= 0.002


def test_the_deviation_round_trips_through_grid_json(tmp_path):
    image, _ = drifting_white((300, 300), 7.4, 8.0, rotation_deg=1.0)
    grid = find_grid(image).grid
    data = json.loads(json.dumps(grid.to_json_dict(), allow_nan=False))
    assert data["model"] == "smooth" and data["deviation"]["degree"] == grid.deviation.degree
    back = LensGrid.from_json_dict(data)
    assert back == grid
    np.testing.assert_array_equal(back.centers_xy_px(), grid.centers_xy_px())
    np.testing.assert_allclose(np.array(data["centers_xy_px"]), grid.centers_xy_px().reshape(-1, 2))
    # a rigid grid writes no deviation and reads back rigid
    rigid = LensGrid("rectangular", 10.0, 0.0, (5.0, 5.0), 3, 4)
    assert LensGrid.from_json_dict(rigid.to_json_dict()) == rigid
    assert rigid.to_json_dict()["model"] == "rigid" and rigid.to_json_dict()["deviation"] is None


def test_smooth_deviation_is_evaluated_at_the_rigid_position():
    dev = SmoothDeviation(1, (50.0, 40.0), (50.0, 40.0), (0.5, 0.0, 0.25, 0.0), (0.0, -0.1, 0.0, 0.0))
    grid = LensGrid("rectangular", 10.0, 0.0, (0.0, 0.0), 9, 11, deviation=dev)
    # Legendre P0 = 1, P1 = t: dx = 0.5 + 0.25 * xn, dy = -0.1 * yn with xn = (x - 50)/50, yn = (y - 40)/40
    xy = grid.lens_xy(2, 7)  # rigid position (70, 20)
    np.testing.assert_allclose(xy, [70 + 0.5 + 0.25 * 0.4, 20 - 0.1 * (-0.5)])


@pytest.mark.parametrize("name, kind, pitch, sigma, square, noise, limit, remove_offset", [
    ("a", "rectangular", 142.857, 12.0, True, 0.25, 0.1, True),  # 5 x 5 large noisy squares
    ("b", "hexagonal", 66.7, 9.0, False, 0.05, 0.03, False),
    ("c", "hexagonal", 21.16, 3.0, False, 0.05, 0.03, False),
])
def test_plenopticam_like_spot_whites(name, kind, pitch, sigma, square, noise, limit, remove_offset):
    shape = (720, 720)
    true = covering_grid(shape, kind, pitch, 1.0 if name == "c" else 0.0, (0.37, -0.21))
    image = spot_white(shape, true, sigma, noise_sigma=noise, square=square, seed=3)
    grid = find_grid(image).grid
    truth = true_centres_inside(true, shape, 0.5 * pitch)
    assert centre_rms(grid, truth, shape, 0.5 * pitch, remove_offset) <= limit
