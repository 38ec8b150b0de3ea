"""lfproc.depth on rendered scenes with known depth: accuracy, confidence, bounds, outputs and the CLI.

The scene: a textured wall, a textured card in front of its left half, and a textureless card in front
of its lower right quarter, at refocus parameters between the sweep's slices. Accuracy is measured on
the simulator's ideal views (the method alone) and on the decoded capture (method + decoding).
"""

import json
import math

import numpy as np
import pytest
from conftest import assert_clean_error, run_cli
from scipy import ndimage

import lfproc
from lfproc import Camera, LightField, geometry, simulate
from lfproc.io import read_capture, read_metadata, write_image
from lfproc.api import DecodeSetup
from lfproc.simulate import Noise, Plane, Scene, Uniform
from lfproc.camera import MainLens

A_TRUE = {"card": 1.43, "blank": 1.1, "wall": 0.57}   # off the sweep's 0.1-spaced slices


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    cam = Camera(0.009, 0.1, 0.4, MainLens(50.0, 50.0, f_number=4.0), black_level=64, white_level=16383, cfa="RGGB", name="depth-test")
    dist = {k: float(geometry.slice_distance_mm(cam, a)) for k, a in A_TRUE.items()}
    planes = (Plane(dist["card"], Noise(feature_mm=3.0, seed=4, low=0.15, high=0.9), region_mm=(-60, -2, -60, 60)),
              Plane(dist["blank"], Uniform(0.5), region_mm=(4, 60, 4, 60)),
              Plane(dist["wall"], Noise(feature_mm=6.0, seed=7, low=0.1, high=0.9)))
    sim = simulate.render(cam, Scene(planes, background=0.05), (400, 560), rotation_deg=0.2, offset_px=(0.3, -0.2),
                          shot_noise_photons=100000, seed=3, ideal_views=True)
    folder = tmp_path_factory.mktemp("depth")
    write_image(folder / "capture.png", sim.raw)
    write_image(folder / "white.png", sim.white)
    (folder / "camera.toml").write_text(cam.to_toml())
    decoded = DecodeSetup(cam, sim.grid, read_capture(folder / "white.png", cam)).decode(folder / "capture.png")
    truth_a = np.array([A_TRUE["card"], A_TRUE["blank"], A_TRUE["wall"]])[np.maximum(sim.plane_label, 0)]
    return {"camera": cam, "sim": sim, "folder": folder, "decoded": decoded, "truth_a": truth_a,
                "ideal": LightField.from_views(sim.ideal_views, cam, sim.grid)}


def region(sim, index, camera, margin=None):
    """Lenses that see plane ``index`` in every view: eroded by the largest parallax between planes
    (c·Δa lenses, occlusions) plus the aggregation window, and off the borders."""
    if margin is None:
        margin = math.ceil(camera.center_index * (A_TRUE["card"] - A_TRUE["wall"])) + 2
    mask = ndimage.binary_erosion(sim.plane_label == index, iterations=margin, border_value=0)
    return mask


def scores(depth_map, camera, truth_a, mask):
    """Median |distance error| / DOF, BadPix (share off by more than the DOF), share inside [near, far]."""
    truth = geometry.slice_geometry(camera, truth_a[mask])
    error = (depth_map.distance_mm[mask] - truth.distance_mm) / truth.dof_mm
    inside = (depth_map.near_mm[mask] <= truth.distance_mm) & (truth.distance_mm <= depth_map.far_mm[mask])
    return float(np.nanmedian(np.abs(error))), float(np.mean(~(np.abs(error) <= 1.0))), float(np.mean(inside))


@pytest.fixture(scope="module")
def ideal_depth(scene):
    return lfproc.depth_map(scene["ideal"])


@pytest.mark.parametrize("plane", [0, 2])
def test_textured_planes_from_ideal_views_meet_the_accuracy_targets(scene, ideal_depth, plane):
    mask = region(scene["sim"], plane, scene["camera"])
    assert mask.sum() > 80
    median, badpix, inside = scores(ideal_depth, scene["camera"], scene["truth_a"], mask)
    assert median <= 0.05, median       # sub-slice: slices are 0.1 apart in a, about a third of the DOF
    assert badpix <= 0.05, badpix
    assert inside >= 0.90, inside


