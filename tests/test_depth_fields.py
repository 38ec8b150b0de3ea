"""One set of fields for any main optics (issue 31): a depth map's ``depth``, ``near``, ``far`` in its ``space``.

A camera's depth map is in millimetres from the sensor, a microscope's in micrometres from the native object
plane; both carry the camera's ``object_space`` and the contract's names (``distance_mm``, ``near_mm``,
``far_mm`` / ``z_um``, ``z_near_um``, ``z_far_um``) read the same arrays, ``None`` in the other space. The
positions are checked against the geometry independently: a camera's depth is Eq. 21 of its ``a``, a
microscope's z is linear in ``a`` (z = a·m̂·f_s·n/M²), and the bounds hold the position on the side the
space orders as nearer.
"""

import numpy as np
import pytest
from scipy import ndimage

import lfproc
from lfproc import Camera, LightField, geometry
from lfproc.camera import NATIVE_PLANE_UM, SENSOR_MM, MainLens
from lfproc.depth._metric import metric_depth

from scopefile import TINY_LFM

LENS_CAMERA = Camera(0.02, 0.1, 0.4, MainLens(50.0, 50.5, f_number=4.0), name="fields")
MICROSCOPE = Camera.from_toml_string(TINY_LFM)

CONTRACT = {"mm": ("distance_mm", "near_mm", "far_mm"), "um": ("z_um", "z_near_um", "z_far_um")}


def plane_views(camera, shift=1, size=28, seed=5):
    """Views of a textured plane whose view k is displaced shift·(c − k) lenses: the slice a = ``shift``."""
    m, c = camera.m_hat, camera.center_index
    texture = ndimage.gaussian_filter(np.random.default_rng(seed).random((size + 2 * m, size + 2 * m)), 1.2)
    views = np.empty((m, m, size, size, 1), np.float32)
    for ky in range(m):
        for kx in range(m):
            dy, dx = shift * (c - ky), shift * (c - kx)
            views[ky, kx, :, :, 0] = texture[m - dy:m - dy + size, m - dx:m - dx + size]
    return views


@pytest.fixture(scope="module", params=["camera", "microscope"])
def estimate(request):
    camera = LENS_CAMERA if request.param == "camera" else MICROSCOPE
    lf = LightField.from_views(plane_views(camera), camera)
    return camera, lfproc.depth_map(lf, a_range=(0.2, 1.8), min_confidence=0.0, half_apertures=False)


def test_one_set_of_fields_in_the_cameras_space(estimate):
    camera, dm = estimate
    assert dm.space == camera.main_optics.object_space
    assert dm.space == (SENSOR_MM if camera is LENS_CAMERA else NATIVE_PLANE_UM)
    assert not hasattr(dm, "microscope")
    mine, other = CONTRACT[dm.space.unit], CONTRACT["um" if dm.space.unit == "mm" else "mm"]
    for name, field in zip(mine, (dm.depth, dm.near, dm.far)):
        assert getattr(dm, name) is field, name
        assert field.dtype == np.float32 and field.shape == dm.a.shape
    for name in other:
        assert getattr(dm, name) is None, name
    with pytest.raises(AttributeError):
        dm.z_um = dm.depth                                  # read-only: the one set is the only storage


def test_positions_are_the_geometrys_and_the_bounds_are_ordered(estimate):
    camera, dm = estimate
    known = np.isfinite(dm.a)
    assert known.mean() > 0.5
    a = dm.a[known].astype(np.float64)
    if camera is LENS_CAMERA:         # Eq. 21 of the estimate's a; nearer is less distance from the sensor
        expected = geometry.slice_distance_mm(camera, a)
        lower, upper = dm.near[known], dm.far[known]
    else:                             # z = a·m̂·f_s·n/M² µm, independently of the ray transfer
        scope = camera.main_optics
        expected = a * camera.m_hat * camera.mla_focal_length_mm * 1000.0 * scope.immersion_index \
            / scope.objective_magnification ** 2
        lower, upper = dm.far[known], dm.near[known]         # nearer the objective is the larger z
    np.testing.assert_allclose(dm.depth[known], expected, rtol=1e-6)
    assert np.all(lower <= dm.depth[known]) and np.all(dm.depth[known] <= upper)
    assert np.all(upper - lower > 0)
    assert np.all(np.isnan(dm.depth[~known]) & np.isnan(dm.near[~known]) & np.isnan(dm.far[~known]))
    # the plane sits at a = 1: most lenses find it (the test can fail if positions or bounds are off)
    assert abs(float(np.median(a)) - 1.0) < 0.1


