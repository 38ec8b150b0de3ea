"""Atomic writes: nothing partial, usual permissions, one-line errors for unwritable targets."""

import os
import stat

import pytest

from lfproc import LfprocError, LensGrid
from lfproc.atomic import atomic_path, write_json_atomic


def test_success_renames_and_keeps_usual_permissions(tmp_path):
    target = tmp_path / "sub" / "out.json"
    write_json_atomic(target, {"a": float("inf")})
    assert target.read_text().strip().replace(" ", "").replace("\n", "") == '{"a":null}'
    umask = os.umask(0)
    os.umask(umask)
    assert stat.S_IMODE(target.stat().st_mode) == 0o666 & ~umask
    assert [p.name for p in target.parent.iterdir()] == ["out.json"]


def test_failure_leaves_nothing(tmp_path):
    target = tmp_path / "out.txt"
    with pytest.raises(RuntimeError):
        with atomic_path(target) as tmp:
            with open(tmp, "w") as fh:
                fh.write("half")
            raise RuntimeError("writer failed")
    assert list(tmp_path.iterdir()) == []


def test_unwritable_targets_are_one_line_errors(tmp_path):
    blocker = tmp_path / "blocker"
    blocker.write_text("a file, not a folder")
    with pytest.raises(LfprocError, match="cannot write there"):
        write_json_atomic(blocker / "x.json", {})
    folder_target = tmp_path / "adir"
    folder_target.mkdir()
    (folder_target / "keep").write_text("")
    with pytest.raises(LfprocError, match="cannot write there"):
        write_json_atomic(folder_target, {})
    assert sorted(p.name for p in tmp_path.iterdir()) == ["adir", "blocker"]


@pytest.mark.parametrize("field, value", [("pitch_px", 0.0), ("pitch_px", float("nan")), ("rows", 0),
                                          ("cols", 2.5), ("rotation_deg", float("inf"))])
def test_grids_with_impossible_fields_are_refused(field, value):
    fields = dict(kind="rectangular", pitch_px=10.0, rotation_deg=0.0, origin_xy_px=(5, 5), rows=3, cols=4)
    fields[field] = value
    with pytest.raises(LfprocError):
        LensGrid(**fields)


def test_grid_file_with_bad_numbers_is_a_clean_error():
    good = LensGrid("hexagonal", 10.0, 0.5, (5, 5), 3, 4).to_json_dict()
    assert LensGrid.from_json_dict(good).rows == 3
    for key, value in [("rows", 0), ("rows", float("inf")), ("pitch_px", -5.0)]:
        with pytest.raises(LfprocError, match="grid.json"):
            LensGrid.from_json_dict(dict(good, **{key: value}), source="grid.json")
