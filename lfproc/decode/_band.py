"""Reading one band of a :class:`._plan.ReadPlan`: its sensor strip converted once, its views remapped.

Reading own cells (``plan.cells``), the strip is converted once per lens class (masked to that class's
cells, demosaiced or rim-aware) into a vertical *stack* of four class strips with rows of 0 between
them, so that one ``cv2.remap`` reads every lens from its own class's strip, as if from that strip alone.
"""

from __future__ import annotations

import numpy as np

from ..grid import LensGrid
from ._cells import CLASSES, class_weight, lens_class, masked
from ._demosaic import channel_count, demosaic_u16, quantize, quantize_levels, quantized_zero, to_channels
from ._plan import Band, ReadPlan
from ._resample import cv_flag, remap_into
from ._rim_demosaic import RATIO_FLOOR, RATIO_LIMIT, phase_channels

#: interpolations whose weights are >= 0 (each sample within its taps' range: safe on 16-bit data)
CONVEX_INTERPOLATIONS = ("nearest", "linear")


def read_band(plan: ReadPlan, band: Band, sensor: np.ndarray, scratch: dict | None = None, sink=None,
              levels: tuple | None = None) -> np.ndarray | None:
    """The raw (not devignetted) views of ``band``'s lens rows: ``(m̂, m̂, len(rows), cols, C)`` float32.

    Only the sensor strip of the band is converted (demosaiced): no full-size temporaries. Only the
    plan's ``runs`` of views are read; the others are left undefined. ``scratch`` (a dict kept by the
    caller across bands) lends the result's and the stack's memory: the result is then valid until the
    next call with the same ``scratch``. With ``sink``, each run is handed to ``sink(ky, kx0, kx1, views)``
    (``views``: ``(1, kx1 − kx0, len(rows), cols, C)``, valid during the call) as soon as it is read,
    while it is still in the processor's cache, and None is returned. ``levels``: the 16-bit quantization
    of the whole ``sensor`` (:func:`sensor_levels`), for a Bayer mosaic demosaiced by OpenCV (else each
    strip is quantized by its own range: the output then depends on the bands).
    """
    grid, m_hat, rows = plan.grid, plan.m_hat, band.rows
    n, cols = len(rows), grid.cols
    channels = channel_count(sensor, plan.cfa)
    out = None if sink is not None else borrowed(scratch, "views", (m_hat, m_hat, n, cols, channels), np.float32)

    def target(ky, kx0, kx1):
        if out is not None:
            return flat_out(out, ky, kx0, kx1)
        return borrowed(scratch, "run", ((kx1 - kx0) * n, cols, channels), np.float32)

    def deliver(ky, kx0, kx1, block):
        if sink is not None:
            sink(ky, kx0, kx1, block.reshape(1, kx1 - kx0, n, cols, channels))

    if band.y1 <= band.y0:
        for ky, kx0, kx1 in plan.runs:
            block = target(ky, kx0, kx1)
            block[...] = 0.0
            deliver(ky, kx0, kx1, block)
        return out
    flag = cv_flag(plan.interpolation)
    positions = plan.positions(band)
    y0, y1 = band.y0, band.y1
    if plan.cells is None:
        strip = np.ascontiguousarray(to_channels(sensor[y0:y1], plan.cfa, plan.demosaic_method, levels))
        for ky, kx0, kx1 in plan.runs:   # map rows run over (kx, r): a run of views is a block of map rows
            block = target(ky, kx0, kx1)
            remap_into(block, strip, *plan.run_maps(positions, band, ky, kx0, kx1), flag)
            deliver(ky, kx0, kx1, block)
        return out
    shares = None if plan.shares is None else tuple(a[y0:y1] for a in plan.shares)
    if plan.rim is not None:
        stack, scale, low, zero = _rim_stack(plan, band, sensor[y0:y1], shares, scratch)
    else:
        stack, scale, low, zero = _class_stack(plan, band, sensor[y0:y1], shares, scratch, levels)
    height, gap, reach = band.height, plan.gap, plan.reach
    step = class_step(height, gap)
    r, q = np.meshgrid(np.arange(rows.start, rows.stop), np.arange(cols), indexing="ij")
    base = (gap + lens_class(r, q) * step).astype(np.float32)   # each lens's strip in the stack
    clipped = y0 == 0 or y1 == plan.sensor_shape[0]     # only there can samples reach past the strip's gap rows
    for ky, kx0, kx1 in plan.runs:
        map_x, map_y = plan.run_maps(positions, band, ky, kx0, kx1)
        my = map_y.reshape(kx1 - kx0, n, cols) + base
        if clipped:    # reading past the gap, a sample reads only 0 in its own strip: so it does here
            y = my - base
            my[(y < reach - 1 - gap) | (y >= height + gap - reach)] = -2 * gap - 2
        block = target(ky, kx0, kx1)
        remap_into(block, stack, map_x, my.reshape(-1, cols), flag, scale=scale, offset=low, border=zero)
        deliver(ky, kx0, kx1, block)
    return out


def class_step(height: int, gap: int) -> int:
    """Rows from one class strip of a stack to the next: the strip, ``gap`` rows of 0 on each side, and one
    more where ``height`` is odd. Even (as ``gap`` and a strip's ``y0`` are), so that a map position moved
    into the stack keeps its rounding (OpenCV's nearest rounds halves to even)."""
    return height + 2 * gap + (height & 1)


