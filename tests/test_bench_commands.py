"""scripts/bench_commands.py's results: a run into a new folder (no earlier results) and the merging of runs.

Only the result handling is tested (no command is timed): ``--out NEWDIR`` used to fail when NEWDIR held
no earlier ``benchmarks-commands.json``.
"""

import json
import sys

from conftest import ROOT

sys.path.insert(0, str(ROOT / "scripts"))
import bench_commands as bc  # noqa: E402

ROW = {"case": "refocus --calib, 5 slices (cache ready)", "seconds": 4.2, "cpu_s": 3.9, "peak_gb": 0.9}
DISK = {"bytes": 732_000_000, "files": 450, "tiff_bytes": 733_000_000, "floor_s": 0.4, "views_s": 0.6,
        "floor_mb_s": 1830.0, "views_mb_s": 1221.0, "ratio": 0.66, "repeats": 3, "floor_runs_s": [0.5, 0.4, 0.45],
        "views_runs_s": [0.7, 0.6, 0.65]}


def test_merge_without_earlier_results_is_this_run():
    new = {"date": "d", "commands": [ROW]}
    assert bc.merge_results(None, new) == new


def test_merge_keeps_sections_this_run_did_not_measure_and_replaces_the_others():
    previous = {"date": "old", "commands": [dict(ROW, seconds=9.0)], "disk": DISK}
    merged = bc.merge_results(previous, {"date": "new", "commands": [ROW], "batch": None})
    assert merged["date"] == "new" and merged["commands"] == [ROW] and merged["disk"] == DISK
    assert "batch" not in merged
    assert previous["commands"][0]["seconds"] == 9.0        # the earlier results are not modified


def test_markdown_of_partial_and_older_results():
    """A disk-only run into a new folder, and rows of an older run without CPU times, both render."""
    assert "Writing the views against the disk" in bc.markdown({"date": "d", "machine": "m", "disk": DISK})
    old_row = {"case": "views, 225 TIFFs, --calib", "seconds": 10.7, "peak_gb": 2.02}
    page = bc.markdown({"date": "d", "machine": "m", "commands": [old_row, ROW], "before_commands": [old_row]})
    assert "| `lfproc views, 225 TIFFs, --calib` | 10.7 s, 2.02 GB | 10.7 | — | 2.02 |" in page
    assert "| `lfproc refocus --calib, 5 slices (cache ready)` | — | 4.2 | 3.9 | 0.90 |" in page
    assert "≤ 5 s, ≤ 1.5 GB" in page


def test_disk_only_run_into_a_new_folder(tmp_path, monkeypatch):
    """``--disk-only --out NEWDIR`` writes both files although NEWDIR did not exist (the disk measurement
    itself is replaced by a stand-in: it writes 0.7 GB)."""
    monkeypatch.setattr(bc, "disk_floor_and_views", lambda folder: DISK)
    out = tmp_path / "new" / "folder"
    assert bc.main(["--disk-only", "--out", str(out), "--keep", str(tmp_path / "work")]) == 0
    results = json.loads((out / "benchmarks-commands.json").read_text())
    assert results["disk"] == DISK
    assert "1221" in (out / "benchmarks-commands.md").read_text()


def test_measured_processes_import_the_checkout_they_measure(tmp_path, monkeypatch):
    """``--before CHECKOUT`` measures CHECKOUT's code even when the script runs from another checkout
    (``python -m`` and ``-c`` put the working folder first on sys.path: the old column measured the new code)."""
    other = tmp_path / "before"
    (other / "lfproc").mkdir(parents=True)
    (other / "lfproc" / "__init__.py").write_text("")
    monkeypatch.chdir(ROOT)
    assert bc.imported_lfproc(bc.child_env(str(other), tmp_path / "cache")) == str(other.resolve())
    assert bc.imported_lfproc(bc.child_env(None, tmp_path / "cache")) == str(ROOT.resolve())
