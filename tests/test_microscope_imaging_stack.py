"""Focal stacks as one file (issue 21): ImageJ hyperstack and OME-TIFF z-stacks with physical spacing,
read back with tifffile (the library Fiji's and napari's TIFF readers agree with on these tags)."""

import json

import numpy as np
import pytest
import tifffile

import lfproc

from lfproc import Camera, LightField
from lfproc.camera import NATIVE_PLANE_UM
from lfproc.outputs import lateral_um_per_lens, write_focal_stack

from conftest import SAMPLES, run_cli

LFM_20X = SAMPLES / "cameras" / "lfm-20x.toml"


def microscope_records(z_values):
    return [{"source": "x", "a": z / 10.0, "z_um": z, "z_near_um": z - 1, "z_far_um": z + 1, "dof_um": 2.0}
            for z in z_values]


def slices(k, h=6, w=7, c=1, seed=0):
    return np.random.default_rng(seed).random((k, h, w, c)).astype(np.float32)


def test_lateral_sampling_is_pitch_over_magnification():
    camera = Camera.from_toml(LFM_20X)
    assert lateral_um_per_lens(camera) == pytest.approx(125.0 / 20.0)
    assert lateral_um_per_lens(Camera.from_toml(SAMPLES / "sample" / "camera.toml")) is None


@pytest.mark.parametrize("upsample", [1, 3])
def test_imagej_hyperstack_has_micron_spacing(tmp_path, upsample):
    z = [-4.0, -2.0, 0.0, 2.0, 4.0]
    images = slices(5)
    path = write_focal_stack(str(tmp_path / "s_stack.tif"), images[::-1], microscope_records(z[::-1]), NATIVE_PLANE_UM,
                             kind="imagej", lens_um=6.25, upsample=upsample)
    with tifffile.TiffFile(path) as tif:
        meta = tif.imagej_metadata
        assert tif.series[0].axes == "ZYX" and tif.series[0].shape == (5, 6, 7)
        assert meta["unit"] == "micron" and meta["spacing"] == pytest.approx(2.0)
        assert meta["slices"] == 5 and meta["hyperstack"]
        x_res = tif.pages[0].tags["XResolution"].value
        y_res = tif.pages[0].tags["YResolution"].value
        assert x_res[1] / x_res[0] == pytest.approx(6.25 / upsample, rel=1e-6)
        assert y_res[1] / y_res[0] == pytest.approx(6.25 / upsample, rel=1e-6)
        data = tif.asarray()
        info = json.loads(meta["Info"])
    # ordered by increasing z whatever the order given
    assert np.array_equal(data, images[::-1][::-1, :, :, 0])
    assert [s["z_um"] for s in info["slices"]] == z
    assert meta["Labels"][0].startswith("a=-0.4 z=-4 µm")


def test_ome_tiff_has_physical_sizes_and_plane_positions(tmp_path):
    z = [0.0, 1.5, 3.0]
    images = slices(3, c=3)
    path = write_focal_stack(str(tmp_path / "s_stack.ome.tif"), images, microscope_records(z), NATIVE_PLANE_UM, kind="ome",
                             lens_um=6.25, upsample=2)
    with tifffile.TiffFile(path) as tif:
        assert tif.is_ome
        series = tif.series[0]
        assert series.axes == "ZCYX" and series.shape == (3, 3, 6, 7)
        assert np.array_equal(series.asarray(), np.moveaxis(images, 3, 1))
        xml = tif.ome_metadata
    import xml.etree.ElementTree as ET
    ns = {"ome": "http://www.openmicroscopy.org/Schemas/OME/2016-06"}
    pixels = ET.fromstring(xml).find(".//ome:Pixels", ns)
    assert float(pixels.get("PhysicalSizeX")) == pytest.approx(3.125)
    assert float(pixels.get("PhysicalSizeY")) == pytest.approx(3.125)
    assert float(pixels.get("PhysicalSizeZ")) == pytest.approx(1.5)
    assert pixels.get("PhysicalSizeXUnit") == pixels.get("PhysicalSizeZUnit") == "µm"
    planes = pixels.findall("ome:Plane", ns)
    assert [(int(p.get("TheZ")), float(p.get("PositionZ"))) for p in planes if p.get("TheC") == "0"] == \
        [(0, 0.0), (1, 1.5), (2, 3.0)]


def test_refocus_stack_of_a_photographic_capture_carries_distances(tmp_path):
    """``lfproc refocus --stack``: one file beside the slices, in the order of a, each slice's distance kept."""
    camera = Camera.from_toml(SAMPLES / "sample" / "camera.toml")
    views = np.random.default_rng(1).random((camera.m_hat, camera.m_hat, 12, 14, 1)).astype(np.float32)
    LightField.from_views(views, camera).save(tmp_path / "cap.lfp.npz")
    for kind, name in (("imagej", "cap_stack.tif"), ("ome", "cap_stack.ome.tif")):
        out = tmp_path / kind
        proc = run_cli("refocus", tmp_path / "cap.lfp.npz", "--a", "1,0,0.5", "--stack", kind, "-o", out)
        assert proc.returncode == 0, proc.stderr
        sidecars = {json.loads(p.read_text())["a"]: json.loads(p.read_text()) for p in out.glob("cap_*_a*.json")}
        assert len(sidecars) == 3 and f"z-stack -> {out / name}" in proc.stdout, proc.stdout   # issue 32
        with tifffile.TiffFile(out / name) as tif:
            data = tif.asarray()
            info = json.loads(tif.imagej_metadata["Info"] if kind == "imagej" else _ome_description(tif.ome_metadata))
        assert data.shape == (3, 12, 14)
        assert [s["a"] for s in info["slices"]] == [0.0, 0.5, 1.0]
        for s in info["slices"]:
            assert s["distance_mm"] == sidecars[s["a"]]["distance_mm"]
        slice_half = tifffile.imread(out / "cap_01_a+0.500.tif")   # a = 0, 0.5, 1 in focus order: 0.5 second
        assert np.array_equal(data[1], np.squeeze(slice_half))


