"""Pictures for people: refocus and view animations, mosaic previews (8-bit sRGB, enlarged, labelled).

Each preview is tone-mapped with one exposure for all its frames (:class:`ToneMap`, documented
there), enlarged to at least :data:`MIN_LONG_SIDE_PX` on its long side (:func:`upscale`, Lanczos by
default) and, for focal stacks, each frame is labelled with its distance and depth of field in
metres. The linear TIFF/EXR outputs stay the data products; these files are for looking at. PNG/JPEG
previews embed what they show and their label (:func:`write_png_preview`), for ``lfproc info``.
"""

from __future__ import annotations

import os

import numpy as np

from .. import geometry
from ..io import write_gif_frames, write_png_preview
from ..viewpoints import circular_walk
from ._display import DEFAULT_UPSCALE, MIN_LONG_SIDE_PX, add_label, as_rgb, slice_label, upscale, upscale_factor
from ._names import slice_names, view_name
from ._optics_tags import lens_spacing_tag
from ._products import mosaic_of_shown, shown_block
from ._tone import ToneMap

SLICE_FRAME_MS, VIEW_FRAME_MS = 400, 80


def display_frames(images, tone: ToneMap | None = None, min_long_side: int = MIN_LONG_SIDE_PX,
                   method: str = DEFAULT_UPSCALE, labels=None) -> list[np.ndarray]:
    """8-bit display frames of linear images (grey ``(H, W)`` or RGB ``(H, W, 3)``): one exposure, enlarged
    (``method``: :func:`upscale`), optionally labelled."""
    images = np.asarray(images)
    tone = tone or ToneMap.for_images(images)
    factor = upscale_factor(images.shape[1:], min_long_side)
    frames = []
    for k, image in enumerate(images):
        frame = _grey_or_rgb(upscale(tone(image), factor, method))
        frames.append(add_label(frame, labels[k]) if labels is not None else frame)
    return frames


def _grey_or_rgb(image: np.ndarray) -> np.ndarray:
    """``(H, W)`` for a one-channel image (a third of the bytes to encode), ``(H, W, 3)`` otherwise."""
    if image.ndim == 3 and image.shape[2] == 1:
        return image[:, :, 0]
    return image if image.ndim == 2 else as_rgb(image)


PREVIEW_FORMATS = {"png": ".png", "jpeg": ".jpg"}


def slice_labels(camera, a_values, view_mask=None) -> list[str]:
    """Each slice's label: its distance and depth of field in metres (:func:`slice_label`), the DOF of the
    views ``view_mask`` marks (all without it)."""
    extent = None if view_mask is None else geometry.summed_view_extent(view_mask)
    geo = geometry.slice_geometry(camera, np.asarray(a_values, dtype=np.float64), extent)
    depth, near, far = (np.atleast_1d(x) for x in (geo.depth, geo.near, geo.far))
    if geo.space.toward_optics < 0:   # distances, to infinity: in metres
        return [slice_label(d / geo.space.per_mm, lo / geo.space.per_mm, hi / geo.space.per_mm)
                for d, lo, hi in zip(depth, near, far)]
    space = geo.space                 # signed depths (µm from the native object plane): the DOF low to high
    return [f"{space.letter} {z:+.1f} {space.symbol} | DOF {min(lo, hi):+.1f} to {max(lo, hi):+.1f} {space.symbol}"
            for z, lo, hi in zip(depth.tolist(), near.tolist(), far.tolist())]


