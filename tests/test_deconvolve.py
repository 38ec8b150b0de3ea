"""lfproc deconvolve / lfproc.deconvolve (issue 39): beads at known 3-D positions come back where they are.

* the bead sample of docs/deconvolution.md, rendered by lfproc's ray-traced microscope simulator (geometric
  optics, independent of the wave model), through calibration, decoding and the command with its defaults
  (and with --no-filter): each bead within a voxel laterally and on its own plane;
* points rendered by the wave model itself between voxels and between planes (finer field sampling, Poisson
  noise), with and without the anti-aliasing filter: within a voxel laterally, on the nearest plane;
* the files: an OME-TIFF (axes ZYX) whose physical sizes are the voxel in µm, and the record's contract keys;
* one-line refusals before any work; operators built once, pickled, reused, cached; no NaN, no divergence.
"""

from __future__ import annotations

import json
import os
import pickle
import re
import warnings

import numpy as np
import pytest

import lfproc
from lfproc.camera import Microscope
from lfproc.cli import main
from lfproc.errors import LfprocError
from lfproc.simulate import lens_of_point
from lfproc.wave import build_operators, lens_radius, voxel_patterns

from conftest import ROOT

DOC = (ROOT / "docs" / "deconvolution.md").read_text()
BEADS = ((-40.0, 25.0, -20.0), (30.0, -35.0, 20.0), (35.0, 40.0, 30.0))      # the doc's (x, y, z) in µm


def _doc_block(language: str, heading: str = "## Try it on rendered beads") -> str:
    section = DOC[DOC.index(heading):]
    return re.search(rf"```{language}\n(.*?)```", section, re.S).group(1)


@pytest.fixture(scope="module")
def bead_sample(tmp_path_factory):
    """The doc's scene file (the bundled sample, the same text) rendered by the doc's ``lfproc simulate`` line, in a
    folder of its own: ``beads.toml`` and ``beads/`` (capture.png, white.png, camera.toml, ground_truth.json)."""
    folder = tmp_path_factory.mktemp("beads")
    scene = _doc_block("toml")
    assert scene in lfproc.sample_path("microscope/beads.toml").read_text()
    (folder / "beads.toml").write_text(scene)
    simulate = _doc_block("sh").strip().splitlines()[0].split()
    assert simulate[:2] == ["lfproc", "simulate"]
    cwd = os.getcwd()
    os.chdir(folder)
    try:
        assert main(simulate[1:]) == 0
    finally:
        os.chdir(cwd)
    return folder


def _found(volume, z_um, voxel_um, camera, lenses, superres, bead):
    """(z of the plane, lateral distance in voxels) of the brightest voxel within 5 voxels of the bead."""
    x, y, _ = bead
    row, col = lens_of_point(camera, lenses, x, y)
    ey, ex = row * superres + (superres - 1) / 2, col * superres + (superres - 1) / 2
    y0, x0 = int(round(ey)) - 5, int(round(ex)) - 5
    window = volume[:, y0:y0 + 11, x0:x0 + 11]
    k = np.unravel_index(int(np.argmax(window)), window.shape)
    return float(z_um[k[0]]), float(np.hypot(k[1] + y0 - ey, k[2] + x0 - ex))