def test_decoded_capture_keeps_every_lens_within_its_dof(scene):
    """Decoding adds its own bias (the sharpest slice of decoded views sits a few % farther, decode's issue;
    most of it from the outer rings of views), so the 5 % median target is checked on ideal views; BadPix
    and the bounds must hold here too."""
    depth_map = lfproc.depth_map(scene["decoded"])
    for plane in (0, 2):
        mask = region(scene["sim"], plane, scene["camera"])
        median, badpix, inside = scores(depth_map, scene["camera"], scene["truth_a"], mask)
        assert median <= 0.12 and badpix <= 0.05 and inside >= 0.90, (plane, median, badpix, inside)


@pytest.mark.parametrize("source", ["ideal", "decoded"])
def test_textureless_card_has_no_confident_wrong_value(scene, ideal_depth, source):
    depth_map = ideal_depth if source == "ideal" else lfproc.depth_map(scene["decoded"])
    mask = region(scene["sim"], 1, scene["camera"], margin=1)
    assert mask.sum() > 100
    truth = geometry.slice_geometry(scene["camera"], A_TRUE["blank"])
    wrong = ~(np.abs(depth_map.distance_mm[mask] - truth.distance_mm) <= truth.dof_mm)
    confident = depth_map.confidence[mask] >= 0.5
    assert not np.any(wrong & confident)
    assert np.isnan(depth_map.distance_mm[mask]).mean() > 0.5    # mostly unknown, not made up
    centre = region(scene["sim"], 1, scene["camera"])             # far from any edge: nothing to see
    assert np.isnan(depth_map.distance_mm[centre]).all()


def test_sub_slice_estimate_beats_picking_the_sharpest_slice(scene, ideal_depth):
    """The naive baseline: the sharpest (gradient energy) of slices 0.05 apart in a."""
    cam, truth_a = scene["camera"], scene["truth_a"]
    a_values = np.round(np.arange(0.3, 1.8, 0.05), 10)
    stack = lfproc.refocus(scene["ideal"], a_values)[..., 1]
    gy, gx = np.gradient(stack, axis=(1, 2))
    energy = ndimage.uniform_filter(gx ** 2 + gy ** 2, size=(1, 3, 3))
    naive = a_values[np.argmax(energy, axis=0)]
    mask = region(scene["sim"], 0, cam)
    naive_error = np.median(np.abs(naive[mask] - truth_a[mask]))
    ours = np.nanmedian(np.abs(ideal_depth.a[mask] - truth_a[mask]))
    assert ours < 0.5 * naive_error, (ours, naive_error)


def test_depth_map_fields_and_metric_consistency(scene, ideal_depth):
    d, cam = ideal_depth, scene["camera"]
    ny, nx = scene["ideal"].lens_shape
    for name in ("distance_mm", "confidence", "near_mm", "far_mm", "a"):
        arr = getattr(d, name)
        assert arr.shape == (ny, nx) and arr.dtype == np.float32, name
    assert d.allfocus.shape == (ny, nx, 3) and d.allfocus.dtype == np.float32
    known = np.isfinite(d.a)
    assert np.array_equal(known, np.isfinite(d.distance_mm))
    assert np.all((d.confidence >= 0) & (d.confidence <= 1))
    assert np.all(d.confidence[known] >= 0.1)
    np.testing.assert_allclose(d.distance_mm[known], geometry.slice_distance_mm(cam, d.a[known].astype(float)),
                               rtol=1e-6)
    assert np.all(d.near_mm[known] <= d.distance_mm[known]) and np.all(d.distance_mm[known] <= d.far_mm[known])
    assert "variance across the views" in d.method


def test_all_in_focus_is_sharper_than_any_single_slice(scene, ideal_depth):
    """Against the ideal central view (the scene as seen through the central virtual camera)."""
    reference = scene["ideal"].views[5, 5]
    inner = (slice(3, -3), slice(3, -3))
    err_all = np.mean((ideal_depth.allfocus[inner] - reference[inner]) ** 2)
    for a in (A_TRUE["wall"], A_TRUE["card"]):
        err_slice = np.mean((lfproc.refocus(scene["ideal"], a, interpolation="cubic")[inner] - reference[inner]) ** 2)
        assert err_all < err_slice


def test_depth_range_limits_the_search_and_leaves_outside_surfaces_unknown(scene):
    cam = scene["camera"]
    near = float(geometry.slice_distance_mm(cam, 0.9))
    depth_map = lfproc.depth_map(scene["ideal"], depth_range_mm=(near, math.inf))
    assert depth_map.a_searched[-1] <= 0.9 + 0.25 and depth_map.a_searched[0] <= 0.0
    card = region(scene["sim"], 0, cam)                      # the card (a = 1.43) is nearer than the range
    assert np.isnan(depth_map.distance_mm[card]).mean() > 0.9
    wall = region(scene["sim"], 2, cam)
    median, badpix, _ = scores(depth_map, cam, scene["truth_a"], wall)
    assert median <= 0.05 and badpix <= 0.05


