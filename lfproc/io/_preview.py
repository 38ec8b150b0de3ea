"""8-bit pictures for people (previews, animations), written atomically with lfproc's tags embedded.

The tags (a JSON-able dict: what the picture shows, its label) are embedded the way `write_image` embeds
lfproc's metadata in its data products, so ``lfproc info`` can tell a preview for what it is. Pillow is
imported inside the writers.
"""

from __future__ import annotations

import os

import numpy as np

from ..atomic import atomic_path, json_safe
from ..errors import LfprocError


def write_gif_frames(path: str | os.PathLike, frames, duration_ms: float, tags: dict | None = None) -> str:
    """An endlessly looping GIF of 8-bit RGB frames (Pillow), written atomically.

    ``tags`` go into the GIF comment as JSON with ``"software": "lfproc"`` (GIF has no Software tag), for
    ``lfproc info``.
    """
    from PIL import Image

    path = os.fspath(path)
    if not frames:
        raise LfprocError(f"{path}: no frames to write; pass at least one image")
    images = [Image.fromarray(np.ascontiguousarray(frame)) for frame in frames]
    comment = {} if tags is None else {"comment": _tag_text(dict(tags, software="lfproc"))}
    try:
        with atomic_path(path, suffix=".gif") as tmp:
            images[0].save(tmp, format="GIF", save_all=True, append_images=images[1:],
                           duration=int(round(duration_ms)), loop=0, **comment)
    except OSError as exc:
        raise LfprocError(f"{path}: cannot write GIF ({exc.strerror or exc}); check the folder and "
                          f"permissions") from None
    return path


_JPEG_PREVIEW_QUALITY = 92
#: zlib level of PNG previews: 1 encodes a smooth (Lanczos) picture ~5x faster than Pillow's default 6 for
#: files ~15 % larger (a preview must cost a small fraction of the refocus it shows; docs/benchmarks-commands.md)
_PNG_PREVIEW_LEVEL = 1


def write_png_preview(path: str | os.PathLike, image: np.ndarray, tags: dict | None = None) -> str:
    """Write an 8-bit image as PNG, or as JPEG where ``path`` ends in ``.jpg``/``.jpeg`` (Pillow), atomically.

    ``tags`` (a JSON-able dict: what the picture shows, its label) are embedded as lfproc embeds them in its
    data products (``Software`` "lfproc", the JSON as the PNG ``Description`` text or the JSON EXIF
    ``ImageDescription``), so ``lfproc info`` can tell the picture for what it is.
    """
    from PIL import Image

    path = os.fspath(path)
    jpeg = path.lower().endswith((".jpg", ".jpeg"))
    pixels = image[:, :, 0] if image.ndim == 3 and image.shape[2] == 1 else image
    try:
        with atomic_path(path, suffix=".jpg" if jpeg else ".png") as tmp:
            picture = Image.fromarray(np.ascontiguousarray(pixels))
            if jpeg:
                picture.save(tmp, format="JPEG", quality=_JPEG_PREVIEW_QUALITY, **_embedded(tags, jpeg))
            else:
                picture.save(tmp, format="PNG", compress_level=_PNG_PREVIEW_LEVEL, **_embedded(tags, jpeg))
    except OSError as exc:
        raise LfprocError(f"{path}: cannot write {'JPEG' if jpeg else 'PNG'} ({exc.strerror or exc}); check the "
                          f"folder and permissions") from None
    return path


def _embedded(tags: dict | None, jpeg: bool) -> dict:
    """Pillow's save options that embed ``tags`` the way `lfproc.io.write_image` does (``Software`` "lfproc",
    strict ASCII JSON as the image description)."""
    if tags is None:
        return {}
    from PIL import Image, PngImagePlugin

    text = _tag_text(tags)
    if jpeg:
        exif = Image.Exif()
        exif[0x0131], exif[0x010E] = "lfproc", text       # EXIF Software, ImageDescription
        return {"exif": exif}
    info = PngImagePlugin.PngInfo()
    info.add_text("Software", "lfproc")
    info.add_text("Description", text)
    return {"pnginfo": info}


def _tag_text(tags: dict) -> str:
    import json

    return json.dumps(json_safe(dict(tags)), allow_nan=False)