@pytest.mark.parametrize("no_filter", [False, True])
def test_the_docs_bead_sample_comes_back(bead_sample, tmp_path, no_filter, monkeypatch):
    """The doc's lfproc deconvolve line as written (its defaults: 8 iterations, S = 3, the anti-aliasing filter)
    on the doc's rendered beads, and with --no-filter: every bead on its own plane, within a voxel laterally."""
    deconvolve = _doc_block("sh").strip().splitlines()[1].split()
    assert deconvolve[:2] == ["lfproc", "deconvolve"]
    assert not {"--iterations", "--superres", "--no-filter", "--background"} & set(deconvolve)    # the defaults
    args = deconvolve[1:] + (["--no-filter"] if no_filter else [])
    args[args.index("-o") + 1] = str(tmp_path / "out")
    monkeypatch.chdir(bead_sample)
    monkeypatch.setenv("LFPROC_CACHE_DIR", str(tmp_path / "cache"))
    assert main(args) == 0
    import tifffile

    volume = tifffile.imread(tmp_path / "out" / "capture_volume.ome.tif")
    record = json.loads((tmp_path / "out" / "capture_volume.json").read_text())
    truth = json.loads((bead_sample / "beads" / "ground_truth.json").read_text())
    assert sorted((b["x_um"], b["y_um"], b["z_um"]) for b in truth["beads"]) == sorted(BEADS)
    camera = lfproc.Camera.from_toml(str(bead_sample / "beads" / "camera.toml"))
    s = record["superres"]
    lenses = (volume.shape[1] // s, volume.shape[2] // s)
    for bead in BEADS:
        z, lateral = _found(volume, np.array(record["z_um"]), record["voxel_um"], camera, lenses, s, bead)
        assert lateral <= 1.0 and z == bead[2], (bead, z, lateral)
    assert record["antialiasing_filter"] is not no_filter and record["iterations"] == 8 and s == 3
    assert np.isfinite(volume).all() and volume.min() >= 0


def test_bead_scene_files_are_checked_in_one_line():
    """[[bead]] needs a microscope camera and excludes [[plane]]s; its keys are named."""
    from lfproc.simulate import parse_scene_dict
    from lfproc.tomlfile import read_toml

    scene = read_toml(str(lfproc.sample_path("microscope/beads.toml")), "scene file", "")
    assert len(parse_scene_dict(scene).beads) == 3
    photo = dict(scene, camera=str(ROOT / "lfproc" / "samples" / "cameras" / "paper-f100.toml"))
    for data, words in ((photo, "needs a microscope camera"),
                        (dict(scene, bead=[{"x_um": 1.0, "y_um": 2.0}]), "missing z_um"),
                        (dict(scene, bead=[{"x_um": 1.0, "y_um": 2.0, "z_um": 3.0, "size": 1}]), "unknown key(s)"),
                        (dict(scene, bead=[{"x_um": 1.0, "y_um": 2.0, "z_um": float("nan")}]), "z_um must be a finite number"),
                        (dict(scene, plane=[{"distance_mm": 100.0, "texture": "uniform"}]), "not both")):
        with pytest.raises(LfprocError, match=re.escape(words)):
            parse_scene_dict(data)


def _wave_rendered(camera, lenses, points, oversample=5, seed=3):
    """Views (m̂, m̂, Ny, Nx, 1) of points (x, y, z) µm in the sample through the wave model at their exact
    positions (sampled finer than the operators), with Poisson noise; x, y as for the ray simulator."""
    optics = camera.main_optics.wave_optics
    m = camera.m_hat
    pitch_um, f_um = camera.mla_pitch_mm * 1000.0, camera.mla_focal_length_mm * 1000.0
    views = np.zeros((m, m) + lenses)
    for x, y, z in points:
        row, col = lens_of_point(camera, lenses, x, y)
        jy, jx = int(round(row)), int(round(col))
        offset = ((row - jy) * pitch_um, (col - jx) * pitch_um)
        r = lens_radius(optics, pitch_um, z)
        pattern = voxel_patterns(optics, pitch_um, f_um, m, oversample, z, [offset], r)[0]
        views[:, :, jy - r:jy + r + 1, jx - r:jx + r + 1] += pattern
    rng = np.random.default_rng(seed)
    views = rng.poisson(views / views.max() * 5000.0) / 5000.0
    return views[..., None]


def _camera(m_hat=9):
    return lfproc.Camera(pixel_pitch_mm=0.125 / m_hat, mla_pitch_mm=0.125, mla_focal_length_mm=2.433,
                         main_optics=Microscope(20.0, 0.5, 1.33, 200.0, wavelength_nm=510.0), micro_image_px=m_hat)


@pytest.mark.parametrize("antialias", [True, False])
def test_points_between_voxels_and_planes_come_back(antialias):
    """Points 0.3–0.4 voxel and up to 2.5 µm off the voxel grid (planes every 10 µm), rendered by the wave model
    with 5 × 5 sub-samples and Poisson noise: each within a voxel laterally, on the nearest plane."""
    camera, lenses = _camera(), (25, 25)
    points = ((-41.0, 26.0, -22.5), (31.0, -34.0, 18.0), (-30.0, -38.0, 32.0), (42.0, 30.0, -31.0))
    lf = lfproc.LightField.from_views(_wave_rendered(camera, lenses, points), camera)
    vol = lfproc.deconvolve(lf, z_um=np.arange(-40.0, 41.0, 10.0), superres=3, iterations=30, antialias=antialias)
    for point in points:
        z, lateral = _found(vol.data, vol.z_um, vol.voxel_um, camera, lenses, 3, point)
        assert lateral <= 1.0 and z == 10.0 * round(point[2] / 10.0), (point, z, lateral)
    if not antialias:   # plain Richardson–Lucy: every iteration explains the data better
        assert np.all(np.diff(vol.residuals) < 0)


@pytest.fixture(scope="module")
def small():
    """A small light field of two wave-rendered points and its operators."""
    camera, lenses = _camera(m_hat=7), (16, 16)
    lf = lfproc.LightField.from_views(_wave_rendered(camera, lenses, ((-10.0, 12.0, -20.0), (15.0, -8.0, 10.0)),
                                                     oversample=3), camera)
    return lf, build_operators(camera, [-20.0, 0.0, 10.0], 3)


def test_the_files_carry_their_scale_and_the_record(small, tmp_path):
    import tifffile

    lf, ops = small
    vol = lfproc.deconvolve(lf, iterations=3, superres=3, operators=ops)
    paths = vol.save(tmp_path, stem="points")
    assert [os.path.basename(p) for p in paths] == ["points_volume.ome.tif", "points_volume.json"]
    dz, dy, dx = vol.voxel_um
    assert dy == dx == pytest.approx(125.0 / 3 / 20.0) and dz == pytest.approx(15.0)
    with tifffile.TiffFile(paths[0]) as tif:
        series = tif.series[0]
        assert series.axes == "ZYX" and series.shape == vol.data.shape
        pixels = tif.ome_metadata
        for name, value in (("PhysicalSizeX", dx), ("PhysicalSizeY", dy), ("PhysicalSizeZ", dz)):
            assert float(re.search(rf'{name}="([^"]+)"', pixels).group(1)) == pytest.approx(value)
            assert re.search(rf'{name}Unit="µm"', pixels)
        np.testing.assert_array_equal(series.asarray(), vol.data)
    record = json.loads(open(paths[1]).read())
    for key in ("z_um", "voxel_um", "iterations", "superres", "optics", "provenance", "residuals"):
        assert key in record
    assert record["z_um"] == [-20.0, 0.0, 10.0] and record["iterations"] == 3 and record["superres"] == 3
    assert record["optics"]["numerical_aperture"] == 0.5 and record["optics"]["wavelength_nm"] == 510.0
    assert "lfproc_version" in record["provenance"]
    assert repr(vol).count("\n") <= 1


def test_info_names_a_volume_with_its_voxel_and_planes(small, tmp_path):
    """``lfproc info`` on a volume: a deconvolved volume (not a focal stack), its planes' depths and the voxel size
    in µm, as read from the OME-TIFF's own PhysicalSize tags (what Fiji and napari read)."""
    from conftest import run_cli

    lf, ops = small
    vol = lfproc.deconvolve(lf, iterations=1, superres=3, operators=ops)
    stack = vol.save(tmp_path, stem="points")[0]
    info = json.loads(run_cli("info", "--json", stack).stdout)
    assert info["product"] == "deconvolved volume" and info["planes"] == 3 and info["z_um"] == [-20.0, 0.0, 10.0]
    assert info["voxel_um"] == pytest.approx(list(vol.voxel_um)) and (info["width"], info["height"]) == (48, 48)
    text = run_cli("info", stack).stdout
    assert "deconvolved volume" in text and "focal stack" not in text and "slices" not in text


def test_operators_built_once_serve_every_frame(small, tmp_path, monkeypatch):
    """The same volume from operators passed in, unpickled (as a Dask worker receives them) or cached on disk;
    operators of other optics are refused."""
    lf, ops = small
    reference = lfproc.deconvolve(lf, z_um=[-20.0, 0.0, 10.0], iterations=3, superres=3)
    shipped = pickle.loads(pickle.dumps(ops))
    np.testing.assert_array_equal(lfproc.deconvolve(lf, iterations=3, superres=3, operators=shipped).data,
                                  reference.data)
    monkeypatch.setenv("LFPROC_CACHE_DIR", str(tmp_path))
    first = lfproc.deconvolve(lf, z_um=[-20.0, 0.0, 10.0], iterations=3, superres=3, cache=True)
    entries = list((tmp_path / "decoders").glob("*.lfdec"))
    assert len(entries) == 1
    again = lfproc.deconvolve(lf, z_um=[-20.0, 0.0, 10.0], iterations=3, superres=3, cache=True)
    np.testing.assert_array_equal(first.data, reference.data)
    np.testing.assert_array_equal(again.data, reference.data)
    with pytest.raises(LfprocError, match="operators= were built for other"):
        lfproc.deconvolve(lf, iterations=3, superres=1, operators=ops)


def test_nothing_becomes_nan_or_diverges(small):
    lf, ops = small
    dark = lfproc.LightField.from_views(np.zeros_like(lf.views), lf.camera)
    assert not lfproc.deconvolve(dark, iterations=2, superres=3, operators=ops).data.any()
    damaged = lf.views.copy()
    damaged[3, 3, 5, 5, 0] = np.nan
    damaged[2, 4, 7, 7, 0] = -1.0
    vol = lfproc.deconvolve(lfproc.LightField.from_views(damaged, lf.camera), iterations=5, superres=3,
                            operators=ops)
    assert np.isfinite(vol.data).all() and np.isfinite(vol.residuals).all()
    # a uniform plane: the border voxels, which half the measurement sees, stay at the level of the rest
    uniform = lfproc.LightField.from_views(np.ones_like(lf.views), lf.camera)
    vol = lfproc.deconvolve(uniform, iterations=20, superres=3, operators=ops, background=0)
    assert vol.data.max() < 20 * np.median(vol.data[vol.data > 0])


def test_refusals_name_the_argument(small):
    lf, ops = small
    with pytest.raises(LfprocError, match="superres=8 is finer than the 7 samples"):
        lfproc.deconvolve(lf, z_um=[0.0], superres=8)
    with pytest.raises(LfprocError, match=r"half of the light field's 16 lenses: these optics image z from"):
        lfproc.deconvolve(lf, z_um=[0.0, 150.0])
    with pytest.raises(LfprocError, match="z_um="):
        lfproc.deconvolve(lf)
    with pytest.raises(LfprocError, match="iterations="):
        lfproc.deconvolve(lf, z_um=[0.0], iterations=0)
    with pytest.raises(LfprocError, match="background="):
        lfproc.deconvolve(lf, z_um=[0.0], background="high")


def test_the_command_refuses_in_one_line_before_any_work(bead_sample, tmp_path, capsys):
    photo = str(ROOT / "lfproc" / "samples" / "cameras" / "paper-f100.toml")
    beads = bead_sample / "beads"
    common = [str(beads / "capture.png"), "--white", str(beads / "white.png"), "-o", str(tmp_path / "o")]
    cases = [(["--camera", photo, "--z-range", "-10:10:10"], "microscope optics"),
             (["--camera", str(beads / "camera.toml"), "--z-range", "-10:10:10", "--superres", "12"],
              "--superres 12 is finer than the 9 samples"),
             (["--camera", str(beads / "camera.toml"), "--z-range", "-3000:3000:1000"],
              "these optics image z from"),
             (["--camera", str(beads / "camera.toml"), "--z-range", "-10:10"], "Z0:Z1:STEP")]
    for extra, words in cases:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            assert main(["deconvolve", *common, *extra]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and words in err[0], err
        assert not (tmp_path / "o").exists()


def test_to_xarray_labels_the_axes_in_micrometres(small):
    lf, ops = small
    vol = lfproc.deconvolve(lf, iterations=1, operators=ops)
    try:
        import xarray  # noqa: F401
    except ImportError:
        with pytest.raises(LfprocError, match="pip install xarray"):
            vol.to_xarray()
        return
    array = vol.to_xarray()
    assert array.dims == ("z", "y", "x") and list(array["z"].values) == [-20.0, 0.0, 10.0]
    assert float(array["x"][1] - array["x"][0]) == pytest.approx(vol.voxel_um[2])
