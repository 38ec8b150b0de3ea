"""Argument parsing helpers shared by the subcommands (no heavy imports here)."""

from __future__ import annotations

import json
import math
import sys

from ..atomic import json_safe
from ..errors import LfprocError


def parse_number_list(text: str, what: str = "--a") -> list[float]:
    """Parse comma-separated numbers and inclusive ranges ``START:STOP[:STEP]`` (contract's LIST).

    ``0:5`` is 0, 1, …, 5; ``0:1:0.25`` is 0, 0.25, 0.5, 0.75, 1; ``5:0:-1`` counts down. A range
    whose step does not land on STOP ends at the last value before it.
    """
    values: list[float] = []
    if text is None or not text.strip():
        raise LfprocError(f"{what}: empty list; give numbers like 0,1.5 or a range like 0:5")
    for item in text.split(","):
        item = item.strip()
        if not item:
            continue
        parts = item.split(":")
        try:
            nums = [float(p) for p in parts]
        except ValueError:
            raise LfprocError(f"{what}: {item!r} is not a number or START:STOP[:STEP] range") from None
        if any(not math.isfinite(n) for n in nums) or len(nums) > 3:
            raise LfprocError(f"{what}: {item!r} is not a finite number or START:STOP[:STEP] range")
        if len(nums) == 1:
            values.append(nums[0])
            continue
        start, stop = nums[0], nums[1]
        step = nums[2] if len(nums) == 3 else (1.0 if stop >= start else -1.0)
        if step == 0 or (stop - start) * step < 0:
            raise LfprocError(f"{what}: range {item!r} never reaches its end; check the sign of STEP")
        count = int(math.floor((stop - start) / step + 1e-9)) + 1
        if count > 100000:
            raise LfprocError(f"{what}: range {item!r} has {count} values; use a larger STEP")
        values.extend(round(start + k * step, 12) for k in range(count))
    if not values:
        raise LfprocError(f"{what}: empty list; give numbers like 0,1.5 or a range like 0:5")
    return values


def parse_depth_range(text: str) -> tuple[float, float]:
    """Parse ``NEAR_MM:FAR_MM`` (FAR may be ``inf``)."""
    parts = text.split(":")
    try:
        near, far = (float(p) for p in parts)
    except ValueError:
        raise LfprocError(f"--depth-range: {text!r} must be NEAR_MM:FAR_MM, e.g. 200:400 or 1000:inf") from None
    if not (math.isfinite(near) and near > 0 and far >= near):
        raise LfprocError(f"--depth-range: {text!r} needs 0 < NEAR <= FAR")
    return near, far


def dumps_strict(obj, **kwargs) -> str:
    """Strict JSON at full double precision; infinity becomes ``null``."""
    return json.dumps(json_safe(obj), allow_nan=False, **kwargs)


def add_slice_planning_options(p) -> None:
    """``--max-gap`` and ``--integer``: compute fewer or cheaper slices for a ``--depth-range``."""
    p.add_argument("--max-gap", type=float, default=0.0, metavar="MM",
                   help="with --depth-range: allow uncovered depths up to MM between slices (fewer slices)")
    p.add_argument("--integer", action="store_true",
                   help="with --depth-range: integer a only (fastest slices; may leave gaps, which are listed)")


def slice_parameters(camera, a_list=None, depth_range=None, at_mm=None, max_gap_mm=0.0,
                     integer=False, what: str = "--a") -> list[float]:
    """The refocus parameters one of --a, --depth-range or --at asks for (holes reported on stderr)."""
    from .. import geometry

    if a_list is not None:
        return parse_number_list(a_list, what)
    if depth_range is not None:
        near, far = parse_depth_range(depth_range)
        a_values = geometry.plan_slices(camera, near, far, max_gap_mm=max_gap_mm, integer=integer)
        holes = geometry.uncovered_depths(camera, a_values, near, far)
        if holes:
            listed = ", ".join(f"{lo:.1f}..{hi:.1f}" for lo, hi in holes)
            print(f"lfproc: note: no slice is in focus at {listed} mm", file=sys.stderr)
        return [float(a) for a in a_values]
    if at_mm is None:
        raise LfprocError("give one of --a, --depth-range or --at")
    if not math.isfinite(at_mm):
        raise LfprocError(f"--at must be a finite distance in mm from the sensor, got {at_mm}")
    return [float(geometry.refocus_parameter(camera, at_mm))]
