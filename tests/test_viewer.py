"""lfproc viewer without a browser: the page's files and data, depth from focus on a rendered scene, the
local server, several captures; and the previews for people (tone mapping, enlarging, labels, mosaics)."""

import json
from pathlib import Path
import re
import shutil
import subprocess
import sys
import urllib.request

import numpy as np
import pytest
from PIL import Image

from lfproc import geometry
from lfproc.io import read_image, srgb_encode
from lfproc.outputs import (ToneMap, metres, slice_label, upscale, upscale_factor, write_mosaic_preview,
                            write_slice_gif)

from conftest import ROOT, assert_clean_error, run_cli
from viewer_scene import camera as scene_camera, inner_lenses, render_capture


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    return render_capture(tmp_path_factory.mktemp("scene"))


@pytest.fixture(scope="module")
def page(scene, tmp_path_factory):
    folder = scene["folder"]
    out = tmp_path_factory.mktemp("page") / "viewer"
    proc = run_cli("viewer", folder / "capture.png", "--camera", folder / "camera.toml", "--calib",
                   folder / "grid.json", "-o", out)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip().splitlines()[-1] == f"viewer: {out / 'index.html'}"
    return out


# ------------------------------------------------------------------ previews
def test_tone_map_is_a_percentile_stretch_then_srgb():
    rng = np.random.default_rng(1)
    images = rng.gamma(2.0, 0.1, (3, 40, 50, 3)).astype(np.float32)
    tone = ToneMap.for_images(images)
    assert tone.black == pytest.approx(np.percentile(images, 0.5))
    assert tone.white == pytest.approx(np.percentile(images, 99.5))
    expected = np.round(srgb_encode((images - tone.black) / (tone.white - tone.black)) * 255)
    assert np.abs(tone(images).astype(int) - expected).max() <= 1
    assert tone(images).min() == 0 and tone(images).max() == 255  # the whole display range: not washed out


def test_previews_are_resampled_not_blocks():
    """Issue 32: previews were one lens per nearest-neighbour block. The default (Lanczos) follows a smooth
    scene between the lenses: each display pixel within 1.5 DN of the scene at that place (pixel centres
    kept: display pixel x is at lens (x + 0.5)/7 - 0.5), where blocks are off by 22 DN; no block is flat."""
    def scene(y, x):
        return 128 + 100 * np.sin(2 * np.pi * x / 15) * np.cos(2 * np.pi * y / 12)

    y, x = np.mgrid[0:53, 0:75].astype(float)
    image = np.round(scene(y, x)).astype(np.uint8)
    for shape in ((53, 75), (53, 75, 1), (53, 75, 3)):
        lenses = image if len(shape) == 2 else np.repeat(image[:, :, None], shape[2], axis=2)
        big = upscale(lenses, 7)
        assert big.shape == (371, 525) + shape[2:] and big.dtype == np.uint8
    big = upscale(image, 7).astype(float)
    yy, xx = np.mgrid[0:371, 0:525]
    truth = scene((yy + 0.5) / 7 - 0.5, (xx + 0.5) / 7 - 0.5)
    inner = (slice(28, -28), slice(28, -28))                    # 4 lenses from the border (the kernel's reach)
    assert np.abs(big - truth)[inner].max() < 1.5
    assert np.abs(upscale(image, 7, "nearest") - truth)[inner].max() > 20
    blocks = big[:364, :525].reshape(52, 7, 75, 7).transpose(0, 2, 1, 3).reshape(52, 75, 49)
    assert (np.ptp(blocks, axis=2) > 0).mean() > 0.95           # not piecewise constant


def test_upscaling_reaches_the_display_size_and_nearest_keeps_blocks():
    image = np.arange(53 * 75 * 3, dtype=np.uint8).reshape(53, 75, 3)
    factor = upscale_factor(image.shape)
    assert factor == 7 and 75 * 6 < 512 <= 75 * 7
    big = upscale(image, factor, "nearest")
    assert big.shape == (371, 525, 3)
    np.testing.assert_array_equal(big[::7, ::7], image)
    np.testing.assert_array_equal(big[6::7, 6::7], image)
    assert upscale(image, factor, "smooth").shape == big.shape
    assert upscale_factor((434, 625)) == 1


