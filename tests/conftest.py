"""Shared helpers: the command line in this process (or, where the process is what a test checks, in a
subprocess exactly as a user runs it), and the bundled sample calibrated and decoded once per test run."""

import atexit
import fcntl
import io
import os
import shutil
import sys
import tempfile
import traceback
from pathlib import Path
from subprocess import CompletedProcess
from subprocess import run as run_process

import pytest

ROOT = Path(__file__).resolve().parent.parent
SAMPLES = ROOT / "lfproc" / "samples"   # the package data (samples/ at the top links here)
SAMPLE = SAMPLES / "sample"             # the bundled sample: capture.png, white.png, camera.toml

# the decoder cache (lfproc.decoder_cache) of the test run: its own folder, not the user's ~/.cache,
# inherited by the CLI subprocesses (and pytest-xdist's workers); removed at the end
if "LFPROC_CACHE_DIR" not in os.environ:
    os.environ["LFPROC_CACHE_DIR"] = tempfile.mkdtemp(prefix="lfproc-test-cache-")
    atexit.register(shutil.rmtree, os.environ["LFPROC_CACHE_DIR"], True)
# a folder of this test run, shared with pytest-xdist's workers (they inherit the environment): its locks
if "LFPROC_TEST_RUN_DIR" not in os.environ:
    os.environ["LFPROC_TEST_RUN_DIR"] = tempfile.mkdtemp(prefix="lfproc-test-run-")
    atexit.register(shutil.rmtree, os.environ["LFPROC_TEST_RUN_DIR"], True)
RUN_DIR = Path(os.environ["LFPROC_TEST_RUN_DIR"])


def run_cli(*args, cwd=None, subprocess=False, timeout=600):
    """Run ``lfproc ARGS``; returns a CompletedProcess (text mode) with its exit status, stdout and stderr.

    By default the command runs in this process, ``lfproc.cli.main(ARGS)`` with file descriptors 1 and 2
    sent to files, so stdout and stderr hold everything written to them as a subprocess's pipes would:
    Python's prints and warnings, and C libraries' own writes, in order. A usage error's or ``--help``'s
    ``SystemExit`` gives its status; an uncaught exception gives status 1 with its traceback on stderr, like
    ``python -m lfproc``. ``subprocess=True`` runs ``python -m lfproc ARGS`` in a fresh interpreter (with a
    ``timeout`` in seconds): for what only a process shows (signals, a fresh interpreter's imports and their
    warnings, the module entry point).
    """
    argv = [str(arg) for arg in args]
    if subprocess:
        return run_process([sys.executable, "-m", "lfproc", *argv], capture_output=True, text=True, cwd=cwd,
                           env=dict(os.environ, PYTHONUNBUFFERED="1"), timeout=timeout)
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        status = _main_with_fds_to(out, err, argv, cwd)
        return CompletedProcess(["lfproc", *argv], status, _text(out), _text(err))


def _main_with_fds_to(out, err, argv, cwd):
    """``lfproc.cli.main(argv)`` in ``cwd`` with fds 1 and 2 (and sys.stdout, sys.stderr) on ``out``, ``err``;
    returns the exit status."""
    from lfproc.cli import main

    sys.stdout.flush()
    sys.stderr.flush()
    streams, saved_fds, saved_cwd = (sys.stdout, sys.stderr), (os.dup(1), os.dup(2)), os.getcwd()
    try:
        os.dup2(out.fileno(), 1)
        os.dup2(err.fileno(), 2)
        sys.stdout, sys.stderr = _fd_text(1, "strict"), _fd_text(2, "backslashreplace")
        if cwd is not None:
            os.chdir(cwd)
        try:
            return main(argv)
        except SystemExit as stop:
            if stop.code is None or isinstance(stop.code, int):
                return stop.code or 0
            print(stop.code, file=sys.stderr)
            return 1
        except Exception:
            traceback.print_exc()
            return 1
    finally:
        sys.stdout.flush()
        sys.stderr.flush()
        sys.stdout, sys.stderr = streams
        os.chdir(saved_cwd)
        for fd, saved in zip((1, 2), saved_fds):
            os.dup2(saved, fd)
            os.close(saved)


