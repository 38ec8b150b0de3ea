#!/usr/bin/env python3
"""Regenerate the simulated Lytro-format sample ``samples/lytro/``, deterministically.

Renders an Illum-like capture (1.4 um pixels, 20 um hexagonal lenses, f_s 40.6 um, f_U 77.6 mm at
f/2.11, GRBG, 10-bit levels 64..1023, main lens focused at infinity) of a textured plane with
``lfproc.simulate`` and writes it as real Lytro files do, using the Illum fixture's metadata with
only the sensor size, serial, motor steps and exit pupil changed (the simulator's main lens is
image-side telecentric, so the metadata says so: ``exitPupilOffset.z`` = 10000 m, as F01 files do):

* ``IMG_0001.lfr``: a container with a thumbnail, private metadata, the packed raw and its metadata;
* ``caldata/MOD_0000.RAW`` + ``.TXT``: the matching white image (zoom step -1040, focus step -300);
* ``caldata/MOD_0001.RAW`` + ``.TXT``: a white image of another zoom (-600), which --white-dir skips.

Running it twice gives the same bytes; it prints each file's size and SHA-256.
"""

from lfproc.camera import MainLens
import hashlib
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))       # the byte-level Lytro writer the tests use

import lytrogen  # noqa: E402
from lfproc import Camera, geometry, simulate  # noqa: E402
from lfproc.simulate import Noise, Plane, Scene  # noqa: E402

SAMPLE = ROOT / "samples" / "lytro"
SHAPE = (336, 448)        # sensor rows, columns: about 22 x 26 lenses
CAMERA = Camera(0.0014, 0.020, 0.0406, MainLens(77.59, 77.59, f_number=2.11), grid="hexagonal", cfa="GRBG", black_level=64, white_level=1023)
NEAR_A, FAR_A = 1.25, 0.25   # the slices that focus on the two planes (|a| <= 1.8 fits 13 views on 23 lenses)
TELECENTRIC = 10000.0     # exitPupilOffset.z of a main lens whose exit pupil is at infinity


def main() -> int:
    near, far = geometry.slice_distance_mm(CAMERA, NEAR_A), geometry.slice_distance_mm(CAMERA, FAR_A)

    def lens_footprint(distance_mm):     # one lens's width seen in a plane at that distance
        return CAMERA.mla_pitch_mm * distance_mm / CAMERA.main_optics.focal_length_mm

    scene = Scene((Plane(near, Noise(feature_mm=4 * lens_footprint(near), seed=11), region_mm=(-40, 0, -40, 40),
                         tint=(1.0, 0.6, 0.3)),
                   Plane(far, Noise(feature_mm=4 * lens_footprint(far), seed=12), tint=(0.4, 0.7, 1.0))),
                  background=0.2)
    sim = simulate.render(CAMERA, scene, SHAPE, rotation_deg=-0.0316, pixel_samples=2, aperture_samples=3, seed=1,
                          ideal_views=False)
    height, width = SHAPE
    caldata = SAMPLE / "caldata"
    caldata.mkdir(parents=True, exist_ok=True)
    capture_doc = lytrogen.illum_document(width, height, modulation=False, exit_pupil_m=TELECENTRIC)
    lytrogen.write_container(SAMPLE / "IMG_0001.lfr", sim.raw, 10, "little", *lytrogen.frame_metadata_of(capture_doc),
                             modulation=False)
    lytrogen.write_raw_pair(caldata / "MOD_0000.RAW", sim.white, 10, "little",
                            lytrogen.illum_document(width, height, exit_pupil_m=TELECENTRIC), ".TXT")
    lytrogen.write_raw_pair(caldata / "MOD_0001.RAW", sim.white, 10, "little",
                            lytrogen.illum_document(width, height, zoom_step=-600, focal_length_m=0.0500,
                                                                    exit_pupil_m=TELECENTRIC), ".TXT")
    total = 0
    for path in sorted(p for p in SAMPLE.rglob("*") if p.is_file()):
        data = path.read_bytes()
        total += len(data)
        print(f"{str(path.relative_to(SAMPLE)):24s} {len(data):>9d} B  sha256 {hashlib.sha256(data).hexdigest()[:16]}")
    print(f"{'total':24s} {total:>9d} B   (near plane {near:.1f} mm, far plane {far:.1f} mm from the sensor)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