def test_slice_label_gives_distance_and_dof_in_metres():
    cam = scene_camera()
    rec = geometry.slice_geometry(cam, 1.3).records()[0]
    text = slice_label(rec["distance_mm"], rec["near_mm"], rec["far_mm"])
    assert text == (f"focus {rec['distance_mm'] / 1000:.3f} m | DOF {rec['near_mm'] / 1000:.3f} m to "
                    f"{rec['far_mm'] / 1000:.3f} m")
    assert metres(1236.4) == "1.24 m" and metres(float("inf")) == "inf" and metres(658.99) == "0.659 m"


def test_refocus_gif_is_enlarged_labelled_and_uses_the_display_range(tmp_path):
    cam = scene_camera()
    ramp = np.linspace(0.2, 0.3, 37, dtype=np.float32)  # a dim, low-contrast stack of grey ramps
    stack = np.broadcast_to(ramp[None, None, :, None], (3, 25, 37, 3)) * np.float32([1.0, 0.98, 0.96])[:, None, None,
                                                                                                     None]
    path = write_slice_gif(str(tmp_path), "s", stack, cam, [0.4, 0.8, 1.3])
    with Image.open(path) as gif:
        assert gif.n_frames == 4  # there and back
        width, height = gif.size
        assert max(width, height) >= 512 and width == 37 * 14
        frames = []
        for k in range(3):
            gif.seek(k)
            frames.append(np.asarray(gif.convert("RGB")))
    pictures = np.stack([frame[:25 * 14] for frame in frames])
    for frame in frames:
        band = frame[25 * 14:]
        assert band.shape[0] >= 12 and (band > 200).any() and (band < 30).mean() > 0.5  # white text on black
    assert pictures.min() <= 5 and pictures.max() >= 250  # one exposure for all frames, the whole range
    assert not np.array_equal(frames[0][25 * 14:], frames[1][25 * 14:])  # each frame has its own label


