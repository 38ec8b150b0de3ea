"""Shared helpers: run the CLI in a subprocess exactly as a user would."""

import atexit
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
SAMPLES = ROOT / "lfproc" / "samples"   # the package data (samples/ at the top links here)

# the decoder cache (lfproc.decoder_cache) of the test run: its own folder, not the user's ~/.cache,
# inherited by the CLI subprocesses; removed at the end
if "LFPROC_CACHE_DIR" not in os.environ:
    os.environ["LFPROC_CACHE_DIR"] = tempfile.mkdtemp(prefix="lfproc-test-cache-")
    atexit.register(shutil.rmtree, os.environ["LFPROC_CACHE_DIR"], True)


def run_cli(*args, cwd=None, timeout=600):
    """Run ``python -m lfproc ARGS``; returns the CompletedProcess (text mode)."""
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    return subprocess.run([sys.executable, "-m", "lfproc", *map(str, args)], capture_output=True, text=True,
                          cwd=cwd, env=env, timeout=timeout)


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
