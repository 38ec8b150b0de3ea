"""``lfproc export``: a processed Lytro picture's focus stack, perspective views and depth map as lfproc outputs.

Files written into OUTDIR for a picture with stem STEM (contract: ``ARCHITECTURE.md``, "Dark frames,
apertures, pictures"), each with its sidecar ``NAME.json`` and the same metadata embedded:

* ``STEM_stack_KK.jpg`` — focus stack image K, the stored JPEG's bytes (one comment segment with the
  metadata inserted after its start marker; the compressed data is untouched); with ``tiff``
  also ``STEM_stack_KK.tif``, the JPEG decoded and linearised (sRGB transfer function inverted), float32;
  the sidecar holds ``source``, ``lambda`` and, where the camera is known, ``a``, ``distance_mm``,
  ``near_mm``, ``far_mm``, ``dof_mm`` with ``"distance_from": "lambda"``;
* ``STEM_parallax_KK.tif`` — perspective view K of an edofParallax block, linear float32, with its
  aperture coordinate ``coord`` [x, y];
* ``STEM_depth_lambda.tif`` — the depth map in lambda (``unit`` "lambda"), float32;
  ``STEM_depth_confidence.tif`` where the picture has a confidence map;
* where the camera is known: ``STEM_depth.tif`` in mm from the sensor (``unit`` "mm", NaN where
  unknown, ``inf`` at and beyond infinity) and ``STEM_depth_preview.png``, coloured with a legend in
  metres.
"""

from __future__ import annotations

import io
import os
import struct

import numpy as np

from ..errors import LfprocError, warn


def export_picture(path: str, outdir: str, stem: str, *, tiff: bool = False, camera=None,
                   camera_path: str | None = None, focus_distance_mm: float | None = None, views_jpeg: bool = False,
                   wobble: bool = False) -> list[str]:
    """Write every image of the picture at ``path`` into ``outdir``; returns the image paths written.

    Parameters
    ----------
    camera : Camera, optional
        The camera (from ``camera_path``) for a picture whose metadata does not describe it, or to
        override it: lambda becomes a and mm through its f_number, pitch and b_U (``docs/lytro.md``).
    focus_distance_mm : float, optional
        Where the main lens focused (mm from the sensor): b_U from the thin-lens equation instead of
        the metadata's ``infinityLambda`` (or the camera file's b_U).
    views_jpeg, wobble : bool
        Perspective views also as sRGB JPEG (``STEM_parallax_KK.jpg``); an animation walking them
        around the aperture (``STEM_wobble.gif``).

    Raises
    ------
    LfprocError
        Not a picture, damaged, an undecodable depth map or H.264 block, a focus distance without a
        camera. Everything is read and decoded before the first file is written.

    Warns
    -----
    LfprocWarning
        No camera (lambda only, and how to get distances); stack images beyond infinity for the camera's focus.
    """
    from ..io import confidence_map, depth_lambda, open_picture, picture_lambda_map
    from ..io import camera_lambda_map, refocused_map
    from ..io import stack_images
    from ._lytro_views import lambda_preview_writer, view_jobs
    from ..provenance import provenance

    picture = open_picture(path)
    source = os.path.abspath(path)
    meta, mapping, note = picture_lambda_map(picture)
    camera_from = "picture metadata"
    if camera is not None:
        mapping, camera_from = camera_lambda_map(camera, camera_path or "camera"), f"camera file {camera_path}"
    if focus_distance_mm is not None:
        if mapping is None:
            raise LfprocError(f"{path}: `focus_distance_mm=` needs the camera, and this picture's metadata does not "
                              f"describe it ({note}); add `camera=...` (e.g. from "
                              f"`lfproc.read_camera(path) of a Lytro file of the same camera`)")
        mapping = refocused_map(mapping, focus_distance_mm)
    common = {"source": source, "camera_model": meta.model if meta else None}
    if mapping is None:
        common["camera_note"] = (f"no distances: {note}; give the camera with --camera CAM.toml "
                                 f"(and --focus-distance MM)")
    else:
        common["camera"] = _camera_record(mapping, camera_from, focus_distance_mm)
    common["provenance"] = provenance({"capture": path, "camera": camera_path if camera is not None else None})
    jobs = []        # (writer, path) run after everything is decoded
    records = mapping.slices([s.lambda_ for s in picture.stack]) if mapping and picture.stack else \
        [{"lambda": s.lambda_} for s in picture.stack]
    _say_what_has_no_distance(path, mapping, note, records)
    for image, record, (data, rgb) in zip(picture.stack, records, stack_images(picture)):
        name = os.path.join(outdir, f"{stem}_stack_{image.index:02d}")
        metadata = dict(common, kind="focus stack image", index=image.index, **record)
        stored = "JPEG as stored (sRGB)" if rgb is None else \
            "H.264 frame of the refocus stack block, re-encoded as JPEG (quality 95, sRGB)"
        metadata["encoding"] = stored + ("; .tif: decoded, linear float32" if tiff else "")
        jobs.append((name + ".jpg", _jpeg_writer(data, metadata)))
        if tiff:
            linear = _linear_from_jpeg(data, path) if rgb is None else _linear(rgb)
            jobs.append((name + ".tif", _image_writer(linear, metadata)))
    if picture.parallax is not None:
        jobs += view_jobs(picture, common, outdir, stem, jpeg=views_jpeg, wobble=wobble)
    if picture.depth is not None:
        lam = depth_lambda(picture)
        jobs += _depth_jobs(picture, lam, confidence_map(picture), mapping, common, outdir, stem)
        if mapping is None:
            jobs.append((os.path.join(outdir, f"{stem}_depth_lambda_preview.png"), lambda_preview_writer(lam)))
    os.makedirs(outdir, exist_ok=True)
    written = []
    for target, write in jobs:
        write(target)
        written.append(target)
    return written