def test_views_inside_aperture_mosaic_blacks_out_the_others(scene, tmp_path):
    folder, cam = scene["folder"], scene["camera"]
    base = [folder / "capture.png", "--camera", folder / "camera.toml", "--calib", folder / "grid.json", "--mosaic"]
    assert run_cli("views", *base, "-o", tmp_path / "all").returncode == 0
    proc = run_cli("views", *base, "--inside-aperture", "-o", tmp_path / "inside")
    assert proc.returncode == 0, proc.stderr
    m = cam.m_hat
    lit = np.array([[(tmp_path / "all" / f"capture_view_{ky:02d}_{kx:02d}.tif").is_file() for kx in range(m)]
                    for ky in range(m)])               # views without light are not written at all
    keep = geometry.views_inside_aperture(cam) & lit
    assert not keep.all()
    view_shape = read_image(next((tmp_path / "all").glob("capture_view_*.tif"))).shape[:2]

    def blocks(folder):
        """The mosaic's blocks by view index (ky, kx), from the offset its sidecar gives (lit views only)."""
        tiled = read_image(folder / "capture_views_mosaic.tif")
        side = json.loads((folder / "capture_views_mosaic.json").read_text())
        (ky0, kx0), (ny, nx) = side["first_view"], view_shape
        return side, {(ky0 + by, kx0 + bx): tiled[by * ny:(by + 1) * ny, bx * nx:(bx + 1) * nx]
                      for by in range(tiled.shape[0] // ny) for bx in range(tiled.shape[1] // nx)}

    side_in, inside = blocks(tmp_path / "inside")
    _, full = blocks(tmp_path / "all")
    for (ky, kx), block in inside.items():
        if keep[ky, kx]:
            view = read_image(tmp_path / "inside" / f"capture_view_{ky:02d}_{kx:02d}.tif")
            np.testing.assert_array_equal(block, view.reshape(block.shape))
            np.testing.assert_array_equal(block, full[ky, kx])
        else:
            assert not block.any(), (ky, kx)
            assert not (tmp_path / "inside" / f"capture_view_{ky:02d}_{kx:02d}.tif").exists()
    assert {tuple(k) for k in np.argwhere(keep)} <= set(inside)
    assert len(side_in["views"]) == keep.sum()


def test_mosaic_writer_blacks_out_views_the_mask_leaves_out(tmp_path):
    """Independent of what the decoder leaves in views outside the aperture: the mosaic shows them black."""
    from lfproc.outputs import write_view_mosaic

    cam = scene_camera()
    m = cam.m_hat
    views = np.full((m, m, 4, 6, 1), 0.5, np.float32)
    keep = geometry.views_inside_aperture(cam)
    write_view_mosaic(str(tmp_path), "all", "src", cam, views, "tiff")
    write_view_mosaic(str(tmp_path), "inside", "src", cam, views, "tiff", keep)
    full = read_image(tmp_path / "all_views_mosaic.tif")[..., 0].reshape(m, 4, m, 6)
    assert np.all(full == 0.5)
    rows, cols = np.flatnonzero(keep.any(1)), np.flatnonzero(keep.any(0))   # cropped to the views shown
    inside = read_image(tmp_path / "inside_views_mosaic.tif")[..., 0].reshape(len(rows), 4, len(cols), 6)
    shown = keep[rows[0]:rows[-1] + 1, cols[0]:cols[-1] + 1]
    np.testing.assert_array_equal(inside.max(axis=(1, 3)), np.where(shown, 0.5, 0.0))


def test_mosaic_preview_is_enlarged_8bit_with_black_views_outside(scene, tmp_path):
    m = 5
    views = np.full((m, m, 20, 30, 3), 0.5, np.float32)
    keep = np.ones((m, m), bool)
    keep[0, 0] = False
    path = write_mosaic_preview(str(tmp_path), "p", views, keep)
    with Image.open(path) as image:
        pixels = np.asarray(image)
    assert max(pixels.shape[:2]) >= 512 and pixels.dtype == np.uint8
    factor = upscale_factor((m * 21 - 1, m * 31 - 1))
    assert not pixels[: 20 * factor, : 30 * factor].any() and pixels[: 20 * factor, 31 * factor: 61 * factor].min() > 0


# ------------------------------------------------------------------ depth from focus and slice choice
def test_page_depth_finds_each_plane_and_its_slice(scene):
    """The per-lens depth the page uses (lfproc.depth through estimate_depth) and the slice a click shows."""
    from lfproc.api import prepare_decoding
    from lfproc.viewer import estimate_depth, scene_slices, sharpest_slice
    from lfproc.viewer._plan import slice_intervals_a

    folder, cam = scene["folder"], scene["camera"]
    lf = prepare_decoding(cam, grid=str(folder / "grid.json"), cache=True).decode(str(folder / "capture.png"))
    focus = estimate_depth(lf)
    a_values = scene_slices(cam, focus)
    geo = geometry.slice_geometry(cam, a_values)
    index = sharpest_slice(cam, a_values, focus.a)
    intervals = slice_intervals_a(cam, a_values)
    for plane, truth in enumerate(scene["distances"]):
        region = inner_lenses(scene["label"], plane)
        chosen = index[region]
        # what the page shows on a click: the lens's distance, within the chosen slice's DOF of the truth
        assert (np.abs(focus.distance_mm[region] - truth) <= geo.dof_mm[chosen]).mean() >= 0.95, plane
        # the estimate is accurate to a small part of a slice's DOF (its width in a, Eq. 31 inverted)
        true_a = geometry.refocus_parameter(cam, truth)
        k_true = int(np.argmin(np.maximum(intervals[:, 0] - true_a, true_a - intervals[:, 1])))
        assert intervals[k_true, 0] <= true_a <= intervals[k_true, 1]
        width = intervals[k_true, 1] - intervals[k_true, 0]
        assert abs(np.median(focus.a[region]) - true_a) <= 0.15 * width, (plane, np.median(focus.a[region]))
        # the slice shown is the one sharp at the truth, or (where the truth sits near the border of two
        # slices' DOFs and the estimate is a hair off) its neighbour
        assert (np.abs(chosen.astype(int) - k_true) <= 1).mean() >= 0.95
        assert (chosen == k_true).mean() >= 0.5, (plane, (chosen == k_true).mean())
        estimate = float(np.median(focus.distance_mm[region]))
        k = int(np.bincount(chosen).argmax())
        assert abs(estimate - truth) <= 0.5 * geo.dof_mm[k], (plane, estimate, truth)
        assert np.median(focus.confidence[region]) > 0.5


# ------------------------------------------------------------------ the page
def test_page_is_self_contained_and_its_data_is_the_geometry(page, scene):
    html = (page / "index.html").read_text()
    links = re.findall(r'(?:src|href)="([^"]*)"', html)
    assert all(not re.match(r"[a-z]+:", link) for link in links), links  # only relative links ...
    assert "fetch(" not in html and "XMLHttpRequest" not in html and "<link" not in html  # ... and nothing loaded
    data = json.loads((page / "geometry.json").read_text())
    cam = scene["camera"]
    summed = np.zeros((cam.m_hat, cam.m_hat), bool)   # the DOF of the views the slices average (issue 20)
    summed[tuple(np.transpose(data["apertures"][0]["summed_views"]))] = True
    expected = geometry.slice_geometry(cam, [s["a"] for s in data["slices"]],
                                       geometry.summed_view_extent(summed)).records()
    for got, want in zip(data["slices"], expected):
        for key in ("a", "distance_mm", "near_mm", "far_mm", "dof_mm"):
            assert got[key] == pytest.approx(want[key], rel=1e-12) or (got[key] is None and want[key] == np.inf)
        with Image.open(page / got["image"]) as image:
            assert image.mode in ("L", "RGB") and image.size == (data["lens_shape"][1], data["lens_shape"][0])
    keep = geometry.views_inside_aperture(cam)   # and, where the decoder marks views without light, those
    shown = {tuple(v["view"]) for v in data["views"]["items"]}
    assert shown <= set(map(tuple, np.argwhere(keep).tolist())) and len(shown) >= 0.7 * keep.sum()
    for item in data["views"]["items"]:
        with Image.open(page / item["image"]) as image:
            assert np.asarray(image).max() > 0, item["view"]   # every view offered carries light
    assert all((page / v["image"]).is_file() for v in data["views"]["items"])
    assert data["views"]["baseline_mm"] == pytest.approx(geometry.baseline_mm(cam, 1))
    assert (page / "depth.png").is_file() and data["display"]["scale"] * max(data["lens_shape"]) >= 512
    embedded = json.loads(re.search(r'<script type="application/json" id="lfproc-data">(.*?)</script>', html,
                                    re.S).group(1))
    assert embedded == data


def test_several_captures_get_a_page_each_and_an_index(scene, tmp_path):
    folder = scene["folder"]
    other = render_capture(tmp_path / "other", seed=9, flip=True)["folder"]
    shutil.copy(folder / "capture.png", tmp_path / "left.png")
    shutil.copy(other / "capture.png", tmp_path / "right.png")
    out = tmp_path / "out"
    proc = run_cli("viewer", tmp_path / "left.png", tmp_path / "right.png", "--camera", folder / "camera.toml",
                   "--calib", folder / "grid.json", "-o", out, "--depth-range", "400:2000")
    assert proc.returncode == 0, proc.stderr
    index = (out / "index.html").read_text()
    for stem in ("left", "right"):
        assert f'href="{stem}/index.html"' in index
        page_html = (out / stem / "index.html").read_text()
        assert '"index_href":"../index.html"' in page_html
        data = json.loads((out / stem / "geometry.json").read_text())
        cam = scene["camera"]
        summed = np.zeros((cam.m_hat, cam.m_hat), bool)   # planned with the DOF of the views summed (issue 20)
        summed[tuple(np.transpose(data["apertures"][0]["summed_views"]))] = True
        planned = geometry.plan_slices(cam, 400.0, 2000.0, view_extent=geometry.summed_view_extent(summed))
        np.testing.assert_allclose([s["a"] for s in data["slices"]], planned, rtol=1e-12)


def test_serve_binds_localhost_and_serves_the_page(scene, tmp_path):
    folder = scene["folder"]
    cmd = [sys.executable, "-m", "lfproc", "viewer", str(folder / "capture.png"), "--camera",
           str(folder / "camera.toml"), "--calib", str(folder / "grid.json"), "-o", str(tmp_path), "--a", "0.4,1.3",
           "--serve", "--port", "0"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    try:
        line = ""
        while not line.startswith("serving"):
            line = proc.stdout.readline()
            assert line, "the viewer exited before serving"
        url = re.search(r"(http://\S+/)", line).group(1)
        assert url.startswith("http://127.0.0.1:")
        with urllib.request.urlopen(url + "index.html", timeout=10) as response:
            assert response.read() == (tmp_path / "index.html").read_bytes()
    finally:
        proc.terminate()
        proc.wait(timeout=10)


def test_bad_viewer_options_are_one_line_errors(scene, tmp_path):
    folder = scene["folder"]
    base = [folder / "capture.png", "--camera", folder / "camera.toml", "--calib", folder / "grid.json"]
    assert_clean_error(run_cli("viewer", *base, "-o", tmp_path / "a", "--display-size", "4"), "--display-size")
    assert_clean_error(run_cli("viewer", *base, "-o", tmp_path / "b", "--serve", "--port", "70000"), "--port")
    assert_clean_error(run_cli("viewer", *base, "-o", tmp_path / "c", "--max-gap", "5"), "--depth-range")
    assert not any(tmp_path.iterdir())


def test_demo_writes_the_viewer_and_enlarged_labelled_previews(tmp_path):
    proc = run_cli("demo", "-o", tmp_path / "demo")
    assert proc.returncode == 0, proc.stderr
    match = re.search(r"^viewer: (.+index\.html)", proc.stdout, re.M)
    assert match and (tmp_path / "demo" / "viewer" / "index.html").samefile(match.group(1))
    with Image.open(tmp_path / "demo" / "sample_refocus.gif") as gif:
        assert max(gif.size) >= 512
    assert (ROOT / "samples" / "sample" / "capture.png").is_file()


def test_default_sweep_starts_at_infinity_and_stays_where_views_overlap():
    import dataclasses

    from lfproc.viewer._estimate import sweep_range

    cam = scene_camera()                                   # focused at infinity: a_inf = 0, c = 5
    assert sweep_range(cam, (200, 300)) == (0.0, 3.0)
    assert sweep_range(cam, (27, 37)) == (0.0, pytest.approx(27 / 15))   # outer views shift <= 9 of 27 lenses
    near_focus = cam.with_optics(dataclasses.replace(cam.main_optics, image_distance_mm=51.0))        # a_inf = -delta (b_U - f_U) / p_m
    a_inf = geometry.infinity_parameter(near_focus)
    assert a_inf == pytest.approx(-(0.1 / 11 / 0.4) * 1.0 / 0.1)
    assert sweep_range(near_focus, (200, 300)) == (pytest.approx(a_inf), pytest.approx(a_inf + 3.0))
    assert sweep_range(near_focus, (9, 9)) == (pytest.approx(a_inf), pytest.approx(0.6))  # 9 / (3 c)
    far_focus = cam.with_optics(dataclasses.replace(cam.main_optics, image_distance_mm=60.0))          # a_inf = -2.27, beyond the reach
    assert sweep_range(far_focus, (9, 9)) == (pytest.approx(-0.6), pytest.approx(0.6))


def test_server_binds_the_loopback_interface_only(tmp_path):
    from lfproc import LfprocError
    from lfproc.viewer import make_server

    server = make_server(str(tmp_path), 0)
    try:
        host, port = server.server_address[:2]
        assert host == "127.0.0.1" and port > 0
        with pytest.raises(LfprocError, match="another port="):
            make_server(str(tmp_path), port)   # taken: a one-line error naming the fix
    finally:
        server.server_close()


def test_viewpoint_marker_moves_the_way_the_perspective_does(page, scene):
    """Issue 20: the aperture diagram draws each view at its virtual camera (position_mm) as the pictures
    show it. In the page's own view images the near card moves against the far wall when the view index
    kx grows; a camera that moves right sees near things move left, so the marker must move opposite to
    the card's shift (it moved with it when drawn at position_mm)."""
    data = json.loads((page / "geometry.json").read_text())
    items = {tuple(v["view"]): v for v in data["views"]["items"]}
    c = data["views"]["center"]
    label = scene["label"]
    card, wall = inner_lenses(label, 0), inner_lenses(label, 1)

    def shift_x(image0, image1, region):
        """Sub-lens shift along x of ``image1`` against ``image0`` over ``region`` (least squares)."""
        gx = np.gradient(image0, axis=1)
        return -float((gx * (image1 - image0))[region].sum() / (gx * gx)[region].sum())

    def grey(view):
        with Image.open(page / items[view]["image"]) as image:
            return np.asarray(image.convert("L"), dtype=np.float64)

    centre, right = grey((c, c)), grey((c, c + 1))
    parallax = shift_x(centre, right, card) - shift_x(centre, right, wall)   # the card against the wall
    assert abs(parallax) > 0.3   # about 0.9 lens per view step (a = 1.3 against 0.4)
    marker_step = items[(c, c + 1)]["marker_mm"][1] - items[(c, c)]["marker_mm"][1]
    assert np.sign(marker_step) == -np.sign(parallax)
    for v in items.values():   # the marker is the virtual camera, turned by 180 degrees with the picture
        assert v["marker_mm"] == [-v["position_mm"][0] + 0.0, -v["position_mm"][1] + 0.0]


def test_page_offers_synthetic_apertures_with_their_dof(page, scene):
    """Issue 20: the viewer's aperture control: the same slices through fewer views, each with the DOF
    those views give (deeper as the aperture closes), in metres on the page."""
    data = json.loads((page / "geometry.json").read_text())
    cam = scene["camera"]
    apertures = data["apertures"]
    assert [ap["f_number"] for ap in apertures] == [None, 8.0, 16.0]   # f/32 would leave the central view alone
    previous = None
    for ap in apertures:
        summed = np.zeros((cam.m_hat, cam.m_hat), bool)
        summed[tuple(np.transpose(ap["summed_views"]))] = True
        if ap["f_number"] is not None:
            assert not (summed & ~geometry.aperture_views(cam, ap["f_number"])).any()
        assert ap["views_summed"] == summed.sum()
        extent = geometry.summed_view_extent(summed)
        assert ap["aperture_f_number"] == pytest.approx(geometry.equivalent_f_number(cam, extent))
        want = geometry.slice_geometry(cam, [s["a"] for s in ap["slices"]], extent)
        far = [np.inf if s["far_mm"] is None else s["far_mm"] for s in ap["slices"]]
        assert np.allclose(far, want.far_mm, rtol=1e-12)
        for s in ap["slices"]:
            assert (page / s["image"]).is_file()
        if previous is not None:   # narrower: never a shallower DOF
            assert all(n <= p for n, p in zip([s["near_mm"] for s in ap["slices"]], previous))
        previous = [s["near_mm"] for s in ap["slices"]]
    js = (ROOT / "lfproc" / "viewer" / "assets" / "viewer.js").read_text()
    assert "aperture-select" in js and "marker_mm" in js


def test_depth_preview_is_resampled_and_unknown_stays_unknown():
    """Issue 32: the depth preview is resampled (Lanczos) like the other previews, but an unknown lens is
    never smeared: exactly the display pixels nearest an unknown lens are grey, and known colours next to
    them are those of the known lenses (a constant depth stays one colour up to the unknown block)."""
    from lfproc.depth._preview import TARGET_SIZE_PX, colour_map, preview_image
    from lfproc.outputs import UNKNOWN_COLOUR

    ny, nx = 30, 40
    scale = round(TARGET_SIZE_PX / nx)
    distance = np.full((ny, nx), 1000.0)
    distance[:, 20:] = np.linspace(600.0, 3000.0, 20)[None, :]     # a smooth ramp on the right
    distance[10:16, 5:12] = np.nan                                 # unknown inside the constant part
    distance[3:6, 30:33] = np.nan                                  # and inside the ramp
    body = preview_image(distance)[10:10 + ny * scale, :nx * scale]
    grey = np.all(body == np.array(UNKNOWN_COLOUR, np.uint8), axis=2)
    unknown = np.repeat(np.repeat(np.isnan(distance), scale, axis=0), scale, axis=1)
    np.testing.assert_array_equal(grey, unknown)
    constant = body[:, : 15 * scale][~unknown[:, : 15 * scale]]     # 5 lenses from the ramp: past the kernel
    reference = body[0, 0]
    assert np.all(constant == reference)                           # no grey bled into the known colours
    ramp = body[20 * scale:25 * scale, 22 * scale:38 * scale].astype(int)
    assert (np.ptp(ramp[:scale].reshape(scale, -1, scale, 3), axis=(0, 2)) > 0).any(axis=1).mean() > 0.9


def test_depth_preview_and_viewer_share_one_colour_scale():
    """Issue 20: the depth preview (lfproc depth) used its own red-to-blue ramp; the viewer viridis."""
    from lfproc.depth._preview import preview_image
    from lfproc.outputs import DEPTH_COLOURS, UNKNOWN_COLOUR

    distance = np.full((40, 40), np.nan)
    distance[:, :20] = np.linspace(500.0, 2000.0, 20)[None, :]   # near to far along x
    distance[:, 20:30] = 500.0
    distance[:, 30:39] = 2000.0
    rgb = preview_image(distance)
    body = rgb[10:10 + 40 * 12:12, 0:40 * 12:12]   # one pixel per lens (scale 12, 10 px margin on top)
    assert tuple(body[5, 25]) == tuple(DEPTH_COLOURS[-1])    # nearest: the last (yellow) colour
    assert tuple(body[5, 35]) == tuple(DEPTH_COLOURS[0])     # farthest: the first (dark purple)
    assert tuple(body[5, 39]) == UNKNOWN_COLOUR


# ------------------------------------------------------------------ one path: the page is the Python API's (issue 31)
SLICE_TAGS = {"a", "distance_mm", "near_mm", "far_mm", "dof_mm", "z_um", "z_near_um", "z_far_um", "dof_um"}


def _tag_equal(got, want) -> bool:
    """A page number (JSON: null for infinity) against the API's (``inf``), to 1e-9."""
    if got is None:
        return want == np.inf
    return got == pytest.approx(want, rel=1e-9, abs=1e-12)


def _pixels(path, shape):
    with Image.open(path) as image:
        return np.asarray(image).reshape(shape)


def assert_page_is_the_api(page_dir, lf):
    """Every slice of every aperture of the page is lfproc.focal_stack's (tags to 1e-9, pixels those of the
    API's float32 slices through the page's tone map), every view lfproc.view_stack's (the lit views inside
    the aperture, their tags and pixels)."""
    import lfproc

    data = json.loads((page_dir / "geometry.json").read_text())
    tone = ToneMap(data["display"]["tone_map"]["black"], data["display"]["tone_map"]["white"])
    a_values = [s["a"] for s in data["slices"]]
    for aperture in data["apertures"]:
        fs = lfproc.focal_stack(lf, a=a_values, aperture=aperture["f_number"])   # the commands' defaults
        assert aperture["views_summed"] == fs.views_summed
        assert aperture["aperture_f_number"] == (None if fs.aperture_f_number is None else
                                                 pytest.approx(fs.aperture_f_number, rel=1e-9))
        assert len(aperture["slices"]) == len(fs) == len(a_values)
        for k, (got, want) in enumerate(zip(aperture["slices"], fs.records())):
            tags = SLICE_TAGS & set(want)
            assert set(got) == tags | {"image"}, (set(got), tags)
            assert all(_tag_equal(got[key], want[key]) for key in tags), (got, want)
            expected = tone(fs.images[k])
            assert np.array_equal(_pixels(page_dir / got["image"], expected.shape), expected), got["image"]
    vs = lfproc.view_stack(lf, inside_aperture=True)
    items = data["views"]["items"]
    assert [item["view"] for item in items] == vs.view.tolist() and len(items) > 0
    for k, (item, record) in enumerate(zip(items, vs.records())):
        for key, value in record.items():
            if key not in ("source", "provenance"):
                assert np.allclose(item[key], value, rtol=1e-9, atol=1e-12), (key, item[key], value)
        expected = tone(vs.images[k])
        assert np.array_equal(_pixels(page_dir / item["image"], expected.shape), expected), item["image"]


def test_page_slices_and_views_are_the_python_apis(page, scene):
    """A camera's page (three synthetic apertures, a decoded view mask): one path with lfproc refocus/views."""
    import lfproc

    folder = scene["folder"]
    lf = lfproc.read_light_field(str(folder / "capture.png"), str(folder / "camera.toml"),
                                 grid=str(folder / "grid.json"))
    data = json.loads((page / "geometry.json").read_text())
    assert len(data["apertures"]) >= 2 and len(data["slices"]) >= 2
    assert_page_is_the_api(page, lf)


def test_microscope_page_slices_and_views_are_the_python_apis(tmp_path):
    """A tiny microscope render refocused with the sine condition's per-view shifts: the page's µm tags,
    slices and views are lfproc.focal_stack's and lfproc.view_stack's."""
    import lfproc
    from scopefile import write_tiny_lfm

    folder = write_tiny_lfm(tmp_path)
    (folder / "lfm.toml").write_text((folder / "lfm.toml").read_text() + "aplanatic = true\n")  # [microscope]
    assert lfproc.Camera.from_toml(folder / "lfm.toml").main_optics.aplanatic is True
    proc = run_cli("calibrate", folder / "white.tif", "--camera", folder / "lfm.toml", "-o", folder / "grid.json")
    assert proc.returncode == 0, proc.stderr
    out = tmp_path / "viewer"
    proc = run_cli("viewer", folder / "capture.tif", "--camera", folder / "lfm.toml", "--calib", folder / "grid.json",
                   "--a=-0.4,0,0.45", "-o", out)
    assert proc.returncode == 0, proc.stderr
    data = json.loads((out / "geometry.json").read_text())
    assert data["unit"] == "um" and [s["a"] for s in data["slices"]] == pytest.approx([-0.4, 0.0, 0.45])
    assert ["refocusing", "aplanatic (sine condition)"] in data["camera"]
    lf = lfproc.read_light_field(str(folder / "capture.tif"), str(folder / "lfm.toml"), grid=str(folder / "grid.json"))
    assert_page_is_the_api(out, lf)
    # the sine condition's shifts are not the paraxial ones: the page shows the former
    (folder / "paraxial.toml").write_text((folder / "lfm.toml").read_text().replace("aplanatic = true", "aplanatic = false"))
    paraxial = lfproc.read_light_field(str(folder / "capture.tif"), str(folder / "paraxial.toml"),
                                       grid=str(folder / "grid.json"))
    tone = ToneMap(data["display"]["tone_map"]["black"], data["display"]["tone_map"]["white"])
    other = tone(lfproc.focal_stack(paraxial, a=[0.45]).images[0])
    assert not np.array_equal(_pixels(out / data["slices"][-1]["image"], other.shape), other)


def test_fallback_plan_stays_within_the_slices_focal_stack_takes(monkeypatch):
    """Where nothing can be covered (plan_depth_range refuses), the even steps in a start at infinity, not
    beyond it (focal_stack refuses slices beyond infinity)."""
    from lfproc.errors import LfprocError
    from lfproc.viewer import FocusDepth, scene_slices

    cam = scene_camera()
    a_inf = geometry.infinity_parameter(cam)

    def refuse(*args, **kwargs):
        raise LfprocError("nothing coverable")

    monkeypatch.setattr(geometry, "plan_depth_range", refuse)
    a = np.linspace(a_inf - 0.5, a_inf + 1.0, 400).reshape(20, 20)
    focus = FocusDepth(a, a, np.ones_like(a), np.linspace(a_inf - 0.5, a_inf + 1.0, 16))
    planned = scene_slices(cam, focus)
    assert planned[0] == pytest.approx(a_inf) and np.all(np.diff(planned) > 0) and len(planned) >= 2
    geometry.check_usable_a(cam, planned)   # every slice real


def test_a_given_focal_stack_is_the_one_the_page_shows(page, scene, tmp_path):
    """build_page(focal_stack=...) (the demo hands over the stack it wrote) shows that stack's slices, not a
    second refocus of its own (here one made with other interpolation, so the two differ); a stack of other
    slices is refused."""
    import lfproc
    from lfproc.viewer import build_page

    folder = scene["folder"]
    lf = lfproc.read_light_field(str(folder / "capture.png"), str(folder / "camera.toml"),
                                 grid=str(folder / "grid.json"))
    a_values = [float(r["a"]) for r in json.loads((page / "geometry.json").read_text())["slices"]]
    given = lfproc.focal_stack(lf, a=a_values, interpolation="nearest")
    assert not np.allclose(given.images, lfproc.focal_stack(lf, a=a_values).images)
    html = build_page(lf, str(tmp_path / "given"), source="capture.png", stem="capture", a_values=a_values,
                      focal_stack=given)
    data = json.loads((Path(html).parent / "geometry.json").read_text())
    tone = ToneMap(data["display"]["tone_map"]["black"], data["display"]["tone_map"]["white"])
    for k, record in enumerate(data["apertures"][0]["slices"]):
        expected = tone(given.images[k])
        assert np.array_equal(_pixels(Path(html).parent / record["image"], expected.shape), expected)
    with pytest.raises(ValueError, match="a_values"):
        build_page(lf, str(tmp_path / "other"), source="capture.png", stem="capture", a_values=a_values,
                   focal_stack=lfproc.focal_stack(lf, a=a_values[:1]))
