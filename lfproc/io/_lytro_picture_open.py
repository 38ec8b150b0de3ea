"""Opening processed Lytro pictures: verified reading, the cheap header-only test, refusals, camera metadata."""

from __future__ import annotations

from ..errors import LfprocError
from ._lytro_container import LytroContainer, frames
from ._lytro_picture import LytroPicture, _list, has_picture_content, read_picture, reference


def picture_metadata(picture: LytroPicture):
    """``(LytroMetadata, None)`` of the picture's camera, or ``(None, why not)``."""
    from ._lytro_metadata import parse_metadata

    if picture.metadata is None:
        named = [reference(entry.get("frame"), "metadataRef", "metadataUrl") for entry in frames(picture.container.toc)]
        named = [ref for ref in named if ref is not None]
        if named:
            return None, (f"the picture carries no camera metadata (its frame metadata section {named[0]} is "
                          f"referenced, not contained)")
        return None, "the picture carries no camera metadata"
    try:
        return parse_metadata(picture.metadata, picture.private, picture.path), None
    except LfprocError as exc:
        return None, str(exc).split(": ", 1)[-1]


def picture_lambda_map(picture: LytroPicture):
    """``(LytroMetadata or None, LambdaMap or None, why not)``: the picture's camera and its map from lambda
    to the paper's a and distances, or the reason there is none (no camera metadata, or metadata that does
    not describe the optics)."""
    from ._lytro_lambda import lambda_map

    meta, why = picture_metadata(picture)
    if meta is None:
        return None, None, why
    try:
        return meta, lambda_map(meta), None
    except LfprocError as exc:
        return meta, None, str(exc).split(": ", 1)[-1]


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

    from ._lytro_container import frame_without_image

    path = existing_file(path)
    container = read_container(path, verify=True)
    if not is_picture(container):
        found = frame_without_image(container)
        if found is not None:     # the raw image section removed (ExifTool's test file): neither picture nor capture
            raise LfprocError(f"{path}: holds a raw frame's metadata but not its image (the section {found[1]} is "
                              f"not in the file: removed, or an incomplete copy), and no processed picture: nothing to "
                              f"export or refocus; its metadata still gives the camera (`lfproc.read_camera`)")
        raise LfprocError(f"{path}: holds the raw light field, not a processed picture; `read it with "
                          f"lfproc.read_light_field`")
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

    from ._lytro_container import frame_without_image
    from ._lytro_metadata import parse_metadata

    if has_container_extension(path) or is_container(path):
        container = read_container(path, verify=True)
        if is_picture(container):
            meta, why = picture_metadata(read_picture(container))
            if meta is None:
                raise LfprocError(f"{path}: a processed Lytro picture whose metadata does not describe the camera "
                                  f"({why}); use the raw .lfr/.lfp the camera wrote, or write the camera file by hand")
            return meta
        found = frame_without_image(container)
        if found is not None:    # the raw image section is gone, its metadata is not: it still describes the camera
            frame = found[0]
            return parse_metadata(frame.metadata, frame.private, path, frame.modulation_frame)
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
