"""``lfproc batch`` (issue 8): a folder of simulated captures, processed locally and on a Dask cluster.

The reference is one local run (2 worker processes). Every other run must produce the same files, byte
for byte: on a dask.distributed ``LocalCluster``, with a worker killed mid-run (Dask and local pool),
after an interruption and a rerun, after deleting an output. Reruns must skip exactly the captures
whose outputs and parameters are unchanged, without touching their files; a corrupt capture is failed
alone, with its error in the manifest and the summary, and exit status 2.
"""

import contextlib
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import time

import pytest

from lfproc import batch, simulate
from lfproc.camera import Camera
from lfproc.cli import main
from lfproc.io import write_image
from lfproc.simulate import Noise, Plane, Scene

import faults
from conftest import ROOT, assert_clean_error, run_cli

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
    from lfproc.api import prepare_decoding

    camera = Camera.from_toml(data / "camera.toml")
    lf = prepare_decoding(camera, white=str(data / "white.png"), cache=True).decode(str(data / "captures" / "cap0.png"))
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


def run_cli_with_faults(argv, spec, popen=False):
    """``python -m lfproc ARGV`` with tests/faults.py's ``spec`` installed in it and in every process it
    starts; ``popen``: started in its own process group (as a shell job) and returned running."""
    env = dict(os.environ, PYTHONUNBUFFERED="1", LFPROC_FAULTS=json.dumps(spec),
               PYTHONPATH=os.pathsep.join([str(ROOT / "tests" / "fault_site"), str(ROOT),
                                           os.environ.get("PYTHONPATH", "")]))
    command = [sys.executable, "-m", "lfproc", *map(str, argv)]
    if popen:
        return subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
                                start_new_session=True)
    return subprocess.run(command, capture_output=True, text=True, env=env, timeout=300)


def without_warnings(stderr: str) -> str:
    """A batch's stderr without its summary of the captures' warnings (every capture here warns at a = 1.5)."""
    lines = stderr.splitlines(keepends=True)
    start = next((i for i, line in enumerate(lines) if "captures processed warned" in line), len(lines))
    end = start + 1
    while end < len(lines) and lines[end].startswith("  "):
        end += 1
    return "".join(lines[:start] + lines[end:])


def partial_files(outdir) -> list:
    return [name for name in os.listdir(outdir) if ".part" in name]


@pytest.fixture(scope="module")
def reference(data):
    """The local run everything else is compared with: 2 worker processes."""
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
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=None) as lc, \
            distributed.Client(lc) as client:
        yield lc, client


# ----------------------------------------------------------------------------- same bytes everywhere
def test_batch_outputs_are_those_of_lfproc_refocus(data, reference, tmp_path):
    """Batching changes nothing in an output: cap0's slices equal `lfproc refocus`'s, byte for byte."""
    proc = run_cli("refocus", data / "captures" / "cap0.png", "--camera", data / "camera.toml",
                   "--white", data / "white.png", "--a", REFOCUS, "-o", tmp_path)
    assert proc.returncode == 0, proc.stderr
    single = tree_bytes(tmp_path)
    assert sorted(single) == ["cap0_00_a+0.000.json", "cap0_00_a+0.000.tif", "cap0_01_a+1.500.json", "cap0_01_a+1.500.tif"]
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


# ----------------------------------------------------------------------------- lost workers (tests/faults.py)
def test_a_dask_worker_killed_mid_capture_still_completes(data, reference, cluster, tmp_path):
    """A worker SIGKILLs itself just before its 10th file of cap1 (temporary files of cap1 exist): the
    scheduler reruns the task elsewhere, the batch exits 0 and its outputs are the local run's, file for file."""
    lc, client = cluster
    marker = tmp_path / "killed"
    client.run(faults.install, {"kill": {"stem": "cap1", "after": 10, "marker": str(marker)}})
    try:
        proc = run_cli(*batch_argv(data, tmp_path / "out", "--scheduler", lc.scheduler_address), timeout=300)
    finally:
        client.run(faults.uninstall)
    assert proc.returncode == 0, proc.stderr
    assert marker.is_file()
    victim = int(marker.read_text())
    assert victim not in client.run(os.getpid).values()  # that worker process is gone (its nanny started another)
    assert statuses(tmp_path / "out") == {f"cap{i}.png": ("done", "done") for i in range(4)}
    assert tree_bytes(tmp_path / "out") == reference[1]  # and nothing the killed worker had half-written remains


