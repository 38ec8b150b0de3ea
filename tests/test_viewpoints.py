"""Viewpoint stacks (Eq. 32) and each view's virtual camera (Eqs. 17, 33, 34) in two dimensions."""

import math

import numpy as np
import pytest

from lfproc import Camera, LfprocError, LightField, geometry, viewpoints
from lfproc.viewpoints import aperture_mask, circular_walk, mosaic, viewpoint_geometry
from lfproc.camera import MainLens

from conftest import SAMPLES


def test_view_geometry_in_two_dimensions_matches_table4():
    cam = Camera.from_toml(SAMPLES / "cameras" / "paper-f100-b20.toml")
    table = viewpoint_geometry(cam)
    corner = table[0][0]           # (ky, kx) = (0, 0): offsets (-12, -12)
    assert corner.offset == (-12, -12)
    assert corner.position_mm == pytest.approx((4.344, 4.344), abs=1e-3)
    assert [abs(t) for t in corner.tilt_deg] == pytest.approx([0.504, 0.504], abs=0.002)
    assert corner.baseline_to_center_mm == pytest.approx(4.344 * math.sqrt(2), abs=2e-3)
    assert corner.baseline_to_neighbour_mm == pytest.approx(0.362, abs=1e-3)
    mixed = table[11][24]          # offsets (-1, +12)
    assert mixed.position_mm == pytest.approx((0.362, -4.344), abs=1e-3)
    assert mixed.tilt_deg[0] == pytest.approx(0.042, abs=0.002) and mixed.tilt_deg[1] == pytest.approx(-0.504, abs=0.002)
    centre = table[12][12]
    assert centre.position_mm == (0.0, 0.0) and centre.baseline_to_center_mm == 0.0
    meta = centre.metadata()
    assert meta["view"] == [12, 12] and set(meta) >= {"view", "position_mm", "tilt_deg"}


def test_mosaic_layout_is_block_ky_kx():
    views = np.arange(3 * 3 * 2 * 4, dtype=np.float32).reshape(3, 3, 2, 4, 1)
    tiled = mosaic(views, gap=1)
    assert tiled.shape == (3 * 2 + 2, 3 * 4 + 2, 1)
    for ky in range(3):
        for kx in range(3):
            y0, x0 = ky * 3, kx * 5
            np.testing.assert_array_equal(tiled[y0:y0 + 2, x0:x0 + 4], views[ky, kx])
    assert tiled[2, :].max() == 0 and tiled[:, 4].max() == 0  # the gaps


def test_inside_aperture_blacks_out_views_outside_the_stop():
    cam = Camera(0.01, 0.11, 0.4, MainLens(50.0, 50.0, f_number=6.0))
    views = np.ones((11, 11, 2, 2, 1), np.float32)
    lf = LightField.from_views(views, cam)
    kept = viewpoints(lf, inside_aperture=True)
    mask = aperture_mask(lf)
    pos = geometry.view_positions_mm(cam)
    expect = np.hypot(pos[:, None], pos[None, :]) <= 50.0 / 12.0
    np.testing.assert_array_equal(mask, expect)
    assert 0 < mask.sum() < 121
    np.testing.assert_array_equal(kept[..., 0, 0, 0], expect.astype(np.float32))
    with pytest.raises(LfprocError, match="camera"):
        viewpoints(LightField.from_views(views), inside_aperture=True)


def test_circular_walk_stays_inside_the_mask_and_moves():
    path = circular_walk(11, frames=24)
    assert len(path) > 8 and len(set(path)) == len(path)
    assert all(abs(ky - 5) <= 5 and abs(kx - 5) <= 5 for ky, kx in path)
    mask = np.zeros((11, 11), bool)
    mask[3:8, 3:8] = True
    inside = circular_walk(11, mask=mask)
    assert all(mask[k] for k in inside) and len(inside) > 1
    assert circular_walk(1) == [(0, 0)]
