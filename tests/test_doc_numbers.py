"""Measured numbers quoted in README.md and docs/*.md equal the benchmark JSON they come from
(scripts/doc_numbers.py: a marker after each number names its source)."""

from __future__ import annotations

import importlib.util
import shutil
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="module")
def numbers():
    spec = importlib.util.spec_from_file_location("doc_numbers", ROOT / "scripts" / "doc_numbers.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_every_quoted_number_is_its_json_value(numbers):
    problems = numbers.check()
    assert not problems, "\n".join(problems)


def test_every_number_of_the_registry_is_quoted(numbers):
    quoted = {name for _, _, _, kind, name in numbers.quotes() if kind == "n"}
    assert set(numbers.NUMBERS) - quoted == set(), "numbers nobody quotes: drop them from scripts/doc_numbers.py"


def test_every_json_source_exists_and_every_number_resolves(numbers):
    for name in numbers.SOURCES:
        assert (numbers.DOCS / name).is_file(), name
    for name, (_, value) in numbers.NUMBERS.items():
        assert isinstance(value(), (int, float)), name


def test_the_benchmark_tables_quote_no_measured_number_without_its_source(numbers):
    problems = numbers.unmarked()
    assert not problems, "\n".join(problems)


def test_the_depth_map_time_is_one_number_everywhere(numbers):
    """The quantity that used to drift (2.9–3.5 s / 1.7 s / 4.58 s) is quoted only through its marker, so every
    quote is the same JSON value."""
    depth = [written for _, _, written, kind, name in numbers.quotes() if name == "depth.default_s"]
    assert len(depth) >= 3 and len(set(depth)) == 1, depth      # docs/benchmarks.md, commands.md, depth.md


def _copy_docs(tmp_path):
    (tmp_path / "docs").mkdir()
    for path in [ROOT / "README.md", *ROOT.glob("docs/*.md"), *ROOT.glob("docs/*.json")]:
        shutil.copy(path, tmp_path / path.relative_to(ROOT))
    return tmp_path


def test_a_drifted_quote_and_an_unmarked_time_are_caught(numbers, tmp_path, monkeypatch):
    root = _copy_docs(tmp_path)
    monkeypatch.setattr(numbers, "ROOT", root)
    monkeypatch.setattr(numbers, "DOCS", root / "docs")
    numbers.load.cache_clear()
    page = root / "docs" / "benchmarks-refocus.md"
    text = page.read_text(encoding="utf-8")
    page.write_text(text.replace("0.032<!--n:refocus.integer_s--> s (23", "0.027<!--n:refocus.integer_s--> s (23", 1)
                    .replace("| 0.145<!--n:refocus.five_separate_s--> s |", "| 2.9–3.5 s |", 1), encoding="utf-8")
    drift = numbers.check()
    assert any("refocus.integer_s is quoted as 0.027" in p for p in drift), drift
    missing = numbers.unmarked()
    assert any("2.9 in column 2" in p for p in missing) and any("3.5 in column 2" in p for p in missing), missing
    numbers.load.cache_clear()


def test_a_rerun_that_moves_a_number_is_caught(numbers, tmp_path, monkeypatch):
    """A benchmark rerun rewrites its JSON: every quote of a number that moved fails."""
    import json

    root = _copy_docs(tmp_path)
    monkeypatch.setattr(numbers, "ROOT", root)
    monkeypatch.setattr(numbers, "DOCS", root / "docs")
    numbers.load.cache_clear()
    depth = json.loads((root / "docs" / "benchmarks-depth.json").read_text(encoding="utf-8"))
    depth["speed"][0]["median_s"] = 3.21
    (root / "docs" / "benchmarks-depth.json").write_text(json.dumps(depth), encoding="utf-8")
    drift = [p for p in numbers.check() if "depth.default_s" in p]
    assert len(drift) >= 3 and all("its source says 3.21" in p for p in drift), drift
    numbers.load.cache_clear()