def _say_what_has_no_distance(path: str, mapping, note: str, records: list) -> None:
    """Warn (`LfprocWarning`, one line) where the outputs get no distances: the camera unknown, or stack images
    focused beyond infinity by the camera's focus (their ``distance_mm`` is null)."""
    import math
    import warnings

    from ..errors import LfprocWarning

    if mapping is None:
        warn(f"{path}: no distances, lambda only: {note}; pass `camera=` the camera that took it (e.g. "
             f"from `lfproc.read_camera(path) of a Lytro file of the same camera`) and `focus_distance_mm=` where "
             f"its lens focused")
        return
    beyond = [r["lambda"] for r in records if r.get("distance_mm") is None or not math.isfinite(r["distance_mm"])]
    if beyond:
        warn(f"{path}: {len(beyond)} of {len(records)} stack images (lambda {min(beyond):+.3g} to "
             f"{max(beyond):+.3g}) lie beyond infinity for the camera's focus (infinity at lambda "
             f"{mapping.infinity_lambda:.3g}), so their distance_mm is null: the lens focused nearer than "
             f"the camera says; pass `focus_distance_mm=` where it focused, if known")


def _linear(rgb: np.ndarray) -> np.ndarray:
    from ..io import srgb_decode

    return srgb_decode(np.asarray(rgb, np.float32) / 255.0)


def _camera_record(mapping, camera_from: str, focus_distance_mm) -> dict:
    from ..geometry import slice_distance_mm

    cam = mapping.camera
    if focus_distance_mm is not None:
        focus_from = f"--focus-distance {focus_distance_mm:g} mm (thin-lens equation)"
    elif camera_from == "picture metadata":
        focus_from = "lambda (infinityLambda x fNumber x lensPitch, docs/lytro.md)"
    else:
        focus_from = f"the {camera_from} (its b_U)"
    return {"from": camera_from, "focal_length_mm": mapping.focal_length_mm, "f_number": mapping.f_number,
            "image_distance_mm": mapping.image_distance_mm, "focus_distance_mm": slice_distance_mm(cam, 0.0),
            "infinity_lambda": mapping.infinity_lambda, "lambda_unit_mm": mapping.unit_mm,
            "image_distance_from": focus_from}