def test_the_result_reads_its_arrays_and_tags(estimate):
    """One result type: the contract's names read the arrays themselves; the tags are explicit attributes."""
    camera, dm = estimate
    assert dm.unit == dm.space.unit and type(dm) is lfproc.DepthMap
    for name, array in zip(("distance_mm", "near_mm", "far_mm"), (dm.depth, dm.near, dm.far)):
        assert getattr(dm, name) is (array if dm.space.unit == "mm" else None), name
    for name, array in zip(("z_um", "z_near_um", "z_far_um"), (dm.depth, dm.near, dm.far)):
        assert getattr(dm, name) is (array if dm.space.unit == "um" else None), name
    tags = dm.tags()
    for key in ("method", "a_step", "view_step", "views_used_up_to_offset", "min_confidence", "lens_grid"):
        assert getattr(dm, key) == tags[key], key
    assert tags["camera"] == dm.camera_name == camera.name and tags["source"] is dm.source is None
    assert tags["min_confidence"] == 0.0          # the threshold the map was made with (it said 0.1 whatever it was)
    assert not hasattr(type(dm), "__getattr__")


@pytest.mark.parametrize("camera", [LENS_CAMERA, MICROSCOPE], ids=["camera", "microscope"])
def test_metric_depth_one_path(camera):
    """Positions and bounds of given estimates, with basins open at either end (±inf) and unknowns (NaN)."""
    a = np.array([[0.3, 1.0, np.nan, 2.0]])
    a_low = np.array([[0.2, -np.inf, 0.0, 1.9]])
    a_high = np.array([[0.4, 1.1, 0.0, np.inf]])
    m = metric_depth(camera, a, a_low, a_high, 1.0)
    assert m.space == camera.main_optics.object_space and not hasattr(m, "distance_mm")   # a private result
    assert np.isnan(m.depth[0, 2]) and np.isnan(m.near[0, 2]) and np.isnan(m.far[0, 2])
    dof = geometry.slice_geometry(camera, np.array([0.3, 1.0, 2.0]), 1.0)   # the DOF of the views summed
    cols = [0, 1, 3]
    np.testing.assert_allclose(m.depth[0, cols], dof.depth, rtol=1e-12)
    if camera is LENS_CAMERA:
        assert np.all(m.near[0, cols] <= dof.near) and np.all(m.far[0, cols] >= dof.far)
        assert m.far[0, 1] == np.inf                                         # a_low = −inf: beyond infinity
        assert m.near[0, 3] == pytest.approx(geometry.front_focal_plane_mm(camera))   # a_high = +inf
    else:
        assert np.all(m.near[0, cols] >= dof.near) and np.all(m.far[0, cols] <= dof.far)
        assert m.far[0, 1] == -np.inf and m.near[0, 3] == np.inf             # z linear in a: ±inf at a = ±inf


def test_a_camera_below_the_slice_at_infinity_is_at_infinity():
    a_inf = geometry.infinity_parameter(LENS_CAMERA)
    a = np.array([a_inf - 0.5, -50.0])     # beyond infinity, and below a_0 = −δ·b_U/p_m = −25.25 ("macro")
    m = metric_depth(LENS_CAMERA, a, a - 0.1, a + 0.1)
    assert np.all(m.depth == np.inf) and np.all(m.far == np.inf)
    # not the paraxial formula's "macro" distance far below a_∞
    assert float(geometry.slice_distance_mm(LENS_CAMERA, a[1])) < np.inf