def write_slice_previews(outdir: str, stem: str, images: np.ndarray, camera, a_values, fmt: str = "png", *,
                         view_mask=None, min_long_side: int = MIN_LONG_SIDE_PX, method: str = DEFAULT_UPSCALE) -> list[str]:
    """Display-ready pictures of refocused slices: ``OUTDIR/NAME_preview.png`` (or ``.jpg``) beside each slice.

    One exposure for the whole stack (:class:`ToneMap`), so slices compare; enlarged to at least
    ``min_long_side`` pixels and labelled with the slice's distance and DOF in metres (of the views
    ``view_mask`` marks: those summed). Up to four slices are enlarged and written at a time.
    """
    from concurrent.futures import ThreadPoolExecutor

    images = np.asarray(images)
    labels = slice_labels(camera, a_values, view_mask)
    tone = ToneMap.for_images(images)
    names = slice_names(stem, a_values, camera)
    a_list = [float(a) for a in np.atleast_1d(a_values)]

    def one(k: int) -> str:   # enlarging (OpenCV) and encoding (zlib) release the GIL: slices in parallel
        frame = display_frames(images[k][None], tone, min_long_side, method, [labels[k]])[0]
        return write_png_preview(os.path.join(outdir, f"{names[k]}_preview{PREVIEW_FORMATS[fmt]}"), frame,
                                 {"preview": "refocused slice", "a": a_list[k], "label": labels[k]})

    with ThreadPoolExecutor(max_workers=min(4, os.cpu_count() or 1, max(len(names), 1))) as pool:
        return list(pool.map(one, range(len(names))))


def view_label(camera, ky: int, kx: int, centre=None) -> str:
    """``"view [5, 7] | 0.72 mm from the centre"``: the view and its virtual camera's offset (Eq. 17); an
    orthographic view (a microscope's): its angle in the object (sine condition). ``centre``: where the
    central view was read (``LightField.view_centre``), as in the views' tags."""
    cy, cx = (0.0, 0.0) if centre is None else (float(centre[0]), float(centre[1]))
    offsets = geometry.view_offsets(camera)
    along_y, along_x = geometry.place_views(camera, offsets + cy), geometry.place_views(camera, offsets + cx)
    if along_y.orthographic:   # directions: the angle in the object
        return f"view [{ky}, {kx}] | {np.hypot(along_y.tilt_deg[ky], along_x.tilt_deg[kx]):.1f} deg in the object"
    return f"view [{ky}, {kx}] | {np.hypot(along_y.position_mm[ky], along_x.position_mm[kx]):.2f} mm from the centre"


def write_view_previews(outdir: str, stem: str, views: np.ndarray, keep: np.ndarray | None, camera,
                        fmt: str = "png", *, min_long_side: int = MIN_LONG_SIDE_PX,
                        method: str = DEFAULT_UPSCALE, centre=None) -> list[str]:
    """Display-ready pictures of the views ``keep`` marks: ``OUTDIR/STEM_view_KY_KX_preview.png``, one exposure."""
    m = views.shape[0]
    chosen = [(ky, kx) for ky in range(m) for kx in range(m) if keep is None or keep[ky, kx]]
    if not chosen:
        return []
    tone = ToneMap.for_images(np.stack([views[k] for k in chosen]))
    paths = []
    for ky, kx in chosen:
        label = view_label(camera, ky, kx, centre)
        frame = display_frames(views[ky, kx][None], tone, min_long_side, method, [label])[0]
        paths.append(write_png_preview(os.path.join(outdir, f"{view_name(stem, ky, kx)}_preview{PREVIEW_FORMATS[fmt]}"),
                                       frame, {"preview": "view", "view": [ky, kx], "label": label}))
    return paths


def write_slice_gif(outdir: str, stem: str, images: np.ndarray, camera=None, a_values=None, *,
                    min_long_side: int = MIN_LONG_SIDE_PX, method: str = DEFAULT_UPSCALE, view_mask=None) -> str:
    """An animation running through a focal stack in the given order and back: ``OUTDIR/STEM_refocus.gif``.

    With ``camera`` and ``a_values`` (one per image) each frame is labelled with its distance and DOF
    in metres (:func:`lfproc.geometry.slice_geometry`), the DOF of the views ``view_mask`` marks (all when
    ``None``).
    """
    images = np.asarray(images)
    labels = slice_labels(camera, a_values, view_mask) if camera is not None and a_values is not None else None
    frames = display_frames(images, min_long_side=min_long_side, method=method, labels=labels)
    tags = {"preview": "refocus animation", "frames": len(frames)}
    if a_values is not None:
        tags["a"] = [float(a) for a in np.atleast_1d(a_values)]
    if len(frames) > 2:
        frames = frames + frames[-2:0:-1]
    return write_gif_frames(os.path.join(outdir, f"{stem}_refocus.gif"), frames, SLICE_FRAME_MS, tags)


