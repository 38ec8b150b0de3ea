"""Processed Lytro pictures: focus stacks, depth maps and perspective views, found through the table of contents.

Both generations (``lytro-format.md``, "Processed pictures"; ``docs/lytro.md``):

* first generation: ``picture.accelerationArray[]`` entries by ``type`` —
  ``com.lytro.acceleration.refocusStack`` (``vendorContent.imageArray[]`` JPEGs with their ``lambda``,
  ``defaultLambda``, a ``depthLut``), ``com.lytro.acceleration.depthMap`` (``width``/``height``,
  ``minLambda``/``maxLambda``, ``depthMap``/``confidenceMap``), ``com.lytro.acceleration.edofParallax``
  (a ``blockOfImages`` with ``blockOfImagesRef`` to an H.264 stream and ``metadataArray[]`` of view
  sizes and ``coord``); the frame (``picture.frameArray[0].frame``) names metadata, serial numbers and
  the raw image by reference;
* Illum: ``views[].accelerations[]`` with a focus stack (``perImage[]`` with ``focus`` = lambda, a
  ``depthMap`` with ``minLambda``/``maxLambda``), ``frames[].frame`` with the camera ``metadata``.

References are read wherever the format puts them: a key ending in ``Ref`` or ``Url`` whose value is
``sha1-…`` (a ``blob:`` prefix is dropped). The raw frame of a picture is referenced but not contained;
any other referenced section that is absent makes the file damaged.
"""

from __future__ import annotations

import io
from dataclasses import dataclass

import numpy as np

from ..errors import LfprocError
from ._lytro_container import LytroContainer, frames

STACK, DEPTH_MAP, DEPTH_LUT, PARALLAX = (f"com.lytro.acceleration.{t}" for t in
                                         ("refocusStack", "depthMap", "depthLut", "edofParallax"))
_FIX = "re-copy the file from the camera, its memory card or Lytro Desktop's library"


@dataclass(frozen=True)
class StackImage:
    """One image of a focus stack: its lambda (Lytro's refocus unit) and the section holding it."""

    index: int
    lambda_: float
    reference: str
    representation: str = "jpeg"
    width: int | None = None
    height: int | None = None


@dataclass(frozen=True)
class DepthEntry:
    """A depth map (or the first generation's depth lookup table) as the table of contents describes it."""

    kind: str                 # "depth map" or "depth lookup table"
    reference: str
    width: int | None
    height: int | None
    min_lambda: float | None
    max_lambda: float | None
    representation: str
    confidence_reference: str | None = None


@dataclass(frozen=True)
class ParallaxBlock:
    """An ``edofParallax`` block: an H.264 stream of all-in-focus views and each view's aperture coordinate."""

    reference: str
    representation: str
    views: tuple             # ((width, height, x, y), …)


@dataclass(frozen=True, eq=False)
class LytroPicture:
    """What a container without a raw frame holds (``stack``, ``depth``, ``parallax``) and its camera metadata."""

    container: LytroContainer
    generation: str                      # "first" or "illum"
    stack: tuple
    default_lambda: float | None
    depth: DepthEntry | None
    parallax: ParallaxBlock | None
    metadata: dict | None
    private: dict | None
    raw_reference: str | None
    missing: tuple                       # referenced sections (other than the raw frame) that are absent

    @property
    def path(self) -> str:
        return self.container.path

    @property
    def contents(self) -> list[str]:
        """``["focus stack", "depth map", "perspective views"]``, those present."""
        held = ["focus stack"] if self.stack else []
        held += [self.depth.kind] if self.depth else []
        held += ["perspective views"] if self.parallax else []
        return held

    @property
    def damaged(self) -> bool:
        return bool(self.missing) or not all(s.sha1_ok for s in self.container.sections)

    def image_bytes(self, reference: str) -> bytes:
        data = self.container.chunk(reference)
        if data is None:
            raise LfprocError(f"{self.path}: section {reference} named by the table of contents is missing "
                              f"(truncated or incomplete picture); {_FIX}")
        return bytes(data)