def _fd_text(fd, errors):
    """A text stream on file descriptor ``fd`` written through at once, like an unbuffered sys.stdout."""
    return io.TextIOWrapper(io.FileIO(fd, "w", closefd=False), encoding="utf-8", errors=errors,
                            write_through=True)


def _text(file):
    """What was written to ``file``, decoded as ``subprocess.run(text=True)`` does (universal newlines)."""
    file.seek(0)
    return file.read().decode("utf-8", "replace").replace("\r\n", "\n").replace("\r", "\n")


def assert_clean_error(proc, *must_mention):
    """Exit 2, exactly one line on stderr mentioning each string, nothing on stdout, no traceback."""
    assert proc.returncode == 2, (proc.returncode, proc.stdout, proc.stderr)
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1, proc.stderr
    assert "Traceback" not in proc.stderr
    assert proc.stdout == ""
    for text in must_mention:
        assert str(text) in lines[0], (text, lines[0])


@pytest.fixture
def paper_camera():
    return SAMPLES / "cameras" / "paper-f100.toml"


# ----------------------------------------------------------------------------- the sample, once per run
def _shared(path: Path):
    """Yield ``path`` to the tests, then fail if one of them changed it: shared files are read-only."""
    made = path.read_bytes()
    yield path
    assert path.read_bytes() == made, f"a test changed the shared {path}; copy it before changing it"


@pytest.fixture(scope="session")
def sample_grid(tmp_path_factory):
    """The sample's GRID.json as ``lfproc calibrate`` writes it (from ``SAMPLE/white.png``), fitted once per
    run and shared: read-only."""
    grid = tmp_path_factory.mktemp("sample-grid") / "grid.json"
    proc = run_cli("calibrate", SAMPLE / "white.png", "--camera", SAMPLE / "camera.toml", "-o", grid)
    assert proc.returncode == 0, proc.stderr
    yield from _shared(grid)


@pytest.fixture(scope="session")
def sample_lf(tmp_path_factory, sample_grid):
    """The sample's light field as ``lfproc decode`` writes it (with :func:`sample_grid`), decoded once per run
    and shared: read-only."""
    lf = tmp_path_factory.mktemp("sample-lf") / "sample.lfp.npz"
    proc = run_cli("decode", SAMPLE / "capture.png", "--camera", SAMPLE / "camera.toml", "--calib", sample_grid,
                   "-o", lf)
    assert proc.returncode == 0, proc.stderr
    yield from _shared(lf)


# ----------------------------------------------------------------------------- tests that must run alone
def pytest_configure(config):
    config.addinivalue_line("markers", "alone: the test has a wall-clock limit (e.g. processes gone within 2 s of "
                                       "Ctrl-C), so under pytest-xdist no other test runs beside it")


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item, nextitem):
    """Under pytest-xdist, a test marked ``alone`` (its set-up, call and tear-down) holds an exclusive lock that
    every other test holds shared: it waits for the tests running in the other workers to end, and they wait
    for it. A turnstile lock taken before the shared one keeps a waiting ``alone`` test from being passed by
    the next ones."""
    if "PYTEST_XDIST_WORKER" not in os.environ:   # one process: nothing runs beside any test
        yield
        return
    with open(RUN_DIR / "turnstile.lock", "a") as turnstile, open(RUN_DIR / "tests.lock", "a") as tests:
        fcntl.flock(turnstile, fcntl.LOCK_EX)
        if item.get_closest_marker("alone"):
            fcntl.flock(tests, fcntl.LOCK_EX)
        else:
            fcntl.flock(turnstile, fcntl.LOCK_UN)
            fcntl.flock(tests, fcntl.LOCK_SH)
        yield
