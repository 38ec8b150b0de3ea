"""End to end on simulated captures with planes at known depths: refocusing, parallax, and the CLI contract."""

import json
import os
import shutil

import numpy as np
import pytest
from scipy import ndimage

from lfproc import Camera, LightField, geometry
from lfproc import simulate
from lfproc.io import read_metadata, write_image
from lfproc.api import DecodeSetup
from lfproc.io import read_capture
from lfproc.refocusing import refocus
from lfproc.simulate import Checkerboard, Noise, Plane, Scene
from lfproc.camera import MainLens

from conftest import assert_clean_error, run_cli

NEAR_A, FAR_A = 2.0, 0.8


@pytest.fixture(scope="module")
def capture(tmp_path_factory):
    """A mono 9 um / 100 um capture (11.1 px per lens) with a near card on a far textured wall."""
    cam = Camera(0.009, 0.1, 0.4, MainLens(50.0, 50.0, f_number=4.0), black_level=64, white_level=16383, name="e2e")
    d_near, d_far = geometry.slice_distance_mm(cam, [NEAR_A, FAR_A])
    scene = Scene((Plane(d_near, Checkerboard(period_mm=2.4, low=0.15, high=0.9), region_mm=(-30, 0, -40, 40)),
                   Plane(d_far, Noise(feature_mm=5.0, seed=5, low=0.1, high=0.9))), background=0.05)
    sim = simulate.render(cam, scene, (330, 440), rotation_deg=0.3, offset_px=(0.2, 0.4), pixel_samples=2,
                          aperture_samples=4, shot_noise_photons=200000, seed=11, ideal_views=False)
    folder = tmp_path_factory.mktemp("e2e")
    write_image(folder / "capture.png", sim.raw)
    write_image(folder / "white.png", sim.white)
    (folder / "camera.toml").write_text(cam.to_toml())
    lf = DecodeSetup(cam, sim.grid, read_capture(folder / "white.png", cam)).decode(folder / "capture.png")
    return dict(sim=sim, camera=cam, folder=folder, lf=lf, distances=(d_near, d_far))


def plane_region(sim, index, erode=3):
    """Lenses whose central view sees plane ``index``, away from occlusion edges and the border."""
    region = ndimage.binary_erosion(sim.plane_label == index, iterations=erode)
    region[:erode] = region[-erode:] = False
    region[:, :erode] = region[:, -erode:] = False
    assert region.sum() > 50
    return region


def sharpness(image, region):
    """Gradient energy inside the region (the focus measure)."""
    gy, gx = np.gradient(image[..., 0])
    return float(np.mean((gx ** 2 + gy ** 2)[region]))


def test_sharpest_slice_over_each_plane_is_tagged_with_its_distance(capture):
    sim, cam, lf = capture["sim"], capture["camera"], capture["lf"]
    a_values = np.round(np.arange(0.3, 3.01, 0.1), 10)
    stack = refocus(lf, a_values)
    geo = geometry.slice_geometry(cam, a_values)
    for index, distance in enumerate(capture["distances"]):
        region = plane_region(sim, index)
        scores = [sharpness(s, region) for s in stack]
        best = int(np.argmax(scores))
        assert geo.near_mm[best] <= distance <= geo.far_mm[best], (index, a_values[best], distance)
        # and the peak is a clear one: it sits at the plane's own a within the sweep's step
        assert abs(a_values[best] - (NEAR_A, FAR_A)[index]) <= 0.1 + 1e-9


def register(ref, mov, window, axis, span=4.0, step=0.01, other=0.0):
    """Sub-pixel shift s along ``axis`` minimising the squared difference of ref and mov moved by s
    (and by ``other`` along the other axis).

    A direct least-squares search (cubic-spline shifts) inside ``window``; phase correlation is
    biased by the edges of windows this small (a dozen lenses wide).
    """
    best = None
    for s in np.arange(-span, span + step / 2, step):
        moved = ndimage.shift(mov, [s if a == axis else other for a in (0, 1)], order=3, mode="nearest")
        err = float(np.mean((moved[window] - ref[window]) ** 2))
        if best is None or err < best[0]:
            best = (err, s)
    return best[1]