def test_outer_ring_with_compressed_parallax_is_left_out_by_default(scene):
    """Why the outer ring is left out by default: its samples straddle the micro image border, and decoding
    them compresses their parallax (crosstalk, docs/decoding.md). Mimicked on ideal views: the outer ring
    shows the wall with 15 % less parallax; with the ring the wall comes out farther (lower a)."""
    cam, views = scene["camera"], scene["ideal"].views.copy()
    c, a_wall = cam.center_index, A_TRUE["wall"]
    for ky in range(cam.m_hat):
        for kx in range(cam.m_hat):
            if c in (abs(ky - c), abs(kx - c)):   # view k shows j − a(c − k): move it back by 15 % of that
                back = [-0.15 * a_wall * (c - ky), -0.15 * a_wall * (c - kx), 0]   # output j = input j − shift
                views[ky, kx] = ndimage.shift(views[ky, kx], back, order=3, mode="nearest")
    lf = LightField.from_views(views, cam, scene["sim"].grid)
    mask = region(scene["sim"], 2, cam)
    bias = lambda d: np.nanmedian(d.a[mask] - scene["truth_a"][mask])
    with_ring, without = lfproc.depth_map(lf, outer_views=True), lfproc.depth_map(lf)
    assert bias(with_ring) < -0.02 and abs(bias(without)) < 0.01, (bias(with_ring), bias(without))


def test_coarse_pass_narrows_the_sweep_to_the_occupied_range(scene, ideal_depth):
    """The scene spans a = 0.57 … 1.43: the fine sweep covers that, and much less than the default 0 … 3."""
    a = ideal_depth.a_searched
    assert a[0] <= 0.57 - 0.2 and a[-1] >= 1.43 + 0.2
    full = lfproc.depth_map(scene["ideal"], coarse_pass=False)
    assert full.a_searched[-1] >= 3.0 and len(a) < 0.7 * len(full.a_searched)
    known = np.isfinite(ideal_depth.a) & np.isfinite(full.a)
    assert known.mean() > 0.6 and np.median(np.abs(ideal_depth.a[known] - full.a[known])) < 1e-6


def test_views_delivered_as_zero_are_left_out(scene):
    """The decoder delivers views it cannot sample without bias as 0 everywhere: they must not count."""
    views = scene["ideal"].views.copy()
    dead = np.zeros((11, 11), bool)
    dead[:2], dead[-2:], dead[:, :2], dead[:, -2:] = True, True, True, True
    dead[3, 6] = dead[7, 4] = True
    views[dead] = 0.0
    depth_map = lfproc.depth_map(LightField.from_views(views, scene["camera"], scene["sim"].grid))
    for plane in (0, 2):
        mask = region(scene["sim"], plane, scene["camera"])
        median, badpix, inside = scores(depth_map, scene["camera"], scene["truth_a"], mask)
        assert median <= 0.05 and badpix <= 0.05 and inside >= 0.90, (plane, median, badpix, inside)
    views[5, 5] = 0.0
    with pytest.raises(lfproc.LfprocError, match="central view"):
        lfproc.depth_map(LightField.from_views(views, scene["camera"]))


def test_one_depth_function_and_its_errors(scene):
    """``lfproc.depth_map`` is the one depth function (issue 37: no callable ``lfproc.depth`` module)."""
    import lfproc.depth as package

    assert not callable(package) and "depth" not in lfproc.__all__ and "depth_map" in lfproc.__all__
    with pytest.raises(lfproc.LfprocError, match="camera"):
        lfproc.depth_map(LightField.from_views(scene["ideal"].views))
    with pytest.raises(lfproc.LfprocError, match="depth range"):
        lfproc.depth_map(scene["ideal"], depth_range_mm=(10.0, 20.0))
    with pytest.raises(lfproc.LfprocError, match="view_step"):
        lfproc.depth_map(scene["ideal"], view_step=9)


def test_import_of_the_depth_package_stays_light():
    import subprocess
    import sys

    code = "import sys, lfproc, lfproc.depth; print(any(m in sys.modules for m in ('numba', 'cv2', 'OpenImageIO', 'matplotlib')))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "False"