def _ome_description(xml):
    import xml.etree.ElementTree as ET
    ns = {"ome": "http://www.openmicroscopy.org/Schemas/OME/2016-06"}
    return ET.fromstring(xml).find(".//ome:Image/ome:Description", ns).text


def test_microscope_stack_is_to_scale(tmp_path):
    """A microscope's slices (their sidecar records): x/y spacing p_m/M/upsample, z spacing = the z_um step."""
    from lfproc import geometry
    from lfproc.outputs import slice_metadata

    camera = Camera.from_toml(LFM_20X)
    m = camera.m_hat
    views = np.random.default_rng(2).random((m, m, 10, 11, 1)).astype(np.float32)
    a = [0.1, -0.1, 0.0]
    stack = lfproc.refocus(views, a, upsample=2)
    path = write_focal_stack(str(tmp_path / "lfm_stack.tif"), stack, slice_metadata("lfm", camera, a), camera.main_optics.object_space,
                             kind="imagej", lens_um=lateral_um_per_lens(camera), upsample=2)
    with tifffile.TiffFile(path) as tif:
        meta = tif.imagej_metadata
        x_res = tif.pages[0].tags["XResolution"].value
        assert tif.series[0].shape == (3, 19, 21)
        assert np.array_equal(tif.asarray(), stack[[1, 2, 0], :, :, 0])
    z_step = 0.1 * camera.mla_focal_length_mm * 1000 * m * 1.33 / 20.0 ** 2      # contract: a·m̂·f_s·n/M²
    assert meta["unit"] == "micron"
    assert meta["spacing"] == pytest.approx(z_step, rel=1e-9)
    assert meta["spacing"] == pytest.approx(geometry.microscope_slices(camera, 0.1).z_um, rel=1e-9)
    assert x_res[1] / x_res[0] == pytest.approx(125.0 / 20.0 / 2, rel=1e-6)
    assert [s["z_um"] for s in json.loads(meta["Info"])["slices"]] == pytest.approx([-z_step, 0.0, z_step])


def test_refocus_command_writes_a_microscope_stack(tmp_path):
    """``lfproc refocus --stack ome`` on a microscope light field: OME-TIFF with µm sizes and per-plane z."""
    camera = Camera.from_toml(LFM_20X)
    m = camera.m_hat
    views = np.random.default_rng(3).random((m, m, 10, 11, 1)).astype(np.float32)
    LightField.from_views(views, camera).save(tmp_path / "lfm.lfp.npz")
    proc = run_cli("refocus", tmp_path / "lfm.lfp.npz", "--a", "0,0.05,0.1", "--stack", "ome", "-o", tmp_path / "out")
    assert proc.returncode == 0, proc.stderr
    import xml.etree.ElementTree as ET
    ns = {"ome": "http://www.openmicroscopy.org/Schemas/OME/2016-06"}
    with tifffile.TiffFile(tmp_path / "out" / "lfm_stack.ome.tif") as tif:
        pixels = ET.fromstring(tif.ome_metadata).find(".//ome:Pixels", ns)
        assert tif.series[0].shape == (3, 10, 11)
    sidecars = sorted((json.loads(p.read_text()) for p in (tmp_path / "out").glob("lfm_*_z*um.json")),
                      key=lambda r: r["a"])
    z = [r["z_um"] for r in sidecars]
    assert float(pixels.get("PhysicalSizeX")) == pytest.approx(6.25)
    assert float(pixels.get("PhysicalSizeZ")) == pytest.approx(z[1] - z[0], rel=1e-9)
    assert [float(p.get("PositionZ")) for p in pixels.findall("ome:Plane", ns)] == pytest.approx(z)


def test_batch_writes_the_same_stack_as_refocus(tmp_path):
    """``lfproc batch --stack``: per capture the z-stack ``lfproc refocus --stack`` writes, byte for byte."""
    camera = Camera.from_toml(LFM_20X)
    m = camera.m_hat
    views = np.random.default_rng(4).random((m, m, 9, 10, 1)).astype(np.float32)
    LightField.from_views(views, camera).save(tmp_path / "lfm.lfp.npz")
    args = ["--a", "-0.1,0,0.1", "--stack", "imagej"]
    single = run_cli("refocus", tmp_path / "lfm.lfp.npz", *args, "-o", tmp_path / "single")
    batch = run_cli("batch", tmp_path / "lfm.lfp.npz", *args, "--workers", "1", "-o", tmp_path / "batch")
    assert single.returncode == 0, single.stderr
    assert batch.returncode == 0, batch.stderr
    with tifffile.TiffFile(tmp_path / "single" / "lfm_stack.tif") as a, \
            tifffile.TiffFile(tmp_path / "batch" / "lfm_stack.tif") as b:
        assert np.array_equal(a.asarray(), b.asarray())
        assert a.imagej_metadata == b.imagej_metadata
        assert a.imagej_metadata["unit"] == "micron" and a.asarray().shape == (3, 9, 10)
