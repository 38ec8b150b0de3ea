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

from dataclasses import dataclass

from ..errors import LfprocError
from ._lytro_container import LytroContainer, frames

STACK, DEPTH_MAP, PARALLAX = (f"com.lytro.acceleration.{t}" for t in
                              ("refocusStack", "depthMap", "edofParallax"))
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
    frame: int | None = None     # the frame of an H.264 block (``reference``) holding it; None: a stored image


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
            if not _list(content.get("imageArray")) and isinstance(content.get("blockOfImages"), dict):
                stack += _stack_block(content["blockOfImages"], container.path, start=len(stack))
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
    wanted = list(dict.fromkeys(s.reference for s in stack)) + ([depth.reference] if depth else []) + \
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


def _stack_block(block: dict, path: str, start: int = 0) -> list[StackImage]:
    """The images of a refocus stack stored as one H.264 block (a later engine's ``blockOfImages``): one
    ``metadataArray`` entry per frame, in stream order, with its ``lambda``, ``width`` and ``height``."""
    ref = reference(block, "blockOfImagesRef")
    if ref is None:
        raise LfprocError(f"{path}: the refocus stack's blockOfImages has no blockOfImagesRef; {_FIX}")
    images = []
    for k, item in enumerate(_list(block.get("metadataArray"))):
        lam = _number(item.get("lambda"))
        if lam is None:
            raise LfprocError(f"{path}: focus stack image {k} of the H.264 block has no lambda; {_FIX}")
        images.append(StackImage(index=start + k, lambda_=lam, reference=ref,
                                 representation=str(block.get("representation", "h264")).lower(),
                                 width=_int(item.get("width")), height=_int(item.get("height")), frame=k))
    return images


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
