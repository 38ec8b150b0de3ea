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


FORMAT_HELP = ("image format: tiff = float32 linear (default), png16 = 16-bit linear, jpeg = 8-bit sRGB with one "
               "exposure for the set (for viewing), exr = half/float linear")
INTERPOLATION_HELP = ("interpolation between lenses for real a (default cubic-spline: the cubic spline through each "
                      "view, as sharp between lenses as at them, so the sharpest slice of a sweep sits at the true a; "
                      "linear and nearest pull it to integer a)")


def dumps_strict(obj, **kwargs) -> str:
    """Strict JSON at full double precision; infinity becomes ``null``."""
    return json.dumps(json_safe(obj), allow_nan=False, **kwargs)


#: the most slices one command renders unless --max-slices says otherwise (--a lists and --depth-range alike)
DEFAULT_MAX_SLICES = 10000     # = lfproc.geometry.MAX_SLICES (kept literal: this module loads no numpy)


def add_slice_options(p) -> None:
    """``--a`` / ``--depth-range`` / ``--at`` (one of them) and the planning options, as in every command."""
    which = p.add_mutually_exclusive_group()
    which.add_argument("--a", metavar="LIST",
                       help="refocus parameters: numbers and ranges START:STOP[:STEP], e.g. --a -0.4:0.7:0.1")
    which.add_argument("--depth-range", dest="depth_range_mm", metavar="NEAR_MM:FAR_MM",
                       help="render the fewest slices whose depths of field cover this range (FAR may be inf)")
    which.add_argument("--at", dest="distance_mm", metavar="DISTANCE_MM", type=float,
                       help="the slice focused at this distance (mm)")
    which.add_argument("--z-range", dest="z_range_um", metavar="Z0:Z1[:STEP]",
                       help="microscope cameras: the fewest slices whose depths of field cover Z0..Z1 micrometres "
                            "from the native object plane (positive towards the objective); with STEP an evenly "
                            "spaced z-stack")
    add_slice_planning_options(p)
    return which


def add_slice_planning_options(p) -> None:
    """``--max-gap``, ``--integer`` and ``--max-slices``: compute fewer or cheaper slices."""
    p.add_argument("--max-gap", type=float, default=0.0, metavar="MM",
                   help="with --depth-range: allow uncovered depths up to MM between slices (fewer slices)")
    p.add_argument("--integer", action="store_true",
                   help="with --depth-range: integer a only (fastest slices; may leave gaps, which are listed)")
    p.add_argument("--max-slices", type=int, default=DEFAULT_MAX_SLICES, metavar="N",
                   help=f"refuse to render more than N slices per capture (default {DEFAULT_MAX_SLICES})")


def check_slice_options(args) -> None:
    """Option combinations that make no sense, before any work."""
    if (args.max_gap or args.integer) and args.depth_range_mm is None:
        raise LfprocError("--max-gap and --integer apply to --depth-range only")
    if args.max_slices < 1:
        raise LfprocError(f"--max-slices must be >= 1, got {args.max_slices}")


def slice_parameters(camera, a_list=None, depth_range=None, at_mm=None, max_gap_mm=0.0,
                     integer=False, what: str = "--a", max_slices: int = DEFAULT_MAX_SLICES,
                     view_extent=None, z_range: str | None = None) -> list[float]:
    """The refocus parameters one of --a, --depth-range, --at (mm from the sensor) or --z-range (µm from a
    microscope's native object plane) asks for.

    Every list is checked here, before any capture is read: no more than ``max_slices`` slices, no
    duplicate a (two slices would write the same file), positions the camera's optics can focus on. Whether
    each slice images a real object and covers the capture is checked with the capture
    (:func:`lfproc.api.check_slices`: one usable range, the capture's). ``view_extent``: the extent of the
    views the slices will sum (:func:`lfproc.geometry.summed_view_extent`), for the planning.
    """
    from .. import geometry
    from ..camera import SENSOR_MM
    from ..outputs import slice_names

    if depth_range is not None or at_mm is not None:
        geometry.require_space(camera, SENSOR_MM, "--depth-range/--at (use --z-range for a microscope)")
    if a_list is not None:
        values = parse_number_list(a_list, what)
    elif z_range is not None:
        from .geometry import z_range_parameters
        values = [float(a) for a in z_range_parameters(camera, z_range, advise=False)]   # focal_stack advises
        what = "--z-range"
    elif depth_range is not None:
        near, far = parse_depth_range(depth_range)
        geometry.check_usable_distances(camera, near, f"--depth-range {depth_range}")
        plan = geometry.plan_depth_range(camera, near, far, max_gap=max_gap_mm, integer=integer,
                                         max_slices=max_slices, view_extent=view_extent)
        values = [float(a) for a in plan.a]
        if not values:
            raise LfprocError(f"--depth-range {depth_range}: no slice can be planned ({plan.uncovered[0][2]})")
    elif at_mm is None:
        raise LfprocError("give one of --a, --depth-range, --at or --z-range")
    elif not math.isfinite(at_mm):
        raise LfprocError(f"--at must be a finite distance in mm from the sensor, got {at_mm}")
    else:
        geometry.check_usable_distances(camera, at_mm, "--at")
        values = [float(geometry.refocus_parameter(camera, at_mm))]
    if len(values) > max_slices:
        asked = what if a_list is not None or z_range is not None else "--depth-range"
        raise LfprocError(f"{asked} asks for {len(values)} slices, more than --max-slices {max_slices}; use a "
                          f"coarser list, or raise --max-slices")
    slice_names("check", values)   # duplicates raise here, not after the first capture was decoded
    return values