@pytest.mark.parametrize("gap", [1, 3])
def test_parallax_between_views_is_gap_times_a(capture, gap):
    sim, lf = capture["sim"], capture["lf"]
    c = lf.center_index
    region = plane_region(sim, 1, erode=2)  # the far wall: a = FAR_A lenses per view step
    # a rectangle that sees only the wall: the inner rows of the columns the wall fills entirely
    inner_rows = slice(3, region.shape[0] - 3)
    cols = np.nonzero(region[inner_rows].all(axis=0))[0]
    assert len(cols) >= 12
    window = (inner_rows, slice(cols.min(), cols.max() + 1))
    assert region[window].all()
    for axis in (0, 1):
        k0 = (c - 1, c) if axis == 0 else (c, c - 1)
        k1 = (k0[0] + gap, k0[1]) if axis == 0 else (k0[0], k0[1] + gap)
        ref, mov = lf.views[k0][..., 0], lf.views[k1][..., 0]
        # contract: view k at lens j shows what the central view shows at j - a (c - k), so view k + g
        # is view k moved by -g a lenses along the axis: moving it back by +g a registers them
        along = register(ref, mov, window, axis)
        assert along == pytest.approx(gap * FAR_A, abs=0.1)
        assert abs(register(ref, mov, window, 1 - axis, span=1.0, other=along)) < 0.1


def test_refocus_cli_tags_slices_and_embeds_metadata(capture, tmp_path):
    folder, cam = capture["folder"], capture["camera"]
    out = tmp_path / "out"
    proc = run_cli("refocus", folder / "capture.png", "--camera", folder / "camera.toml", "--white",
                   folder / "white.png", "--depth-range", "300:2000", "-o", out)
    assert proc.returncode == 0, proc.stderr
    # the slices are planned and tagged with the DOF of the views they sum (issue 20): the decoder's
    decoded = run_cli("decode", folder / "capture.png", "--camera", folder / "camera.toml", "--white",
                      folder / "white.png", "-o", tmp_path / "cap.lfp.npz")
    assert decoded.returncode == 0, decoded.stderr
    mask = LightField.load(tmp_path / "cap.lfp.npz").view_mask
    extent = None if mask is None else geometry.summed_view_extent(mask)
    a_planned = geometry.plan_slices(cam, 300.0, 2000.0, view_extent=extent)
    images = sorted(p for p in os.listdir(out) if p.endswith(".tif"))
    assert len(images) == len(a_planned)
    covered = []
    for name in images:
        side = json.loads((out / name.replace(".tif", ".json")).read_text())
        assert set(side) >= {"source", "a", "distance_mm", "near_mm", "far_mm", "dof_mm"}
        assert side["source"] == str((folder / "capture.png").resolve())
        expect = geometry.slice_geometry(cam, side["a"], extent)
        for key in ("distance_mm", "near_mm", "far_mm", "dof_mm"):
            assert side[key] == pytest.approx(getattr(expect, key), rel=1e-12)
        if mask is not None:
            assert side["views_summed"] == mask.sum()
            assert side["aperture_f_number"] == pytest.approx(geometry.equivalent_f_number(cam, extent))
        embedded = read_metadata(out / name)  # read back through OpenImageIO
        for key in ("a", "distance_mm", "near_mm", "far_mm", "dof_mm", "source"):
            assert embedded[key] == side[key]
        covered.append((side["near_mm"], side["far_mm"]))
    sides = [json.loads((out / n.replace(".tif", ".json")).read_text()) for n in images]
    assert sorted(side["a"] for side in sides) == pytest.approx(sorted(a_planned), rel=1e-12)
    covered.sort()
    assert covered[0][0] <= 300 and covered[-1][1] >= 2000
    assert all(lo_next <= hi for (_, hi), (lo_next, _) in zip(covered, covered[1:]))


