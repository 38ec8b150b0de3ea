"""A processed Lytro picture's perspective views (edofParallax) and its depth preview in lambda, for ``export``.

* ``STEM_parallax_KK.tif`` — view K, linear float32 (the H.264 frame decoded, sRGB transfer inverted),
  with ``coord`` [x, y], its position in the aperture; with ``jpeg`` also ``STEM_parallax_KK.jpg``, the
  8-bit sRGB frame as a JPEG (quality 95) carrying the same metadata;
* with ``wobble``: ``STEM_wobble.gif``, the views in the order of their angle around the aperture centre
  (a "wobble" animation), looping;
* ``STEM_depth_lambda_preview.png`` where no camera is known: the depth map coloured in lambda (the
  depth preview's colour scale, larger lambda nearer), smoothly enlarged (Lanczos), NaN grey, with a
  legend in lambda.
"""

from __future__ import annotations

import math
import os

import numpy as np

#: display time of each frame of the wobble animation
WOBBLE_FRAME_MS = 120
#: the lambda preview is enlarged to about this long side
PREVIEW_LONG_SIDE_PX = 480


def view_jobs(picture, common: dict, outdir: str, stem: str, *, jpeg: bool = False, wobble: bool = False) -> list:
    """``(target, writer)`` pairs for every perspective view (decoded now, written later)."""
    from ..io import decode_picture_views as decode_views
    from ._lytro_pictures import _image_writer, _jpeg_writer, _linear
    from ..io import encode_jpeg

    views = list(picture.parallax.views)
    frames = decode_views(picture)
    jobs, coords = [], []
    for k, rgb in enumerate(frames):
        view = views[k] if k < len(views) else None
        coord = None if view is None else [view[2], view[3]]
        coords.append(coord)
        metadata = dict(common, kind="perspective view (edofParallax, all in focus)", index=k, **{"lambda": None},
                        coord=coord, encoding="H.264 decoded, linear float32" + (
                            "; .jpg: the decoded 8-bit sRGB frame, JPEG quality 95" if jpeg else ""))
        name = os.path.join(outdir, f"{stem}_parallax_{k:02d}")
        jobs.append((name + ".tif", _image_writer(_linear(rgb), metadata)))
        if jpeg:
            jobs.append((name + ".jpg", _jpeg_writer(encode_jpeg(rgb), metadata)))
    if wobble:
        order = wobble_order(coords)
        tags = {"preview": "perspective view animation", "source": common["source"], "frames": len(order),
                "order": order, "coords": [coords[k] for k in order]}
        shown = [frames[k] for k in order]
        jobs.append((os.path.join(outdir, f"{stem}_wobble.gif"), _gif_writer(shown, tags)))
    return jobs


def wobble_order(coords: list) -> list[int]:
    """View indices sorted by the angle of their aperture coordinate around the views' centre (views
    without a coordinate, or at the centre, keep stream order after the others)."""
    known = [(k, c) for k, c in enumerate(coords) if c is not None and None not in c]
    if len(known) < 2:
        return list(range(len(coords)))
    cx = sum(c[0] for _, c in known) / len(known)
    cy = sum(c[1] for _, c in known) / len(known)
    ring = [(math.atan2(c[1] - cy, c[0] - cx), k) for k, c in known if math.hypot(c[0] - cx, c[1] - cy) > 1e-9]
    ordered = [k for _, k in sorted(ring)]
    return ordered + [k for k in range(len(coords)) if k not in ordered]


def _gif_writer(frames, tags):
    def write(target):
        from ..io import write_gif_frames

        write_gif_frames(target, [np.ascontiguousarray(f, np.uint8) for f in frames], WOBBLE_FRAME_MS, tags)
    return write


def lambda_preview(lam: np.ndarray) -> np.ndarray:
    """uint8 RGB: the depth map in lambda coloured (larger lambda nearer: the depth preview's near colour),
    enlarged with Lanczos to about ``PREVIEW_LONG_SIDE_PX``, NaN grey, and a legend in lambda."""
    from PIL import Image, ImageDraw, ImageFont

    from ..colours import UNKNOWN_COLOUR, colour_scale

    known = lam[np.isfinite(lam)]
    lo, hi = (float(v) for v in np.percentile(known, [1, 99])) if known.size else (-1.0, 1.0)
    if hi <= lo:
        lo, hi = lo - 1.0, hi + 1.0
    t = np.clip((np.nan_to_num(lam, nan=lo) - lo) / (hi - lo), 0.0, 1.0)
    rgb = colour_scale(t)
    rgb[~np.isfinite(lam)] = UNKNOWN_COLOUR
    ny, nx = lam.shape
    scale = max(1.0, PREVIEW_LONG_SIDE_PX / max(ny, nx))
    body = Image.fromarray(np.ascontiguousarray(rgb, np.uint8)).resize(
        (max(1, round(nx * scale)), max(1, round(ny * scale))), Image.LANCZOS)
    margin, bar_w, label_w = 10, 18, 90
    height = max(body.height, 160)
    canvas = Image.new("RGB", (body.width + margin + bar_w + label_w, height + 2 * margin), (255, 255, 255))
    canvas.paste(body, (0, margin))
    bar_h = height - 24
    x0, y0 = body.width + margin, margin + 12
    canvas.paste(Image.fromarray(colour_scale(np.linspace(1.0, 0.0, bar_h)[:, None].repeat(bar_w, axis=1))), (x0, y0))
    draw = ImageDraw.Draw(canvas)
    font = ImageFont.load_default()
    draw.text((x0, margin - 8), "lambda", fill=(0, 0, 0), font=font)
    for position, value in ((1.0, hi), (0.5, (lo + hi) / 2), (0.0, lo)):
        y = y0 + round((1.0 - position) * (bar_h - 1))
        draw.line([(x0 + bar_w, y), (x0 + bar_w + 4, y)], fill=(0, 0, 0))
        draw.text((x0 + bar_w + 6, y - 5), f"{value:.3g}", fill=(0, 0, 0), font=font)
    draw.text((x0, y0 + bar_h + 2), "grey: unknown", fill=(80, 80, 80), font=font)
    return np.asarray(canvas)


def lambda_preview_writer(lam: np.ndarray):
    def write(target):
        from ._previews import write_png_preview

        write_png_preview(target, lambda_preview(lam), {"preview": "depth map", "legend": "lambda"})
    return write