def reference(entry, *keys) -> str | None:
    """The ``sha1-…`` reference an entry holds under ``keys`` (or any ``…Ref``/``…Url`` key), else None."""
    if not isinstance(entry, dict):
        return None
    names = list(keys) + [k for k in entry if isinstance(k, str) and k.endswith(("Ref", "Url")) and k not in keys]
    for key in names:
        value = entry.get(key)
        if isinstance(value, str):
            value = value[5:] if value.lower().startswith("blob:") else value
            if value.lower().startswith("sha1-"):
                return value
    return None


def _find(node, key: str):
    """The first value stored under ``key`` anywhere in ``node`` (depth first), else None."""
    if isinstance(node, dict):
        if key in node:
            return node[key]
        children = node.values()
    elif isinstance(node, list):
        children = node
    else:
        return None
    for child in children:
        found = _find(child, key)
        if found is not None:
            return found
    return None


def _number(value) -> float | None:
    return float(value) if isinstance(value, (int, float)) and not isinstance(value, bool) else None


def _int(value) -> int | None:
    return int(value) if isinstance(value, (int, float)) and not isinstance(value, bool) else None


def _list(value) -> list:
    return [v for v in value if isinstance(v, dict)] if isinstance(value, list) else []


def accelerations(toc: dict) -> list[dict]:
    """First generation's ``picture.accelerationArray`` and the Illum's ``views[].accelerations``."""
    picture = toc.get("picture") if isinstance(toc.get("picture"), dict) else {}
    found = _list(picture.get("accelerationArray"))
    for view in _list(toc.get("views")) + _list(picture.get("viewArray")):
        found += _list(view.get("accelerations"))
    return found


def has_picture_content(toc: dict) -> bool:
    """True when the table of contents describes a focus stack, depth map or perspective views."""
    return any(_kind(entry) for entry in accelerations(toc))


def _kind(entry: dict) -> str | None:
    kind = str(entry.get("type") or entry.get("kind") or "")
    if kind in (STACK, DEPTH_MAP, PARALLAX) or kind == "focusStack":
        return kind
    if isinstance(entry.get("perImage"), list) or _find(entry, "perImage") is not None:
        return "focusStack"
    return None


def describe_contents(toc: dict) -> str:
    """``"a focus stack and a depth map"`` and the like, for messages."""
    kinds = {_kind(entry) for entry in accelerations(toc)}
    held = []
    if kinds & {STACK, "focusStack"}:
        held.append("a focus stack")
    if DEPTH_MAP in kinds or (kinds & {"focusStack"}):
        held.append("a depth map")
    if PARALLAX in kinds:
        held.append("perspective views")
    return " and ".join(held) if held else "no images lfproc knows"


def read_picture(container: LytroContainer) -> LytroPicture:
    """Parse a processed picture's table of contents (sections are not decoded).

    Raises
    ------
    LfprocError
        When the container describes no focus stack, depth map or perspective views.
    """
    toc = container.toc
    stack, default_lambda, depth, lut, parallax = [], None, None, None, None
    generation = "illum" if isinstance(toc.get("views"), list) or isinstance(toc.get("frames"), list) else "first"
    for entry in accelerations(toc):
        kind = _kind(entry)
        content = entry.get("vendorContent") if isinstance(entry.get("vendorContent"), dict) else entry
        if kind == STACK:
            default_lambda = _number(content.get("defaultLambda"))
            for image in _list(content.get("imageArray")):
                stack.append(_stack_image(len(stack), image, image.get("lambda"), container.path))
            table = content.get("depthLut")
            if isinstance(table, dict) and reference(table, "imageRef"):
                lut = _depth_entry("depth lookup table", table, table)
        elif kind == "focusStack":
            for image in _list(_find(entry, "perImage")):
                stack.append(_stack_image(len(stack), image, image.get("focus", image.get("lambda")), container.path))
            table = _find(entry, "depthMap")
            if isinstance(table, dict) and reference(table, "imageRef", "imageUrl"):
                depth = _depth_entry("depth map", table, table)
        elif kind == DEPTH_MAP:
            table = content.get("depthMap")
            if isinstance(table, dict) and reference(table, "imageRef"):
                depth = _depth_entry("depth map", content, table, content.get("confidenceMap"))
        elif kind == PARALLAX:
            parallax = _parallax(entry, container.path)
    depth = depth or lut
    if not (stack or depth or parallax):
        raise LfprocError(f"{container.path}: holds no raw light field and no focus stack, depth map or perspective "
                          f"views lfproc knows; pass the camera's original raw picture (.lfr/.lfp) instead")
    metadata, private, raw_ref = _frame(container, generation)
    wanted = [s.reference for s in stack] + ([depth.reference] if depth else []) + \
        ([parallax.reference] if parallax else [])
    missing = tuple(ref for ref in wanted if container.chunk(ref) is None)
    return LytroPicture(container=container, generation=generation, stack=tuple(stack), default_lambda=default_lambda,
                        depth=depth, parallax=parallax, metadata=metadata, private=private, raw_reference=raw_ref,
                        missing=missing)


