"""Writing Lytro files for the tests, byte for byte as ``lytro-format.md`` describes them.

Independent of lfproc's reader: packing follows the format's bit layout written out directly, and the
container is assembled section by section. Metadata starts from the real fixtures' JSON
(``/work/shared/fixtures/lytro`` or the copies in ``tests/data/lytro``) and changes only what a test
needs (sizes, levels, serial, zoom and focus steps).
"""

from __future__ import annotations

import copy
import hashlib
import json
import struct
from pathlib import Path

import numpy as np

FIXTURES = Path(__file__).resolve().parent / "data" / "lytro"
FILE_MAGIC = b"\x89LFP\r\n\x1a\n"
LFM, LFC = b"\x89LFM\r\n\x1a\n", b"\x89LFC\r\n\x1a\n"


# ----------------------------------------------------------------------------- packing

def pack10_little(dn: np.ndarray) -> bytes:
    """4 pixels in 5 bytes: bytes 0-3 the 8 MSBs of pixels 0-3, byte 4 their 2 LSBs (pixel i at bit 2i)."""
    flat = np.asarray(dn, np.uint16).ravel()
    assert flat.size % 4 == 0 and flat.max(initial=0) < 1024
    groups = flat.reshape(-1, 4)
    out = np.empty((groups.shape[0], 5), np.uint8)
    out[:, :4] = groups >> 2
    out[:, 4] = ((groups[:, 0] & 3) | (groups[:, 1] & 3) << 2 | (groups[:, 2] & 3) << 4
                 | (groups[:, 3] & 3) << 6).astype(np.uint8)
    return out.tobytes()


def pack12_big(dn: np.ndarray) -> bytes:
    """2 pixels in 3 bytes: p0 = b0·16 + (b1 >> 4), p1 = (b1 & 15)·256 + b2."""
    flat = np.asarray(dn, np.uint16).ravel()
    assert flat.size % 2 == 0 and flat.max(initial=0) < 4096
    p0, p1 = flat[0::2].astype(np.uint32), flat[1::2].astype(np.uint32)
    out = np.empty((p0.size, 3), np.uint8)
    out[:, 0] = p0 >> 4
    out[:, 1] = ((p0 & 15) << 4) | (p1 >> 8)
    out[:, 2] = p1 & 255
    return out.tobytes()


def pack(dn, bits, endianness) -> bytes:
    if (bits, endianness) == (10, "little"):
        return pack10_little(dn)
    if (bits, endianness) == (12, "big"):
        return pack12_big(dn)
    raise ValueError((bits, endianness))


# ----------------------------------------------------------------------------- metadata

def fixture(name: str) -> dict:
    return json.loads((FIXTURES / name).read_text())


def illum_document(width, height, *, serial="B5143909630", zoom_step=-1040, focus_step=-300, focal_length_m=None,
                   black=64, white=1023, modulation=True, exit_pupil_m=None) -> dict:
    """The Illum white image's .TXT document with only the given fields changed."""
    doc = copy.deepcopy(fixture("illum-white-image.TXT"))
    frame = doc["master"]["picture"]["frameArray"][0]
    meta = frame["frame"]["metadata"]
    _set_image(meta, width, height, black, white)
    meta["devices"]["lens"]["zoomStep"] = zoom_step
    meta["devices"]["lens"]["focusStep"] = focus_step
    if focal_length_m is not None:
        meta["devices"]["lens"]["focalLength"] = focal_length_m
    if exit_pupil_m is not None:
        meta["devices"]["lens"]["exitPupilOffset"]["z"] = exit_pupil_m
    frame["frame"]["privateMetadata"]["camera"]["serialNumber"] = serial
    frame["parameters"]["vendorContent"]["com.lytro.tags"]["modulationFrame"] = modulation
    return doc


def f01_metadata(width, height, *, black=168, white=4095) -> dict:
    """The F01 frame metadata with only the sizes and levels changed."""
    meta = copy.deepcopy(fixture("f01-frame.json"))
    _set_image(meta, width, height, black, white)
    return meta


def _set_image(meta, width, height, black, white):
    meta["image"]["width"], meta["image"]["height"] = int(width), int(height)
    levels = meta["image"]["rawDetails"]["pixelFormat"]
    levels["black"] = {k: black for k in ("r", "gr", "gb", "b")} if np.isscalar(black) else dict(black)
    levels["white"] = {k: white for k in ("r", "gr", "gb", "b")} if np.isscalar(white) else dict(white)


