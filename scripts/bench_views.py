"""Views (``lfproc.viewpoints``, aperture masks, the mosaic) against a copy of the decoded views; a stage of
``scripts/bench.py`` (also runnable alone: ``python scripts/bench_views.py [--quick]`` prints its section).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import benchlib as bl  # noqa: E402  (this folder)
import benchsim as suite  # noqa: E402


def stage_views(views: np.ndarray, camera, s: suite.Settings) -> dict:
    """viewpoints (plain and aperture-masked) and the mosaic, against a copy of the views."""
    from lfproc import LightField
    from lfproc.geometry import views_inside_aperture
    from lfproc.viewpoints import mosaic, viewpoints

    lf = LightField.from_views(views, camera)
    gb = views.nbytes / 1e9
    floor = bl.measure(lambda: views.copy(), s.cheap_repeats)
    rows = []
    for label, fn in [("viewpoints(lf)", lambda: viewpoints(lf)),
                      ("viewpoints(lf, inside_aperture=True)", lambda: viewpoints(lf, inside_aperture=True)),
                      ("mosaic(views)", lambda: mosaic(views))]:
        timing = bl.measure(fn, s.cheap_repeats)
        no_copy = label == "viewpoints(lf)"   # returns lf.views itself: a throughput would be meaningless
        rows.append({"case": label, "timing": timing.as_dict(), "gb_per_s": None if no_copy else gb / timing.median_s,
                     "ratio_to_floor": timing.median_s / floor.median_s})
    # exactness: every output is the input's samples, bit for bit
    m, _, ny, nx, _ = views.shape
    inside = views_inside_aperture(camera)
    masked = viewpoints(lf, inside_aperture=True)
    tiles = mosaic(views).reshape(m, ny, m, nx, -1).transpose(0, 2, 1, 3, 4)
    exact = {"viewpoints": bool(np.array_equal(viewpoints(lf), views)),
             "inside_aperture": bool(np.array_equal(masked[inside], views[inside]) and not masked[~inside].any()),
             "mosaic": bool(np.array_equal(tiles, views)), "views_inside_aperture": int(inside.sum()),
             "views_total": int(m * m)}
    return {"views_shape": list(views.shape), "floor": floor.as_dict(), "rows": rows, "exact": exact}


def suite_section(r: dict) -> list[str]:
    """The views section of docs/benchmarks.md (``scripts/bench.py``)."""
    out = []
    vw = r["views"]
    ex = vw["exact"]
    out += ["## Views (`lfproc.viewpoints`)", "",
            f"Same light field. Floor: `views.copy()`, {bl.fmt(vw['floor']['median_s'])} s. `viewpoints(lf)` "
            "returns the decoded array itself (Eq. 32 is the layout), so it costs nothing.", "",
            bl.markdown_table(["case", "time s (min)", "GB/s", "× floor", "peak MB"],
                              [[x["case"], bl.fmt_timing(x["timing"]), x["gb_per_s"], x["ratio_to_floor"], bl.fmt_peak(x["timing"])]
                               for x in vw["rows"]]), "",
            f"Accuracy: exact by construction and checked bit for bit — viewpoints {ex['viewpoints']}, aperture mask "
            f"{ex['inside_aperture']} ({ex['views_inside_aperture']} of {ex['views_total']} views inside the f/2 "
            f"stop), mosaic {ex['mosaic']}.", ""]
    return out


def measure(s, big) -> dict:
    from lfproc.decode import make_decoder

    camera = big["camera"]
    views = make_decoder(big["white"], big["sim"].grid, camera.m_hat, camera.cfa)(big["raw"])
    return {"views": stage_views(views, camera, s)}


def main(argv=None) -> int:
    return suite.run_stage_alone(__doc__.splitlines()[0], measure, suite_section, argv)


if __name__ == "__main__":
    sys.exit(main())
