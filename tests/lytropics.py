"""Processed Lytro pictures for the tests, written byte for byte as ``lytro-format.md`` describes them.

Containers are assembled with ``lytrogen``'s section writer (16-byte header, LFM then LFC sections,
SHA-1 references, 16-byte padding). Contents, per the format notes:

* first generation ``NAME-stk.lfp``: ``picture.frameArray[0].frame`` with ``metadataRef`` (the F01
  fixture's frame metadata), ``privateMetadataRef`` and an ``imageRef`` to the raw frame whose section
  is absent; ``picture.accelerationArray[]`` with a ``com.lytro.acceleration.refocusStack`` (JPEG
  ``imageArray[]`` with ``lambda``, ``defaultLambda``, ``displayParameters``, a 20 x 20 ``depthLut``)
  and a ``com.lytro.stars`` entry; optionally an ``edofParallax`` block (H.264 from ``h264pcm``);
* first generation ``NAME-dm.lfp``: a ``com.lytro.acceleration.depthMap`` with ``depthMap`` and
  ``confidenceMap`` sections, ``representation`` "raw";
* Illum ``.LFP``: ``frames[].frame`` with the Illum fixture's full ``metadata`` inline, ``views[]``
  with a ``focusStack`` acceleration (``perImage[]`` with ``focus`` = lambda, a ``depthMap``).

Assumption (the format notes give no element type): "raw" depth maps, lookup tables and confidence
maps are little-endian float32, row-major, width x height values.
"""

from __future__ import annotations

import io
import json
import struct

import numpy as np

import lytrogen
from lytrogen import FILE_MAGIC, LFC, LFM, section, sha1_ref

RAW_REF = "sha1-" + "7" * 40      # the raw frame: referenced, never contained


def jpeg(rgb: np.ndarray, quality: int = 95) -> bytes:
    from PIL import Image

    buffer = io.BytesIO()
    Image.fromarray(np.asarray(rgb, np.uint8)).save(buffer, format="JPEG", quality=quality, subsampling=0)
    return buffer.getvalue()


