"""Tests on real captures from real instruments (``../shared/real`` beside the repository; CI has it)."""

from __future__ import annotations

from pathlib import Path

import pytest

REPO_ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture
def real_dir() -> Path:
    """``<repo root>/../shared/real``; the test is skipped when it is absent."""
    path = REPO_ROOT / ".." / "shared" / "real"
    if not path.is_dir():
        pytest.skip(f"real data not found at {path} (../shared/real beside the repository)")
    return path