def test_refocus_at_a_distance(capture, tmp_path):
    folder = capture["folder"]
    proc = run_cli("refocus", folder / "capture.png", "--camera", folder / "camera.toml", "--white",
                   folder / "white.png", "--at", "650", "--format", "png16", "-o", tmp_path)
    assert proc.returncode == 0, proc.stderr
    (side,) = [json.loads(p.read_text()) for p in tmp_path.glob("*.json")]
    assert side["distance_mm"] == pytest.approx(650.0, rel=1e-12)
    assert len(list(tmp_path.glob("*.png"))) == 1


def test_bad_capture_among_good_ones_is_skipped_and_named(capture, tmp_path):
    folder = capture["folder"]
    good = tmp_path / "good.png"
    shutil.copy(folder / "capture.png", good)
    bad = tmp_path / "bad.png"
    bad.write_bytes((folder / "capture.png").read_bytes()[:5000])  # truncated
    out = tmp_path / "out"
    proc = run_cli("refocus", bad, good, "--camera", folder / "camera.toml", "--white", folder / "white.png",
                   "--a", "0,1", "-o", out)
    assert proc.returncode == 2
    assert "bad.png" in proc.stderr and "Traceback" not in proc.stderr
    assert sorted(p.name for p in out.iterdir()) == ["good_00_a+0.000.json", "good_00_a+0.000.tif",
                                                     "good_01_a+1.000.json", "good_01_a+1.000.tif"]


def test_refocus_bad_inputs_fail_cleanly_and_write_nothing(capture, tmp_path):
    folder = capture["folder"]
    out = tmp_path / "out"
    base = [folder / "capture.png", "--camera", folder / "camera.toml", "-o", out]
    assert_clean_error(run_cli("refocus", *base, "--white", tmp_path / "missing.png", "--a", "1"), "missing.png")
    assert_clean_error(run_cli("refocus", *base, "--white", folder / "white.png", "--depth-range", "10:20"),
                       "--depth-range 10:20", "front focal plane", "usable")
    assert_clean_error(run_cli("refocus", *base, "--white", folder / "white.png", "--at", "20"), "20")
    assert_clean_error(run_cli("refocus", *base, "--a", "1"), "--white")
    small = tmp_path / "small.png"
    write_image(small, np.zeros((64, 64), np.uint16))
    # in a fresh interpreter (python -m lfproc): the exit status and the one line after the first heavy imports
    assert_clean_error(run_cli("refocus", folder / "capture.png", "--camera", folder / "camera.toml",
                               "--white", small, "--a", "1", "-o", out, subprocess=True), "small.png")
    assert not out.exists()


def test_views_cli_writes_tagged_views(capture, tmp_path):
    folder, cam = capture["folder"], capture["camera"]
    proc = run_cli("views", folder / "capture.png", "--camera", folder / "camera.toml", "--white",
                   folder / "white.png", "-o", tmp_path, "--mosaic", "--gif", "--inside-aperture")
    assert proc.returncode == 0, proc.stderr
    keep = geometry.views_inside_aperture(cam)
    views = sorted(tmp_path.glob("capture_view_*.tif"))
    # the views that carry light and lie inside the aperture: every one inside it within two rings of the centre
    written = {tuple(json.loads(p.with_suffix(".json").read_text())["view"]) for p in views}
    c = cam.center_index
    near_centre = {(ky, kx) for ky, kx in np.argwhere(keep) if max(abs(ky - c), abs(kx - c)) <= 2}
    assert near_centre <= written and all(keep[k] for k in written) and len(written) < cam.m_hat ** 2
    positions = geometry.view_positions_mm(cam)
    tilts = geometry.view_tilts_deg(cam)
    for path in views:
        side = json.loads(path.with_suffix(".json").read_text())
        ky, kx = side["view"]
        assert keep[ky, kx]
        assert side["position_mm"] == pytest.approx([positions[ky], positions[kx]], rel=1e-12)
        assert side["tilt_deg"] == pytest.approx([tilts[ky], tilts[kx]], abs=1e-12)
        assert read_metadata(path)["view"] == [ky, kx]
    assert (tmp_path / "capture_views_mosaic.tif").exists()
    assert (tmp_path / "capture_views.gif").read_bytes()[:6] in (b"GIF89a", b"GIF87a")


