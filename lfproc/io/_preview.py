"""8-bit pictures for people (previews, animations), written atomically with lfproc's tags embedded.

The tags (a JSON-able dict: what the picture shows, its label) are embedded the way `write_image` embeds
lfproc's metadata in its data products, so ``lfproc info`` can tell a preview for what it is; the labels drawn
into pictures use `label_font` (one with µ) through `label_text`. Pillow is imported inside the functions.
"""

from __future__ import annotations

import functools
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


@functools.lru_cache(maxsize=32)
def label_font(size: int | None = None):
    """The font of the labels drawn into pictures, one that has µ: DejaVu Sans where the system or matplotlib
    has it, else Pillow's own (``size`` None: Pillow's default size). Pillow's own font has no µ:
    :func:`label_text` then writes "u"."""
    from importlib.util import find_spec

    from PIL import ImageFont

    candidates = ["DejaVuSans.ttf"]      # Pillow looks in the system's font folders
    spec = find_spec("matplotlib")
    if spec is not None and spec.origin:
        candidates.append(os.path.join(os.path.dirname(spec.origin), "mpl-data", "fonts", "ttf", "DejaVuSans.ttf"))
    for name in candidates:
        try:
            return ImageFont.truetype(name, 11 if size is None else size)
        except OSError:
            continue
    try:
        return ImageFont.load_default() if size is None else ImageFont.load_default(size=size)
    except (TypeError, OSError):  # Pillow < 10.1 or without FreeType: the small bitmap font
        return ImageFont.load_default()


def label_text(text: str, font) -> str:
    """``text`` as ``font`` can draw it: "µ" becomes "u" where the font has no glyph for it (only a box)."""
    if "µ" in text and _glyph(font, "µ") == _glyph(font, "\U0010fffd"):
        return text.replace("µ", "u")
    return text


def _glyph(font, character: str) -> bytes:
    mask = font.getmask(character)
    return bytes(mask) + bytes(str(mask.size), "ascii")
