"""The Python API of the contract (ARCHITECTURE.md "Python API", "Provenance"), on the bundled sample and a
light-field microscope: its tags are the sidecars the commands write (1e-9), its images their TIFFs, its
``save`` writes what the commands write, it prints nothing and writes nothing under $HOME, its provenance
hashes are the files' SHA-256, and its errors name Python arguments.

The commands run as ``run_cli`` runs them, the API with HOME pointing at an empty folder and the decoder
cache variables unset (a cache write would land under HOME).
"""

import contextlib
import hashlib
import json
import math
import os
import sys
import tempfile
import warnings
from pathlib import Path

import numpy as np
import pytest
import tifffile

import lfproc
from conftest import SAMPLES, run_cli
from scopefile import write_tiny_lfm

SAMPLE = SAMPLES / "sample"
A_VALUES = [0.5, 0.682, 1.2]


@contextlib.contextmanager
def quiet_library(home: Path):
    """HOME at an empty folder, no decoder cache settings, and everything written to fds 1 and 2 caught;
    yields a dict whose "printed" is what was written (set on exit)."""
    saved = {k: os.environ.get(k) for k in ("HOME", "LFPROC_CACHE_DIR", "XDG_CACHE_HOME")}
    os.environ["HOME"] = str(home)
    os.environ.pop("LFPROC_CACHE_DIR", None)
    os.environ.pop("XDG_CACHE_HOME", None)
    sys.stdout.flush(), sys.stderr.flush()
    caught = tempfile.TemporaryFile(mode="w+b")
    kept = os.dup(1), os.dup(2)
    result = {}
    try:
        os.dup2(caught.fileno(), 1)
        os.dup2(caught.fileno(), 2)
        with warnings.catch_warnings(record=True) as said:
            warnings.simplefilter("always")
            yield result
    finally:
        sys.stdout.flush(), sys.stderr.flush()
        os.dup2(kept[0], 1)
        os.dup2(kept[1], 2)
        os.close(kept[0]), os.close(kept[1])
        caught.seek(0)
        result["printed"] = caught.read().decode(errors="replace")
        result["warnings"] = [w for w in said]
        for key, value in saved.items():
            if value is None:
                os.environ.pop(key, None)
            else:
                os.environ[key] = value


