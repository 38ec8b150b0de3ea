"""The public refocus function: argument checks, sampling plans, and the threaded band driver (Eq. 9)."""

from __future__ import annotations

import math
import numbers
from concurrent.futures import ThreadPoolExecutor

import numba
import numpy as np

from ..errors import LfprocError, warn
from ._kernels import _gather_band, _interpolated_band, _interpolated_rows_band
from ._per_view import refocus_per_view
from ._plan import AxisPlan, axis_plan
from ._spline import postfilter

INTERPOLATIONS = ("nearest", "linear", "cubic", "cubic-sharp", "cubic-spline")

#: dtypes the kernels read directly; other real dtypes are converted (see the module docstring)
NATIVE_DTYPES = (np.dtype(np.float32), np.dtype(np.float64), np.dtype(np.uint16))

#: target size in bytes of one band's float64 accumulators (all slices of the call; the gather's
#: float32 partial sums add half as much again): L2/L3-resident
ACCUMULATOR_BUDGET_BYTES = 4 << 20

#: the largest output (K·Ny'·Nx'·C float32 values) one call may produce, in bytes; an ``upsample`` that
#: needs more raises LfprocError instead of running out of memory
MAX_OUTPUT_BYTES = 16 << 30

#: lower bound on band height, so that many slices in one call do not shrink bands to a few rows
#: (each band also reads the rows its slices' shifts add on top: the shorter the band, the more)
MIN_BAND_ROWS = 8


# ----------------------------------------------------------------------------- public entry point
def refocus(lf, a, interpolation: str = "linear", upsample: int = 1, view_shifts=None, *,
            aperture: float | None = None) -> np.ndarray:
    """Refocused slice(s) of a light field by centred shift-and-sum (Eq. 9).

    Parameters
    ----------
    lf : LightField or ndarray
        A :class:`~lfproc.lightfield.LightField`, or an array shaped ``(m̂, m̂, Ny, Nx, C)`` with m̂ odd
        (float32, float64, unsigned or signed integers; see the module docstring for precision). An array
        carries neither the view mask nor a microscope's per-view shifts: its mean runs over every view
        (dark views, 0 everywhere or far below the brightest, :func:`lit_views`, are warned about with an
        :class:`~lfproc.errors.LfprocWarning`) with Eq. 9's shifts; pass the LightField to refocus as it does.
    a : float or sequence of float
        Refocus parameter(s): the shift in lenses per view step (Eq. 9). Any finite real; positive a
        focuses nearer than a = 0. A sequence is rendered in one pass over the data.
    interpolation : {"nearest", "linear", "cubic", "cubic-sharp", "cubic-spline"}
        How positions between lenses are read (module docstring). ``"linear"`` (the default here) and
        ``"nearest"`` make the sharpest slice of a sweep snap to integer ``a``; ``"cubic-spline"`` (the
        default of the commands: cubic spline interpolation) holds it at the true ``a``. Irrelevant for
        integer ``a`` with ``upsample = 1``, which is a pure gather.
    upsample : int, optional
        Output grid ``s`` times finer: shape ``((Ny − 1)·s + 1, (Nx − 1)·s + 1)``, pixel (py, px) at lens
        position (py/s, px/s). ``1`` (default) is the lens grid itself. The output of the call (all K
        slices) may take at most :data:`MAX_OUTPUT_BYTES` (16 GiB).
    view_shifts : (σ_y, σ_x) or None, optional
        A per-view shift table, two ``(m̂, m̂)`` arrays: view (ky, kx) of slice ``a`` is read at
        ``(py/s + a·σ_y[ky, kx], px/s + a·σ_x[ky, kx])`` instead of ``a·(c − ky), a·(c − kx)``. ``None``
        (default) takes the light field's own table (``LightField.refocus_slopes``: the sine
        condition's shifts of a high-NA microscope, :func:`lfproc.geometry.refocus_slopes`), and Eq. 9
        where it has none — every photographic light field.
    aperture : float, optional
        A synthetic aperture f-number: average only the views inside it (:func:`lfproc.with_aperture`,
        which needs ``lf``'s camera). ``None`` (default): every view that carries light.

    Returns
    -------
    ndarray, float32
        ``(Ny', Nx', C)`` for a scalar ``a``, ``(K, Ny', Nx', C)`` for a sequence of K values.

    Raises
    ------
    LfprocError
        Empty or non-finite ``a``, unknown ``interpolation``, bad ``upsample`` (or an output above
        :data:`MAX_OUTPUT_BYTES`), a malformed light field, non-finite pixels that reach a slice, or
        finite float64 values beyond the float32 range.
    """
    if aperture is not None:
        from ..viewpoints import with_aperture   # light (numpy); the aperture is geometry, not refocusing

        if getattr(lf, "camera", None) is None:
            raise LfprocError("refocus: `aperture=` needs a LightField with its camera")
        lf = with_aperture(lf, aperture)
    views = _views_array(lf)
    slopes, scalar = _slopes(a)
    interpolation = _interpolation(interpolation)
    upsample = _upsample(upsample)
    m, _, ny, nx, channels = views.shape
    _check_output_size(len(slopes), ny, nx, channels, upsample)
    table = _shift_table(lf, view_shifts, m)
    mask = _view_mask(lf, views)
    if table is not None:
        out = refocus_per_view(views, slopes, table, interpolation, upsample, mask, _thread_count())
        _check_finite(out, slopes, views)
        return out[0] if scalar else out
    plan_y = axis_plan(slopes, m, ny, upsample, interpolation)
    plan_x = axis_plan(slopes, m, nx, upsample, interpolation)
    out = _render(views, plan_y, plan_x, upsample)
    bad = ~np.isfinite(out).reshape(len(slopes), -1).all(axis=1)
    if bad.any() and views.dtype == np.float32 and np.isfinite(views).all():
        # finite float32 values near 3.4e38 overflow the float32 row sums: render again in float64
        # (only on this failure path, so the usual call pays nothing)
        out = _render(views.astype(np.float64), plan_y, plan_x, upsample)
        bad = ~np.isfinite(out).reshape(len(slopes), -1).all(axis=1)
    if bad.any():
        first_bad = slopes[int(np.argmax(bad))]
        if np.isfinite(views).all():      # finite float64 beyond float32, or a cubic's overshoot near 3.4e38
            raise LfprocError(f"light field values exceed the float32 range; rescale them (largest magnitude "
                              f"{float(np.abs(views).max()):.3g}, e.g. divide by it) before refocusing "
                              f"(slice a={first_bad:g})")
        raise LfprocError(f"light field has NaN or infinite pixels that reach the slice a={first_bad:g}; "
                          "replace them (e.g. numpy.nan_to_num) before refocusing")
    out = out.reshape(len(slopes), plan_y.count.shape[1], plan_x.count.shape[1], channels)
    if mask is not None:
        out *= _masked_mean_factor(mask, plan_y, plan_x, ny, nx, upsample)[..., None]
    if plan_y.spline.any() or plan_x.spline.any():
        postfilter(out, plan_y.spline, plan_x.spline, upsample)
        _check_finite(out, slopes, views)
    return out[0] if scalar else out


