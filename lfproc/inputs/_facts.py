"""What an input file is, from its header only: size, Bayer pattern, channels, content hash.

Every capture, white image and dark frame is probed before any expensive work, so an unreadable or
unrecognised file fails first and with the diagnosis of the reader that recognises (or fails to
recognise) it, as ``lfproc info`` gives it (issue 23).
"""

from __future__ import annotations

import os
from dataclasses import dataclass

from ..errors import LfprocError

#: bytes read per step when hashing a file


@dataclass(frozen=True)
class ImageFacts:
    """The header facts of a capture, white image or dark frame.

    Attributes
    ----------
    path : str
    height, width : int
        Sensor size in pixels (the data a reader returns has this shape).
    cfa : str or None
        ``"none"``, a Bayer pattern, or ``None`` where the header does not tell (camera raws: known once read).
    channels : int
        1 for a mosaic or monochrome sensor, 3 for RGB files.
    """

    path: str
    height: int
    width: int
    cfa: str | None
    channels: int = 1

    @property
    def size(self) -> str:
        """``"WIDTHxHEIGHT"`` for messages."""
        return f"{self.width}x{self.height}"

    @classmethod
    def of_capture(cls, capture) -> ImageFacts:
        """The facts of an already read :class:`lfproc.io.Capture`."""
        data = capture.data
        return cls(capture.source, int(data.shape[0]), int(data.shape[1]), capture.cfa,
                   1 if data.ndim == 2 else int(data.shape[2]))


def probe_image(path: str, camera=None) -> ImageFacts:
    """Header facts of a capture-like file; refuses (one line) files no reader recognises.

    The diagnosis is the one ``lfproc info`` gives (`lfproc.io.describe_file`): a text file named ``.tif``
    is "not a readable image", not a corrupt camera raw. Single-channel images take the camera file's CFA.
    """
    from ..io import describe_file

    info = describe_file(path)
    if info.get("format") == "lightfield":
        raise LfprocError(f"{path}: is a decoded light field (.lfp.npz), not a sensor image; pass the capture or "
                          f"white image it was decoded from")
    if info.get("raw_light_field") is False:
        raise LfprocError(f"{path}: holds no raw light field (a processed picture); pass a raw capture")
    height, width = info.get("height"), info.get("width")
    if not isinstance(height, int) or not isinstance(width, int) or height <= 0 or width <= 0:
        raise LfprocError(f"{path}: the image has no usable size in its header; re-export it")
    camera_cfa = getattr(camera, "cfa", "none") if camera is not None else "none"
    fmt = info.get("format")
    if fmt in ("lytro-container", "lytro-raw"):
        cfa, channels = info.get("cfa") or "none", 1
    elif fmt == "camera-raw":
        cfa, channels = None, 1
    else:
        names = [str(n).upper() for n in info.get("channel_names", [])]
        colour = [n for n in names if n not in ("A", "ALPHA")]
        channels = 1 if len(colour) == 1 or info.get("channels", 1) == 1 else 3
        cfa = camera_cfa if channels == 1 else "none"
    return ImageFacts(path, height, width, cfa, channels)


def file_hash(path: str) -> str:
    """``"sha256:HEX"`` of a file's bytes (a Lytro raw's metadata file is not included); the digest of
    `lfproc.provenance.sha256_of`, computed once per file and process."""
    from ..provenance import sha256_of

    return "sha256:" + sha256_of(path)


def same_file_content(path: str, recorded_hash: str | None) -> bool:
    """Whether ``path`` exists and holds the content ``recorded_hash`` describes (True without a hash)."""
    if not path or not os.path.isfile(path):
        return False
    return recorded_hash is None or file_hash(path) == recorded_hash