def write_view_gif(outdir: str, stem: str, views: np.ndarray, mask: np.ndarray | None = None, camera=None, *,
                   min_long_side: int = MIN_LONG_SIDE_PX, method: str = DEFAULT_UPSCALE, centre=None) -> str:
    """An animation walking the views along a circle inside the aperture: ``OUTDIR/STEM_views.gif``.

    With ``camera`` each frame is labelled with its view and its virtual camera's distance from the
    central one (Eq. 17) in millimetres.
    """
    walk = circular_walk(views.shape[0], mask=mask)
    frames = np.stack([views[k] for k in walk])
    labels = [view_label(camera, ky, kx, centre) for ky, kx in walk] if camera is not None else None
    tone = ToneMap.for_images(frames)
    shown = display_frames(frames, tone, min_long_side, method, labels)
    return write_gif_frames(os.path.join(outdir, f"{stem}_views.gif"), shown, VIEW_FRAME_MS,
                            {"preview": "view animation", "frames": len(walk), "views_per_side": int(views.shape[0])})


def write_mosaic_preview(outdir: str, stem: str, views: np.ndarray, keep: np.ndarray | None = None, *,
                         camera=None, min_long_side: int = MIN_LONG_SIDE_PX, method: str = DEFAULT_UPSCALE) -> str:
    """The view mosaic as an 8-bit PNG for looking at: ``OUTDIR/STEM_views_mosaic_preview.png``.

    Like the mosaic data product it shows the views ``keep`` marks, cropped to their rows and columns
    (others black); views are separated by 1-pixel black lines. The picture is labelled with how many
    views it shows and, with ``camera``, the baseline of adjacent views (Eq. 34).
    """
    m = views.shape[0]
    tone = ToneMap.for_images(views if keep is None else views[np.asarray(keep, bool)])
    tiled, _ = mosaic_of_shown(views, keep, gap=1)
    shown = m * m if keep is None else int(np.count_nonzero(keep))
    label = f"{shown} of {m}x{m} views" + ("" if shown == m * m else " (black: no light or outside the aperture)")
    if camera is not None:
        key, spacing = lens_spacing_tag(camera)
        label += (f" | {spacing:.3g} µm per lens" if key == "lateral_sampling_um" else
                  f" | baseline {float(spacing):.3g} mm")
    factor = upscale_factor(tiled.shape, min_long_side)
    if factor > 1 and method != "nearest":   # each view enlarged alone: none bleeds into its neighbours or gaps
        from ..viewpoints import mosaic

        rows, cols = shown_block(keep, m)
        lit = np.ones((m, m), bool) if keep is None else np.asarray(keep, bool)
        big = np.stack([np.stack([upscale(tone(views[ky, kx]), factor, method) * np.uint8(lit[ky, kx])
                                  for kx in range(cols.start, cols.stop)]) for ky in range(rows.start, rows.stop)])
        frame = add_label(_grey_or_rgb(mosaic(big, gap=factor).astype(np.uint8)), label)
    else:
        frame = display_frames(tiled[None], tone, min_long_side, method, [label])[0]
    return write_png_preview(os.path.join(outdir, f"{stem}_views_mosaic_preview.png"), frame,
                             {"preview": "view mosaic", "views_shown": shown, "views_per_side": m, "label": label})
