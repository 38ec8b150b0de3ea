"""Every check on every real file: writes docs/real-data.json and the table in docs/real-data.md.

Real files are the public captures in ``../shared/real`` (or the folder ``LFPROC_REAL_DATA`` names; its README
says what each is); the simulated ones
are the bundled sample's capture and white image and the Lytro sample's white image. For each file:
calibration (whites: pitch, its uncertainty, residual, rotation, lenses, m̂ the measured pitch gives), the
white/scene measures of `lfproc.inputs` (texture ratio with its refusal limit, lens-to-lens contrast shared with
neighbouring lenses and their correlation, with the warning limits) and what they decide when the file is given as a white image, and for captures
the lens-level flatness of the decoded views (a white image given as the capture is refused below 0.5 %).

Run from the repository root::

    PYTHONPATH=$PWD python scripts/real_data_report.py

The table in docs/real-data.md is replaced between its ``real-data-table`` markers; nothing else there changes.
"""

from __future__ import annotations

import json
import os
import sys
import time
import warnings
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
REAL = Path(os.environ["LFPROC_REAL_DATA"]).expanduser() if os.environ.get("LFPROC_REAL_DATA") else \
    ROOT.parent / "shared" / "real"
CAMERAS = ROOT / "tests" / "real" / "cameras"
SAMPLES = ROOT / "lfproc" / "samples"
DOC = ROOT / "docs" / "real-data.md"
START, END = "<!-- real-data-table:start -->", "<!-- real-data-table:end -->"

#: (name, file, camera file or None, "white" or "capture", the white image the capture belongs to, origin)
FILES = [
    ("seaurchin radiometry", REAL / "lfm-seaurchin" / "radiometry_frame.tif", CAMERAS / "seaurchin-20x.toml", "white",
     None, "real"),
    ("seaurchin capture", REAL / "lfm-seaurchin" / "light_field.tif", CAMERAS / "seaurchin-20x.toml", "capture",
     "seaurchin radiometry", "real"),
    ("HyLFM flat", REAL / "lfm-hylfm-beads" / "img_bg.tif", CAMERAS / "hylfm.toml", "white", None, "real"),
    ("HyLFM beads", REAL / "lfm-hylfm-beads" / "img_beads.tif", CAMERAS / "hylfm.toml", "capture", "HyLFM flat", "real"),
    ("sample white", SAMPLES / "sample" / "white.png", SAMPLES / "sample" / "camera.toml", "white", None, "simulated"),
    ("sample capture", SAMPLES / "sample" / "capture.png", SAMPLES / "sample" / "camera.toml", "capture",
     "sample white", "simulated"),
    ("Lytro sample white", SAMPLES / "lytro" / "caldata" / "MOD_0000.RAW", None, "white", None, "Lytro F01 (bundled)"),
]
DARK = {"seaurchin radiometry": REAL / "lfm-seaurchin" / "dark_frame.tif",
        "seaurchin capture": REAL / "lfm-seaurchin" / "dark_frame.tif"}