def _masked_mean_factor(mask: np.ndarray, plan_y: AxisPlan, plan_x: AxisPlan, ny: int, nx: int,
                        upsample: int) -> np.ndarray:
    """Per slice and output pixel: (views inside the array) / (marked views inside the array).

    The kernels average over every view whose sample lies inside the array, counting the unmarked ones
    (which hold 0); this factor turns that into the mean over the marked views alone. The marked views
    that count at output (py, px) number ``inside_y[py]ᵀ · mask · inside_x[px]`` (:func:`_marked_slices`).
    Where no marked view reaches a pixel the slice is 0.
    """
    factor = np.empty((len(plan_y.count), plan_y.count.shape[1], plan_x.count.shape[1]), dtype=np.float32)
    for k, marked in _marked_slices(mask, plan_y, plan_x, ny, nx, upsample):   # a slice's counts stay in cache
        every = np.multiply.outer(plan_y.count[k], plan_x.count[k])
        with np.errstate(divide="ignore", invalid="ignore"):
            factor[k] = np.where(marked > 0, every / marked, 0.0)
    return factor


def _marked_slices(weight, plan_y: AxisPlan, plan_x: AxisPlan, ny: int, nx: int, upsample: int):
    """``(k, (Py, Px) float64)`` per slice: the sum of ``weight`` (``(m_y, m_x)``, the plans' views) over the
    views whose sample counts at each output pixel, ``inside_y[k]ᵀ · weight · inside_x[k]``. The columns
    ``inside_x[k][:, px]`` take only a few distinct values (all views inside, except near the ends), so
    the product is formed for those and spread to the pixels by one gather (a five-index einsum, which
    loops over every view pair and pixel, took seconds on an Illum-sized sweep; BLAS with an inner
    dimension of a few views 15 × longer than this)."""
    inside_y = plan_y.inside(ny, upsample).astype(np.float64)     # (K, m_y, Py)
    inside_x = plan_x.inside(nx, upsample)                        # (K, m_x, Px)
    weight = np.asarray(weight, dtype=np.float64)
    for k in range(inside_y.shape[0]):
        columns, which = np.unique(inside_x[k].T, axis=0, return_inverse=True)
        yield k, ((inside_y[k].T @ weight) @ columns.T.astype(np.float64))[:, which.ravel()]


