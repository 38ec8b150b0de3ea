"""Tilted planes and the per-lens depth ground truth of the simulator, against plain-numpy ray formulas and
rotation matrices built here, and a refocus sweep over a tilted plane against the geometry's a(d)."""

import math

import numpy as np
import pytest

from lfproc import geometry, simulate
from lfproc.camera import Camera, MainLens
from lfproc.errors import LfprocError
from lfproc.simulate import Noise, Plane, Scene, Sinusoid, Uniform, parse_scene_dict
from plainref import shifted_views

F_U, H_U, F_S, H_S = 99.5145, -33.184, 2.749, 0.374  # the paper's f100 main lens and micro lens


def camera(m=9, f_number=4.0, **kw):
    """The paper's camera scaled down to m̂ = m px per micro lens (p_m = 0.25 mm), focused at infinity."""
    return Camera(0.25 / m, 0.25, F_S, MainLens(F_U, F_U, principal_plane_gap_mm=H_U, f_number=f_number), mla_principal_plane_gap_mm=H_S, **kw)


def rotation(tx_deg, ty_deg):
    """R_y(tx) · R_x(ty) in (x, y, depth) coordinates: the documented tilt, built from elementary rotations."""
    tx, ty = math.radians(tx_deg), math.radians(ty_deg)
    r_y = np.array([[math.cos(tx), 0, -math.sin(tx)], [0, 1, 0], [math.sin(tx), 0, math.cos(tx)]])
    r_x = np.array([[1, 0, 0], [0, math.cos(ty), -math.sin(ty)], [0, math.sin(ty), math.cos(ty)]])
    return r_y @ r_x


def central_chief_rays(cam, grid, shape):
    """Telecentric central-view chief rays through each lens centre (Eqs. 16-19, m = 0): U and q, (rows, cols, 2)."""
    axis = np.array([(shape[1] - 1) / 2, (shape[0] - 1) / 2])
    u = (grid.centers_xy_px() - axis) * cam.pixel_pitch_mm
    return u, -u / cam.main_optics.focal_length_mm


def hit_on_tilted_plane(cam, grid, shape, distance_mm, tx_deg, ty_deg):
    """Where each central chief ray meets the plane depth = D + x·tan tx + y·tan ty / cos tx: (x, y, depth)."""
    u, q = central_chief_rays(cam, grid, shape)
    big_l = cam.main_optics.sensor_path_mm(cam.mla_path_mm)
    kx, ky = math.tan(math.radians(tx_deg)), math.tan(math.radians(ty_deg)) / math.cos(math.radians(tx_deg))
    # plane coordinates are the ray heights negated: x = −(U + q·z); depth = z + L
    z = (distance_mm - big_l - u[..., 0] * kx - u[..., 1] * ky) / (1 + q[..., 0] * kx + q[..., 1] * ky)
    xy = -(u + q * z[..., None])
    return xy[..., 0], xy[..., 1], z + big_l


# ---------------------------------------------------------------------------- the plane model
@pytest.mark.parametrize("tilt", [(0.0, 0.0), (25.0, 0.0), (0.0, -40.0), (30.0, 20.0), (-70.0, 55.0)])
def test_distance_at_and_the_frame_match_the_documented_rotation(tilt):
    plane = Plane(500.0, Uniform(), tilt_deg=tilt)
    rot = rotation(*tilt)
    np.testing.assert_allclose(plane.frame(), rot.T, atol=1e-15)  # rows e1, e2, n = the rotated x, y, depth axes
    rng = np.random.default_rng(1)
    a, b = rng.uniform(-30, 30, (2, 50))
    points = rot @ np.stack([a, b, np.zeros_like(a)])  # plane points relative to its centre point
    np.testing.assert_allclose(plane.distance_at(points[0], points[1]), 500.0 + points[2], rtol=1e-12)
    assert plane.tilted == (tilt != (0.0, 0.0))
    if tilt[1] == 0.0:  # about the y axis only: depth grows with x at the slope tan tx
        assert plane.distance_at(10.0, 7.0) == pytest.approx(500.0 + 10.0 * math.tan(math.radians(tilt[0])))


