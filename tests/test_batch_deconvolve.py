"""``lfproc batch --deconvolve`` (issue 39): a time-lapse of light-field microscope frames into volumes.

Frames: three small light fields (.lfp.npz) of two points that move, rendered by the wave model. The reference
is ``lfproc deconvolve`` run on each frame alone. A batch in local worker processes and one on a dask.distributed
``LocalCluster`` give the same volume files, byte for byte, and build the operators exactly once: counted in
the process that starts the batch (``lfproc.wave.build_operators`` wrapped; workers are given the operators and
never call it: a job without them fails), and recorded as built once in the manifest; the cache holds one entry.
A rerun skips every frame and builds nothing.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

import lfproc
import lfproc.wave
from lfproc import batch
from lfproc.camera import MainLens, Microscope
from lfproc.simulate import lens_of_point
from lfproc.wave import lens_radius, voxel_patterns

from conftest import assert_clean_error, run_cli

Z_RANGE = "-20:10:15"
OPTIONS = ("--z-range", Z_RANGE, "--iterations", "3", "--superres", "3")


def _camera():
    return lfproc.Camera(pixel_pitch_mm=0.125 / 7, mla_pitch_mm=0.125, mla_focal_length_mm=2.433,
                         main_optics=Microscope(20.0, 0.5, 1.33, 200.0, wavelength_nm=510.0), micro_image_px=7)


def _frame(camera, lenses, points):
    """Views (m̂, m̂, Ny, Nx, 1) of points (x, y, z) µm in the sample, through the wave model."""
    optics, m = camera.main_optics.wave_optics, camera.m_hat
    pitch_um, f_um = camera.mla_pitch_mm * 1000.0, camera.mla_focal_length_mm * 1000.0
    views = np.zeros((m, m) + lenses)
    for x, y, z in points:
        row, col = lens_of_point(camera, lenses, x, y)
        jy, jx = int(round(row)), int(round(col))
        r = lens_radius(optics, pitch_um, z)
        pattern = voxel_patterns(optics, pitch_um, f_um, m, 1, z, [((row - jy) * pitch_um, (col - jx) * pitch_um)],
                                 r)[0]
        views[:, :, jy - r:jy + r + 1, jx - r:jx + r + 1] += pattern
    return views[..., None]


@pytest.fixture(scope="module")
def frames(tmp_path_factory):
    """Three frames of a time-lapse and each one's volume from ``lfproc deconvolve`` alone."""
    folder = tmp_path_factory.mktemp("timelapse")
    camera = _camera()
    for t in range(3):
        points = ((-10.0 + 3 * t, 12.0, -20.0), (15.0, -8.0 + 4 * t, 10.0))
        lfproc.LightField.from_views(_frame(camera, (16, 16), points), camera).save(folder / f"t{t}.lfp.npz")
    single = folder / "single"
    for t in range(3):
        proc = run_cli("deconvolve", folder / f"t{t}.lfp.npz", *OPTIONS, "-o", single)
        assert proc.returncode == 0, proc.stderr
    return folder, {p.name: p.read_bytes() for p in sorted(single.glob("*_volume.ome.tif"))}


def _counted_builds(monkeypatch, tmp_path):
    """A fresh cache, and a counter of the operators built in this process."""
    monkeypatch.setenv("LFPROC_CACHE_DIR", str(tmp_path / "cache"))
    builds = []
    build = lfproc.wave.build_operators

    def counting(*args, **kwargs):
        builds.append(args[1])
        return build(*args, **kwargs)

    monkeypatch.setattr(lfproc.wave, "build_operators", counting)
    return builds