def frame_metadata_of(document: dict) -> tuple[dict, dict | None]:
    """(frame metadata, private metadata) of a raw-pair document (F01 top level or Illum's master…)."""
    if "image" in document:
        return document, document.get("privateMetadata")
    frame = document["master"]["picture"]["frameArray"][0]["frame"]
    return frame["metadata"], frame.get("privateMetadata")


# ----------------------------------------------------------------------------- files

def sha1_ref(data: bytes) -> str:
    return "sha1-" + hashlib.sha1(data).hexdigest()


def section(magic: bytes, data: bytes, position: int, reference: str | None = None) -> bytes:
    """magic, uint32 0, uint32 length (big-endian), 80-byte reference, data, zero padding to 16 bytes."""
    ref = (reference or sha1_ref(data)).encode("ascii").ljust(80, b"\0")
    body = magic + struct.pack(">II", 0, len(data)) + ref + data
    end = position + len(body)
    return body + b"\0" * (-end % 16)


def container_bytes(packed: bytes, metadata: dict, private: dict | None, *, thumbnail=b"\xff\xd8\xff\xe0 jpeg",
                    bad_sha1=False, with_raw=True, modulation=None, frame_without_raw_first=False) -> bytes:
    """A raw light field container: LFM first, then a thumbnail, private metadata, raw and metadata chunks
    (the raw is never the first chunk, so a reader must follow the references)."""
    chunks = {"thumb": thumbnail, "meta": json.dumps(metadata, indent=1).encode(),
              "private": json.dumps(private or {}).encode(), "raw": packed}
    refs = {key: sha1_ref(value) for key, value in chunks.items()}
    frame = {"frame": {"metadataRef": refs["meta"], "privateMetadataRef": refs["private"]}}
    if with_raw:
        frame["frame"]["imageRef"] = refs["raw"]
    if modulation is not None:
        frame["parameters"] = {"vendorContent": {"com.lytro.tags": {"modulationFrame": modulation}}}
    frames = [frame]
    if frame_without_raw_first:     # e.g. a frame whose image lives elsewhere: only its metadata is here
        frames.insert(0, {"frame": {"metadataRef": refs["meta"], "imageRef": "sha1-" + "0" * 40}})
    toc = {"picture": {"frameArray": frames, "viewArray": [], "accelerationArray": [], "derivationArray": []},
           "thumbnailArray": [{"imageRef": refs["thumb"], "representation": "jpeg"}],
           "version": {"major": 1, "minor": 0}}
    out = bytearray(FILE_MAGIC + struct.pack(">II", 1, 0))
    out += section(LFM, json.dumps(toc).encode(), len(out))
    for key in ("thumb", "private", "raw", "meta"):
        if key == "raw" and not with_raw:
            continue
        data = chunks[key]
        reference = refs[key]
        if bad_sha1 and key == "raw":
            data = bytes([data[0] ^ 1]) + data[1:]     # one bit flipped after hashing
        out += section(LFC, data, len(out), reference)
    return bytes(out)


def processed_picture_bytes() -> bytes:
    """A refocus stack: JPEG slices and a depth table, no frame with a raw image."""
    slices = [b"\xff\xd8\xff\xe0 slice %d" % k for k in range(3)]
    depth = json.dumps({"depthLut": [1, 2, 3]}).encode()
    refs = [sha1_ref(s) for s in slices]
    toc = {"picture": {"accelerationArray": [{"type": "com.lytro.acceleration.refocusStack",
                                              "vendorContent": {"imageArray": [{"imageRef": r, "lambda": k - 1.0}
                                                                                 for k, r in enumerate(refs)],
                                                                "depthLut": {"imageRef": sha1_ref(depth)}}}],
                       "frameArray": [], "viewArray": []}}
    out = bytearray(FILE_MAGIC + struct.pack(">II", 1, 0))
    out += section(LFM, json.dumps(toc).encode(), len(out))
    for data in (*slices, depth):
        out += section(LFC, data, len(out))
    return bytes(out)


def write_container(path, dn, bits, endianness, metadata, private=None, **kwargs) -> Path:
    path = Path(path)
    path.write_bytes(container_bytes(pack(dn, bits, endianness), metadata, private, **kwargs))
    return path


def write_raw_pair(path, dn, bits, endianness, document, metadata_extension=".TXT") -> Path:
    """``NAME.RAW`` (or whatever ``path`` says) with ``NAME<metadata_extension>`` beside it."""
    path = Path(path)
    path.write_bytes(pack(dn, bits, endianness))
    path.with_suffix(metadata_extension).write_text(json.dumps(document, indent="\t"))
    return path