def _stack_image(index: int, image: dict, lambda_value, path: str) -> StackImage:
    ref = reference(image, "imageRef", "imageUrl")
    lam = _number(lambda_value)
    if ref is None or lam is None:
        raise LfprocError(f"{path}: focus stack image {index} has no image reference or no lambda; {_FIX}")
    return StackImage(index=index, lambda_=lam, reference=ref,
                      representation=str(image.get("representation", "jpeg")).lower(),
                      width=_int(image.get("width")), height=_int(image.get("height")))


def _depth_entry(kind: str, description: dict, image: dict, confidence=None) -> DepthEntry:
    return DepthEntry(kind=kind, reference=reference(image, "imageRef", "imageUrl"),
                      width=_int(description.get("width", image.get("width"))),
                      height=_int(description.get("height", image.get("height"))),
                      min_lambda=_number(description.get("minLambda", image.get("minLambda"))),
                      max_lambda=_number(description.get("maxLambda", image.get("maxLambda"))),
                      representation=str(image.get("representation", "raw")).lower(),
                      confidence_reference=reference(confidence, "imageRef") if isinstance(confidence, dict) else None)


def _parallax(entry: dict, path: str) -> ParallaxBlock:
    block = _find(entry, "blockOfImages")
    block = block if isinstance(block, dict) else entry
    found = _find(entry, "blockOfImagesRef")
    ref = reference(block, "blockOfImagesRef") or reference({"blockOfImagesRef": found}, "blockOfImagesRef")
    if ref is None:
        raise LfprocError(f"{path}: the edofParallax block has no blockOfImagesRef; {_FIX}")
    views = []
    for item in _list(_find(entry, "metadataArray")):
        coord = item.get("coord") if isinstance(item.get("coord"), dict) else {}
        views.append((_int(item.get("width")), _int(item.get("height")), _number(coord.get("x")),
                      _number(coord.get("y"))))
    return ParallaxBlock(reference=ref, representation=str(block.get("representation", "h264")).lower(),
                         views=tuple(views))


def _frame(container: LytroContainer, generation: str):
    """(frame metadata, private metadata, raw image reference) of the picture's frame, inline or by reference."""
    toc = container.toc
    entries = frames(toc) + _list(toc.get("frames"))
    for entry in entries:
        frame = entry.get("frame") if isinstance(entry.get("frame"), dict) else entry
        metadata = frame.get("metadata") if isinstance(frame.get("metadata"), dict) else \
            container.json_chunk(reference(frame, "metadataRef", "metadataUrl"), "frame metadata")
        private = frame.get("privateMetadata") if isinstance(frame.get("privateMetadata"), dict) else \
            container.json_chunk(reference(frame, "privateMetadataRef", "privateMetadataUrl"), "private metadata")
        raw_ref = None
        for key in ("imageRef", "imageUrl"):
            if isinstance(frame.get(key), str):
                raw_ref = reference(frame, key) or frame[key]
        if metadata is not None or raw_ref is not None:
            return metadata, private, raw_ref
    return None, None, None


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


def confidence(picture: LytroPicture) -> np.ndarray | None:
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