def test_a_local_worker_process_killed_mid_capture_still_completes(data, reference, tmp_path):
    """The same for a local worker process: its capture is retried in a fresh process, the others are not charged."""
    marker = tmp_path / "killed"
    proc = run_cli_with_faults(batch_argv(data, tmp_path / "out", "--workers", "2"),
                               {"kill": {"stem": "cap1", "after": 10, "marker": str(marker)}})
    assert proc.returncode == 0, proc.stderr
    assert without_warnings(proc.stderr) == ""
    assert marker.is_file()  # a worker died (the batch itself exited 0)
    assert statuses(tmp_path / "out") == {f"cap{i}.png": ("done", "done") for i in range(4)}
    assert tree_bytes(tmp_path / "out") == reference[1]


# ----------------------------------------------------------------------------- resumability
def test_rerun_skips_everything_and_redoes_exactly_what_changed(data, reference, tmp_path):
    out = tmp_path / "moved"
    shutil.copytree(reference[0], out)  # outputs are recorded relative to OUTDIR: a moved folder still resumes
    before = tree_stats(out)

    assert main(batch_argv(data, out, "--workers", "1")) == 0
    assert manifest(out)["summary"] | {"seconds": 0} == {"done": 0, "skipped": 4, "failed": 0, "total": 4,
                                                          "seconds": 0, "interrupted": False, "warned": 0,
                                                          "failed_captures": []}
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
    assert all((out / f"cap{i}_01_a+2.000.tif").is_file() for i in range(4))
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


# ----------------------------------------------------------------------------- real interrupts (issue 23)
def journal_done(outdir) -> set:
    """Stems of the captures recorded done so far (the journal, then the manifest once saved)."""
    done = set()
    for path in (outdir / batch.MANIFEST_NAME, outdir / batch.JOURNAL_NAME):
        with contextlib.suppress(FileNotFoundError, ValueError):
            if path.name == batch.MANIFEST_NAME:
                entries = json.loads(path.read_text())["captures"].items()
            else:
                entries = [json.loads(line) for line in path.read_text().splitlines() if line.endswith("}]")]
            done |= {os.path.basename(src)[:-4] for src, e in entries if e["status"] == "done"}
    return done


def poll(condition, proc=None, timeout_s=180.0, what=""):
    """Wait (bounded) until ``condition()``; fail at once if ``proc`` exits first."""
    deadline = time.monotonic() + timeout_s
    while not condition():
        if proc is not None and proc.poll() is not None:
            raise AssertionError(f"exited before {what}: {proc.communicate()}")
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        time.sleep(0.02)


def live_processes(pgid) -> list:
    """pids of the processes of group ``pgid`` that are still running (zombies are gone already)."""
    alive = []
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            with contextlib.suppress(OSError):
                stat = open(f"/proc/{entry}/stat").read()
                fields = stat[stat.rindex(")") + 2:].split()
                if int(fields[2]) == pgid and fields[0] != "Z":
                    alive.append(int(entry))
    return alive


def ctrl_c_when(proc, ready, what: str):
    """Once ``ready()``, Ctrl-C the batch's whole process group; returns (its stderr, seconds until every one
    of its processes was gone). Whatever happens, nothing of the group outlives the test."""
    try:
        poll(ready, proc, what=what)
        os.killpg(proc.pid, signal.SIGINT)
        signalled = time.monotonic()
        poll(lambda: not live_processes(proc.pid), timeout_s=60, what="every process to end")
        gone_s = time.monotonic() - signalled
        _, stderr = proc.communicate(timeout=60)
    finally:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(proc.pid, signal.SIGKILL)
    return stderr, gone_s


