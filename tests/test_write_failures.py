"""Full disks and unwritable places (issue 23): a write that fails midway leaves no partial or temporary
file, and the error is one LfprocError line naming the file.

In-process, tests/faults.py's ``disk_full`` makes every Python-level write into the folder fail with
ENOSPC after a few bytes (or the open fail with EACCES): the JSON, text, GIF, PNG/JPEG (Pillow), PLY and
``.lfp.npz`` writers, the batch manifest. OpenImageIO writes in C++, so the TIFF writer is tested with a
real kernel-level failure: the CLI in a subprocess under a file size limit (RLIMIT_FSIZE: writes past it
fail with EFBIG), as a filling disk would.
"""

import errno
import os
import resource
import subprocess
import sys

import numpy as np
import pytest

from lfproc import LfprocError
from lfproc.atomic import write_json_atomic, write_text_atomic

import faults
from conftest import SAMPLES, assert_clean_error

FRAME = np.linspace(0.0, 1.0, 48 * 64 * 3, dtype=np.float32).reshape(48, 64, 3)


def _sidecar(path):
    from lfproc.io import write_sidecar
    write_sidecar(path.with_suffix(".tif"), {"source": "x" * 5000, "a": 1.0})


def _gif(path):
    from lfproc.io import write_gif
    write_gif(path.with_suffix(".gif"), [FRAME, FRAME[::-1]], 100)


def _preview_gif(path):
    from lfproc.outputs._previews import write_gif_frames
    noise = np.random.default_rng(0).integers(0, 255, (3, 40, 40, 3), dtype=np.uint8)
    write_gif_frames(path.with_suffix(".gif"), list(noise), 100)


def _ply(path):
    from lfproc.depth._pointcloud import write_ply
    write_ply(str(path.with_suffix(".ply")), np.ones((500, 3), np.float32))


def _viewer_png(path):
    from lfproc.viewer._images import save_8bit
    save_8bit(str(path.with_suffix(".png")), (FRAME * 255).astype(np.uint8))


def _viewer_jpeg(path):
    from lfproc.viewer._images import save_8bit
    save_8bit(str(path.with_suffix(".jpg")), (FRAME * 255).astype(np.uint8))


def _lightfield(path):
    from lfproc import LightField
    LightField(np.ones((3, 3, 8, 8, 1), np.float32)).save(path.with_suffix(".lfp.npz"))


def _json(path):
    write_json_atomic(path.with_suffix(".json"), {"values": list(range(2000))})


def _text(path):
    write_text_atomic(path.with_suffix(".html"), "<p>" * 5000)


def _manifest(path):
    from lfproc import batch
    manifest = batch.Manifest(str(path.parent), {"note": "x" * 5000})
    manifest.save({"done": 0})


WRITERS = [_sidecar, _gif, _preview_gif, _ply, _viewer_png, _viewer_jpeg, _lightfield, _json, _text, _manifest]


@pytest.mark.parametrize("code", [errno.ENOSPC, errno.EACCES], ids=["ENOSPC", "EACCES"])
@pytest.mark.parametrize("writer", WRITERS, ids=[w.__name__.strip("_") for w in WRITERS])
def test_a_write_failing_midway_leaves_nothing_and_names_the_file(writer, code, tmp_path, monkeypatch):
    out = tmp_path / "out"
    out.mkdir()
    faults.disk_full(monkeypatch, out, after_bytes=100, code=code)
    with pytest.raises(LfprocError) as info:
        writer(out / "product")
    message = str(info.value)
    assert "\n" not in message and str(out) in message
    assert os.strerror(code) in message
    assert os.listdir(out) == []  # neither the file nor its temporary file


def test_a_manifest_record_that_cannot_be_written_is_one_line(tmp_path, monkeypatch):
    """The journal line of each result goes through os.write: a full disk there stops the batch with one
    line (what was recorded before stays recorded)."""
    from lfproc import batch

    manifest = batch.Manifest(str(tmp_path), {})
    job = batch.Job(str(tmp_path / "cap.png"), "cap", str(tmp_path), "", None, None, (0.0,), False)
    manifest.record(job, batch.JobResult(job.source, "done", ()), "f1")
    real_write = os.write

    def write(fd, data):
        if len(data) > 10:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return real_write(fd, data)

    monkeypatch.setattr(os, "write", write)
    with pytest.raises(LfprocError, match="No space left on device") as info:
        manifest.record(job, batch.JobResult(job.source, "failed", (), "x"), "f2")
    assert batch.JOURNAL_NAME in str(info.value)
    monkeypatch.undo()
    assert batch.read_manifest(str(tmp_path))["captures"][job.source]["status"] == "done"


def _limit_file_size(limit_bytes):
    def limit():
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit_bytes, limit_bytes))
    return limit


def test_refocus_on_a_filling_disk_is_one_line_and_leaves_no_file(tmp_path):
    """A real write failure inside OpenImageIO (EFBIG at 8 KiB, as ENOSPC would come): exit 2, one line
    naming the slice, and the output folder holds nothing, not even a temporary file."""
    sample = SAMPLES / "sample"
    out = tmp_path / "out"
    out.mkdir()
    proc = subprocess.run([sys.executable, "-m", "lfproc", "refocus", str(sample / "capture.png"), "--camera",
                           str(sample / "camera.toml"), "--white", str(sample / "white.png"), "--a", "0",
                           "-o", str(out)], capture_output=True, text=True, timeout=300,
                          preexec_fn=_limit_file_size(8192),
                          # the size limit is per process, not per folder: keep it off the decoder cache (another
                          # disk in practice), whose failed store would add its own warning line
                          env=dict(os.environ, LFPROC_NO_CACHE="1"))
    assert proc.returncode == 2 and "Traceback" not in proc.stderr, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and str(out / "capture_00_a+0.000.tif") in lines[0], proc.stderr
    assert os.listdir(out) == []


def test_calibrate_on_a_full_disk_is_one_line_and_leaves_no_file(tmp_path):
    """ENOSPC inside the Python-level writer of a command (tests/fault_site/sitecustomize.py installs it)."""
    import json

    from conftest import ROOT

    sample = SAMPLES / "sample"
    out = tmp_path / "out"
    out.mkdir()
    env = dict(os.environ, LFPROC_FAULTS=json.dumps({"disk_full": {"folder": str(out), "after": 50}}),
               PYTHONPATH=os.pathsep.join([str(ROOT / "tests" / "fault_site"), str(ROOT),
                                           os.environ.get("PYTHONPATH", "")]))
    proc = subprocess.run([sys.executable, "-m", "lfproc", "calibrate", str(sample / "white.png"), "--camera",
                           str(sample / "camera.toml"), "-o", str(out / "grid.json")], capture_output=True,
                          text=True, timeout=300, env=env)
    assert_clean_error(proc, str(out / "grid.json"), "No space left on device")
    assert os.listdir(out) == []