def picture_metadata(picture: LytroPicture):
    """``(LytroMetadata, None)`` of the picture's camera, or ``(None, why not)``."""
    from ._lytro_metadata import parse_metadata

    if picture.metadata is None:
        return None, "the picture carries no camera metadata"
    try:
        return parse_metadata(picture.metadata, picture.private, picture.path), None
    except LfprocError as exc:
        return None, str(exc).split(": ", 1)[-1]


def is_picture(container: LytroContainer) -> bool:
    """True for a container with picture content and no raw frame inside."""
    from ._lytro_container import raw_frame

    if not has_picture_content(container.toc):
        return False
    try:
        raw_frame(container)
    except LfprocError:
        return True
    return False


def open_picture(path: str) -> LytroPicture:
    """Read a processed picture, every section's SHA-1 verified.

    Raises
    ------
    LfprocError
        Not a Lytro container, damaged (truncated, SHA-1 mismatch, a referenced image missing), a raw
        light field rather than a picture.
    """
    from ._checks import existing_file
    from ._lytro_container import read_container

    path = existing_file(path)
    container = read_container(path, verify=True)
    if not is_picture(container):
        raise LfprocError(f"{path}: holds the raw light field, not a processed picture; use lfproc refocus, views or "
                          f"depth on it")
    picture = read_picture(container)
    if picture.missing:
        picture.image_bytes(picture.missing[0])    # raises, naming the section
    return picture


def camera_metadata(path: str):
    """The `LytroMetadata` describing the camera of any Lytro file: a capture, a white image or a picture.

    Raises
    ------
    LfprocError
        A picture whose metadata does not describe the camera, or what `read_lytro_metadata` raises.
    """
    from ._lytro_container import has_container_extension, is_container, read_container
    from ._lytro_read import read_lytro_metadata

    if has_container_extension(path) or is_container(path):
        container = read_container(path, verify=True)
        if is_picture(container):
            meta, why = picture_metadata(read_picture(container))
            if meta is None:
                raise LfprocError(f"{path}: a processed Lytro picture whose metadata does not describe the camera "
                                  f"({why}); use the raw .lfr/.lfp the camera wrote, or write the camera file by hand")
            return meta
    return read_lytro_metadata(path)


def is_picture_file(path: str) -> bool:
    """Cheap test for a processed picture: the table of contents describes picture content and the raw frame
    it names is not among the sections (section headers are read, not their data; nothing is hashed)."""
    import json
    import struct

    from ._lytro_container import FILE_HEADER_BYTES, FILE_MAGIC, SECTION_HEADER_BYTES, SECTION_MAGICS

    try:
        with open(path, "rb") as fh:
            if fh.read(FILE_HEADER_BYTES)[:8] != FILE_MAGIC:
                return False
            toc, references = None, set()
            while True:
                header = fh.read(SECTION_HEADER_BYTES)
                if len(header) < SECTION_HEADER_BYTES or header[:8] not in SECTION_MAGICS:
                    break
                (length,) = struct.unpack(">I", header[12:16])
                references.add(header[16:].rstrip(b"\0").decode("ascii", "replace").lower())
                if toc is None and SECTION_MAGICS[header[:8]] == "LFM":
                    toc = json.loads(fh.read(length).decode("utf-8").rstrip("\0"))
                    fh.seek(-fh.tell() % 16, 1)
                else:
                    fh.seek(length + (-(fh.tell() + length) % 16), 1)
    except (OSError, ValueError, UnicodeDecodeError):
        return False
    if not isinstance(toc, dict) or not has_picture_content(toc):
        return False
    raw = [reference(entry.get("frame"), "imageRef", "imageUrl") for entry in frames(toc) + _list(toc.get("frames"))]
    return not any(r is not None and r.lower() in references for r in raw)


def refuse_pictures(paths) -> None:
    """Raise the one-line refusal for the first processed picture among ``paths`` (cheap: headers only)."""
    from ._lytro_container import has_container_extension, picture_refusal

    for path in paths:
        if has_container_extension(path) and is_picture_file(path):
            raise LfprocError(picture_refusal(path, _toc_of(path)))


def _toc_of(path: str) -> dict:
    from ._lytro_container import read_container

    return read_container(path, verify=False).toc
