"""``lfproc batch`` (issue 8): a folder of simulated captures, processed locally and on a Dask cluster.

The reference is one local run (2 worker processes). Every other run must produce the same files, byte
for byte: on a dask.distributed ``LocalCluster``, with a worker killed mid-run (Dask and local pool),
after an interruption and a rerun, after deleting an output. Reruns must skip exactly the captures
whose outputs and parameters are unchanged, without touching their files; a corrupt capture is failed
alone, with its error in the manifest and the summary, and exit status 2.
"""

import concurrent.futures
import json
import multiprocessing
import os
import shutil
import signal
import subprocess
import sys
import time

import pytest

from lfproc import batch, simulate
from lfproc.camera import Camera
from lfproc.cli import main
from lfproc.io import write_image
from lfproc.simulate import Noise, Plane, Scene

from conftest import assert_clean_error, run_cli

# 7 px per lens (m̂ = 7: 49 views), Bayer, 12-bit: small and fast, yet the whole pipeline
CAMERA_TOML = """name = "batch-test"
[sensor]
pixel_pitch_mm = 0.01
cfa = "RGGB"
black_level = 64
white_level = 4095
[mla]
pitch_mm = 0.07
focal_length_mm = 0.28
principal_plane_gap_mm = 0.0
grid = "rectangular"
[main_lens]
focal_length_mm = 50.0
principal_plane_gap_mm = 0.0
image_distance_mm = 50.0
f_number = 4.0
"""
PLANE_DISTANCES_MM = (300.0, 500.0, 900.0, 2000.0)
REFOCUS = "0,1.5"
N_VIEWS = 49


def files_per_capture(data) -> int:
    """Slices and the views that carry light (the only ones written), each with its sidecar."""
    from lfproc.pipeline import load_lightfield, prepare_decoding

    camera = Camera.from_toml(data / "camera.toml")
    lf = load_lightfield(str(data / "captures" / "cap0.png"), prepare_decoding(camera, white=str(data / "white.png")))
    lit = N_VIEWS if lf.view_mask is None else int(lf.view_mask.sum())
    return 2 * (len(REFOCUS.split(",")) + lit)
BOOKKEEPING = {batch.MANIFEST_NAME, batch.LOCK_NAME}


@pytest.fixture(scope="module")
def data(tmp_path_factory):
    """Four captures of a textured plane at different distances (different noise seeds), a white image, a camera."""
    root = tmp_path_factory.mktemp("batch")
    camera = Camera.from_toml_string(CAMERA_TOML)
    assert camera.m_hat ** 2 == N_VIEWS
    (root / "captures").mkdir()
    for i, distance in enumerate(PLANE_DISTANCES_MM):
        scene = Scene((Plane(distance, Noise(feature_mm=4.0, seed=i + 1)),), background=0.05)
        sim = simulate.render(camera, scene, (150, 200), rotation_deg=0.3, offset_px=(0.2, -0.1), seed=i,
                              read_noise_dn=1.0, ideal_views=False)
        write_image(root / "captures" / f"cap{i}.png", sim.raw)
    write_image(root / "white.png", sim.white)
    (root / "camera.toml").write_text(camera.to_toml())
    return root


def batch_argv(data, outdir, *extra, inputs=None, refocus=REFOCUS):
    return ["batch", str(inputs or data / "captures"), "--camera", str(data / "camera.toml"),
            "--white", str(data / "white.png"), "-o", str(outdir), "--refocus", refocus, "--views", *extra]


def tree_bytes(folder) -> dict:
    """Every file in ``folder`` (hidden ones too) but the manifest and lock: name -> bytes."""
    return {name: (folder / name).read_bytes() for name in sorted(os.listdir(folder)) if name not in BOOKKEEPING}


def tree_stats(folder) -> dict:
    """name -> (inode, mtime_ns): a rewritten file (atomic rename) gets a new inode."""
    return {name: ((st := os.stat(folder / name)).st_ino, st.st_mtime_ns)
            for name in os.listdir(folder) if name not in BOOKKEEPING}


def manifest(outdir) -> dict:
    return json.loads((outdir / batch.MANIFEST_NAME).read_text())


def statuses(outdir) -> dict:
    return {os.path.basename(src): (e["status"], e["last_run"]) for src, e in manifest(outdir)["captures"].items()}


def without_timing(entries: dict) -> dict:
    return {src: {k: v for k, v in e.items() if k != "seconds"} for src, e in entries.items()}


def partial_files(outdir) -> list:
    return [name for name in os.listdir(outdir) if ".part" in name]


