"""Lytro containers (``.lfp``/``.lfr``): sections, their SHA-1 check, and the raw frame found by reference.

Layout (``docs/lytro.md``; facts from ``lytro-format.md``): a 16-byte file header (magic
``\\x89LFP\\r\\n\\x1a\\n``, big-endian uint32 version, uint32 0), then sections until the end of the
file. A section is an 8-byte magic (``\\x89LFM…``: a JSON table of contents; ``\\x89LFC…``: a data
chunk), a big-endian uint32 0, a big-endian uint32 length N, an 80-byte ASCII reference
(``sha1-`` + 40 hex digits, NUL padded), N data bytes, and zero padding to the next multiple of 16
bytes from the start of the file. The reference is the SHA-1 of the N data bytes.
"""

from __future__ import annotations

import hashlib
import json
import os
import struct
from dataclasses import dataclass

from ..errors import LfprocError

FILE_MAGIC = b"\x89LFP\r\n\x1a\n"
SECTION_MAGICS = {b"\x89LFM\r\n\x1a\n": "LFM", b"\x89LFC\r\n\x1a\n": "LFC"}
FILE_HEADER_BYTES = 16
SECTION_HEADER_BYTES = 8 + 4 + 4 + 80
CONTAINER_EXTENSIONS = (".lfp", ".lfr")
_FIX = "re-copy the file from the camera or its memory card"


@dataclass(frozen=True)
class Section:
    """One section of a container.

    Attributes
    ----------
    kind : {"LFM", "LFC"}
        Table of contents (JSON) or data chunk.
    offset : int
        Byte offset of the section's data in the file.
    length : int
        Number of data bytes.
    sha1 : str
        The reference stored in the section header (``sha1-`` + 40 hex digits).
    sha1_ok : bool
        Whether the SHA-1 of the data equals the reference.
    """

    kind: str
    offset: int
    length: int
    sha1: str
    sha1_ok: bool


@dataclass(frozen=True, eq=False)
class LytroContainer:
    """A parsed container: its bytes, sections and table of contents (the first LFM's JSON)."""

    path: str
    data: bytes
    sections: tuple
    toc: dict

    def chunk(self, reference) -> memoryview | None:
        """The data of the section whose reference is ``reference`` (case-insensitive), or None."""
        if not isinstance(reference, str):
            return None
        for section in self.sections:
            if section.sha1.lower() == reference.lower():
                return memoryview(self.data)[section.offset:section.offset + section.length]
        return None

    def json_chunk(self, reference, what: str) -> dict | None:
        """The JSON object stored under ``reference`` (None when the reference is absent)."""
        data = self.chunk(reference)
        if data is None:
            return None
        return parse_json(bytes(data), f"{self.path}: {what}")


def is_container(path: str) -> bool:
    """True when the file starts with the container magic (whatever its extension)."""
    try:
        with open(path, "rb") as fh:
            return fh.read(len(FILE_MAGIC)) == FILE_MAGIC
    except OSError:
        return False


def read_container(path: str, verify: bool = True) -> LytroContainer:
    """Parse every section of a container and check each section's SHA-1 against its reference.

    Parameters
    ----------
    path : str
    verify : bool
        Raise on a section whose SHA-1 does not match (``False``: record it in ``Section.sha1_ok``,
        for ``lfproc info``).

    Raises
    ------
    LfprocError
        Not a container, truncated, a section header that is not one, a SHA-1 mismatch (with
        ``verify``), no table of contents.
    """
    with open(path, "rb") as fh:
        data = fh.read()
    if data[:8] == FILE_MAGIC and len(data) < FILE_HEADER_BYTES:
        raise LfprocError(f"{path}: truncated Lytro container (the file header is cut off); {_FIX}")
    if len(data) < FILE_HEADER_BYTES or data[:8] != FILE_MAGIC:
        raise LfprocError(f"{path}: not a Lytro container (no LFP header); pass an .lfp/.lfr file from a Lytro camera")
    sections = tuple(_sections(data, path, verify))
    toc_section = next((s for s in sections if s.kind == "LFM"), None)
    if toc_section is None:
        raise LfprocError(f"{path}: the Lytro container has no table of contents (LFM section); {_FIX}")
    toc = parse_json(data[toc_section.offset:toc_section.offset + toc_section.length],
                     f"{path}: table of contents")
    return LytroContainer(path=path, data=data, sections=sections, toc=toc)


def _sections(data: bytes, path: str, verify: bool):
    position = FILE_HEADER_BYTES
    size = len(data)
    while position < size:
        if not any(data[position:position + SECTION_HEADER_BYTES]):
            return   # trailing zero padding
        if position + SECTION_HEADER_BYTES > size:
            raise LfprocError(f"{path}: truncated Lytro container (a section header is cut off at byte "
                              f"{position}); {_FIX}")
        kind = SECTION_MAGICS.get(data[position:position + 8])
        if kind is None:
            raise LfprocError(f"{path}: corrupt Lytro container (no section starts at byte {position}); {_FIX}")
        (length,) = struct.unpack(">I", data[position + 12:position + 16])
        reference = data[position + 16:position + SECTION_HEADER_BYTES].rstrip(b"\0").decode("ascii", "replace")
        start = position + SECTION_HEADER_BYTES
        if start + length > size:
            raise LfprocError(f"{path}: truncated Lytro container (section {reference} needs {length} bytes, "
                              f"{size - start} are left); {_FIX}")
        digest = "sha1-" + hashlib.sha1(memoryview(data)[start:start + length]).hexdigest()
        ok = digest.lower() == reference.lower()
        if verify and not ok:
            raise LfprocError(f"{path}: section {reference} fails its SHA-1 check (the data hashes to {digest}): "
                              f"the file is corrupt; {_FIX}")
        yield Section(kind=kind, offset=start, length=length, sha1=reference, sha1_ok=ok)
        position = start + length
        position += -position % 16


