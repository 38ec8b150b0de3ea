"""The pixels of a processed Lytro picture's depth map and confidence map, and its images' sizes.

How depth is stored (``docs/lytro.md``, "Assumptions about stored depth"): ``representation`` "raw" is
little-endian float32, row-major, width x height values; an image (PNG, JPEG, TIFF) spans
``minLambda`` (grey 0) to ``maxLambda`` (the type's maximum) linearly.
"""

from __future__ import annotations

import io

import numpy as np

from ..errors import LfprocError
from ._lytro_picture import DepthEntry, LytroPicture, _FIX


def depth_lambda(picture: LytroPicture) -> np.ndarray:
    """The depth map in lambda, float32 ``(H, W)``.

    Stored as the format says (``docs/lytro.md``): raw little-endian float32, row-major, width × height
    values (``representation`` "raw"); or an 8/16-bit image (PNG, JPEG, TIFF) whose grey levels span
    ``minLambda`` (0) to ``maxLambda`` (the type's maximum) linearly.

    Raises
    ------
    LfprocError
        A section of another size, or an image without ``minLambda``/``maxLambda``.
    """
    entry = picture.depth
    data = picture.image_bytes(entry.reference)
    width, height = entry.width, entry.height
    if data[:4] in (b"\x89PNG", b"II*\x00", b"MM\x00*") or data[:2] == b"\xff\xd8":
        return _depth_from_image(data, entry, picture.path)
    if width and height and len(data) == 4 * width * height:
        return np.frombuffer(data, dtype="<f4").reshape(height, width).astype(np.float32)
    raise LfprocError(f"{picture.path}: the {entry.kind} section holds {len(data)} bytes, not {width} x {height} "
                      f"float32 values nor an image; {_FIX}")


def _depth_from_image(data: bytes, entry: DepthEntry, path: str) -> np.ndarray:
    from PIL import Image

    if entry.min_lambda is None or entry.max_lambda is None:
        raise LfprocError(f"{path}: the {entry.kind} is an image but minLambda/maxLambda are missing, so its grey "
                          f"levels cannot be read as lambda; {_FIX}")
    with Image.open(io.BytesIO(data)) as image:
        values = np.asarray(image)
    if values.ndim == 3:
        values = values[..., 0]
    top = 65535.0 if values.dtype == np.uint16 or values.max(initial=0) > 255 else 255.0
    scaled = entry.min_lambda + values.astype(np.float64) / top * (entry.max_lambda - entry.min_lambda)
    return scaled.astype(np.float32)


def confidence_map(picture: LytroPicture) -> np.ndarray | None:
    """The first generation's confidence map (float32 like the depth map), or None."""
    ref = picture.depth.confidence_reference if picture.depth else None
    data = picture.container.chunk(ref) if ref else None
    w, h = (picture.depth.width, picture.depth.height) if picture.depth else (None, None)
    if data is None or not w or not h or len(data) != 4 * w * h:
        return None
    return np.frombuffer(bytes(data), dtype="<f4").reshape(h, w).astype(np.float32)


def image_size(data: bytes) -> tuple[int, int] | None:
    """(width, height) of an encoded image (Pillow reads only the header), None if unreadable."""
    from PIL import Image, UnidentifiedImageError

    try:
        with Image.open(io.BytesIO(data)) as image:
            return image.size
    except (UnidentifiedImageError, OSError):
        return None


def stack_images(picture: LytroPicture) -> list[tuple[bytes, np.ndarray | None]]:
    """``(JPEG bytes, RGB or None)`` of each focus stack image, in stack order.

    A stored JPEG is returned as it is (RGB None: decode it when needed); the frames of a refocus stack
    stored as an H.264 block are decoded (8-bit RGB) and encoded as JPEG (quality 95, no chroma
    subsampling) for the outputs that need one.
    """
    from ._lytro_h264 import decode_stack_block

    decoded: dict = {}
    out = []
    for image in picture.stack:
        if image.frame is None:
            out.append((picture.image_bytes(image.reference), None))
            continue
        if image.reference not in decoded:
            count = sum(1 for s in picture.stack if s.reference == image.reference)
            decoded[image.reference] = decode_stack_block(picture, image.reference, count)
        rgb = decoded[image.reference][image.frame]
        out.append((encode_jpeg(rgb), rgb))
    return out


def encode_jpeg(rgb: np.ndarray, quality: int = 95) -> bytes:
    """8-bit RGB as a baseline JPEG (Pillow, no chroma subsampling)."""
    from PIL import Image

    buffer = io.BytesIO()
    Image.fromarray(np.asarray(rgb, np.uint8)).save(buffer, format="JPEG", quality=quality, subsampling=0)
    return buffer.getvalue()
