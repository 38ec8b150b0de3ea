"""A viewer page for a processed Lytro picture: its focus stack, the image sharpest where one clicks.

Layout of the page folder: ``index.html`` (data inline) and ``stack/STEM_stack_KK.jpg`` (the stored
JPEGs, copied as they are). Which image is sharpest where is decided before the page is written, on a
grid of regions: from the picture's depth map where it has one (the stack image whose lambda is
nearest the depth's lambda) and otherwise from the images themselves (the largest local contrast,
the mean squared Laplacian of the grey image over each region). Distances come from the lambda map
(``lfproc.io._lytro_lambda``) where the metadata describes the camera.
"""

from __future__ import annotations

import html
import io
import os

import numpy as np

from ..atomic import atomic_path, write_text_atomic
from ..errors import LfprocError
from ._page import _asset, encode_array, script_json

#: regions across the long side when the choice comes from sharpness
REGIONS = 24


def build_picture_page(path: str, outdir: str, *, stem: str, index_href: str | None = None) -> str:
    """Write the viewer page of the picture at ``path`` into ``outdir``; returns its ``index.html``.

    Raises
    ------
    LfprocError
        A damaged picture, or one without a focus stack.
    """
    from ..io import depth_lambda, open_picture, picture_lambda_map

    from ..io import stack_images

    picture = open_picture(path)
    if not picture.stack:
        if picture.parallax is not None:
            return _views_page(picture, outdir, stem=stem, index_href=index_href)
        held = ", ".join(picture.contents)
        raise LfprocError(f"{path}: holds no raw light field but a processed Lytro picture ({held}) with no focus "
                          f"stack and no perspective views to view; use `lfproc.outputs.export_picture` for its depth "
                          f"map, or the raw .lfp/.lfr the camera wrote")
    meta, mapping, why = picture_lambda_map(picture)
    lambdas = np.array([s.lambda_ for s in picture.stack])
    records = mapping.slices(lambdas) if mapping else [{"lambda": float(v)} for v in lambdas]
    jpegs = [data for data, _ in stack_images(picture)]
    if picture.depth is not None and picture.depth.kind == "depth map":
        choice = nearest_lambda(depth_lambda(picture), lambdas)
        method = "sharpest image per region: the stack image whose lambda is nearest the picture's depth map there"
    else:
        choice = sharpest_per_region([_grey(data, path) for data in jpegs])
        method = ("sharpest image per region: the largest mean squared Laplacian of the grey images over "
                  f"{choice.shape[0]} x {choice.shape[1]} regions")
    images = []
    for image, record, data in zip(picture.stack, records, jpegs):
        relative = f"stack/{stem}_stack_{image.index:02d}.jpg"
        _write_bytes(os.path.join(outdir, relative), data)
        images.append(dict(record, image=relative))
    default = picture.default_lambda if picture.default_lambda is not None else float(np.median(lambdas))
    facts = [["source", os.path.abspath(path)], ["holds", ", ".join(picture.contents)]]
    if mapping:
        facts += [["camera", f"Lytro {meta.model}" + (f", serial {meta.serial}" if meta.serial else "")],
                  ["main lens", f"f = {mapping.focal_length_mm:.2f} mm, f/{mapping.f_number:.2f}"],
                  ["distances", "derived from lambda (docs/lytro.md)"]]
    else:
        facts.append(["distances", f"unknown: {why}"])
    data = {"format": "lfproc-picture-viewer-1", "source": os.path.abspath(path), "stem": stem, "images": images,
            "choice": encode_array(choice.astype(np.uint8)), "start": int(np.argmin(np.abs(lambdas - default))),
            "method": method, "facts": facts, "index_href": index_href}
    return _write_page(outdir, stem, data)


def _write_bytes(target: str, data: bytes) -> None:
    os.makedirs(os.path.dirname(target), exist_ok=True)
    with atomic_path(target) as tmp, open(tmp, "wb") as fh:
        fh.write(data)


def _views_page(picture, outdir: str, *, stem: str, index_href: str | None) -> str:
    """The page of a picture that holds only perspective views (an edofParallax block): a click shows the view
    whose aperture coordinate is nearest the clicked point's position in the picture (left edge: the leftmost
    view), the slider steps through them."""
    from ..io import decode_picture_views as decode_views
    from ..io import encode_jpeg

    frames = decode_views(picture)
    views = list(picture.parallax.views)
    coords = []
    for k in range(len(frames)):
        view = views[k] if k < len(views) else None
        coords.append((view[2], view[3]) if view is not None and None not in view[2:] else (0.0, 0.0))
    images = []
    for k, (rgb, (x, y)) in enumerate(zip(frames, coords)):
        relative = f"views/{stem}_parallax_{k:02d}.jpg"
        _write_bytes(os.path.join(outdir, relative), encode_jpeg(rgb))
        images.append({"image": relative, "x": x, "y": y, "label": f"perspective view {k}, aperture position "
                                                                    f"({x:+.3g}, {y:+.3g})"})
    choice = nearest_view(np.array(coords, dtype=np.float64))
    facts = [["source", os.path.abspath(picture.path)], ["holds", ", ".join(picture.contents)],
             ["views", f"{len(images)} all-in-focus perspective views (H.264 edofParallax block)"]]
    data = {"format": "lfproc-picture-viewer-1", "source": os.path.abspath(picture.path), "stem": stem,
            "images": images, "choice": encode_array(choice.astype(np.uint8)),
            "start": int(np.argmin(np.hypot(*np.array(coords, dtype=np.float64).T))),
            "method": "perspective view per region: the view whose aperture position is nearest the point's position "
                      "in the picture", "facts": facts, "index_href": index_href, "kind": "perspective views",
            "prompt": "Click the picture to look from that side of the aperture; the slider steps through the views."}
    return _write_page(outdir, stem, data)