def _check(folder, reference, out, builds):
    volumes = {p.name: p.read_bytes() for p in sorted(out.glob("*_volume.ome.tif"))}
    assert sorted(volumes) == ["t0_volume.ome.tif", "t1_volume.ome.tif", "t2_volume.ome.tif"]
    assert volumes == reference                               # byte for byte those of lfproc deconvolve
    manifest = json.loads((out / batch.MANIFEST_NAME).read_text())
    assert manifest["summary"]["done"] == 3 and manifest["operators"]["built"] == 1
    assert len(builds) == 1 and list(builds[0]) == [-20.0, -5.0, 10.0]
    assert len(list((out.parent / "cache").rglob("*.lfdec"))) == 1
    for t in range(3):
        record = json.loads((out / f"t{t}_volume.json").read_text())
        assert record["iterations"] == 3 and record["z_um"] == [-20.0, -5.0, 10.0]


def test_local_workers_give_the_volumes_of_one_by_one_runs_with_one_operator_build(frames, tmp_path, monkeypatch):
    folder, reference = frames
    builds = _counted_builds(monkeypatch, tmp_path)
    out = tmp_path / "out"
    proc = run_cli("batch", folder / "t*.lfp.npz", "--deconvolve", *OPTIONS, "--workers", "2", "-o", out)
    assert proc.returncode == 0, proc.stderr
    _check(folder, reference, out, builds)
    again = run_cli("batch", folder / "t*.lfp.npz", "--deconvolve", *OPTIONS, "--workers", "2", "-o", out)
    assert again.returncode == 0, again.stderr                # resumed: every frame skipped, nothing built
    manifest = json.loads((out / batch.MANIFEST_NAME).read_text())
    assert manifest["summary"]["skipped"] == 3 and "operators" not in manifest and len(builds) == 1


def test_a_dask_cluster_gives_the_same_volumes_with_one_operator_build(frames, tmp_path, monkeypatch):
    import distributed  # a test dependency (pyproject [test])

    folder, reference = frames
    builds = _counted_builds(monkeypatch, tmp_path)
    out = tmp_path / "out"
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=None) as cluster:
        proc = run_cli("batch", folder / "t*.lfp.npz", "--deconvolve", *OPTIONS, "--scheduler",
                       cluster.scheduler_address, "-o", out)
    assert proc.returncode == 0, proc.stderr
    _check(folder, reference, out, builds)


def test_a_worker_never_builds_operators(frames, tmp_path):
    """A deconvolution job run without the batch's operators fails with one line instead of building them."""
    folder, _ = frames
    job = batch.Job(str(folder / "t0.lfp.npz"), "t0", str(tmp_path), "", None, None, (), False,
                    deconvolve={"z_um": [-20.0, -5.0, 10.0], "iterations": 3, "superres": 3})
    result = batch.run_job(job)
    assert result.status == "failed" and "operators=" in result.error and not list(tmp_path.iterdir())


def test_bad_deconvolution_options_fail_at_once_with_one_line(frames, tmp_path):
    folder, _ = frames
    frame = folder / "t0.lfp.npz"
    assert_clean_error(run_cli("batch", frame, "--deconvolve", "-o", tmp_path / "a"), "--z-range")
    assert_clean_error(run_cli("batch", frame, "--deconvolve", "--z-range", "-20:10", "-o", tmp_path / "b"),
                       "Z0:Z1:STEP")
    assert_clean_error(run_cli("batch", frame, "--deconvolve", *OPTIONS[:2], "--superres", "9", "-o",
                               tmp_path / "c"), "superres")
    plain = lfproc.Camera(pixel_pitch_mm=0.125 / 7, mla_pitch_mm=0.125, mla_focal_length_mm=2.433,
                          main_optics=MainLens(100.0, 105.0), micro_image_px=7)
    lf = lfproc.LightField.load(frame)
    lfproc.LightField.from_views(lf.views, plain).save(tmp_path / "plain.lfp.npz")
    assert_clean_error(run_cli("batch", tmp_path / "plain.lfp.npz", "--deconvolve", *OPTIONS[:2], "-o",
                               tmp_path / "d"), "microscope")
    assert not any((tmp_path / name).exists() for name in "abcd")      # nothing written
