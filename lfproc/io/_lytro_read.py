"""Reading Lytro files as captures: containers (``.lfp``/``.lfr``) and raw pairs (``NAME.raw`` + metadata).

A raw pair is a packed ``NAME.raw`` (any case) with its metadata JSON beside it, ``NAME.txt`` or
``NAME.json`` (any case): calibration white images copied off a camera, some exported captures.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

from ..errors import LfprocError
from ._capture import Capture, normalise_mosaic
from ._checks import existing_file
from ._lytro_container import (RawFrame, has_container_extension, is_container, parse_json, raw_frame,
                               read_container)
from ._lytro_metadata import LytroMetadata, frame_metadata, parse_metadata
from ._lytro_unpack import check_packed_size, unpack_raw

METADATA_EXTENSIONS = (".txt", ".json")


@dataclass(frozen=True, eq=False)
class LytroFile:
    """A Lytro file's raw frame (still packed) and its parsed metadata."""

    frame: RawFrame
    metadata: LytroMetadata
    format: str     # "lytro-container" or "lytro-raw"


def metadata_sibling(path: str) -> str | None:
    """``NAME.txt``/``NAME.json`` (any case) next to a ``NAME.raw``, or None."""
    folder, name = os.path.split(path)
    stem, extension = os.path.splitext(name)
    if extension.lower() != ".raw":
        return None
    try:
        entries = os.listdir(folder or ".")
    except OSError:
        return None
    for wanted in METADATA_EXTENSIONS:
        for entry in sorted(entries):
            entry_stem, entry_ext = os.path.splitext(entry)
            if entry_stem == stem and entry_ext.lower() == wanted:
                return os.path.join(folder, entry)
    return None


def is_lytro_file(path: str) -> bool:
    """A container (by extension or magic) or a ``.raw`` with a metadata file beside it."""
    return has_container_extension(path) or is_container(path) or metadata_sibling(path) is not None


def open_lytro(path: str, verify: bool = True, pixels: bool = True, check_size: bool = True) -> LytroFile:
    """Parse a Lytro file's container or metadata (the raw stays packed; a raw pair's raw is not
    read at all with ``pixels=False``: ``frame.packed`` is then empty).

    Raises
    ------
    LfprocError
        Everything `read_container` and `parse_metadata` raise; a processed picture without raw data.
    """
    path = existing_file(path)
    if has_container_extension(path) or is_container(path):
        frame = raw_frame(read_container(path, verify=verify))
        metadata = parse_metadata(frame.metadata, frame.private, path, frame.modulation_frame)
        return LytroFile(frame=frame, metadata=metadata, format="lytro-container")
    sibling = metadata_sibling(path)
    if sibling is None:
        raise LfprocError(f"{path}: a Lytro .raw needs its metadata beside it (same name, .txt or .json); "
                          f"copy it from the camera with the raw")
    document = parse_json(_read_bytes(sibling), f"{sibling}: metadata")
    metadata, private, modulation = frame_metadata(document, sibling)
    parsed = parse_metadata(metadata, private, path, modulation)
    packed = b""
    if pixels:
        packed = _read_bytes(path)
    elif check_size:   # the size is checked without reading the pixels
        check_packed_size(os.path.getsize(path), parsed.width, parsed.height, parsed.bits_per_pixel,
                          parsed.endianness, path)
    frame = RawFrame(source=path, packed=packed, metadata=metadata, private=private, modulation_frame=modulation)
    return LytroFile(frame=frame, metadata=parsed, format="lytro-raw")


def _read_bytes(path: str) -> bytes:
    try:
        with open(path, "rb") as fh:
            return fh.read()
    except OSError as exc:
        raise LfprocError(f"{path}: cannot read ({exc.strerror or exc}); check the file and its permissions") \
            from None


def read_lytro_metadata(path: str | os.PathLike) -> LytroMetadata:
    """The parsed metadata of a Lytro container or raw pair (the pixels are not unpacked)."""
    return open_lytro(os.fspath(path), pixels=False).metadata


def read_lytro(path: str | os.PathLike) -> tuple[Capture, LytroMetadata]:
    """A Lytro file as a `Capture` and its `LytroMetadata`, the file read once.

    Like camera raws read through LibRaw, Lytro files carry their levels and CFA: the capture is
    ``(raw − black) / (white − black)`` per 2×2 position, CFA from ``mosaic.upperLeftPixel``.
    """
    path = os.fspath(path)
    lytro = open_lytro(path)
    meta = lytro.metadata
    mosaic = unpack_raw(lytro.frame.packed, meta.width, meta.height, meta.bits_per_pixel, meta.endianness, path)
    black, white = meta.levels()
    return Capture(data=normalise_mosaic(mosaic, black, white), cfa=meta.cfa, source=path), meta


def read_lytro_capture(path: str, camera=None) -> Capture:
    """`read_lytro`'s capture (the camera file's levels and CFA are not used for Lytro files)."""
    return read_lytro(path)[0]