def marked_count(weight, plan_y: AxisPlan, plan_x: AxisPlan, ny: int, nx: int, upsample: int = 1) -> np.ndarray:
    """``(K, Py, Px)`` float32: :func:`_marked_slices` of every slice."""
    out = np.empty((len(plan_y.count), plan_y.count.shape[1], plan_x.count.shape[1]), dtype=np.float32)
    for k, marked in _marked_slices(weight, plan_y, plan_x, ny, nx, upsample):
        out[k] = marked
    return out


def _shift_table(lf, view_shifts, m: int):
    """The per-view shift table to use: ``view_shifts``, else the light field's own, else ``None`` (Eq. 9)."""
    table = getattr(lf, "refocus_slopes", None) if view_shifts is None else view_shifts
    if table is None:
        return None
    try:
        sigma_y, sigma_x = (np.asarray(t, dtype=np.float64) for t in table)
    except (TypeError, ValueError):
        raise LfprocError("refocus: view_shifts must be two (m, m) arrays of per-view shift multipliers") from None
    if sigma_y.shape != (m, m) or sigma_x.shape != (m, m) or not (np.isfinite(sigma_y).all()
                                                                  and np.isfinite(sigma_x).all()):
        raise LfprocError(f"refocus: view_shifts must be two finite ({m}, {m}) arrays (one per view), "
                          f"got shapes {sigma_y.shape} and {sigma_x.shape}")
    return sigma_y, sigma_x


def _view_mask(lf, views: np.ndarray):
    """The views the mean runs over: a LightField's ``view_mask`` (None: all). A bare array has no mask: the
    contract's mean runs over all its views (Eq. 9 as it stands), and where some are dark (:func:`lit_views`:
    0 everywhere, as a decoder delivers the views without light, or far below the brightest) an
    :class:`~lfproc.errors.LfprocWarning` says the slices are darker than the LightField's and what to pass
    instead. An array whose every view carries light is refocused without a word."""
    m = views.shape[0]
    if hasattr(lf, "views"):
        mask = getattr(lf, "view_mask", None)
        return None if mask is None else np.asarray(mask, dtype=bool).reshape(m, m)
    lit = lit_views(views)
    if lit is not None:
        n_lit, n = int(np.count_nonzero(lit)), int(lit.size)
        warn(f"refocus: {n - n_lit} of {n} views of this array are dark (0 everywhere, or at most "
             f"{DARK_VIEW_FRACTION:.0%} of the brightest view's mean level) and an array's mean runs over "
             f"every view, so its slices are about {n_lit / n:.2f}x as bright as those of a light field whose "
             f"view_mask leaves the dark views out; pass the LightField (lf, not lf.views), or "
             f"lfproc.LightField.from_views(views, camera, view_mask=...) with the {n_lit} views that "
             f"carry light")
    return None


#: a view whose mean magnitude is at most this fraction of the brightest view's is dark (:func:`lit_views`)
DARK_VIEW_FRACTION = 0.01