def read_float_tiff(path):
    """Pixels as stored, NaN included (lfproc.io.read_image refuses NaN, rightly for captures)."""
    import OpenImageIO as oiio

    inp = oiio.ImageInput.open(str(path))
    try:
        assert inp.spec().format == oiio.FLOAT
        return inp.read_image(oiio.FLOAT)
    finally:
        inp.close()


def read_ply(path):
    data = path.read_bytes()
    header, body = data.split(b"end_header\n", 1)
    count = int(next(line for line in header.decode().splitlines() if line.startswith("element vertex")).split()[-1])
    dtype = [("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("red", "u1"), ("green", "u1"), ("blue", "u1")]
    return np.frombuffer(body, dtype=dtype, count=count)


def test_cli_writes_every_output_with_metadata(scene, tmp_path):
    folder, cam = scene["folder"], scene["camera"]
    proc = run_cli("depth", folder / "capture.png", "--camera", folder / "camera.toml", "--white",
                   folder / "white.png", "--depth-range", "300:inf", "-o", tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert len(list(tmp_path.iterdir())) == 10      # five files, five sidecars, nothing else
    for suffix in ("_depth.tif", "_depth_confidence.tif", "_allfocus.tif", "_depth_preview.png", "_depth_points.ply"):
        assert (tmp_path / f"capture{suffix}").is_file(), suffix
        side = json.loads((tmp_path / f"capture{suffix}").with_suffix(".json").read_text())
        assert side["source"].endswith("capture.png") and "variance across the views" in side["method"]
    side = json.loads((tmp_path / "capture_depth.json").read_text())
    assert side["unit"] == "mm" and side["depth_range_mm"] == [300.0, None]
    assert read_metadata(tmp_path / "capture_depth.tif")["unit"] == "mm"
    depth_image = read_float_tiff(tmp_path / "capture_depth.tif")
    ny, nx = scene["decoded"].lens_shape
    assert depth_image.shape[:2] == (ny, nx) and depth_image.dtype == np.float32
    assert np.isnan(depth_image).any() and np.isfinite(depth_image).mean() > 0.5
    wall = region(scene["sim"], 2, cam)
    truth = geometry.slice_geometry(cam, A_TRUE["wall"])
    assert np.nanmedian(np.abs(depth_image[..., 0][wall] - truth.distance_mm)) < truth.dof_mm
    points = read_ply(tmp_path / "capture_depth_points.ply")
    assert len(points) == np.isfinite(depth_image).sum()
    np.testing.assert_allclose(np.sort(points["z"]), np.sort(depth_image[np.isfinite(depth_image)]), rtol=1e-6)
    from PIL import Image

    preview = np.asarray(Image.open(tmp_path / "capture_depth_preview.png"))
    assert preview.shape[1] > 4 * nx


def test_cli_takes_a_decoded_light_field_without_camera_options(scene, tmp_path):
    scene["decoded"].save(tmp_path / "lf.lfp.npz")
    proc = run_cli("depth", tmp_path / "lf.lfp.npz", "--no-ply", "-o", tmp_path / "out")
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "out" / "lf_depth.tif").is_file() and not (tmp_path / "out" / "lf_depth_points.ply").exists()
    assert "depth known at" in proc.stdout and " m (1st to 99th percentile)" in proc.stdout


def test_cli_bad_inputs_fail_cleanly_and_write_nothing(scene, tmp_path):
    folder = scene["folder"]
    out = tmp_path / "out"
    base = [folder / "capture.png", "--camera", folder / "camera.toml", "-o", out]
    assert_clean_error(run_cli("depth", *base, "--white", tmp_path / "missing.png"), "missing.png")
    assert_clean_error(run_cli("depth", *base, "--white", folder / "white.png", "--depth-range", "10:20"),
                       "depth range")
    assert_clean_error(run_cli("depth", *base, "--white", folder / "white.png", "--depth-range", "abc"),
                       "--depth-range")
    assert_clean_error(run_cli("depth", *base), "--white")
    assert_clean_error(run_cli("depth", *base, "--white", folder / "white.png", "--min-confidence", "2"),
                       "--min-confidence")
    assert_clean_error(run_cli("depth", folder / "capture.png", "--white", folder / "white.png", "-o", out),
                       "--camera")
    small = tmp_path / "small.png"
    write_image(small, np.zeros((64, 64), np.uint16))
    assert_clean_error(run_cli("depth", *base, "--white", small), "small.png")
    assert not out.exists()
    blocker = tmp_path / "blocker"
    blocker.write_text("a file")
    proc = run_cli("depth", folder / "capture.png", "--camera", folder / "camera.toml", "--white",
                   folder / "white.png", "-o", blocker)
    assert proc.returncode == 2 and "cannot write there" in proc.stderr and "Traceback" not in proc.stderr


def test_tilted_plane_from_ideal_views_meets_the_accuracy_targets():
    cam = Camera(0.009, 0.1, 0.4, MainLens(50.0, 50.0, f_number=4.0), cfa="RGGB", name="tilt")
    centre = float(geometry.slice_distance_mm(cam, 1.23))
    # 10 mm features: foreshortened by cos 60° they still span ~4 lenses (finer ones alias, docs/depth.md)
    plane = Plane(centre, Noise(feature_mm=10.0, seed=9, low=0.1, high=0.9), tilt_deg=(60.0, 0.0))
    sim = simulate.render(cam, Scene((plane,), background=0.05), (400, 560), shot_noise_photons=100000, seed=5)
    truth_mm = np.asarray(sim.depth_mm, dtype=np.float64)
    assert np.nanmax(truth_mm) - np.nanmin(truth_mm) > 0.12 * centre     # it really is tilted
    depth_map = lfproc.depth_map(LightField.from_views(sim.ideal_views, cam, sim.grid))
    truth_a = geometry.refocus_parameter(cam, np.nan_to_num(truth_mm, nan=1e9))
    finite = np.isfinite(truth_mm)
    mask = ndimage.binary_erosion(finite, iterations=3, border_value=0)
    median, badpix, inside = scores(depth_map, cam, np.where(finite, truth_a, 0.0), mask)
    assert median <= 0.05 and badpix <= 0.05 and inside >= 0.90, (median, badpix, inside)


def test_point_cloud_of_a_plane_is_flat_and_scaled_like_the_object():
    """Telecentric: a lens s mm off the axis sees the point s·(1 − z/f_U) off it (a plain similar-triangles
    check: the central view looks through the main lens's front focal point)."""
    from lfproc.depth._pointcloud import point_cloud

    cam = Camera(0.009, 0.1, 0.4, MainLens(50.0, 50.0, f_number=4.0), name="pc")
    distance = np.full((5, 7), 600.0)
    distance[0, 0] = np.nan
    points, rgb = point_cloud(cam, None, distance, np.ones((5, 7, 1), np.float32))
    assert points.shape == (34, 3) and rgb.shape == (34, 3)
    np.testing.assert_allclose(points[:, 2], 600.0)
    z_front = 600.0 - cam.main_optics.sensor_path_mm(cam.mla_path_mm) - cam.main_optics.focal_length_mm      # from the front focal point
    magnification = -z_front / cam.main_optics.focal_length_mm
    xs = np.unique(np.round(points[:, 0], 6))
    np.testing.assert_allclose(np.diff(xs), abs(magnification) * cam.mla_pitch_mm, rtol=1e-6)
    last = points[-1]              # lens (4, 6): 3 pitches right of and 2 below the centre lens, seen inverted
    assert last[0] == pytest.approx(3 * cam.mla_pitch_mm * magnification, rel=1e-6) and last[0] < 0
    assert last[1] == pytest.approx(2 * cam.mla_pitch_mm * magnification, rel=1e-6)


def test_lytro_sample_both_planes_found_at_their_distances(tmp_path):
    """samples/lytro: an Illum-like capture of two planes, 9280 mm (a = 1.25) and 45780 mm (a = 0.25) from
    the sensor (samples/lytro/README.md), decoded from the Lytro files with their calibration folder."""
    from conftest import SAMPLES

    lytro = SAMPLES / "lytro"
    proc = run_cli("depth", lytro / "IMG_0001.lfr", "--white-dir", lytro / "caldata", "-o", tmp_path)
    assert proc.returncode == 0, proc.stderr
    distance = read_float_tiff(tmp_path / "IMG_0001_depth.tif")[..., 0]
    known = distance[np.isfinite(distance)]
    assert known.size > 0.7 * distance.size
    for truth, share in ((9280.0, 0.3), (45780.0, 0.3)):
        near_it = known[np.abs(known / truth - 1.0) < 0.1]
        assert near_it.size > share * known.size, truth
        assert abs(np.median(near_it) / truth - 1.0) < 0.03, (truth, np.median(near_it))
    assert np.mean([(abs(d / 9280 - 1) < 0.1) or (abs(d / 45780 - 1) < 0.1) for d in known]) > 0.9
