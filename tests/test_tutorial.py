"""docs/tutorial.md runs: its ```python blocks, in order, in one namespace, in an empty folder, with HOME at an
empty folder; they print what the page says they print, write only under the folder, and nothing under HOME."""

import contextlib
import io
import re
from pathlib import Path

import pytest

TUTORIAL = Path(__file__).resolve().parent.parent / "docs" / "tutorial.md"


def python_blocks(text: str) -> list[str]:
    return re.findall(r"^```python\n(.*?)^```", text, re.M | re.S)


def test_tutorial_runs(tmp_path, monkeypatch):
    blocks = python_blocks(TUTORIAL.read_text())
    assert len(blocks) >= 6
    home, work = tmp_path / "home", tmp_path / "work"
    home.mkdir(), work.mkdir()
    monkeypatch.setenv("HOME", str(home))
    monkeypatch.delenv("LFPROC_CACHE_DIR", raising=False)
    monkeypatch.delenv("XDG_CACHE_HOME", raising=False)
    monkeypatch.chdir(work)
    namespace = {"__name__": "tutorial"}
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        for i, block in enumerate(blocks):
            try:
                exec(compile(block, f"{TUTORIAL.name}[block {i + 1}]", "exec"), namespace)
            except Exception as exc:  # noqa: BLE001 - which block failed, with its output so far
                pytest.fail(f"block {i + 1} of {TUTORIAL.name} failed: {exc!r}\n{out.getvalue()}")
    printed = out.getvalue()
    assert "<LightField 11x11 views (89 carry light) of 53x75 lenses" in printed
    assert "sharpest at z = 12 µm" in printed
    assert list(home.iterdir()) == []
    for folder in ("refocus", "views", "depth", "scope"):
        assert any((work / "out" / folder).iterdir()), folder
    assert (work / "out" / "scope" / "sheet_stack.ome.tif").exists()
