"""Real captures from real instruments (``../shared/real`` beside the repository; see its README)."""

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
CAMERAS = Path(__file__).resolve().parent / "cameras"


@pytest.fixture(scope="session")
def real_dir() -> Path:
    """``<repo root>/../shared/real``; the test is skipped (one line) where it is absent."""
    path = ROOT.parent / "shared" / "real"
    if not path.is_dir():
        pytest.skip(f"{path}: the real data folder is absent (CI has it)")
    return path