@pytest.fixture(scope="module")
def reference(data):
    """The local run everything else is compared with: 2 worker processes, in a subprocess like a user's."""
    out = data / "ref"
    proc = run_cli(*batch_argv(data, out, "--workers", "2"))
    assert proc.returncode == 0, proc.stderr
    assert statuses(out) == {f"cap{i}.png": ("done", "done") for i in range(4)}
    files = tree_bytes(out)
    assert len(files) == 4 * files_per_capture(data) and not partial_files(out)
    summary = manifest(out)["summary"]
    assert (summary["done"], summary["skipped"], summary["failed"], summary["interrupted"]) == (4, 0, 0, False)
    return out, files


@pytest.fixture(scope="module")
def cluster():
    import distributed  # a test dependency (pyproject [test]): never skipped
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as lc, \
            distributed.Client(lc) as client:
        yield lc, client


# ----------------------------------------------------------------------------- same bytes everywhere
def test_batch_outputs_are_those_of_lfproc_refocus(data, reference, tmp_path):
    """Batching changes nothing in an output: cap0's slices equal `lfproc refocus`'s, byte for byte."""
    proc = run_cli("refocus", data / "captures" / "cap0.png", "--camera", data / "camera.toml",
                   "--white", data / "white.png", "--a", REFOCUS, "-o", tmp_path)
    assert proc.returncode == 0, proc.stderr
    single = tree_bytes(tmp_path)
    assert sorted(single) == ["cap0_a+0.000.json", "cap0_a+0.000.tif", "cap0_a+1.500.json", "cap0_a+1.500.tif"]
    assert single == {name: reference[1][name] for name in single}


def _seeded_grids():
    from lfproc import batch as worker_batch
    return len(worker_batch._GRID_SEEDS)


def test_dask_cluster_gives_byte_identical_outputs(data, reference, cluster, tmp_path):
    lc, client = cluster
    proc = run_cli(*batch_argv(data, tmp_path, "--scheduler", lc.scheduler_address))
    assert proc.returncode == 0, proc.stderr
    assert tree_bytes(tmp_path) == reference[1]
    # the workers built their setups from the grid the batch process fitted, not by calibrating again
    assert all(n >= 1 for n in client.run(_seeded_grids).values())
    assert without_timing(manifest(tmp_path)["captures"]) == without_timing(manifest(reference[0])["captures"])