def sha256(path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def read_json(path) -> dict:
    return json.loads(Path(path).read_text())


def assert_same_record(api: dict, sidecar: dict, rel=1e-9):
    """A record of the API equals a sidecar: the same keys, numbers to ``rel`` (JSON null = inf), the rest equal."""
    assert list(api) == list(sidecar)
    for key, value in sidecar.items():
        mine = api[key]
        if isinstance(value, (int, float)) and not isinstance(value, bool) or (value is None and isinstance(mine, float)):
            expected = math.inf if value is None else value
            assert mine == pytest.approx(expected, rel=rel, abs=0), key
        else:
            assert json.loads(json.dumps(mine, allow_nan=True).replace("Infinity", "null")) == value, key


def assert_same_files(folder_a: Path, folder_b: Path):
    """Two output folders hold the same files, equal sidecars and equal image data."""
    names = sorted(p.name for p in folder_a.iterdir())
    assert names == sorted(p.name for p in folder_b.iterdir())
    for name in names:
        if name.endswith(".json"):
            assert read_json(folder_a / name) == read_json(folder_b / name), name
        elif name.endswith(".tif"):
            np.testing.assert_array_equal(tifffile.imread(folder_a / name), tifffile.imread(folder_b / name))


# ----------------------------------------------------------------------------------------------- the sample
@pytest.fixture(scope="module")
def sample_cli(tmp_path_factory):
    """What the commands write for the sample: slices (with a stack file), views, depth."""
    out = tmp_path_factory.mktemp("cli")
    inputs = [SAMPLE / "capture.png", "--camera", SAMPLE / "camera.toml", "--white", SAMPLE / "white.png"]
    a_list = ",".join(str(a) for a in A_VALUES)
    for args in (("refocus", *inputs, "--a", a_list, "--stack", "imagej", "-o", out / "refocus"),
                 ("views", *inputs, "-o", out / "views"),
                 ("depth", *inputs, "-o", out / "depth")):
        proc = run_cli(*args)
        assert proc.returncode == 0, proc.stderr
    return out


@pytest.fixture(scope="module")
def sample_api(tmp_path_factory):
    """The contract's snippet on the sample, run quietly; the results and what was printed or written."""
    home = tmp_path_factory.mktemp("home")
    with quiet_library(home) as run:
        cam = lfproc.Camera.from_toml(str(SAMPLE / "camera.toml"))
        grid = lfproc.calibrate_white(str(SAMPLE / "white.png"), cam, dark=None)
        lf = lfproc.read_light_field(str(SAMPLE / "capture.png"), cam, white=str(SAMPLE / "white.png"), grid=None,
                                     dark=None)
        fs = lfproc.focal_stack(lf, a=A_VALUES)
        vs = lfproc.view_stack(lf)
        dm = lfproc.depth_map(lf)
    run.update(grid=grid, lf=lf, fs=fs, vs=vs, dm=dm, home=home)
    return run


def slice_files(folder, a_values, camera=None, ext=".json"):
    """The files ``lfproc refocus`` writes for ``a_values`` (names in focus order: `lfproc.outputs.slice_names`)."""
    from lfproc.outputs import slice_names

    return [Path(folder) / (name + ext) for name in slice_names("capture", a_values, camera)]


def test_the_snippet_prints_nothing_and_writes_nothing_under_home(sample_api):
    assert sample_api["printed"] == ""
    assert list(sample_api["home"].iterdir()) == []
    assert all(issubclass(w.category, lfproc.LfprocWarning) for w in sample_api["warnings"])
    assert isinstance(sample_api["grid"], lfproc.LensGrid)


def test_focal_stack_tags_are_the_sidecars(sample_api, sample_cli):
    fs = sample_api["fs"]
    sidecars = [read_json(path) for path in slice_files(sample_cli / "refocus", A_VALUES)]
    for record, sidecar in zip(fs.records(), sidecars):
        assert_same_record(record, sidecar)
    for name in ("a", "distance_mm", "near_mm", "far_mm", "dof_mm"):
        np.testing.assert_allclose(getattr(fs, name), [s[name] for s in sidecars], rtol=1e-9)
    assert fs.views_summed == sidecars[0]["views_summed"] == 89
    assert fs.aperture_f_number == pytest.approx(sidecars[0]["aperture_f_number"], rel=1e-9)
    # the slice: the DOF of the views that carry light, not of the full micro image
    assert fs.near_mm[1] == pytest.approx(722.49, abs=0.01) and fs.far_mm[1] == pytest.approx(1235.48, abs=0.01)
    assert fs.z_um is None and fs.images.dtype == np.float32 and fs.images.shape == (3, 53, 75, 3)


def test_focal_stack_holds_one_set_of_tags_in_its_cameras_object_space(sample_api):
    """Issue 31: one set of fields (depth, near, far, dof) and their space; the contract's names read them."""
    import dataclasses

    from lfproc.camera import SENSOR_MM

    fs = sample_api["fs"]
    assert fs.space == SENSOR_MM == sample_api["lf"].camera.main_optics.object_space
    for name, field in zip(SENSOR_MM.keys, ("depth", "near", "far", "dof")):
        assert getattr(fs, name) is getattr(fs, field)
        assert [r[name] for r in fs.records()] == getattr(fs, field).tolist()
    assert all(getattr(fs, name) is None for name in ("z_um", "z_near_um", "z_far_um", "dof_um"))
    assert np.all(fs.near <= fs.depth) and np.all(fs.depth <= fs.far)      # mm from the sensor: near is less
    with pytest.raises(AttributeError):
        fs.distance_mm = fs.depth
    with pytest.raises(dataclasses.FrozenInstanceError):
        fs.depth = fs.near
    assert "mm from the sensor" in repr(fs)


def test_focal_stack_images_are_the_tiffs(sample_api, sample_cli):
    for image, path in zip(sample_api["fs"].images, slice_files(sample_cli / "refocus", A_VALUES, ext=".tif")):
        tiff = tifffile.imread(path)
        np.testing.assert_allclose(image, tiff.reshape(image.shape), rtol=2e-7, atol=1e-7)


def test_save_writes_what_refocus_writes(sample_api, sample_cli, tmp_path):
    written = sample_api["fs"].save(tmp_path, stem="capture", stack="imagej")
    assert len(written) == 4 and all(Path(p).exists() for p in written)
    assert_same_files(tmp_path, sample_cli / "refocus")
    with tifffile.TiffFile(tmp_path / "capture_stack.tif") as tif:
        info = tif.imagej_metadata["Info"]
    assert all("provenance" in s for s in json.loads(info)["slices"])


def test_view_stack_is_what_views_writes(sample_api, sample_cli, tmp_path):
    vs = sample_api["vs"]
    lf = sample_api["lf"]
    assert len(vs) == int(lf.view_mask.sum()) == 89
    assert vs.view.shape == (89, 2) and vs.view.dtype.kind == "i"
    for i in (0, 44, 88):
        ky, kx = vs.view[i]
        sidecar = read_json(sample_cli / "views" / f"capture_view_{ky:02d}_{kx:02d}.json")
        assert_same_record(vs.records()[i], sidecar)
        np.testing.assert_allclose(vs.position_mm[i], sidecar["position_mm"], rtol=1e-9)
        np.testing.assert_allclose(vs.tilt_deg[i], sidecar["tilt_deg"], rtol=1e-9)
        np.testing.assert_array_equal(vs.images[i], lf.views[ky, kx])
    vs.save(tmp_path, stem="capture")
    assert_same_files(tmp_path, sample_cli / "views")


def test_depth_map_is_what_depth_writes(sample_api, sample_cli, tmp_path):
    dm = sample_api["dm"]
    sidecar = read_json(sample_cli / "depth" / "capture_depth.json")
    tags = dm.tags()
    for key in tags:
        assert key in sidecar
    assert dm.method == sidecar["method"] and dm.unit == "mm" and dm.lens_grid == sidecar["lens_grid"]
    dm.save(tmp_path, stem="capture")
    assert_same_files(tmp_path, sample_cli / "depth")
    np.testing.assert_array_equal(dm.distance_mm, tifffile.imread(sample_cli / "depth" / "capture_depth.tif"))


def test_provenance_hashes_are_the_files_sha256(sample_api, sample_cli):
    prov = sample_api["fs"].provenance
    assert prov["lfproc_version"] == lfproc.__version__
    assert list(prov["inputs"]) == ["capture", "camera", "white"]   # no dark frame, no grid file shaped it
    for role, name in (("capture", "capture.png"), ("camera", "camera.toml"), ("white", "white.png")):
        assert prov["inputs"][role] == {"path": str(SAMPLE / name), "sha256": sha256(SAMPLE / name)}
    for path in (*slice_files(sample_cli / "refocus", A_VALUES), sample_cli / "views" / "capture_view_05_05.json",
                 sample_cli / "depth" / "capture_depth.json", sample_cli / "depth" / "capture_allfocus.json"):
        assert read_json(path)["provenance"] == prov, path


def test_a_grid_file_and_a_saved_light_field_are_recorded(sample_api, sample_cli, sample_grid, tmp_path):
    lf = lfproc.read_light_field(SAMPLE / "capture.png", SAMPLE / "camera.toml", grid=sample_grid)
    inputs = lfproc.focal_stack(lf, a=0.682).provenance["inputs"]
    assert list(inputs) == ["capture", "camera", "white", "grid"]   # the grid's recorded white image devignettes
    assert inputs["grid"]["sha256"] == sha256(sample_grid)
    saved = tmp_path / "capture.lfp.npz"
    sample_api["lf"].save(saved)
    again = lfproc.read_light_field(saved)
    fs = lfproc.focal_stack(again, a=A_VALUES)
    inputs = fs.provenance["inputs"]
    assert list(inputs) == ["light_field", "capture", "camera", "white"]
    assert inputs["light_field"] == {"path": str(saved), "sha256": sha256(saved)}
    assert inputs["white"] == sample_api["fs"].provenance["inputs"]["white"]
    proc = run_cli("refocus", saved, "--a", ",".join(map(str, A_VALUES)), "-o", tmp_path / "out")
    assert proc.returncode == 0, proc.stderr
    for record, path in zip(fs.records(), slice_files(tmp_path / "out", A_VALUES)):
        assert_same_record(record, read_json(path))
    np.testing.assert_array_equal(fs.images, sample_api["fs"].images)


def test_grid_save_writes_what_calibrate_writes_byte_for_byte(sample_api, tmp_path):
    """``lfproc.calibrate_white(...).save(path)`` is ``lfproc calibrate -o``: the same bytes, ``made_from``
    included; the file reads back (``LensGrid.load``) to the same lattice and calibration and saves to the same
    bytes again; a grid prints in one line."""
    from lfproc.cli import main

    assert main(["calibrate", str(SAMPLE / "white.png"), "--camera", str(SAMPLE / "camera.toml"),
                 "-o", str(tmp_path / "cli.json")]) == 0
    grid = sample_api["grid"]
    grid.save(tmp_path / "api.json")
    assert (tmp_path / "api.json").read_bytes() == (tmp_path / "cli.json").read_bytes()
    data = read_json(tmp_path / "api.json")
    assert data["made_from"]["white"]["hash"] == "sha256:" + sha256(SAMPLE / "white.png")
    assert data["camera"] == str(SAMPLE / "camera.toml") and data["white_image"] == str(SAMPLE / "white.png")
    loaded = lfproc.LensGrid.load(tmp_path / "api.json")
    assert loaded == grid and loaded.source == str(tmp_path / "api.json")
    assert loaded.calibration.made_from == grid.calibration.made_from
    assert loaded.calibration.pitch_sigma_px == grid.calibration.pitch_sigma_px
    assert loaded.calibration.measured_centers_xy_px is None and len(grid.calibration.measured_centers_xy_px)
    loaded.save(tmp_path / "again.json")
    assert (tmp_path / "again.json").read_bytes() == (tmp_path / "api.json").read_bytes()
    for shown in (grid, loaded, grid.calibration):
        assert "\n" not in repr(shown) and len(repr(shown)) < 200, repr(shown)
    assert "53 x 75 lenses" in repr(grid)


def test_one_path_whether_inputs_are_files_arrays_or_objects(sample_api):
    """The same views whether the capture and white image are files or arrays and the grid is fitted, a
    `LensGrid` or a setup made once (``prepare_decoding``, picklable for batch workers)."""
    import pickle

    from lfproc.io import read_capture

    cam = lfproc.Camera.from_toml(SAMPLE / "camera.toml")
    white, capture = (read_capture(SAMPLE / name, cam).data for name in ("white.png", "capture.png"))
    by_files, grid = sample_api["lf"], sample_api["grid"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", lfproc.LfprocWarning)
        setup = lfproc.prepare_decoding(cam, white=SAMPLE / "white.png")
        decoded = [lfproc.read_light_field(capture, cam, white=white),      # the grid fitted to the array
                   lfproc.read_light_field(SAMPLE / "capture.png", cam, grid=grid),   # its white image devignettes
                   lfproc.read_light_field(capture, cam, white=white, grid=grid),
                   setup.decode(SAMPLE / "capture.png"), setup.decode(capture),
                   pickle.loads(pickle.dumps(setup)).decode(SAMPLE / "capture.png")]
    for lf in decoded:
        np.testing.assert_array_equal(lf.views, by_files.views)
        np.testing.assert_array_equal(lf.view_mask, by_files.view_mask)
    assert list(lfproc.focal_stack(decoded[1], a=0.682).provenance["inputs"]) == ["capture", "camera", "white"]
    assert list(lfproc.focal_stack(decoded[0], a=0.682).provenance["inputs"]) == ["camera"]
    assert "\n" not in repr(setup) and "11x11 views" in repr(setup)


def test_messages_tell_a_python_caller_what_to_call(tmp_path):
    """A missing grid file names ``lfproc.calibrate_white(...).save(...)``, a folder given as the capture says
    so and how to decode many captures in Python: no command, no flag (the commands word them as theirs)."""
    camera = SAMPLE / "camera.toml"
    with pytest.raises(lfproc.LfprocError) as missing:
        lfproc.read_light_field(SAMPLE / "capture.png", camera, grid=tmp_path / "nope.json")
    with pytest.raises(lfproc.LfprocError) as folder:
        lfproc.read_light_field(SAMPLE, camera, white=SAMPLE / "white.png")
    assert "lfproc.calibrate_white(white, camera).save(path)" in str(missing.value)
    assert "is a folder" in str(folder.value) and "lfproc.prepare_decoding(" in str(folder.value)
    for message in (str(missing.value), str(folder.value)):
        assert "lfproc calibrate" not in message and "lfproc batch" not in message and "--" not in message
    proc = run_cli("refocus", SAMPLE / "capture.png", "--camera", camera, "--calib", tmp_path / "nope.json",
                   "--a", "1", "-o", tmp_path / "out")
    assert proc.returncode == 2 and "lfproc calibrate WHITE --camera CAM -o GRID.json" in proc.stderr, proc.stderr


def test_viewer_serve_returns_the_running_server_and_prints_nothing(tmp_path, capfd):
    import urllib.request

    from lfproc import viewer

    (tmp_path / "index.html").write_text("<p>a page</p>")
    server = viewer.serve(str(tmp_path), port=0)
    try:
        assert server.url.startswith("http://127.0.0.1:")
        with urllib.request.urlopen(server.url + "index.html", timeout=10) as response:
            assert response.read() == b"<p>a page</p>"
    finally:
        server.shutdown()
        server.server_close()
    assert capfd.readouterr() == ("", "")


def test_distance_parameters_and_aperture(sample_api):
    lf, fs = sample_api["lf"], sample_api["fs"]
    by_distance = lfproc.focal_stack(lf, distance_mm=fs.distance_mm)
    np.testing.assert_allclose(by_distance.a, fs.a, rtol=1e-9)
    narrow = lfproc.focal_stack(lf, a=[0.682], aperture=8.0)
    assert narrow.aperture_f_number >= 8.0 * 0.99 and narrow.views_summed < fs.views_summed
    assert narrow.dof_mm[0] > fs.dof_mm[1]


def test_a_depth_range_plans_the_slices_the_command_plans(sample_api, tmp_path):
    """focal_stack(lf, depth_range_mm=...) renders the slices `lfproc refocus --depth-range` renders (the DOF of
    the views that carry light), with the same tags; a microscope's z_range_um= those of --z-range Z0:Z1."""
    lf = sample_api["lf"]
    proc = run_cli("refocus", SAMPLE / "capture.png", "--camera", SAMPLE / "camera.toml", "--white",
                   SAMPLE / "white.png", "--depth-range", "300:2000", "-o", tmp_path / "cli")
    assert proc.returncode == 0, proc.stderr
    fs = lfproc.focal_stack(lf, depth_range_mm=(300.0, 2000.0))
    sidecars = sorted((tmp_path / "cli").glob("*.json"))
    assert len(sidecars) == len(fs) >= 3
    for record, sidecar in zip(fs.records(), sidecars):
        assert_same_record(record, read_json(sidecar))
    assert fs.near_mm.min() <= 300.0 and fs.far_mm.max() >= 2000.0          # the range is covered
    with pytest.raises(lfproc.LfprocError, match="exactly one of"):
        lfproc.focal_stack(lf, a=[1.0], depth_range_mm=(300.0, 2000.0))
    with pytest.raises(lfproc.LfprocError, match="z_range_um= is a range of positions"):
        lfproc.focal_stack(lf, z_range_um=(-10.0, 10.0))


def test_arrays_refocus_like_the_light_field_or_are_told_why_not(sample_api):
    from lfproc.refocusing import refocus

    lf = sample_api["lf"]
    masked = lfproc.LightField.from_views(lf.views, lf.camera, view_mask=lf.view_mask)
    np.testing.assert_array_equal(refocus(masked, 0.682), refocus(lf, 0.682))
    with pytest.warns(lfproc.LfprocWarning, match=r"pass the LightField.*view_mask"):
        dark = refocus(lf.views, 0.682)
    ratio = float(dark.mean() / refocus(lf, 0.682).mean())
    assert ratio == pytest.approx(89 / 121, rel=0.02)


def test_reprs_are_small(sample_api):
    """Every result's repr is one line (issue 37): a LensGrid does not print its coefficients, a Camera not its
    optics' every field, a DepthMap not its arrays (a Volume's: tests/test_deconvolve.py)."""
    shown = dict(sample_api, camera=sample_api["lf"].camera)
    for name in ("lf", "fs", "vs", "dm", "grid", "camera"):
        text = repr(shown[name])
        assert len(text) < 200 and "\n" not in text, (name, text)
    assert repr(shown["camera"]).startswith("<Camera 'lfproc-sample': MainLens, 11x11 views")
    assert repr(sample_api["dm"]).startswith("<DepthMap ") and "depth known at" in repr(sample_api["dm"])
    assert "89 carry light" in repr(sample_api["lf"])


def test_errors_name_python_arguments(sample_api, tmp_path):
    lf = sample_api["lf"]
    cases = [
        (lambda: lfproc.read_light_field(SAMPLE / "capture.png", SAMPLE / "camera.toml"), "white="),
        (lambda: lfproc.read_light_field(SAMPLE / "capture.png"), "camera="),
        (lambda: lfproc.focal_stack(lf), "a="),
        (lambda: lfproc.focal_stack(lf, a=[1.0], aperture=0.5), "aperture="),
        (lambda: lfproc.focal_stack(lf, z_um=[1.0]), "distance_mm="),
        (lambda: lfproc.focal_stack(lf.views, a=[1.0]), "LightField"),
        (lambda: lfproc.read_light_field(tmp_path / "missing.png", SAMPLE / "camera.toml", white=SAMPLE / "white.png"),
         "missing.png"),
    ]
    for call, named in cases:
        with pytest.raises(lfproc.LfprocError) as info:
            call()
        message = str(info.value)
        assert named in message and "--" not in message and "\n" not in message, message


def test_to_xarray_when_xarray_is_there(sample_api):
    # xarray is not a dependency of lfproc (to_xarray says how to install it): tested only where present
    xarray = pytest.importorskip("xarray")
    da = sample_api["fs"].to_xarray()
    assert isinstance(da, xarray.DataArray) and da.dims == ("slice", "y", "x", "channel")
    np.testing.assert_allclose(da.coords["distance_mm"].values, sample_api["fs"].distance_mm)


# ------------------------------------------------------------------------------------------ a microscope
@pytest.fixture(scope="module")
def lfm(tmp_path_factory):
    """A tiny light-field microscope's white image and capture (as tests/test_microscope_cli.py renders them)."""
    return write_tiny_lfm(tmp_path_factory.mktemp("lfm"))


def test_microscope_stack_in_micrometres_equals_the_command(lfm, tmp_path):
    a_values = [-0.5, 0.0, 0.75]
    proc = run_cli("refocus", lfm / "capture.tif", "--camera", lfm / "lfm.toml", "--white", lfm / "white.tif",
                   "--a", ",".join(map(str, a_values)), "-o", tmp_path / "cli")
    assert proc.returncode == 0, proc.stderr
    (tmp_path / "home").mkdir()
    with quiet_library(tmp_path / "home") as run:
        lf = lfproc.read_light_field(str(lfm / "capture.tif"), str(lfm / "lfm.toml"), white=str(lfm / "white.tif"))
        fs = lfproc.focal_stack(lf, a=a_values)
        by_depth = lfproc.focal_stack(lf, z_um=fs.z_um)
    assert run["printed"] == "" and list((tmp_path / "home").iterdir()) == []
    assert fs.distance_mm is None and fs.aperture_f_number is None
    from lfproc.camera import NATIVE_PLANE_UM
    assert fs.space == NATIVE_PLANE_UM and fs.z_um is fs.depth and fs.dof_um is fs.dof
    assert all(getattr(fs, name) is None for name in ("distance_mm", "near_mm", "far_mm", "dof_mm"))
    assert np.all(fs.z_near_um >= fs.z_um) and np.all(fs.z_far_um <= fs.z_um)   # signed z: near is more
    assert " µm from the native object plane" in repr(fs) and "from the sensor" not in repr(fs)
    np.testing.assert_allclose(by_depth.a, a_values, rtol=1e-9, atol=1e-12)
    for i, name in enumerate(p.stem for p in slice_files(tmp_path / "cli", a_values, lf.camera)):
        sidecar = read_json(tmp_path / "cli" / f"{name}.json")
        assert_same_record(fs.records()[i], sidecar)
        for key in ("z_um", "z_near_um", "z_far_um", "dof_um"):
            assert getattr(fs, key)[i] == pytest.approx(sidecar[key], rel=1e-9)
        tiff = tifffile.imread(tmp_path / "cli" / f"{name}.tif")
        np.testing.assert_allclose(fs.images[i], tiff.reshape(fs.images[i].shape), rtol=2e-7, atol=1e-7)
    assert sidecar["provenance"]["inputs"]["camera"]["sha256"] == sha256(lfm / "lfm.toml")
    fs.save(tmp_path / "api")
    assert_same_files(tmp_path / "api", tmp_path / "cli")


def test_microscope_z_range_plans_the_slices_the_command_plans(lfm, tmp_path):
    proc = run_cli("refocus", lfm / "capture.tif", "--camera", lfm / "lfm.toml", "--white", lfm / "white.tif",
                   "--z-range", "-20:20", "-o", tmp_path / "cli")
    assert proc.returncode == 0, proc.stderr
    lf = lfproc.read_light_field(str(lfm / "capture.tif"), str(lfm / "lfm.toml"), white=str(lfm / "white.tif"))
    fs = lfproc.focal_stack(lf, z_range_um=(20.0, -20.0))                       # either order
    sidecars = sorted((tmp_path / "cli").glob("*.json"))
    assert len(sidecars) == len(fs) >= 2
    by_z = sorted(fs.records(), key=lambda r: r["z_um"])                        # files run from low to high z
    for record, sidecar in zip(by_z, sidecars):
        assert_same_record(record, read_json(sidecar))


def test_microscope_grid_views_and_depth_equal_the_commands(lfm, tmp_path):
    """On a microscope render: ``calibrate_white(...).save`` writes ``lfproc calibrate``'s bytes, and the
    views and depth map of ``read_light_field(grid=...)`` are what ``lfproc views`` and ``lfproc depth --calib``
    write (files, sidecars and images)."""
    from lfproc.cli import main

    cli, camera, capture = tmp_path / "cli", str(lfm / "lfm.toml"), str(lfm / "capture.tif")
    cli.mkdir()
    assert main(["calibrate", str(lfm / "white.tif"), "--camera", camera, "-o", str(cli / "grid.json")]) == 0
    for command in ("views", "depth"):
        assert main([command, capture, "--camera", camera, "--calib", str(cli / "grid.json"), "-o",
                     str(cli / command)]) == 0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", lfproc.LfprocWarning)
        lfproc.calibrate_white(lfm / "white.tif", camera).save(tmp_path / "grid.json")
        lf = lfproc.read_light_field(capture, camera, grid=cli / "grid.json")
        lfproc.view_stack(lf).save(tmp_path / "views")
        lfproc.depth_map(lf).save(tmp_path / "depth")
    assert (tmp_path / "grid.json").read_bytes() == (cli / "grid.json").read_bytes()
    assert_same_files(tmp_path / "views", cli / "views")
    assert_same_files(tmp_path / "depth", cli / "depth")


def test_each_input_is_hashed_once_per_process(tmp_path, monkeypatch):
    import lfproc.provenance as prov

    files = []
    for name in ("a.bin", "b.bin"):
        (tmp_path / name).write_bytes(name.encode() * 1000)
        files.append(tmp_path / name)
    calls = []

    class CountingHashlib:
        @staticmethod
        def sha256(*args):
            calls.append(1)
            return hashlib.sha256(*args)

    monkeypatch.setattr(prov, "hashlib", CountingHashlib)
    first = prov.provenance({"capture": files[0], "white": files[1]})
    again = prov.provenance({"white": files[1], "capture": str(files[0])})
    assert first == again and len(calls) == 2
    assert list(first["inputs"]) == ["capture", "white"]
    assert first["inputs"]["white"]["sha256"] == sha256(files[1])
    (tmp_path / "a.bin").write_bytes(b"changed, and longer than before")   # a new size: hashed again
    assert prov.provenance({"capture": files[0]})["inputs"]["capture"]["sha256"] == sha256(files[0])
    assert len(calls) == 3


def test_decode_stores_its_inputs_and_outputs_of_the_light_field_name_them(tmp_path):
    inputs = [SAMPLE / "capture.png", "--camera", SAMPLE / "camera.toml", "--white", SAMPLE / "white.png"]
    proc = run_cli("decode", *inputs, "-o", tmp_path / "lf.lfp.npz")
    assert proc.returncode == 0, proc.stderr
    proc = run_cli("views", tmp_path / "lf.lfp.npz", "--mosaic", "-o", tmp_path / "views")
    assert proc.returncode == 0, proc.stderr
    for name in ("lf_view_05_05.json", "lf_views_mosaic.json"):
        recorded = read_json(tmp_path / "views" / name)["provenance"]["inputs"]
        assert list(recorded) == ["light_field", "capture", "camera", "white"], name
        assert recorded["light_field"]["sha256"] == sha256(tmp_path / "lf.lfp.npz")
        assert recorded["capture"] == {"path": str(SAMPLE / "capture.png"), "sha256": sha256(SAMPLE / "capture.png")}


def test_commands_keep_their_flags_in_errors(tmp_path):
    proc = run_cli("refocus", SAMPLE / "capture.png", "--camera", SAMPLE / "camera.toml", "--a", "1",
                   "-o", tmp_path / "out")
    assert proc.returncode == 2 and "--white WHITE" in proc.stderr and "white=" not in proc.stderr, proc.stderr