def add_aperture_option(p) -> None:
    """``--aperture F_NUMBER``: a synthetic aperture (refocus, depth, viewer, batch)."""
    p.add_argument("--aperture", type=float, metavar="F_NUMBER",
                   help="synthetic aperture: average only the views inside this f-number (from the main lens's "
                        "f-number to one view's); the DOF tags follow (sidecar aperture_f_number)")


def aperture_extent(camera, f_number) -> float | None:
    """The DOF extent of the views inside ``--aperture`` (before decoding; ``None`` without one); checks it."""
    if f_number is None:
        return None
    from .. import geometry

    return geometry.summed_view_extent(geometry.aperture_views(camera, f_number))


def describe_slices(camera, a_values, depth_range=None, out=None, *, max_gap_mm: float = 0.0,
                    integer: bool = False, max_slices: int = DEFAULT_MAX_SLICES, view_mask=None) -> None:
    """One line per slice (a, distance, [near, far] in mm; in the camera's object space, so a microscope's
    z in µm) and the depths no slice covers, with the reason, on stdout. The planning options are those the
    slices were planned with; the DOF is that of the views ``view_mask`` marks (all when ``None``)."""
    import numpy as np

    from .. import geometry

    out = out or sys.stdout
    extent = None if view_mask is None else geometry.summed_view_extent(view_mask)
    geo = geometry.slice_geometry(camera, a_values, extent)
    if extent is not None:
        print(f"{int(np.count_nonzero(view_mask))} views summed ({geometry.aperture_text(camera, extent)}); the DOF "
              f"follows them", file=out)
    print(f"{len(a_values)} slice(s):", file=out)
    space = geo.space
    for a, position, near, far in zip(*(np.atleast_1d(x).tolist() for x in (geo.a, geo.depth, geo.near, geo.far))):
        low, high = space.low_high(near, far)      # in focus, low to high
        print(f"  a={a:+.4f}  {space.text(position)}  in focus {space.interval(low, high)}", file=out)
    if depth_range is None:
        return
    near, far = parse_depth_range(depth_range)
    plan = geometry.plan_depth_range(camera, near, far, max_gap=max_gap_mm, integer=integer,
                                     max_slices=max_slices, view_extent=extent)
    for lo, hi, why in plan.uncovered:
        print(f"  no slice is in focus at {_mm(lo)}..{_mm(hi)}: {why}", file=out)
    if not plan.uncovered:
        print(f"  together in focus over all of {_mm(near)}..{_mm(far)}", file=out)


def _mm(value: float) -> str:
    return "inf mm" if math.isinf(value) else f"{value:.1f} mm"


#: options whose value may start with '-' (a negative number or range): argparse would take it for an option
NEGATIVE_VALUE_OPTIONS = ("--a", "--refocus", "--disparity", "--gap", "--z-range")


def join_negative_values(argv: list[str]) -> list[str]:
    """``--a -0.4:0.7`` → ``--a=-0.4:0.7``, so that negative lists work with or without ``=``."""
    out, i = [], 0
    while i < len(argv):
        item = argv[i]
        if item in NEGATIVE_VALUE_OPTIONS and i + 1 < len(argv) and _looks_negative(argv[i + 1]):
            out.append(f"{item}={argv[i + 1]}")
            i += 2
            continue
        out.append(item)
        i += 1
    return out


def _looks_negative(text: str) -> bool:
    return len(text) > 1 and text[0] == "-" and (text[1].isdigit() or text[1] == "." or text[1:4] == "inf")


def add_preview_option(p, what: str) -> None:
    """``--preview`` (and ``--preview-format``): display-ready pictures beside the data products (refocus, views)."""
    p.add_argument("--preview", action="store_true",
                   help=f"also a display-ready picture of {what} (NAME_preview.png): tone-mapped sRGB with one "
                        f"exposure for all, enlarged to at least 512 px and labelled")
    p.add_argument("--preview-format", choices=("png", "jpeg"), default="png",
                   help="with --preview: png (default) or jpeg (NAME_preview.jpg)")


def preview_format(args) -> str | None:
    """The format of ``--preview`` pictures, or None without ``--preview``."""
    return args.preview_format if args.preview else None
