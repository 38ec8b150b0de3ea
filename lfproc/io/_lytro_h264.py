"""The perspective views of an ``edofParallax`` block: an H.264 (Annex B) stream decoded with OpenCV.

OpenCV's FFmpeg backend (in the opencv-contrib-python-headless wheel) decodes H.264 (its wheel has
no H.264 encoder, which reading does not need). ``cv2.VideoCapture`` reads files, so the stream is
written to a temporary ``.h264`` file first and removed afterwards.
"""

from __future__ import annotations

import os
import shutil
import tempfile

import numpy as np

from ..errors import LfprocError


def decode_views(picture) -> list[np.ndarray]:
    """The block's frames as 8-bit RGB ``(H, W, 3)`` arrays, in stream order (one per ``metadataArray`` entry).

    Raises
    ------
    LfprocError
        Not an H.264 block, this OpenCV cannot decode H.264, or the stream holds fewer frames than the
        metadata lists.
    """
    block = picture.parallax
    if block.representation not in ("h264", "avc", "h.264"):
        raise LfprocError(f"{picture.path}: the edofParallax block is {block.representation!r}, not H.264; lfproc "
                          f"decodes only H.264 perspective views")
    data = picture.image_bytes(block.reference)
    frames = decode_h264(data, picture.path)
    if len(frames) < len(block.views):
        raise LfprocError(f"{picture.path}: the edofParallax block decodes to {len(frames)} views, its metadata lists "
                          f"{len(block.views)}; the H.264 stream is damaged, re-copy the file")
    return frames[:len(block.views)] if block.views else frames


def decode_stack_block(picture, reference: str, count: int) -> list[np.ndarray]:
    """The frames of a refocus stack stored as an H.264 block (``count`` listed in its ``metadataArray``).

    Raises
    ------
    LfprocError
        This OpenCV cannot decode H.264, or the stream holds fewer frames than the metadata lists.
    """
    frames = decode_h264(picture.image_bytes(reference), picture.path, "refocus stack")
    if len(frames) < count:
        raise LfprocError(f"{picture.path}: the refocus stack's H.264 block decodes to {len(frames)} images, its "
                          f"metadata lists {count}; the stream is damaged, re-copy the file")
    return frames[:count]


def decode_h264(data: bytes, where: str, what: str = "edofParallax") -> list[np.ndarray]:
    """Every frame of an H.264 Annex B stream, 8-bit RGB."""
    import cv2

    folder = tempfile.mkdtemp(prefix="lfproc-h264-")
    path = os.path.join(folder, "views.h264")
    try:
        with open(path, "wb") as fh:
            fh.write(data)
        capture = cv2.VideoCapture(path, cv2.CAP_FFMPEG)
        frames = []
        try:
            if not capture.isOpened():
                raise LfprocError(f"{where}: OpenCV cannot open the {what} H.264 stream (this OpenCV build has "
                                  f"no H.264 decoder, or the stream is damaged); export the focus stack and depth "
                                  f"map, which need no video decoder")
            while True:
                ok, frame = capture.read()
                if not ok:
                    break
                frames.append(np.ascontiguousarray(frame[:, :, ::-1]))
        finally:
            capture.release()
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    if not frames:
        raise LfprocError(f"{where}: the {what} H.264 stream decodes to no frames (damaged stream or no H.264 "
                          f"decoder in this OpenCV build); re-copy the file")
    return frames