def borrowed(scratch: dict | None, name: str, shape: tuple, dtype) -> np.ndarray:
    """An uninitialised array: ``scratch[name]``'s memory (grown when too small) reused, or new without
    ``scratch``. Reusing a band's buffers for the next band spares the kernel from mapping and zeroing
    fresh pages for each (a band's stack and views are tens of MB; system time was a third of decoding)."""
    size = int(np.prod(shape)) * np.dtype(dtype).itemsize
    if scratch is None:
        return np.empty(shape, dtype)
    if name not in scratch or scratch[name].nbytes < size:
        scratch[name] = np.empty(size, np.uint8)
    return scratch[name][:size].view(dtype).reshape(shape)


def flat_out(out: np.ndarray, ky: int, kx0: int, kx1: int) -> np.ndarray:
    """``out[ky, kx0:kx1]`` as map rows over (kx, r): ``((kx1 − kx0)·rows, cols, C)``."""
    m_hat, _, rows, cols, channels = out.shape
    return out.reshape(m_hat, m_hat * rows, cols, channels)[ky, kx0 * rows:kx1 * rows]


def sensor_levels(plan: ReadPlan, sensor: np.ndarray) -> tuple | None:
    """The ``(low, scale)`` every strip of ``sensor`` is quantized with (:func:`._demosaic.quantize_levels`)
    where ``plan`` reads it through OpenCV's 16-bit demosaicing, else None."""
    if plan.rim is not None or np.ndim(sensor) != 2 or plan.cfa == "none":
        return None
    return quantize_levels(sensor)


def _class_stack(plan: ReadPlan, band: Band, raw: np.ndarray, shares: tuple | None, scratch: dict | None,
                 levels: tuple | None = None) -> tuple[np.ndarray, float | None, float, int]:
    """The sensor strip once per lens class, masked to that class's cells and converted to channels,
    stacked vertically (class c at rows ``gap + c·step``, :func:`class_step`) with rows of 0 around each.

    A Bayer mosaic is quantized once (:func:`quantize`) and its classes demosaiced straight into a
    uint16 stack: returns ``(stack, 1 / scale, low, zero)``, ``linear = value / scale + low`` (``zero``: the
    value that stands for 0, :func:`quantized_zero`, read outside the stack), so that only the resampled
    samples are converted to float (the remap rounds them to the 16-bit unit, as the mosaic was). Other
    images, and every image when the interpolation is not convex (its negative lobes over- and
    undershoot the 16-bit range), give a float32 linear stack and ``(stack, None, 0.0, 0)``.
    """
    cfa, method, gap, rows, grid = plan.cfa, plan.demosaic_method, plan.gap, band.rows, plan.grid
    classes = plan.cells[band.y0:band.y1]
    height, width = raw.shape[:2]
    step = class_step(height, gap)
    channels = channel_count(raw, cfa)
    present = set(np.unique(lens_class(*np.meshgrid(np.arange(rows.start, min(rows.start + 2, rows.stop)),
                                                    np.arange(min(2, grid.cols)), indexing="ij"))).tolist())
    quantized = raw.ndim == 2 and cfa != "none"
    assert shares is None or not quantized, "cell shares weigh float images only"
    if quantized:
        as_u16, low, scale = quantize(raw, levels)
        zero = quantized_zero(low, scale)
    else:
        low, scale, zero = 0.0, None, 0
    stack = borrowed(scratch, "stack", (CLASSES * step, width, channels), np.uint16 if quantized else np.float32)
    for cls in range(CLASSES):
        top = gap + cls * step
        stack[top - gap:top] = zero
        stack[top + height:top - gap + step] = zero
        dst = stack[top:top + height]
        if cls not in present:
            dst[...] = zero
        elif quantized:
            demosaic_u16(masked(as_u16, classes, cls, zero), cfa, method, dst=dst)
        elif shares is not None:
            weight = class_weight(classes, *shares, cls)
            dst[...] = to_channels(raw * (weight if raw.ndim == 2 else weight[..., None]), cfa, method)
        else:
            dst[...] = to_channels(masked(raw, classes, cls), cfa, method)
    if scale is None:
        return stack, None, 0.0, 0
    if plan.interpolation not in CONVEX_INTERPOLATIONS:
        linear = stack.astype(np.float32)
        linear *= np.float32(1.0 / scale)
        linear += np.float32(low)
        return linear, None, 0.0, 0
    return stack, 1.0 / scale, low, zero


def _rim_stack(plan: ReadPlan, band: Band, raw: np.ndarray, shares: tuple,
               scratch: dict | None) -> tuple[np.ndarray, None, float, int]:
    """:func:`_class_stack` for rim-aware decoding (:mod:`._rim_demosaic`): each class's ``ŵ·rgb``, float32."""
    from ._rim_kernel import rim_stack

    grid, gap = plan.grid, plan.gap
    balanced, levels = plan.rim
    height, width = raw.shape[:2]
    step = class_step(height, gap)
    stack = borrowed(scratch, "stack", (CLASSES * step, width, 3), np.float32)
    rim_stack(raw, balanced[band.y0:band.y1], plan.cells[band.y0:band.y1], shares[0], shares[1],
              (1.0 / np.asarray(levels, np.float64)), phase_channels(plan.cfa).astype(np.int64), band.y0,
              lattice_of(grid), gap, RATIO_FLOOR, RATIO_LIMIT, stack,
              borrowed(scratch, "own lens", (height, width), np.int32),
              borrowed(scratch, "other lens", (height, width), np.int32), step=step)
    return stack, None, 0.0, 0


def lattice_of(grid: LensGrid) -> np.ndarray:
    """The rigid lattice as the rim kernel reads it: (ox, oy, ux, uy, vx, vy, pitch, row spacing, hexagonal)."""
    u, v = grid.axes
    return np.array([grid.origin_xy_px[0], grid.origin_xy_px[1], u[0], u[1], v[0], v[1], grid.pitch_px,
                     grid.row_spacing_px, 1.0 if grid.kind == "hexagonal" else 0.0])
