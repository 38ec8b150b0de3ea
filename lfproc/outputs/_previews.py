"""Pictures for people: refocus and view animations, mosaic previews (8-bit sRGB, enlarged, labelled).

Each preview is tone-mapped with one exposure for all its frames (:class:`ToneMap`, documented
there), enlarged to at least :data:`MIN_LONG_SIDE_PX` on its long side (:func:`upscale`, nearest by
default) and, for focal stacks, each frame is labelled with its distance and depth of field in
metres. The linear TIFF/EXR outputs stay the data products; these files are for looking at.
"""

from __future__ import annotations

import os

import numpy as np

from .. import geometry
from ..atomic import atomic_path
from ..errors import LfprocError
from ..viewpoints import circular_walk, mosaic
from ._display import MIN_LONG_SIDE_PX, add_label, as_rgb, slice_label, upscale, upscale_factor
from ._products import masked_views
from ._tone import ToneMap

SLICE_FRAME_MS, VIEW_FRAME_MS = 400, 80


def display_frames(images, tone: ToneMap | None = None, min_long_side: int = MIN_LONG_SIDE_PX,
                   method: str = "nearest", labels=None) -> list[np.ndarray]:
    """8-bit RGB display frames of linear images: one exposure, enlarged, optionally labelled."""
    images = np.asarray(images)
    tone = tone or ToneMap.for_images(images)
    factor = upscale_factor(images.shape[1:], min_long_side)
    frames = []
    for k, image in enumerate(images):
        frame = as_rgb(upscale(tone(image), factor, method))
        frames.append(add_label(frame, labels[k]) if labels is not None else frame)
    return frames


def write_gif_frames(path: str | os.PathLike, frames, duration_ms: float) -> str:
    """An endlessly looping GIF of 8-bit RGB frames (Pillow), written atomically."""
    from PIL import Image

    path = os.fspath(path)
    if not frames:
        raise LfprocError(f"{path}: no frames to write; pass at least one image")
    images = [Image.fromarray(np.ascontiguousarray(frame)) for frame in frames]
    try:
        with atomic_path(path, suffix=".gif") as tmp:
            images[0].save(tmp, format="GIF", save_all=True, append_images=images[1:],
                           duration=int(round(duration_ms)), loop=0)
    except OSError as exc:
        raise LfprocError(f"{path}: cannot write GIF ({exc.strerror or exc}); check the folder and "
                          f"permissions") from None
    return path


def write_png_preview(path: str | os.PathLike, image: np.ndarray) -> str:
    """Write an 8-bit image as PNG (Pillow), atomically."""
    from PIL import Image

    path = os.fspath(path)
    pixels = image[:, :, 0] if image.ndim == 3 and image.shape[2] == 1 else image
    try:
        with atomic_path(path, suffix=".png") as tmp:
            Image.fromarray(np.ascontiguousarray(pixels)).save(tmp, format="PNG")
    except OSError as exc:
        raise LfprocError(f"{path}: cannot write PNG ({exc.strerror or exc}); check the folder and "
                          f"permissions") from None
    return path


def write_slice_gif(outdir: str, stem: str, images: np.ndarray, camera=None, a_values=None, *,
                    min_long_side: int = MIN_LONG_SIDE_PX, method: str = "nearest") -> str:
    """An animation running through a focal stack in the given order and back: ``OUTDIR/STEM_refocus.gif``.

    With ``camera`` and ``a_values`` (one per image) each frame is labelled with its distance and DOF
    in metres (:func:`lfproc.geometry.slice_geometry`).
    """
    images = np.asarray(images)
    labels = None
    if camera is not None and a_values is not None:
        geo = geometry.slice_geometry(camera, np.asarray(a_values, dtype=np.float64))
        if geo.microscope:
            labels = [f"z {r['z_um']:+.1f} um | DOF {r['z_far_um']:+.1f} - {r['z_near_um']:+.1f} um"
                      for r in geo.records()]
        else:
            labels = [slice_label(d, lo, hi) for d, lo, hi in zip(np.atleast_1d(geo.distance_mm),
                                                                  np.atleast_1d(geo.near_mm),
                                                                  np.atleast_1d(geo.far_mm))]
    frames = display_frames(images, min_long_side=min_long_side, method=method, labels=labels)
    if len(frames) > 2:
        frames = frames + frames[-2:0:-1]
    return write_gif_frames(os.path.join(outdir, f"{stem}_refocus.gif"), frames, SLICE_FRAME_MS)


def write_view_gif(outdir: str, stem: str, views: np.ndarray, mask: np.ndarray | None = None, camera=None, *,
                   min_long_side: int = MIN_LONG_SIDE_PX, method: str = "nearest") -> str:
    """An animation walking the views along a circle inside the aperture: ``OUTDIR/STEM_views.gif``.

    With ``camera`` each frame is labelled with its view and its virtual camera's distance from the
    central one (Eq. 17) in millimetres.
    """
    walk = circular_walk(views.shape[0], mask=mask)
    frames = np.stack([views[k] for k in walk])
    labels = None
    if camera is not None and camera.is_microscope:
        angles = geometry.microscope_views(camera).angle_deg
        labels = [f"view [{ky}, {kx}] | {np.hypot(angles[ky], angles[kx]):.1f} deg in the object" for ky, kx in walk]
    elif camera is not None:
        positions = geometry.view_positions_mm(camera)
        labels = [f"view [{ky}, {kx}] | {np.hypot(positions[ky], positions[kx]):.2f} mm from the centre"
                  for ky, kx in walk]
    tone = ToneMap.for_images(frames)
    shown = display_frames(frames, tone, min_long_side, method, labels)
    return write_gif_frames(os.path.join(outdir, f"{stem}_views.gif"), shown, VIEW_FRAME_MS)


def write_mosaic_preview(outdir: str, stem: str, views: np.ndarray, keep: np.ndarray | None = None, *,
                         min_long_side: int = MIN_LONG_SIDE_PX, method: str = "nearest") -> str:
    """The view mosaic as an 8-bit PNG for looking at: ``OUTDIR/STEM_views_mosaic_preview.png``.

    Views are separated by 1-pixel black lines; views that ``keep`` does not mark are black.
    """
    shown = masked_views(views, keep)
    tone = ToneMap.for_images(shown if keep is None else views[np.asarray(keep, bool)])
    tiled = mosaic(shown, gap=1)
    frame = display_frames(tiled[None], tone, min_long_side, method)[0]
    return write_png_preview(os.path.join(outdir, f"{stem}_views_mosaic_preview.png"), frame)