def test_tilt_is_validated_described_and_read_from_scene_files():
    with pytest.raises(LfprocError, match="tilt_deg"):
        Plane(500.0, Uniform(), tilt_deg=(85.0, 0.0))
    with pytest.raises(LfprocError, match="tilt_deg"):
        Plane(500.0, Uniform(), tilt_deg=(10.0,))
    assert "tilt_deg" not in Plane(500.0, Uniform()).describe()
    assert Plane(500.0, Uniform(), tilt_deg=(10, -5)).describe()["tilt_deg"] == [10.0, -5.0]
    cam_table = {"sensor": {"pixel_pitch_mm": 0.01}, "mla": {"pitch_mm": 0.1, "focal_length_mm": 0.4},
                 "main_lens": {"focal_length_mm": 50.0, "image_distance_mm": 50.0, "f_number": 4.0}}
    parsed = parse_scene_dict({"camera": cam_table, "plane": [{"distance_mm": 600.0, "texture": "uniform",
                                                               "tilt_deg": [12.5, -3]}]})
    assert parsed.scene.planes[0].tilt_deg == (12.5, -3.0)
    with pytest.raises(LfprocError, match=r"tilt_deg"):
        parse_scene_dict({"camera": cam_table, "plane": [{"distance_mm": 600.0, "texture": "uniform",
                                                          "tilt_deg": 12}]})


# ---------------------------------------------------------------------------- depth ground truth
def test_depth_on_fronto_parallel_planes_is_their_distance_and_nan_on_the_background():
    cam = camera(m=7)
    shape = (140, 160)
    scene = Scene((Plane(700.0, Uniform(0.3), region_mm=(-100.0, 100.0, -100.0, 0.0)),
                   Plane(400.0, Uniform(0.9), region_mm=(0.0, 50.0, -50.0, 50.0))))
    cap = simulate.render(cam, scene, shape, ideal_views=False)
    assert cap.depth_mm.shape == (cap.grid.rows, cap.grid.cols)
    labels = cap.plane_label
    assert set(np.unique(labels)) == {-1, 0, 1}
    np.testing.assert_allclose(cap.depth_mm[labels == 0], 700.0, rtol=1e-12)
    np.testing.assert_allclose(cap.depth_mm[labels == 1], 400.0, rtol=1e-12)
    assert np.isnan(cap.depth_mm[labels == -1]).all()
    assert cap.lens_grid == cap.grid  # telecentric: micro images sit under their lenses


@pytest.mark.parametrize("tilt", [(30.0, 0.0), (-20.0, 35.0)])
def test_depth_on_a_tilted_plane_follows_the_chief_ray(tilt):
    cam = camera(m=7)
    shape, d = (150, 170), 450.0
    cap = simulate.render(cam, Scene((Plane(d, Noise(2.0), tilt_deg=tilt),)), shape, ideal_views=False)
    x, y, depth = hit_on_tilted_plane(cam, cap.grid, shape, d, *tilt)
    assert np.all(cap.plane_label == 0)
    np.testing.assert_allclose(cap.depth_mm, depth, rtol=1e-10)
    assert np.ptp(depth) > 5.0  # the tilt shows across the field
    np.testing.assert_allclose(Plane(d, Uniform(), tilt_deg=tilt).distance_at(x, y), depth, rtol=1e-10)