def focus_scene(count: int, size: int = 48, seed: int = 0) -> list[np.ndarray]:
    """``count`` 8-bit RGB images of one scene in vertical bands: image k is sharp (a fine checkerboard)
    in band k and blurred (flat grey of the same mean) elsewhere, as a focus stack of ``count`` depths."""
    band = size // count
    yy, xx = np.mgrid[0:size, 0:size]
    sharp = np.where((yy // 2 + xx // 2) % 2 == 0, 40, 215).astype(np.float64)
    images = []
    for k in range(count):
        image = np.full((size, size), 127.5)
        image[:, k * band:(k + 1) * band] = sharp[:, k * band:(k + 1) * band]
        images.append(np.repeat(image[:, :, None], 3, axis=2).astype(np.uint8))
    return images


def assemble(toc: dict, chunks: list[bytes], *, cut: int = 0, corrupt: int | None = None) -> bytes:
    """Header, the table of contents, then ``chunks`` as LFC sections; ``cut`` bytes removed from the end;
    ``corrupt`` = index of a chunk whose data gets one bit flipped after hashing."""
    out = bytearray(FILE_MAGIC + struct.pack(">II", 1, 0))
    out += section(LFM, json.dumps(toc, indent=1).encode(), len(out))
    for k, data in enumerate(chunks):
        reference = sha1_ref(data)
        if k == corrupt:
            data = bytes([data[0] ^ 1]) + data[1:]
        out += section(LFC, data, len(out), reference)
    return bytes(out[:len(out) - cut] if cut else out)


def first_gen_stack(lambdas=(-8.92, -5.78, -2.6), *, size=48, parallax=None, with_metadata=True, **kwargs) -> bytes:
    """A first-generation ``-stk.lfp``; ``parallax`` = list of ``(rgb, x, y)`` views adds an edofParallax
    block (16-pixel multiples)."""
    images = [jpeg(im) for im in focus_scene(len(lambdas), size)]
    lut = np.linspace(min(lambdas), max(lambdas), 400, dtype="<f4").reshape(20, 20).tobytes()
    meta = json.dumps(lytrogen.f01_metadata(3280, 3280), indent=1).encode()
    private = json.dumps({"camera": {"serialNumber": "A502030123"}}).encode()
    chunks = [meta, private, *images, lut]
    stack = {"type": "com.lytro.acceleration.refocusStack", "vendorContent": {
        "viewParameters": {"validViewRect": {"x": 0, "y": 0, "w": 1, "h": 1}},
        "displayParameters": {"displayDimensions": {"mode": "fixedToValue", "value": {"width": size, "height": size}}},
        "defaultLambda": float(lambdas[len(lambdas) // 2]),
        "depthLut": {"width": 20, "height": 20, "representation": "raw", "imageRef": sha1_ref(lut)},
        "imageArray": [{"representation": "jpeg", "width": size, "height": size, "lambda": float(lam),
                        "imageRef": sha1_ref(data)} for lam, data in zip(lambdas, images)]}}
    accelerations = [stack, {"type": "com.lytro.stars", "vendorContent": {"stars": []}}]
    if parallax is not None:
        import h264pcm

        block = h264pcm.h264_stream([rgb for rgb, _, _ in parallax])
        chunks.append(block)
        height, width = parallax[0][0].shape[:2]
        accelerations.append({"type": "com.lytro.acceleration.edofParallax", "vendorContent": {"blockOfImages": {
            "representation": "h264", "blockOfImagesRef": sha1_ref(block),
            "metadataArray": [{"width": width, "height": height, "coord": {"x": x, "y": y}}
                              for _, x, y in parallax]}}})
    frame = {"frame": {"metadataRef": sha1_ref(meta), "privateMetadataRef": sha1_ref(private), "imageRef": RAW_REF}}
    if not with_metadata:
        frame = {"frame": {"imageRef": RAW_REF}}
        chunks = chunks[2:]
    toc = {"picture": {"frameArray": [frame], "viewArray": [], "accelerationArray": accelerations,
                       "derivationArray": [RAW_REF]}, "version": {"major": 1, "minor": 0}}
    return assemble(toc, chunks, **kwargs)


def first_gen_depth(depth_lambda: np.ndarray, confidence: np.ndarray | None = None, **kwargs) -> bytes:
    """A first-generation ``-dm.lfp``: the depth in lambda and its confidence as raw float32 sections."""
    depth_lambda = np.asarray(depth_lambda, "<f4")
    height, width = depth_lambda.shape
    confidence = np.ones_like(depth_lambda) if confidence is None else np.asarray(confidence, "<f4")
    depth_bytes, conf_bytes = depth_lambda.tobytes(), confidence.tobytes()
    meta = json.dumps(lytrogen.f01_metadata(3280, 3280), indent=1).encode()
    toc = {"picture": {"frameArray": [{"frame": {"metadataRef": sha1_ref(meta), "imageRef": RAW_REF}}],
                       "accelerationArray": [{"type": "com.lytro.acceleration.depthMap", "vendorContent": {
                           "width": width, "height": height, "minLambda": float(np.nanmin(depth_lambda)),
                           "maxLambda": float(np.nanmax(depth_lambda)),
                           "depthMap": {"representation": "raw", "imageRef": sha1_ref(depth_bytes)},
                           "confidenceMap": {"representation": "raw", "imageRef": sha1_ref(conf_bytes)}}}]}}
    return assemble(toc, [meta, depth_bytes, conf_bytes], **kwargs)


def illum_picture(lambdas=(-15.0, -10.0, -5.0, 0.0, 5.0, 10.0, 12.5), *, size=48, depth=None,
                  depth_as_png=False, metadata_overrides=None, **kwargs) -> bytes:
    """An Illum ``.LFP`` picture: the fixture's camera metadata inline, a focus stack and a depth map."""
    doc = lytrogen.illum_document(7728, 5368, modulation=False)
    frame = doc["master"]["picture"]["frameArray"][0]["frame"]
    metadata = frame["metadata"]
    for key, value in (metadata_overrides or {}).items():
        metadata["devices"]["lens"][key] = value
    images = [jpeg(im) for im in focus_scene(len(lambdas), size)]
    depth = np.linspace(min(lambdas), max(lambdas), 16 * 16, dtype="<f4").reshape(16, 16) if depth is None \
        else np.asarray(depth, "<f4")
    lo, hi = float(np.nanmin(depth)), float(np.nanmax(depth))
    if depth_as_png:
        from PIL import Image
        buffer = io.BytesIO()
        Image.fromarray(np.round((depth - lo) / (hi - lo) * 255).astype(np.uint8)).save(buffer, format="PNG")
        depth_bytes, representation = buffer.getvalue(), "png"
    else:
        depth_bytes, representation = depth.tobytes(), "raw"
    thumb = jpeg(focus_scene(1, 16)[0])
    toc = {"thumbnails": [{"imageRef": sha1_ref(thumb), "width": 16, "height": 16, "representation": "jpeg"}],
           "frames": [{"frame": {"metadata": metadata, "privateMetadata": frame["privateMetadata"],
                                 "imageRef": RAW_REF}}],
           "views": [{"type": "com.lytro.views.refocus", "accelerations": [{
               "kind": "focusStack", "generator": "lfproc tests",
               "depthMap": {"width": depth.shape[1], "height": depth.shape[0], "minLambda": lo, "maxLambda": hi,
                            "representation": representation, "imageRef": sha1_ref(depth_bytes)},
               "perImage": [{"focus": float(lam), "representation": "jpeg", "width": size, "height": size,
                             "imageRef": sha1_ref(data)} for lam, data in zip(lambdas, images)]}]}]}
    return assemble(toc, [thumb, *images, depth_bytes], **kwargs)


def write(path, data: bytes):
    path.write_bytes(data)
    return path


# ----------------------------------------------------------------------------- the real Illum picture schema

def illum_schema_toc(lambdas=(-15.0, -10.0, -5.0, 0.0, 5.0, 10.0, 12.5), *, depth_size=(12, 8)) -> dict:
    """A table of contents in the schema of a real Illum processed picture (``picture_schema`` 2.1.4, as the
    real ``illum-picture-toc.json`` of ``../shared/real/lytro`` has it): ``frames[0].frame.metadata`` inline
    with the raw frame's ``pixelPacking``, ``pixelFormat`` and ``mosaic`` directly under ``image`` (no
    ``rawDetails``), ``camera.model`` "ILLUM", ``privateMetadata`` inline, no ``imageRef`` for the frame;
    ``views[0].accelerations[0]`` a ``focusStack`` with ``perImage`` (``focus`` = lambda) and a ``depthMap``
    of ``representation`` "packedFloat". Camera numbers from the Illum fixture; references are placeholders
    (``illum_picture_from_toc`` fills them)."""
    import copy

    doc = lytrogen.illum_document(7728, 5368, modulation=False)
    frame = copy.deepcopy(doc["master"]["picture"]["frameArray"][0]["frame"])
    image = frame["metadata"]["image"]
    raw = image.pop("rawDetails")
    image.pop("representation", None)
    image.update(pixelPacking=raw["pixelPacking"], pixelFormat=raw["pixelFormat"], mosaic=raw["mosaic"])
    frame["metadata"]["camera"]["model"] = "ILLUM"
    width, height = depth_size
    return {"schema": "http://schema.lytro.com/lfp/picture/2.1.4/picture_schema.json", "thumbnails": [],
            "frames": [{"frame": {"metadata": frame["metadata"], "privateMetadata": frame["privateMetadata"]}}],
            "views": [{"recipe": {"viewFocus": 0}, "accelerations": [{
                "kind": "focusStack", "width": 64, "height": 48, "representation": "jpeg",
                "depthMap": {"width": width, "height": height, "imageRef": "sha1-" + "0" * 40,
                             "representation": "packedFloat", "minLambda": min(lambdas), "maxLambda": max(lambdas)},
                "perImage": [{"imageRef": "sha1-" + "0" * 40, "focus": lam} for lam in lambdas]}]}]}


def illum_picture_from_toc(toc: dict, *, size=48, depth=None, **kwargs) -> tuple[bytes, dict]:
    """A container around a real (or ``illum_schema_toc``) table of contents: its JSON kept as it is except
    each image reference, which now names a section written here — one small JPEG per ``perImage`` entry
    (``focus_scene``), the depth map as little-endian float32 of the TOC's ``width`` x ``height`` (a ramp
    from ``minLambda`` to ``maxLambda`` unless ``depth`` is given). Returns (bytes, the TOC written)."""
    import copy

    toc = copy.deepcopy(toc)
    stack = toc["views"][0]["accelerations"][0]
    entries = stack["perImage"]
    images = [jpeg(im) for im in focus_scene(len(entries), size)]
    for entry, data in zip(entries, images):
        entry["imageRef"] = sha1_ref(data)
    table = stack["depthMap"]
    if depth is None:
        depth = np.linspace(table["minLambda"], table["maxLambda"], table["width"] * table["height"],
                            dtype="<f4").reshape(table["height"], table["width"])
    depth_bytes = np.asarray(depth, "<f4").tobytes()
    table["imageRef"] = sha1_ref(depth_bytes)
    return assemble(toc, [*images, depth_bytes], **kwargs), toc


def first_gen_h264_stack(lambdas, parallax, *, with_metadata=True) -> bytes:
    """A later engine's first-generation picture: the refocus stack as one H.264 block (``refocusStack``
    ``vendorContent.blockOfImages``, ``metadataArray[]`` with each frame's ``lambda``) beside an
    ``edofParallax`` block of perspective views, and a 20 x 20 depth lookup table. ``lambdas`` go with
    ``focus_scene`` images of 32 x 32 pixels; ``parallax`` is a list of ``(rgb, x, y)``."""
    import h264pcm

    images = focus_scene(len(lambdas), 32)
    stack_block = h264pcm.h264_stream(images)
    views_block = h264pcm.h264_stream([rgb for rgb, _, _ in parallax])
    lut = np.linspace(min(lambdas), max(lambdas), 400, dtype="<f4").reshape(20, 20).tobytes()
    meta = json.dumps(lytrogen.f01_metadata(3280, 3280), indent=1).encode()
    private = json.dumps({"camera": {"serialNumber": "A502030123"}}).encode()
    height, width = parallax[0][0].shape[:2]
    display = {"displayDimensions": {"mode": "fixedToValue", "value": {"width": 32, "height": 32}}}
    accelerations = [
        {"type": "com.lytro.acceleration.refocusStack", "vendorContent": {
            "viewParameters": {}, "displayParameters": display, "defaultLambda": 0,
            "depthLut": {"width": 20, "height": 20, "representation": "raw", "imageRef": sha1_ref(lut)},
            "blockOfImages": {"representation": "h264", "blockOfImagesRef": sha1_ref(stack_block),
                              "metadataArray": [{"width": 32, "height": 32, "lambda": float(lam)}
                                                for lam in lambdas]}}},
        {"type": "com.lytro.acceleration.edofParallax", "vendorContent": {
            "displayParameters": display,
            "blockOfImages": {"representation": "h264", "blockOfImagesRef": sha1_ref(views_block),
                              "metadataArray": [{"width": width, "height": height, "coord": {"x": x, "y": y}}
                                                for _, x, y in parallax]}}}]
    frame = {"frame": {"metadataRef": sha1_ref(meta), "privateMetadataRef": sha1_ref(private), "imageRef": RAW_REF}}
    chunks = [meta, private] if with_metadata else []
    toc = {"picture": {"frameArray": [frame], "viewArray": [], "accelerationArray": accelerations,
                       "derivationArray": [RAW_REF]}, "version": {"major": 1, "minor": 0}}
    return assemble(toc, chunks + [stack_block, views_block, lut])


def parallax_only(parallax) -> bytes:
    """A first-generation picture holding only an edofParallax block of perspective views."""
    import h264pcm

    block = h264pcm.h264_stream([rgb for rgb, _, _ in parallax])
    height, width = parallax[0][0].shape[:2]
    toc = {"picture": {"frameArray": [{"frame": {"imageRef": RAW_REF}}], "accelerationArray": [
        {"type": "com.lytro.acceleration.edofParallax", "vendorContent": {"blockOfImages": {
            "representation": "h264", "blockOfImagesRef": sha1_ref(block),
            "metadataArray": [{"width": width, "height": height, "coord": {"x": x, "y": y}}
                              for _, x, y in parallax]}}}]}}
    return assemble(toc, [block])


def cli(capsys, *args):
    """``lfproc ARGS`` in this process: (status, stdout, stderr lines)."""
    from lfproc.cli import main

    status = main([str(a) for a in args])
    out, err = capsys.readouterr()
    return status, out, err.strip().splitlines()


def info_of(capsys, path) -> dict:
    """``lfproc info PATH --json`` as a dict (strict JSON: no NaN or Infinity)."""
    status, out, err = cli(capsys, "info", path, "--json")
    assert status == 0, err

    def strict(constant):
        raise AssertionError(f"non-strict JSON {constant}")

    return json.loads(out, parse_constant=strict)


def illum_thin_lens(toc) -> dict:
    """The thin-lens numbers of a real Illum picture's metadata (``frames[0].frame.metadata.devices``), in mm:
    ``f_u``, ``n`` (f-number), ``p_m``, ``f_s`` and ``b_u`` = f_U + infinityLambda·N·p_m (docs/lytro.md)."""
    devices = toc["frames"][0]["frame"]["metadata"]["devices"]
    f_u, n = devices["lens"]["focalLength"] * 1e3, devices["lens"]["fNumber"]
    p_m, f_s = devices["mla"]["lensPitch"] * 1e3, devices["mla"]["sensorOffset"]["z"] * 1e3
    return {"f_u": f_u, "n": n, "p_m": p_m, "f_s": f_s, "b_u": f_u + devices["lens"]["infinityLambda"] * n * p_m}