def measure(name, path, camera_path, kind, white_of, origin, grids) -> dict:
    """The row of one file (module docstring)."""
    from lfproc.calibrate import TEXTURE_LIMIT, find_grid
    from lfproc.camera import Camera
    from lfproc.errors import LfprocError
    from lfproc.inputs import (SCENE_CONTRAST_LIMIT, SCENE_CORRELATION_LIMIT, WHITE_FLATNESS, check_white_is_white,
                               lens_flatness, measured_m_hat, read_dark, subtract_dark, white_evidence)
    from lfproc.io import read_capture

    camera = Camera.from_toml(str(camera_path)) if camera_path else None
    start = time.perf_counter()
    image = read_capture(str(path), camera)
    if name in DARK:
        image = subtract_dark(image, read_dark(str(DARK[name]), camera), kind)
    row = {"file": str(path.relative_to(path.parents[2] if origin == "real" else ROOT)), "origin": origin,
           "kind": kind, "size": f"{image.data.shape[1]} x {image.data.shape[0]}", "dark": name in DARK}
    if kind == "white":
        estimate = find_grid(image.data, kind=camera.grid if camera else "hexagonal",
                             approx_pitch_px=camera.pitch_px if camera else None, cfa=image.cfa, source=name)
        grid = grids[name] = estimate.grid
        row.update(pitch_px=grid.pitch_px, pitch_sigma_px=estimate.pitch_sigma_px,
                   residual_px=grid.residual_rms_px, rotation_deg=grid.rotation_deg, lenses=grid.rows * grid.cols,
                   lenses_fitted=int(estimate.inlier.sum()), model=grid.model)
        if camera is not None:
            row.update(nominal_pitch_px=camera.pitch_px, m_hat=measured_m_hat(camera, grid.pitch_px).camera.m_hat,
                       nominal_m_hat=camera.m_hat, m_hat_given=camera.micro_image_px_given)
    else:
        grid = grids[white_of]
    evidence = white_evidence(image.data, image.cfa, grid)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            check_white_is_white(name, image.data, image.cfa, grid)
            verdict = "warned" if caught else "accepted"
        except LfprocError:
            verdict = "refused"
    row.update(texture_ratio=evidence.texture, texture_limit=TEXTURE_LIMIT, lens_contrast=evidence.contrast,
               lens_correlation=evidence.correlation, contrast_limit=SCENE_CONTRAST_LIMIT,
               correlation_limit=SCENE_CORRELATION_LIMIT, as_white=verdict)
    if kind == "capture" and camera is not None:
        from lfproc.decode import make_decoder
        white = read_capture(str(dict((n, p) for n, p, *_ in FILES)[white_of]), camera)
        if white_of in DARK:
            white = subtract_dark(white, read_dark(str(DARK[white_of]), camera), "white image")
        m_hat = measured_m_hat(camera, grid.pitch_px).camera.m_hat
        decoder = make_decoder(white.data, grid, m_hat, white.cfa)
        views = decoder(image.data, image.cfa)
        from lfproc.depth import UNLIT_FRACTION, lit_lenses
        lit = lit_lenses(views, decoder.views_delivered)
        row.update(lens_flatness=lens_flatness(views, decoder.views_delivered), flatness_limit=WHITE_FLATNESS,
                   m_hat=m_hat, lit_lens_fraction=float(lit.mean()), unlit_fraction=UNLIT_FRACTION)
    row["seconds"] = time.perf_counter() - start
    return row


def markdown(rows) -> str:
    def num(v, fmt):
        return "—" if v is None else format(v, fmt)

    head = ("| file | origin | kind | calibration: pitch px (± σ) | residual px | rotation ° | lenses (fitted) | m̂ used "
            "(nominal) | texture ratio (refused > 0.04) | lens-to-lens contrast shared with neighbours, their correlation "
            "(warned > 0.5 % and 0.3) | given as "
            "white | decoded lens flatness (white < 0.5 %) | lit lenses (≥ 5 % of the bright level) | time s |")
    lines = [head, "| " + " | ".join(["---"] * 14) + " |"]
    for r in rows:
        cal = (f"{r['pitch_px']:.4f} (± {r['pitch_sigma_px']:.4f})" if "pitch_px" in r else "—")
        lenses = f"{r['lenses']} ({r['lenses_fitted']})" if "lenses" in r else "—"
        m_hat = (f"{r['nominal_m_hat']} (stated)" if r.get("m_hat_given") else
                 f"{r['m_hat']} ({r['nominal_m_hat']})" if "nominal_m_hat" in r else str(r.get("m_hat", "—")))
        flat = f"{100 * r['lens_flatness']:.1f} %" if "lens_flatness" in r else "—"
        lit = f"{100 * r['lit_lens_fraction']:.1f} %" if "lit_lens_fraction" in r else "—"
        lines.append(f"| `{r['file']}`{' (dark subtracted)' if r['dark'] else ''} | {r['origin']} | {r['kind']} | {cal} | "
                     f"{num(r.get('residual_px'), '.4f')} | {num(r.get('rotation_deg'), '.4f')} | {lenses} | {m_hat} | "
                     f"{r['texture_ratio']:.4f} | {100 * r['lens_contrast']:.2f} %, {r['lens_correlation']:+.2f} | "
                     f"{r['as_white']} | {flat} | {lit} | {r['seconds']:.1f} |")
    return "\n".join(lines)


def main() -> int:
    if not REAL.is_dir():
        print(f"{REAL}: missing; the real files are not here", file=sys.stderr)
        return 2
    grids, rows = {}, []
    for entry in FILES:
        rows.append({"name": entry[0], **measure(*entry, grids)})
        print(f"{entry[0]}: done in {rows[-1]['seconds']:.1f} s", file=sys.stderr)
    safe = [{k: (None if isinstance(v, float) and v != v or v in (float("inf"),) else v) for k, v in r.items()}
            for r in rows]
    (ROOT / "docs" / "real-data.json").write_text(json.dumps(safe, indent=1, default=float, allow_nan=False) + "\n")
    text = DOC.read_text()
    before, rest = text.split(START, 1)
    after = rest.split(END, 1)[1]
    DOC.write_text(before + START + "\n" + markdown(rows) + "\n" + END + after)
    return 0


if __name__ == "__main__":
    sys.exit(main())