def test_a_tilted_plane_occludes_a_fronto_parallel_one_where_it_is_nearer():
    """Both planes pass through the axis at 500 mm; the tilted one is nearer for x < 0 (plane coordinates)."""
    cam = camera(m=7)
    shape = (140, 160)
    scene = Scene((Plane(500.0, Uniform(0.2), name="wall"), Plane(500.0, Uniform(0.9), tilt_deg=(30.0, 0.0))))
    cap = simulate.render(cam, scene, shape)
    x, _, depth = hit_on_tilted_plane(cam, cap.grid, shape, 500.0, 30.0, 0.0)
    clear = np.abs(x) > 0.5
    np.testing.assert_array_equal(cap.plane_label[clear], np.where(x[clear] < 0, 1, 0))
    np.testing.assert_allclose(cap.depth_mm[clear], np.minimum(depth[clear], 500.0), rtol=1e-10)
    c = cam.center_index
    far_from_edge = np.abs(x) > 2.0  # the central view's sample footprint stays on one plane
    np.testing.assert_allclose(cap.ideal_views[c, c, ..., 0][far_from_edge],
                               np.where(x[far_from_edge] < 0, 0.9, 0.2), atol=1e-6)


def test_textures_on_a_tilted_plane_use_the_planes_own_coordinates():
    """A grating along the plane's e1 axis, tilted 60° about y: the ideal central view follows its period along
    the plane, i.e. half of it laterally (cos 60°)."""
    cam = camera(m=7, f_number=2.0)
    shape, d, period = (150, 170), 450.0, 30.0
    plane = Plane(d, Sinusoid(period_mm=period, low=0.1, high=0.9), tilt_deg=(60.0, 0.0))
    views, _, grid = simulate.render_ideal_views(cam, Scene((plane,)), shape, rim_radius_mm=None)
    x, y, depth = hit_on_tilted_plane(cam, grid, shape, d, 60.0, 0.0)
    along = np.tensordot(rotation(60.0, 0.0)[:, 0], np.stack([x, y, depth - d]), axes=1)  # along the plane's e1
    expected = 0.1 + 0.8 * (0.5 + 0.5 * np.cos(2 * np.pi * along / period))
    c = cam.center_index
    # the central sample integrates over ~1.5 mm along the tilted plane (1/20 of the period): blur below 0.01
    np.testing.assert_allclose(views[c, c, ..., 0], expected, atol=0.01)


# ---------------------------------------------------------------------------- refocusing a tilted plane
def test_the_sharpest_refocus_parameter_follows_the_tilt_across_the_plane():
    """Cross-view agreement of the shifted ideal views, per block of lenses, peaks at the a that the geometry
    gives for the plane's depth at that block (refocus_parameter of distance_at), and a changes across it."""
    cam = camera(m=9)
    d = geometry.slice_distance_mm(cam, 1.5)
    tilt = (60.0, -30.0)
    plane = Plane(d, Noise(1.5, seed=4), tilt_deg=tilt)  # features of about two lens footprints
    views, weight, grid = simulate.render_ideal_views(cam, Scene((plane,)), (560, 560), rim_radius_mm=None)
    assert weight.min() > 0.99
    _, _, depth = hit_on_tilted_plane(cam, grid, (560, 560), d, *tilt)
    a_grid = np.round(np.arange(1.1, 2.0001, 0.02), 6)
    variance = np.array([shifted_views(views, a).var(axis=0) for a in a_grid])  # (A, rows, cols)
    border, block = 9, 11  # border > max a·c = 8 lenses
    peaks, truths = [], []
    for r0 in range(border, grid.rows - border - block + 1, block):
        for q0 in range(border, grid.cols - border - block + 1, block):
            window = (slice(r0, r0 + block), slice(q0, q0 + block))
            consistency = -variance[(slice(None), *window)].mean(axis=(1, 2))
            k = int(np.clip(np.argmax(consistency), 1, len(a_grid) - 2))
            y0, y1, y2 = consistency[k - 1:k + 2]
            peaks.append(a_grid[k] + 0.5 * (y0 - y2) / (y0 - 2 * y1 + y2) * 0.02)
            truths.append(geometry.refocus_parameter(cam, float(np.mean(depth[window]))))
    peaks, truths = np.array(peaks), np.array(truths)
    assert len(peaks) >= 9 and np.ptp(truths) > 0.15  # the blocks see clearly different depths
    # 0.03 in a: a block spans about ±0.05 in a and the slice's depth of field about ±1/(2c) = ±0.125
    np.testing.assert_allclose(peaks, truths, atol=0.03)