def test_decode_cli_round_trip(capture, tmp_path):
    from lfproc import LightField

    folder = capture["folder"]
    grid_path = tmp_path / "grid.json"
    proc = run_cli("calibrate", folder / "white.png", "--camera", folder / "camera.toml", "-o", grid_path)
    assert proc.returncode == 0, proc.stderr
    grid = json.loads(grid_path.read_text())
    assert set(grid) >= {"grid", "pitch_px", "rotation_deg", "residual_rms_px", "centers_xy_px"}
    assert grid["rotation_deg"] == pytest.approx(0.3, abs=0.01)
    out = tmp_path / "lf.lfp.npz"
    proc = run_cli("decode", folder / "capture.png", "--camera", folder / "camera.toml", "--calib", grid_path,
                   "-o", out)
    assert proc.returncode == 0, proc.stderr
    lf = LightField.load(out)
    assert lf.views.shape[:2] == (11, 11) and lf.camera.name == "e2e"
    # calibrated vs true grid, over the views inside the aperture (outside it, samples at the white
    # image's dark threshold flip between 0 and signal with a 0.01 px change of the grid)
    keep = geometry.views_inside_aperture(lf.camera)
    diff = lf.views[keep] - capture["lf"].views[keep]
    psnr = 10 * np.log10(capture["lf"].views[keep].max() ** 2 / np.mean(diff ** 2))
    assert psnr > 45.0
    # sample by sample, over the views read at their nominal position: the outer views read past it
    # (lfproc.decode._view_mask) sample the rim pixels, which change lens at the cell boundary with the
    # grid's 0.01 px (measured: up to 0.28 on a few samples of the four outermost views on the axes)
    from lfproc.decode import make_decoder
    white = read_capture(capture["folder"] / "white.png", capture["camera"]).data
    nominal = make_decoder(white, capture["sim"].grid, 11).view_shift_px
    nominal = keep & (np.hypot(nominal[..., 0], nominal[..., 1]) == 0)
    assert np.abs(lf.views[nominal] - capture["lf"].views[nominal]).max() < 0.05


def test_rgb_capture_without_white_image_decodes_with_a_warning(capture, tmp_path):
    """--calib whose recorded white image is gone: an RGB capture decodes (flat white), with a warning."""
    import warnings

    from lfproc.api import prepare_decoding

    cam = capture["camera"]
    grid_json = dict(capture["sim"].grid.to_json_dict(), white_image=str(tmp_path / "gone.png"))
    (tmp_path / "grid.json").write_text(json.dumps(grid_json))
    rgb = np.repeat(capture["sim"].raw[:, :, None], 3, axis=2)
    write_image(tmp_path / "rgb.tif", rgb)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        setup = prepare_decoding(cam, grid=str(tmp_path / "grid.json"), cache=True)
    assert any("devignetting" in str(w.message) for w in caught)
    lf = setup.decode(str(tmp_path / "rgb.tif"))
    assert lf.views.shape[-1] == 3 and np.all(np.isfinite(lf.views))


@pytest.mark.parametrize("command", ["refocus", "views"])
def test_output_folder_that_is_a_file_is_a_clean_error(capture, tmp_path, command):
    folder = capture["folder"]
    blocker = tmp_path / "blocker"
    blocker.write_text("a file")
    extra = ["--a", "1"] if command == "refocus" else []
    proc = run_cli(command, folder / "capture.png", "--camera", folder / "camera.toml", "--white",
                   folder / "white.png", "-o", blocker, *extra)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert "cannot write there" in proc.stderr


def test_slice_names_stay_apart():
    from lfproc import LfprocError
    from lfproc.outputs import slice_names

    assert slice_names("c", [1.0, -0.0, 0.5]) == ["c_02_a+1.000", "c_00_a+0.000", "c_01_a+0.500"]
    assert slice_names("c", [1.0001, 1.0002]) == ["c_00_a+1.0001", "c_01_a+1.0002"]
    with pytest.raises(LfprocError, match="equal"):
        slice_names("c", [2.0, 2.0])