def _kill_a_busy_dask_worker(client, timeout_s=20.0):
    """SIGKILL a worker process that holds lfproc tasks; returns (its address, the keys it held)."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        for address, keys in client.processing().items():
            keys = [k for k in keys if str(k).startswith("lfproc-")]
            if keys:
                pid = client.run(os.getpid, workers=[address])[address]
                os.kill(pid, signal.SIGKILL)
                return address, keys
        time.sleep(0.005)
    raise AssertionError("no worker was processing an lfproc task")


def test_a_dask_worker_killed_mid_run_still_completes(data, reference, cluster, tmp_path, monkeypatch):
    _, client = cluster
    killed = []
    run_dask = batch.run_dask

    def run_dask_killing_a_worker(jobs, scheduler, on_result, **kwargs):
        def on_result_then_kill(job, result):
            on_result(job, result)
            if not killed:  # after the first result, while the others run
                killed.append(_kill_a_busy_dask_worker(client))
        return run_dask(jobs, client, on_result_then_kill, **kwargs)  # one Client (event loop) in this process

    monkeypatch.setattr(batch, "run_dask", run_dask_killing_a_worker)
    assert main(batch_argv(data, tmp_path, "--scheduler", client.scheduler.address)) == 0
    assert killed
    address, keys = killed[0]
    # the scheduler took the killed worker's tasks back from it and ran them elsewhere
    story = [record for record in client.story(*keys) if record[0] == "scheduler"]
    assert any(record[2:4] == ("processing", "released") for record in story), story
    assert address not in client.scheduler_info()["workers"]
    assert statuses(tmp_path) == {f"cap{i}.png": ("done", "done") for i in range(4)}
    assert tree_bytes(tmp_path) == reference[1]  # and nothing half-written by the killed worker remains


def test_a_local_worker_process_killed_mid_run_still_completes(data, reference, tmp_path, monkeypatch):
    killed, pools = [], []
    run_local = batch.run_local

    class CountedPool(concurrent.futures.ProcessPoolExecutor):
        def __init__(self, *args, **kwargs):
            pools.append(self)
            super().__init__(*args, **kwargs)

    def run_local_killing_a_worker(jobs, workers, on_result, **kwargs):
        others = {p.pid for p in multiprocessing.active_children()}  # e.g. the Dask cluster's processes

        def on_result_then_kill(job, result):
            on_result(job, result)
            if not killed:
                victim = next(p for p in multiprocessing.active_children() if p.pid not in others)
                os.kill(victim.pid, signal.SIGKILL)
                killed.append(victim.pid)
        return run_local(jobs, workers, on_result_then_kill, **kwargs)

    monkeypatch.setattr(batch, "run_local", run_local_killing_a_worker)
    monkeypatch.setattr(concurrent.futures, "ProcessPoolExecutor", CountedPool)
    assert main(batch_argv(data, tmp_path, "--workers", "2")) == 0
    assert killed
    assert len(pools) >= 2  # the kill broke the first pool; the captures it held ran again in fresh ones
    assert statuses(tmp_path) == {f"cap{i}.png": ("done", "done") for i in range(4)}
    assert tree_bytes(tmp_path) == reference[1]


# ----------------------------------------------------------------------------- resumability
def test_rerun_skips_everything_and_redoes_exactly_what_changed(data, reference, tmp_path):
    out = tmp_path / "moved"
    shutil.copytree(reference[0], out)  # outputs are recorded relative to OUTDIR: a moved folder still resumes
    before = tree_stats(out)

    assert main(batch_argv(data, out, "--workers", "1")) == 0
    assert manifest(out)["summary"] | {"seconds": 0} == {"done": 0, "skipped": 4, "failed": 0, "total": 4,
                                                          "seconds": 0, "interrupted": False, "failed_captures": []}
    assert statuses(out) == {f"cap{i}.png": ("done", "skipped") for i in range(4)}
    assert tree_stats(out) == before  # not a single file rewritten

    os.remove(out / "cap2_view_03_04.json")  # a lost sidecar: cap2 alone is redone
    assert main(batch_argv(data, out, "--workers", "1")) == 0
    assert statuses(out) == {"cap0.png": ("done", "skipped"), "cap1.png": ("done", "skipped"),
                             "cap2.png": ("done", "done"), "cap3.png": ("done", "skipped")}
    after = tree_stats(out)
    assert {name for name in before if after[name] != before[name]} == \
        {name for name in before if name.startswith("cap2_")}
    assert tree_bytes(out) == reference[1]

    assert main(batch_argv(data, out, "--workers", "1", refocus="0,2")) == 0  # a changed parameter: all redone
    assert statuses(out) == {f"cap{i}.png": ("done", "done") for i in range(4)}
    assert all((out / f"cap{i}_a+2.000.tif").is_file() for i in range(4))
    assert manifest(out)["captures"][str(data / "captures" / "cap0.png")]["parameters"]["refocus_a"] == [0.0, 2.0]


@pytest.mark.parametrize("workers, signum", [(1, signal.SIGINT), (2, signal.SIGTERM)])
def test_an_interrupted_run_leaves_no_partial_file_and_a_rerun_completes(data, reference, tmp_path, workers, signum):
    out = tmp_path / "out"
    proc = subprocess.Popen([sys.executable, "-m", "lfproc", *batch_argv(data, out, "--workers", str(workers))],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 60
    # as soon as the first (temporary) image file appears: the signal lands while files are being written
    while not (out.is_dir() and any(name.endswith(".tif") for name in os.listdir(out))):
        assert proc.poll() is None and time.monotonic() < deadline, proc.communicate()
        time.sleep(0.005)
    proc.send_signal(signum)
    _, stderr = proc.communicate(timeout=60)
    assert proc.returncode == 130, stderr
    assert "interrupted" in stderr
    assert "rerun the same command to resume" in stderr and "of 4 captures" in stderr   # counts and the hint
    assert partial_files(out) == []
    first = manifest(out)
    assert first["summary"]["interrupted"] is True
    done_first = {src for src, e in first["captures"].items() if e["status"] == "done"}
    assert len(done_first) < 4

    assert main(batch_argv(data, out, "--workers", "1")) == 0
    again = manifest(out)
    assert (again["summary"]["skipped"], again["summary"]["done"]) == (len(done_first), 4 - len(done_first))
    assert tree_bytes(out) == reference[1]


# ----------------------------------------------------------------------------- failures
def test_a_corrupt_capture_is_reported_and_the_rest_complete(data, tmp_path):
    inputs = tmp_path / "captures"
    shutil.copytree(data / "captures", inputs)
    good = (inputs / "cap1.png").read_bytes()
    (inputs / "cap1.png").write_bytes(good[: len(good) // 2])  # truncated mid-transfer
    out = tmp_path / "out"

    proc = run_cli(*batch_argv(data, out, "--workers", "2", inputs=inputs))
    assert proc.returncode == 2, proc.stderr
    assert f"failed: {inputs / 'cap1.png'}" in proc.stdout
    assert statuses(out) == {"cap0.png": ("done", "done"), "cap1.png": ("failed", "failed"),
                             "cap2.png": ("done", "done"), "cap3.png": ("done", "done")}
    entry = manifest(out)["captures"][str(inputs / "cap1.png")]
    assert "truncated or corrupt" in entry["error"] and entry["outputs"] == []
    summary = manifest(out)["summary"]
    assert (summary["done"], summary["failed"]) == (3, 1)
    assert summary["failed_captures"] == [{"source": str(inputs / "cap1.png"), "error": entry["error"]}]
    assert not any(name.startswith("cap1_") for name in os.listdir(out)) and partial_files(out) == []

    (inputs / "cap1.png").write_bytes(good)  # repaired: the rerun does it, and only it
    assert main(batch_argv(data, out, "--workers", "1", inputs=inputs)) == 0
    assert statuses(out) == {"cap0.png": ("done", "skipped"), "cap1.png": ("done", "done"),
                             "cap2.png": ("done", "skipped"), "cap3.png": ("done", "skipped")}


def test_bad_setups_fail_at_once_with_one_line(data, tmp_path):
    broken_white = tmp_path / "white.png"
    broken_white.write_bytes(b"not an image")
    argv = batch_argv(data, tmp_path / "out")
    argv[argv.index("--white") + 1] = str(broken_white)
    assert_clean_error(run_cli(*argv), str(broken_white))
    assert not os.path.exists(tmp_path / "out")  # nothing written: no folder, no lock, no manifest
    assert_clean_error(run_cli(*batch_argv(data, tmp_path / "out", "--workers", "0")), "--workers")
    assert_clean_error(run_cli(*batch_argv(data, tmp_path / "out", "--workers", "2", "--scheduler", "tcp://x:1")),
                       "--scheduler")


def test_one_batch_at_a_time_per_output_folder(data, tmp_path):
    with batch.lock_outdir(str(tmp_path)):  # as if another lfproc batch were running on this folder
        assert_clean_error(run_cli(*batch_argv(data, tmp_path, "--workers", "1")), "another lfproc batch")
    assert not os.path.exists(tmp_path / batch.MANIFEST_NAME)


# ----------------------------------------------------------------------------- sizing
def test_default_workers_follow_cores_and_memory(data, monkeypatch):
    sample = str(data / "captures" / "cap0.png")
    per_process = batch.PROCESS_BASE_BYTES + 150 * 200 * batch.BYTES_PER_SENSOR_PIXEL
    monkeypatch.setattr(os, "cpu_count", lambda: 64)
    monkeypatch.setattr(batch._resources, "available_memory_bytes", lambda: 2 * 5.5 * per_process)
    assert batch.default_workers(sample) == 5            # half the memory holds 5.5 processes
    monkeypatch.setattr(batch._resources, "available_memory_bytes", lambda: 1e15)
    assert batch.default_workers(sample) == 64           # the cores
    monkeypatch.setattr(batch._resources, "available_memory_bytes", lambda: 1.0)
    assert batch.default_workers(sample) == 1            # never fewer than one
    assumed = batch.PROCESS_BASE_BYTES + 40e6 * batch.BYTES_PER_SENSOR_PIXEL
    monkeypatch.setattr(batch._resources, "available_memory_bytes", lambda: 2 * 3.5 * assumed)
    assert batch.default_workers(None) == 3              # unknown size: a 40-megapixel sensor is assumed


def test_calib_only_fingerprints_the_recorded_white_image(data, tmp_path):
    """With --calib alone the white image named in GRID.json is used, so replacing it redoes the captures."""
    import shutil

    white = tmp_path / "white.png"
    shutil.copy(data / "white.png", white)
    grid_path = tmp_path / "grid.json"
    proc = run_cli("calibrate", white, "--camera", data / "camera.toml", "-o", grid_path)
    assert proc.returncode == 0, proc.stderr
    out = tmp_path / "out"
    argv = ["batch", data / "captures" / "cap0.png", "--camera", data / "camera.toml", "--calib", grid_path,
            "--refocus", "1", "-o", out, "--workers", "1"]
    assert run_cli(*argv).returncode == 0
    manifest = json.loads((out / batch.MANIFEST_NAME).read_text())
    assert manifest["parameters"]["white"] == str(white)
    assert run_cli(*argv).returncode == 0
    assert json.loads((out / batch.MANIFEST_NAME).read_text())["summary"]["skipped"] == 1
    os.utime(white, ns=(1, 1))  # the recorded white image changed: the capture is redone
    assert run_cli(*argv).returncode == 0
    assert json.loads((out / batch.MANIFEST_NAME).read_text())["summary"]["done"] == 1