def _depth_jobs(picture, lam, conf, mapping, common, outdir, stem) -> list:
    entry = picture.depth
    base = dict(common, kind=entry.kind, min_lambda=entry.min_lambda, max_lambda=entry.max_lambda,
                width=int(lam.shape[1]), height=int(lam.shape[0]), **{"lambda": None})   # per pixel
    jobs = [(os.path.join(outdir, f"{stem}_depth_lambda.tif"),
             _image_writer(lam[:, :, None], dict(base, unit="lambda"), allow_nonfinite=True))]
    if conf is not None:
        jobs.append((os.path.join(outdir, f"{stem}_depth_confidence.tif"),
                     _image_writer(conf[:, :, None], dict(base, unit="confidence (as stored)"), allow_nonfinite=True)))
    if mapping is not None:
        distance = mapping.distance_mm(lam).astype(np.float32)
        depth_meta = dict(base, unit="mm", distance_from="lambda", measured_from="sensor")
        jobs.append((os.path.join(outdir, f"{stem}_depth.tif"),
                     _image_writer(distance[:, :, None], depth_meta, allow_nonfinite=True)))
        jobs.append((os.path.join(outdir, f"{stem}_depth_preview.png"), _preview_writer(distance)))
    return jobs


def _image_writer(pixels, metadata, allow_nonfinite=False):
    def write(target):
        from ..io import write_image, write_sidecar

        write_image(target, pixels, metadata, allow_nonfinite=allow_nonfinite)
        write_sidecar(target, metadata)
    return write


def _jpeg_writer(data: bytes, metadata: dict):
    def write(target):
        from ..atomic import atomic_path
        from ..io import write_sidecar

        tagged = with_metadata(data, metadata)
        try:
            with atomic_path(target) as tmp, open(tmp, "wb") as fh:
                fh.write(tagged)
        except OSError as exc:
            raise LfprocError(f"{target}: cannot write ({exc.strerror or exc}); check the folder") from None
        write_sidecar(target, metadata)
    return write


def _preview_writer(distance):
    def write(target):
        from ..depth import write_preview

        write_preview(target, distance)
    return write


def with_metadata(jpeg: bytes, metadata: dict) -> bytes:
    """The JPEG with lfproc's metadata segments (a COM comment and an Exif APP1 with ``ImageDescription``, as
    `write_image` writes them, so `read_metadata` reads them back) inserted after its JFIF APP0; the
    compressed image data is untouched."""
    import tempfile

    from ..io import write_image

    if jpeg[:2] != b"\xff\xd8":
        raise LfprocError("a focus stack image is not a JPEG (no SOI marker); re-copy the picture")
    with tempfile.TemporaryDirectory(prefix="lfproc-jpeg-") as folder:
        carrier = os.path.join(folder, "metadata.jpg")
        write_image(carrier, np.zeros((8, 8, 1), np.float32), metadata)
        with open(carrier, "rb") as fh:
            ours = fh.read()
    inserted = b"".join(data for marker, data in _header_segments(ours) if marker in (0xFE, 0xE1))
    position = 2
    for marker, data in _header_segments(jpeg):
        if marker != 0xE0:
            break
        position += len(data)
    return jpeg[:position] + inserted + jpeg[position:]


def _header_segments(jpeg: bytes):
    """(marker, bytes) of the segments between SOI and the first non-APP/COM segment."""
    position = 2
    while jpeg[position:position + 1] == b"\xff" and (0xE0 <= jpeg[position + 1] <= 0xEF or jpeg[position + 1] == 0xFE):
        length = struct.unpack(">H", jpeg[position + 2:position + 4])[0]
        yield jpeg[position + 1], jpeg[position:position + 2 + length]
        position += 2 + length


def _linear_from_jpeg(data: bytes, where: str) -> np.ndarray:
    from ..io import srgb_decode
    from PIL import Image, UnidentifiedImageError

    try:
        with Image.open(io.BytesIO(data)) as image:
            rgb = np.asarray(image.convert("RGB"), dtype=np.float32) / 255.0
    except (UnidentifiedImageError, OSError) as exc:
        raise LfprocError(f"{where}: a focus stack JPEG cannot be decoded ({exc}); re-copy the picture") from None
    return srgb_decode(rgb)
