"""docs/speed-accuracy.md is what scripts/bench_tradeoffs.py writes from docs/speed-accuracy.json: the page's
numbers, and the settings it recommends, come from the measured results (the benchmark itself is not run)."""

from __future__ import annotations

import copy
import json
import sys

import pytest
from conftest import ROOT

sys.path.insert(0, str(ROOT / "scripts"))
import bench_tradeoffs  # noqa: E402

DOCS = ROOT / "docs"


@pytest.fixture(scope="module")
def script():
    return bench_tradeoffs


@pytest.fixture(scope="module")
def results():
    return json.loads((DOCS / "speed-accuracy.json").read_text(encoding="utf-8"))


def test_the_page_is_the_script_output_for_the_json(script, results):
    assert (DOCS / "speed-accuracy.md").read_text(encoding="utf-8") == script.markdown(results)


def test_the_page_is_a_full_run(results):
    assert not results["quick"] and results["command"] == "python scripts/bench_tradeoffs.py"


def test_a_moved_number_changes_the_page_and_the_recommendation_follows_the_numbers(script, results):
    moved = copy.deepcopy(results)
    linear = next(r for r in moved["decode"]["accuracy"] if r["capture"] == "mono" and r["interpolation"] == "linear")
    linear["psnr_db"] = 99.0                              # linear now the most accurate decode
    page = script.markdown(moved)
    assert page != script.markdown(results)
    assert "**Publication images**: decode with `linear`" in page
    assert "99.0 |" in page


def test_the_page_says_which_setting_to_pick_for_what(script, results):
    page = script.markdown(results)
    for use in ("**Preview**", "**Publication images**", "**Metric measurement**", "**Many slices**",
                "**Microscopes**"):
        assert use in page