def parse_json(raw: bytes, where: str) -> dict:
    """A JSON object from bytes; one-line error naming ``where`` otherwise."""
    try:
        value = json.loads(bytes(raw).decode("utf-8").rstrip("\0"))
    except (UnicodeDecodeError, ValueError) as exc:
        raise LfprocError(f"{where} is not valid JSON ({' '.join(str(exc).split())}); {_FIX}") from None
    if not isinstance(value, dict):
        raise LfprocError(f"{where} is not a JSON object; {_FIX}")
    return value


@dataclass(frozen=True, eq=False)
class RawFrame:
    """The raw light field of a Lytro file: packed bytes, frame metadata, private metadata, flags."""

    source: str
    packed: memoryview | bytes
    metadata: dict
    private: dict | None
    modulation_frame: bool | None


def frames(toc: dict) -> list:
    """The ``picture.frameArray`` entries of a table of contents (``[]`` for processed pictures)."""
    picture = toc.get("picture") if isinstance(toc, dict) else None
    array = picture.get("frameArray") if isinstance(picture, dict) else None
    return [entry for entry in array if isinstance(entry, dict)] if isinstance(array, list) else []


def picture_kind(toc: dict) -> str:
    """A short description of what a container without a raw frame holds (for messages and info)."""
    from ._lytro_picture import describe_contents, has_picture_content

    if has_picture_content(toc):
        return f"a processed Lytro picture: {describe_contents(toc)}"
    picture = toc.get("picture") if isinstance(toc.get("picture"), dict) else {}
    if picture.get("accelerationArray") or picture.get("viewArray"):
        return "a processed Lytro picture"
    return "a Lytro file without a raw frame"


def picture_refusal(path: str, toc: dict) -> str:
    """The one line for a processed picture given where a raw light field is needed."""
    from ._lytro_picture import describe_contents, has_picture_content

    if not has_picture_content(toc):
        return (f"{path}: holds no raw light field but a processed Lytro picture of a kind lfproc does not read; "
                f"use the raw .lfp/.lfr the camera wrote")
    return (f"{path}: holds no raw light field but a processed Lytro picture ({describe_contents(toc)}); use "
            f"`lfproc.outputs.export_picture` for its images and depth map, or the raw .lfp/.lfr the camera wrote")


def raw_frame(container: LytroContainer) -> RawFrame:
    """The first frame whose ``imageRef`` points at a chunk, found by reference, never by position.

    Raises
    ------
    LfprocError
        When no frame has a raw image (a processed picture) or its metadata is missing.
    """
    path = container.path
    missing = []
    for entry in frames(container.toc):
        frame = entry.get("frame")
        if not isinstance(frame, dict):
            continue
        packed = container.chunk(frame.get("imageRef"))
        if packed is None:
            if isinstance(frame.get("imageRef"), str):
                missing.append(frame["imageRef"])
            continue
        metadata = container.json_chunk(frame.get("metadataRef"), "frame metadata")
        if metadata is None:
            raise LfprocError(f"{path}: the raw frame has no metadata section ({frame.get('metadataRef')}); {_FIX}")
        private = container.json_chunk(frame.get("privateMetadataRef"), "private metadata")
        return RawFrame(source=path, packed=packed, metadata=metadata, private=private,
                        modulation_frame=modulation_flag(entry))
    from ._lytro_picture import accelerations

    if accelerations(container.toc):   # a processed picture (of a kind lfproc reads or not): not damage
        raise LfprocError(picture_refusal(path, container.toc))
    if missing:
        raise LfprocError(f"{path}: the raw image section {missing[0]} is missing (truncated or incomplete "
                          f"container); {_FIX}")
    raise LfprocError(f"{path}: holds no raw light field ({picture_kind(container.toc)}); pass the camera's "
                      f"original raw picture (the .lfr/.lfp the camera wrote) instead")


def modulation_flag(entry: dict) -> bool | None:
    """``parameters.vendorContent["com.lytro.tags"].modulationFrame`` of a frame entry (None if absent)."""
    try:
        value = entry["parameters"]["vendorContent"]["com.lytro.tags"]["modulationFrame"]
    except (KeyError, TypeError):
        return None
    return bool(value) if isinstance(value, bool) else None


def has_container_extension(path: str) -> bool:
    return os.path.splitext(path)[1].lower() in CONTAINER_EXTENSIONS


def frame_without_image(container: LytroContainer):
    """``(RawFrame with empty data, raw image reference)`` of the first frame whose metadata section is present
    but whose raw image section is not (a container whose image was removed, e.g. ExifTool's test file), else
    None. Its metadata still describes the camera."""
    for entry in frames(container.toc):
        frame = entry.get("frame")
        if not isinstance(frame, dict) or container.chunk(frame.get("imageRef")) is not None:
            continue
        metadata = container.json_chunk(frame.get("metadataRef"), "frame metadata")
        if metadata is not None:
            private = container.json_chunk(frame.get("privateMetadataRef"), "private metadata")
            return (RawFrame(source=container.path, packed=b"", metadata=metadata, private=private,
                             modulation_frame=modulation_flag(entry)), frame.get("imageRef"))
    return None
