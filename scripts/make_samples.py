#!/usr/bin/env python3
"""Regenerate the bundled sample ``samples/sample/`` from its scene file, deterministically.

Renders ``samples/sample/scene.toml`` with ``lfproc simulate`` and keeps what the demo and the tests
need: ``capture.png``, ``white.png``, ``camera.toml`` and ``ground_truth.json`` (its lens grid without
the list of centres, which the grid's origin, pitch and rotation define; it does not name the 5.7 MB
``ground_truth.npz``, which is not shipped). Running it twice gives the
same bytes; it prints each file's size and SHA-256.
"""

import hashlib
import json
import shutil
import sys
import tempfile
from pathlib import Path

from lfproc.atomic import write_json_atomic
from lfproc.cli import main as lfproc_main

SAMPLE = Path(__file__).resolve().parent.parent / "samples" / "sample"
KEEP = ("capture.png", "white.png", "camera.toml")
NOT_SHIPPED = ("ground_truth.npz (ideal views, per-lens plane labels) is not shipped: "
               "'lfproc simulate scene.toml -o DIR' renders it")


def main() -> int:
    with tempfile.TemporaryDirectory() as tmp:
        status = lfproc_main(["simulate", str(SAMPLE / "scene.toml"), "-o", tmp])
        if status:
            return status
        for name in KEEP:
            shutil.copyfile(Path(tmp) / name, SAMPLE / name)
        truth = json.loads((Path(tmp) / "ground_truth.json").read_text())
    truth["scene"] = "scene.toml"
    truth["grid"].pop("centers_xy_px", None)
    truth.pop("ideal_views", None)   # names ground_truth.npz (5.7 MB), which the package does not ship
    truth["arrays"] = NOT_SHIPPED
    write_json_atomic(SAMPLE / "ground_truth.json", truth)
    total = 0
    for name in (*KEEP, "ground_truth.json", "scene.toml"):
        data = (SAMPLE / name).read_bytes()
        total += len(data)
        print(f"{name:20s} {len(data):>9d} B  sha256 {hashlib.sha256(data).hexdigest()[:16]}")
    print(f"{'total':20s} {total:>9d} B")
    return 0


if __name__ == "__main__":
    sys.exit(main())
