"""The README's two set-up commands are the ones CI runs, and its examples are real."""

import re

import pytest

from conftest import ROOT

README = (ROOT / "README.md").read_text()
CI = (ROOT / ".ci" / "run").read_text()


def test_ci_runs_the_readme_test_command():
    ci_lines = [line for line in CI.splitlines() if "pytest" in line and not line.startswith("#")]
    assert len(ci_lines) == 1
    assert ci_lines[0].strip() in README


def test_readme_first_screen_has_both_commands():
    first_screen = "\n".join(README.splitlines()[:40])
    assert re.search(r"^python3 -m venv .*lfproc demo$", first_screen, re.M)
    assert re.search(r"^python3 -m venv .*pytest.*$", first_screen, re.M)


def _blocks(language):
    return re.findall(rf"```{language}\n(.*?)```", README, re.S)


def test_python_example_runs(monkeypatch, capsys, tmp_path):
    """The README's example runs, and what it prints and saves is what ``lfproc refocus`` writes (the tags of
    the views that carry light: 722-1236 mm around a = 0.682, not the full micro image's 754-1174 mm)."""
    import json

    (code,) = _blocks("python")
    code = code.replace("/tmp/lfproc-readme", str(tmp_path / "out"))
    monkeypatch.chdir(ROOT)
    namespace = {}
    exec(compile(code, "README.md", "exec"), namespace)
    assert "'distance_mm': 650.0" in capsys.readouterr().out
    fs = namespace["fs"]
    sidecars = sorted((tmp_path / "out").glob("capture_*_a*.json"))   # named in focus order: far first
    assert len(sidecars) == 2
    assert [json.loads(p.read_text())["distance_mm"] for p in sidecars] == pytest.approx([1200.0, 650.0])
    records = fs.records()
    assert json.loads(sidecars[1].read_text()) == json.loads(json.dumps(records[0]))
    assert fs.views_summed == 89


def test_camera_file_example_is_the_paper_camera():
    from lfproc import Camera

    toml = next(block for block in _blocks("toml") if "[main_lens]" in block)
    text = "\n".join(line.strip() for line in toml.splitlines())
    assert Camera.from_toml_string(text) == Camera.from_toml(ROOT / "samples" / "cameras" / "paper-f100.toml")