def lit_views(views: np.ndarray) -> np.ndarray | None:
    """``(m̂, m̂)`` booleans marking the views of an array that carry light, or None when all do (or none does).

    A view is dark where its mean magnitude (over its lenses and channels) is at most
    :data:`DARK_VIEW_FRACTION` of the brightest view's: 0 everywhere, as the decoder delivers the views
    without light (``LightField.view_mask``), or a faint remainder (a black-level residue, stray light) that
    darkens an all-view mean as a view of zeros does. Views with non-finite values are never dark.

    Cheap: 16 evenly spread lens rows of every view give each view's level, and only the views that may be
    dark are read in full."""
    axes = tuple(range(2, views.ndim))
    sample = views[:, :, ::max(1, views.shape[2] // 16)]
    level = np.abs(sample).mean(axis=axes, dtype=np.float64)
    finite = np.isfinite(level)
    if not finite.any():
        return None
    top = float(level[finite].max())
    if top <= 0.0:                     # no view carries any light: nothing to tell apart
        return None
    limit = DARK_VIEW_FRACTION * top
    dark = finite & (level <= limit)
    if not dark.any():
        return None
    for ky, kx in zip(*np.nonzero(dark)):
        dark[ky, kx] = bool(np.abs(views[ky, kx]).mean(dtype=np.float64) <= limit)
    return None if not dark.any() else ~dark


def _check_finite(out: np.ndarray, slopes, views: np.ndarray) -> None:
    bad = ~np.isfinite(out).reshape(len(slopes), -1).all(axis=1)
    if bad.any() and np.isfinite(views).all():
        # finite views, non-finite slice: values beyond the float32 range (or a cubic spline's overshoot)
        raise LfprocError(f"light field values exceed the float32 range in the slice a={slopes[int(np.argmax(bad))]:g}; "
                          f"rescale them (largest magnitude {float(np.abs(views).max()):.3g}, e.g. divide by it) "
                          "before refocusing")
    if bad.any():
        raise LfprocError(f"light field has NaN or infinite pixels that reach the slice a={slopes[int(np.argmax(bad))]:g}; "
                          "replace them (e.g. numpy.nan_to_num) before refocusing")


# ----------------------------------------------------------------------------- input validation
def _views_array(lf) -> np.ndarray:
    """The ``(m̂, m̂, Ny, Nx, C)`` array of ``lf``, C-contiguous, in a dtype the kernels read."""
    views = getattr(lf, "views", lf)
    try:
        views = np.asarray(views)
    except Exception:  # pragma: no cover - exotic array-likes
        raise LfprocError("refocus needs a LightField or an array shaped (m, m, Ny, Nx, C)") from None
    if views.ndim != 5 or views.shape[0] != views.shape[1] or views.shape[0] % 2 == 0 or min(views.shape) < 1:
        raise LfprocError(f"refocus needs views shaped (m, m, Ny, Nx, C) with m odd and no empty axis, "
                          f"got shape {views.shape}; pass a LightField or reshape the array")
    kind = views.dtype.kind
    if views.dtype in NATIVE_DTYPES:
        pass
    elif kind in "iu":
        views = views.astype(np.float32 if views.dtype.itemsize == 1 else np.float64)
    elif kind == "f" and views.dtype.itemsize > 8:
        views = views.astype(np.float64)      # longdouble: keep the precision float64 can hold
    elif kind in "fb":
        views = views.astype(np.float32)
    else:
        raise LfprocError(f"refocus needs real-valued views, got dtype {views.dtype}; convert to float32")
    return np.ascontiguousarray(views)


def _check_output_size(n_slices: int, ny: int, nx: int, channels: int, upsample: int) -> None:
    """Refuse outputs above :data:`MAX_OUTPUT_BYTES` before allocating anything."""
    size = n_slices * ((ny - 1) * upsample + 1) * ((nx - 1) * upsample + 1) * channels * 4
    if size > MAX_OUTPUT_BYTES:
        raise LfprocError(f"refocus: upsample={upsample} with {n_slices} slice(s) would produce "
                          f"{size / 2**30:.1f} GiB of output (limit {MAX_OUTPUT_BYTES / 2**30:g} GiB); "
                          "use a smaller upsample or fewer a values per call")


def _slopes(a) -> tuple[tuple[float, ...], bool]:
    """``a`` as a tuple of finite floats, and whether it was a scalar."""
    arr = np.asarray(a, dtype=object) if not isinstance(a, np.ndarray) else a
    if arr.ndim > 1:
        raise LfprocError(f"refocus: a must be a number or a flat list of numbers, got shape {arr.shape}")
    scalar = arr.ndim == 0
    items = [arr.item()] if scalar else list(np.ravel(arr))
    if not items:
        raise LfprocError("refocus: the list of a values is empty; give at least one number")
    values = []
    for item in items:
        if isinstance(item, (bool, np.bool_)) or not isinstance(item, (numbers.Real, np.integer, np.floating)):
            raise LfprocError(f"refocus: a={item!r} is not a number; give real numbers like 0, 1.5, -2")
        value = float(item)
        if not math.isfinite(value):
            raise LfprocError(f"refocus: a={value} is not finite; give finite numbers like 0, 1.5, -2")
        values.append(value)
    return tuple(values), scalar


def _interpolation(name) -> str:
    if name not in INTERPOLATIONS:
        raise LfprocError(f"refocus: unknown interpolation {name!r}; use one of {', '.join(INTERPOLATIONS)}")
    return name


def _upsample(s) -> int:
    if isinstance(s, (bool, np.bool_)) or not isinstance(s, (numbers.Integral, np.integer)) or s < 1:
        raise LfprocError(f"refocus: upsample must be an integer >= 1, got {s!r}")
    return int(s)


# ----------------------------------------------------------------------------- driver
def _thread_count() -> int:
    """Worker threads: ``NUMBA_NUM_THREADS`` (default: the CPUs available)."""
    return max(1, int(numba.config.NUMBA_NUM_THREADS))


def _bands(n_slices: int, n_rows: int, row_len: int, threads: int) -> list[tuple[int, int]]:
    """Output row ranges processed one per task: float64 accumulators of all slices near the budget,
    and a number of bands that is a multiple of the thread count (so the threads finish together)."""
    accumulator_bytes = n_slices * n_rows * row_len * 8
    n_bands = max(threads, -(-accumulator_bytes // ACCUMULATOR_BUDGET_BYTES))
    n_bands = min(n_bands, max(threads, n_rows // MIN_BAND_ROWS))   # many slices: keep bands tall
    n_bands = min(n_rows, -(-n_bands // threads) * threads)
    edges = [i * n_rows // n_bands for i in range(n_bands + 1)]          # sizes differ by at most one
    return list(zip(edges[:-1], edges[1:]))


def _phase0(arr: np.ndarray) -> np.ndarray:
    """The ``r = 0`` phase of a ``(K, m, s)`` plan array, as a C-ordered ``(K, m)`` array."""
    return np.ascontiguousarray(arr[:, :, 0])


def _weights0(weights: np.ndarray) -> np.ndarray:
    """The ``r = 0`` phase of a ``(K, m, s, 4)`` weight array, as a C-ordered ``(K, m, 4)`` array."""
    return np.ascontiguousarray(weights[:, :, 0, :])


def _render(views: np.ndarray, plan_y: AxisPlan, plan_x: AxisPlan, upsample: int) -> np.ndarray:
    """Run the kernel that fits the plans over all bands of output rows; returns ``(K, Ny', Nx'·C)`` float32.

    The band kernels release the GIL, so bands run in parallel on a thread pool; they write disjoint
    rows of ``out``.
    """
    m_y, m_x, ny, nx, channels = views.shape     # m_y ≠ m_x: a block of the views (._block)
    flat = views.reshape(m_y, m_x, ny, nx * channels)
    n_slices, out_rows = plan_y.count.shape
    out_cols = plan_x.count.shape[1]
    out = np.empty((n_slices, out_rows, out_cols * channels), dtype=np.float32)
    # per-view-row partial sums: float32 unless the views are float64 (module docstring, Precision)
    part = np.zeros(0, dtype=np.float64 if views.dtype == np.float64 else np.float32)
    if upsample == 1 and plan_y.whole_lens and plan_x.whole_lens:
        args = (flat, channels, _phase0(plan_y.first), _phase0(plan_y.ntaps), _phase0(plan_y.lo), _phase0(plan_y.hi),
                _phase0(plan_x.first), _phase0(plan_x.lo), _phase0(plan_x.hi), plan_y.count, plan_x.count)
        kernel = _gather_band
    elif upsample == 1:
        args = (flat, channels, _phase0(plan_y.first), _phase0(plan_y.ntaps), _weights0(plan_y.weights),
                _phase0(plan_y.lo), _phase0(plan_y.hi), _phase0(plan_x.first), _phase0(plan_x.ntaps),
                _weights0(plan_x.weights).astype(part.dtype), _phase0(plan_x.lo), _phase0(plan_x.hi),
                plan_y.count, plan_x.count)
        kernel = _interpolated_rows_band
    else:
        args = (flat, channels, upsample, plan_y.first, plan_y.ntaps, plan_y.weights, plan_y.lo, plan_y.hi,
                plan_x.first, plan_x.ntaps, plan_x.weights.astype(part.dtype), plan_x.lo, plan_x.hi,
                plan_y.count, plan_x.count)
        kernel = _interpolated_band
    threads = _thread_count()
    bands = _bands(n_slices, out_rows, out_cols * channels, threads)
    if threads == 1 or len(bands) == 1:
        for row0, row1 in bands:
            kernel(*args, row0, row1, part, out)
    else:
        with ThreadPoolExecutor(max_workers=min(threads, len(bands))) as pool:
            list(pool.map(lambda rows: kernel(*args, rows[0], rows[1], part, out), bands))
    return out

