"""Real captures from real instruments (``../shared/real`` beside the repository, or the folder
``LFPROC_REAL_DATA`` names; see its README)."""

import os
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
CAMERAS = Path(__file__).resolve().parent / "cameras"


def real_data_folder() -> Path:
    """``$LFPROC_REAL_DATA`` where set (a copy of the real data anywhere), else ``<repo root>/../shared/real``."""
    given = os.environ.get("LFPROC_REAL_DATA")
    return Path(given).expanduser().resolve() if given else ROOT.parent / "shared" / "real"


@pytest.fixture(scope="session")
def real_dir() -> Path:
    """The real data folder (:func:`real_data_folder`); the test is skipped (one line) where it is absent."""
    path = real_data_folder()
    if not path.is_dir():
        pytest.skip(f"{path}: the real data folder is absent; set LFPROC_REAL_DATA to a copy of it")
    return path
