"""Reading captures (``lfproc.io.read_capture``): a 16-bit PNG and TIFF of the Lytro-sized raw against
OpenImageIO's own read and ``numpy.fromfile``; a stage of ``scripts/bench.py`` (also runnable alone:
``python scripts/bench_read.py [--quick]`` prints its section).
"""

from __future__ import annotations

import os
import tempfile
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import benchlib as bl  # noqa: E402  (this folder)
import benchsim as suite  # noqa: E402


def stage_read(raw_dn: np.ndarray, camera, s: suite.Settings, tmp: str) -> dict:
    """read_capture of a 16-bit PNG and TIFF against OpenImageIO's own read and numpy.fromfile."""
    import cv2
    import OpenImageIO as oiio
    import tifffile

    from lfproc.io import read_capture

    paths = {"PNG": os.path.join(tmp, "raw.png"), "TIFF": os.path.join(tmp, "raw.tif")}
    if not cv2.imwrite(paths["PNG"], raw_dn):
        raise RuntimeError("cv2 could not write the PNG")
    tifffile.imwrite(paths["TIFF"], raw_dn)
    truth = (raw_dn.astype(np.float64) - camera.black_level) / (camera.white_level - camera.black_level)
    mpx = raw_dn.size / 1e6

    def oiio_native(path):
        inp = oiio.ImageInput.open(path)
        try:
            return inp.read_image(0, 0, 0, 1, "uint16")
        finally:
            inp.close()

    rows = []
    for fmt, path in paths.items():
        size_mb = os.path.getsize(path) / 1e6
        timing = bl.measure(lambda: read_capture(path, camera), s.cheap_repeats)
        floor = bl.measure(lambda: oiio_native(path), s.cheap_repeats, memory=False)
        data = read_capture(path, camera).data
        err = float(np.max(np.abs(data.astype(np.float64) - truth)))
        rows.append({"case": f"read_capture, 16-bit {fmt}", "file_mb": size_mb, "timing": timing.as_dict(),
                     "mpx_per_s": mpx / timing.median_s, "file_mb_per_s": size_mb / timing.median_s,
                     "floor": "OpenImageIO native uint16 read", "floor_s": floor.median_s,
                     "ratio_to_floor": timing.median_s / floor.median_s, "max_abs_error": err})
    fromfile = bl.measure(lambda: np.fromfile(paths["TIFF"], dtype=np.uint8), s.cheap_repeats, memory=False)
    return {"sensor_shape": list(raw_dn.shape), "rows": rows,
            "fromfile_tiff_s": fromfile.median_s,
            "fromfile_tiff_mb_per_s": os.path.getsize(paths["TIFF"]) / 1e6 / fromfile.median_s}


def suite_section(r: dict) -> list[str]:
    """The read section of docs/benchmarks.md (``scripts/bench.py``)."""
    out = []
    rd = r["read"]
    out += ["## Read (`lfproc.io.read_capture`)", "",
            f"Raw of {rd['sensor_shape'][1]} × {rd['sensor_shape'][0]} px, 16-bit. Floor: OpenImageIO's own "
            f"read of the same file as uint16 (no conversion). Reading the uncompressed TIFF's bytes with "
            f"`numpy.fromfile` (page cache) takes {bl.fmt(rd['fromfile_tiff_s'])} s "
            f"({rd['fromfile_tiff_mb_per_s']:.0f} MB/s). Accuracy: largest difference from "
            f"(DN − black)/(white − black) computed in float64.", "",
            bl.markdown_table(["case", "file MB", "time s (min)", "Mpx/s", "file MB/s", "× floor", "peak MB",
                               "max abs error"],
                              [[x["case"], x["file_mb"], bl.fmt_timing(x["timing"]), x["mpx_per_s"], x["file_mb_per_s"],
                                x["ratio_to_floor"], bl.fmt_peak(x["timing"]), x["max_abs_error"]] for x in rd["rows"]]), ""]
    return out


def measure(s, big) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        return {"read": stage_read(big["sim"].raw, big["camera"], s, tmp)}


def main(argv=None) -> int:
    return suite.run_stage_alone(__doc__.splitlines()[0], measure, suite_section, argv)


if __name__ == "__main__":
    sys.exit(main())