def assert_only_recorded_outputs(outdir, data):
    """Every file in OUTDIR belongs to a capture recorded done, all of its files: a stopped capture left
    nothing."""
    done = journal_done(outdir)
    names = [n for n in os.listdir(outdir) if n not in BOOKKEEPING]
    assert not partial_files(outdir)
    assert {n.split("_")[0] for n in names} == done, (sorted(names)[:5], done)
    assert len(names) == len(done) * files_per_capture(data)


SLOW = {"stems": ["cap1", "cap2", "cap3"], "seconds": 0.15}


@pytest.mark.alone
def test_ctrl_c_stops_a_local_batch_at_once_and_the_rerun_does_only_the_rest(data, reference, tmp_path):
    """SIGINT to the process group (what Ctrl-C does) while cap0 is recorded and cap1 is being written:
    one stderr line, exit 130, every lfproc process gone within 2 s, cap0 in the manifest, nothing of
    cap1, no lock; the rerun skips cap0 and does the rest, and the outputs are the reference's."""
    out, announced = tmp_path / "out", tmp_path / "announced"
    announced.mkdir()
    proc = run_cli_with_faults(batch_argv(data, out, "--workers", "2"), {"announce": str(announced), "slow": SLOW},
                               popen=True)
    stderr, gone_s = ctrl_c_when(proc, lambda: "cap0" in journal_done(out) and (announced / "cap1").exists(),
                                 "cap0 done, cap1 begun")
    assert proc.returncode == 130, stderr
    assert len(stderr.splitlines()) == 1 and "interrupted" in stderr and "Traceback" not in stderr, stderr
    assert gone_s < 2.0, gone_s
    assert "cap1" not in journal_done(out) and not (out / batch.JOURNAL_NAME).exists()
    assert_only_recorded_outputs(out, data)
    assert not (out / batch.LOCK_NAME).exists()
    done_first = journal_done(out)

    assert main(batch_argv(data, out, "--workers", "2")) == 0
    again = manifest(out)["summary"]
    assert (again["skipped"], again["done"]) == (len(done_first), 4 - len(done_first))
    assert tree_bytes(out) == reference[1]


@pytest.mark.alone
def test_ctrl_c_while_the_workers_start_is_one_line_too(data, tmp_path):
    """The tracebacks of issue 23 came from workers hit by Ctrl-C while their interpreter started
    (multiprocessing/spawn.py … KeyboardInterrupt): SIGINT to the group exactly then."""
    out, starting = tmp_path / "out", tmp_path / "starting"
    starting.mkdir()
    proc = run_cli_with_faults(batch_argv(data, out, "--workers", "2"),
                               {"starting": {"dir": str(starting), "seconds": 0.3}}, popen=True)
    stderr, gone_s = ctrl_c_when(proc, lambda: any(starting.iterdir()), "a worker to start")
    assert proc.returncode == 130, stderr
    assert len(stderr.splitlines()) == 1 and "interrupted" in stderr, stderr
    assert gone_s < 2.0, gone_s
    assert_only_recorded_outputs(out, data)


def test_a_killed_batch_resumes_from_its_journal_and_takes_over_its_lock(data, reference, tmp_path):
    """SIGKILL to the batch process itself (no chance to save anything): its workers end with it, the
    captures it had recorded are skipped by the rerun, which takes the dead process's lock over with one
    line and removes what the workers left half-written."""
    out, announced = tmp_path / "out", tmp_path / "announced"
    announced.mkdir()
    proc = run_cli_with_faults(batch_argv(data, out, "--workers", "2"), {"announce": str(announced), "slow": SLOW},
                               popen=True)
    try:
        poll(lambda: "cap0" in journal_done(out) and (announced / "cap1").exists(), proc, what="cap0 done, cap1 begun")
        os.kill(proc.pid, signal.SIGKILL)
        proc.communicate(timeout=60)
        poll(lambda: not live_processes(proc.pid), timeout_s=60, what="the workers to end with their parent")
    finally:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(proc.pid, signal.SIGKILL)
    assert not (out / batch.MANIFEST_NAME).exists() and (out / batch.LOCK_NAME).exists()
    assert journal_done(out) == {"cap0"}

    rerun = run_cli(*batch_argv(data, out, "--workers", "2"))
    assert rerun.returncode == 0, rerun.stderr
    assert without_warnings(rerun.stderr).splitlines() == [
                                         f"lfproc batch: note: took over the lock of process {proc.pid} on "
                                         f"{socket.gethostname()}, since {rerun.stderr.split('since ')[1].split(',')[0]}, "
                                         f"which is no longer running (interrupted or killed); resuming"]
    summary = manifest(out)["summary"]
    assert (summary["skipped"], summary["done"]) == (1, 3)
    assert tree_bytes(out) == reference[1] and not (out / batch.LOCK_NAME).exists()


