"""``lfproc info`` on a processed Lytro picture: what it holds, each image's lambda, its camera, damage.

Added to the contract keys of ``_describe`` (``format`` "lytro-container", ``raw_light_field`` false,
``width``/``height`` of the stack images or the depth map, ``camera_model``, ``sections``):
``picture`` (the contents), ``focus_stack``, ``depth_map``, ``perspective_views``, ``raw_frame``
("referenced, not contained"), ``camera_known`` with the lambda map's ``focus_distance_mm`` or
``camera_note``, ``damaged`` and ``missing_sections``.
"""

from __future__ import annotations

from ._lytro_picture import read_picture
from ._lytro_picture_open import picture_lambda_map
from ._lytro_picture_pixels import image_size


def describe_picture(container) -> dict:
    """The picture's fields for ``lfproc info`` (nothing decoded but image headers)."""
    from ._describe import _metadata_fields
    from ._lytro_lambda import DISTANCE_FROM

    picture = read_picture(container)
    meta, mapping, why = picture_lambda_map(picture)
    info = {"picture": picture.contents, "generation": picture.generation}
    parts = []
    if picture.stack:
        images = [_stack_record(picture, image) for image in picture.stack]
        if mapping is not None:
            for record, geometry in zip(images, mapping.slices([i.lambda_ for i in picture.stack])):
                record.update({k: v for k, v in geometry.items() if k != "lambda"})
        info["focus_stack"] = {"count": len(images), "default_lambda": picture.default_lambda, "images": images}
        info["width"], info["height"] = images[0]["width"], images[0]["height"]
        parts.append(f"focus stack ({len(images)} images, lambda {min(i.lambda_ for i in picture.stack):g} to "
                     f"{max(i.lambda_ for i in picture.stack):g})")
    if picture.depth:
        depth = picture.depth
        record = {"kind": depth.kind, "width": depth.width, "height": depth.height, "min_lambda": depth.min_lambda,
                  "max_lambda": depth.max_lambda, "representation": depth.representation,
                  "confidence": depth.confidence_reference is not None}
        if mapping is not None and depth.min_lambda is not None and depth.max_lambda is not None:
            record["near_mm"] = float(mapping.distance_mm(depth.min_lambda))
            record["far_mm"] = float(mapping.distance_mm(depth.max_lambda))
            record["distance_from"] = DISTANCE_FROM
        info["depth_map"] = record
        if info.get("width") is None:
            info["width"], info["height"] = depth.width, depth.height
        span = f", lambda {depth.min_lambda:g} to {depth.max_lambda:g}" if None not in (depth.min_lambda,
                                                                                      depth.max_lambda) else ""
        parts.append(f"{depth.kind} ({depth.width} x {depth.height}{span})")
    if picture.parallax:
        views = [{"width": w, "height": h, "x": x, "y": y} for w, h, x, y in picture.parallax.views]
        info["perspective_views"] = {"count": len(views), "representation": picture.parallax.representation,
                                     "views": views}
        if info.get("width") is None and views:
            info["width"], info["height"] = views[0]["width"], views[0]["height"]
        parts.append(f"perspective views ({len(views)}, {picture.parallax.representation} edofParallax block)")
    info["content"] = "processed Lytro picture: " + ", ".join(parts)
    if picture.raw_reference is None:
        info["raw_frame"] = "not referenced"
    elif picture.container.chunk(picture.raw_reference) is None:
        info["raw_frame"] = "referenced, not contained (the camera's raw .lfr/.lfp holds it)"
    else:
        info["raw_frame"] = "contained"
    info["raw_frame_reference"] = picture.raw_reference
    if meta is not None:
        fields = _metadata_fields(meta)
        fields["raw_frame_width"], fields["raw_frame_height"] = fields.pop("width"), fields.pop("height")
        for key in ("bits_per_pixel", "endianness", "black_level", "white_level", "modulation_frame"):
            fields.pop(key)
        info.update(fields)
    info["camera_known"] = mapping is not None
    if mapping is not None:
        from ..geometry import slice_distance_mm

        info["focus_distance_mm"] = slice_distance_mm(mapping.camera, 0.0)
        info["distance_from"] = DISTANCE_FROM
    else:
        info["camera_note"] = f"no distances: {why}; `lfproc.outputs.export_picture(..., camera=...) gives them`"
    info["missing_sections"] = list(picture.missing)
    info["damaged"] = picture.damaged
    return info


def _stack_record(picture, image) -> dict:
    width, height = image.width, image.height
    if width is None or height is None:
        data = picture.container.chunk(image.reference)
        size = image_size(bytes(data[:65536])) if data is not None else None
        width, height = size if size else (None, None)
    return {"index": image.index, "lambda": image.lambda_, "width": width, "height": height,
            "representation": image.representation}