def nearest_view(coords: np.ndarray, regions: int = REGIONS) -> np.ndarray:
    """Per region of a ``regions`` x ``regions`` grid over the picture, the index of the view whose aperture
    coordinate (scaled so the views span the grid) is nearest the region's centre."""
    centre = coords.mean(axis=0)
    half = np.abs(coords - centre).max(axis=0)
    half = np.where(half > 0, half, 1.0)
    t = (np.arange(regions) + 0.5) / regions * 2.0 - 1.0
    gy, gx = np.meshgrid(t * half[1] + centre[1], t * half[0] + centre[0], indexing="ij")
    distance = np.hypot(gx[..., None] - coords[:, 0], gy[..., None] - coords[:, 1])
    return np.argmin(distance, axis=-1)


def _write_page(outdir: str, stem: str, data: dict) -> str:
    page = os.path.join(outdir, "index.html")
    write_text_atomic(page, _asset("picture.html")
                      .replace("{{TITLE}}", html.escape(f"lfproc viewer: {stem}"))
                      .replace("{{CSS}}", _asset("viewer.css"))
                      .replace("{{DATA}}", script_json(data)))
    return page


def nearest_lambda(depth: np.ndarray, lambdas: np.ndarray) -> np.ndarray:
    """Per depth map pixel, the index of the stack lambda nearest the depth's lambda (NaN → the middle image)."""
    distance = np.abs(np.nan_to_num(depth, nan=float(np.median(lambdas)))[..., None] - lambdas)
    return np.argmin(distance, axis=-1)


def sharpest_per_region(grey: list[np.ndarray], regions: int = REGIONS) -> np.ndarray:
    """Per region of a grid (``regions`` across the long side), the index of the image with the largest mean
    squared Laplacian there."""
    height, width = grey[0].shape
    cell = max(2, int(np.ceil(max(height, width) / regions)))
    rows, cols = int(np.ceil(height / cell)), int(np.ceil(width / cell))
    energy = np.zeros((len(grey), rows, cols))
    for k, image in enumerate(grey):
        lap = np.zeros_like(image)
        lap[1:-1, 1:-1] = (image[:-2, 1:-1] + image[2:, 1:-1] + image[1:-1, :-2] + image[1:-1, 2:]
                           - 4.0 * image[1:-1, 1:-1])
        padded = np.zeros((rows * cell, cols * cell))
        padded[:height, :width] = lap ** 2
        energy[k] = padded.reshape(rows, cell, cols, cell).mean(axis=(1, 3))
    return np.argmax(energy, axis=0)


def _grey(data: bytes, where: str) -> np.ndarray:
    from PIL import Image, UnidentifiedImageError

    try:
        with Image.open(io.BytesIO(data)) as image:
            return np.asarray(image.convert("L"), dtype=np.float64)
    except (UnidentifiedImageError, OSError) as exc:
        raise LfprocError(f"{where}: a focus stack JPEG cannot be decoded ({exc}); re-copy the picture") from None


def build_picture_pages(paths: list[str], outdir: str, stems: dict) -> str:
    """One page per picture (in ``OUTDIR/STEM/`` when there are several, linked from ``OUTDIR/index.html``);
    returns the page to open."""
    from ._build import write_index

    if len(paths) == 1:
        return build_picture_page(paths[0], outdir, stem=stems[paths[0]])
    entries = []
    for path in paths:
        folder = os.path.join(outdir, stems[path])
        build_picture_page(path, folder, stem=stems[path], index_href="../index.html")
        entries.append(_entry(outdir, folder))
    return write_index(outdir, entries)


def _entry(outdir: str, folder: str) -> dict:
    """The index card of a picture page (read back from its inline data)."""
    import json

    with open(os.path.join(folder, "index.html"), encoding="utf-8") as fh:
        text = fh.read()
    start = text.index('id="lfproc-data">') + len('id="lfproc-data">')
    data = json.loads(text[start:text.index("</script>", start)])
    relative = os.path.relpath(folder, outdir).replace(os.sep, "/")
    lambdas = [s["lambda"] for s in data["images"] if s.get("lambda") is not None]
    span = f"lambda {min(lambdas):g} to {max(lambdas):g}" if lambdas else f"{len(data['images'])} perspective views"
    return {"stem": data["stem"], "href": f"{relative}/index.html",
            "thumbnail": f"{relative}/{data['images'][data['start']]['image']}", "source": data["source"],
            "slices": len(data["images"]), "range": span}