def _busy_threads(dask_worker):
    return len(dask_worker.active_threads)


def test_ctrl_c_stops_a_dask_batch_and_its_tasks_write_nothing_more(data, reference, cluster, tmp_path):
    """SIGINT to a batch running on a real scheduler (two workers on 127.0.0.1): one stderr line, exit 130;
    the tasks still computing abandon their capture (nothing of it lands in OUTDIR, even later); the rerun
    does only the rest."""
    lc, client = cluster
    out, announced = tmp_path / "out", tmp_path / "announced"
    announced.mkdir()
    client.run(faults.install, {"announce": str(announced), "slow": SLOW})
    try:
        proc = subprocess.Popen([sys.executable, "-m", "lfproc", *batch_argv(data, out, "--scheduler",
                                                                              lc.scheduler_address)],
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True)
        poll(lambda: journal_done(out) and any(p.name not in journal_done(out) for p in announced.iterdir()), proc,
             what="a capture done and another begun")
        os.killpg(proc.pid, signal.SIGINT)
        _, stderr = proc.communicate(timeout=60)
        poll(lambda: not any(client.run(_busy_threads).values()), timeout_s=120, what="the workers to go idle")
    finally:
        client.run(faults.uninstall)
    assert proc.returncode == 130, stderr
    assert len(stderr.splitlines()) == 1 and "interrupted" in stderr, stderr
    done_first = journal_done(out)
    assert 1 <= len(done_first) < 4
    assert_only_recorded_outputs(out, data)

    assert run_cli(*batch_argv(data, out, "--scheduler", lc.scheduler_address)).returncode == 0
    again = manifest(out)["summary"]
    assert (again["skipped"], again["done"]) == (len(done_first), 4 - len(done_first))
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
        assert_clean_error(run_cli(*batch_argv(data, tmp_path, "--workers", "1")), "another batch (process")
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


def test_warnings_are_recorded_per_capture_and_summed_up_once(data, tmp_path, capsys):
    """Every LfprocWarning a capture gives is in its manifest entry, worded for the command line; the command
    says how many captures warned and each distinct warning once (here a = 1.5: fewer than half the pixels of
    these 21 x 28 lenses average all views, for every capture alike)."""
    inputs = [str(data / "captures" / name) for name in ("cap0.png", "cap1.png")]
    out = tmp_path / "out"
    argv = ["batch", *inputs, "--camera", str(data / "camera.toml"), "--white", str(data / "white.png"),
            "--a", "0,1.5", "--workers", "1", "-o", str(out)]
    assert main(argv) == 0
    err = capsys.readouterr().err
    entries = manifest(out)["captures"]
    for source in inputs:
        said = entries[source]["warnings"]
        assert len(said) == 1 and said[0].startswith(f"{source}: in 1 slice(s) (up to a=+1.5) fewer than half"), said
    assert manifest(out)["summary"]["warned"] == 2
    assert "2 of 2 captures processed warned" in err
    assert err.count("fewer than half the pixels") == 1 and "(and 1 more capture(s) alike)" in err
    assert main(argv) == 0                       # a rerun skips both: nothing new to say, the entries keep theirs
    assert "warned" not in capsys.readouterr().err
    assert [entries[s]["warnings"] for s in inputs] == [manifest(out)["captures"][s]["warnings"] for s in inputs]
