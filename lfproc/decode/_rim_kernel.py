"""The numba kernel of rim-aware decoding (:mod:`._rim_demosaic`): per-lens hue, then each class's ``ŵ·rgb``.

Compiled on first call and cached on disk (``cache=True``). Lenses are found from the rigid lattice and
the decoder's class map: the rigid estimate's neighbour of the pixel's class nearest to the pixel (a
smooth deviation of the lattice moves a centre by far less than the two pitches between lenses of a
class), so a lens's pixels are summed together whatever the grid's deviation.
"""

import numpy as np
from numba import njit, prange


@njit(cache=True, inline="always")
def _rigid_lens(x, y, lattice):
    """(r, q) of the rigid lattice point nearest to (x, y); ``lattice`` = (ox, oy, ux, uy, vx, vy, pitch,
    spacing, hexagonal)."""
    dx = x - lattice[0]
    dy = y - lattice[1]
    a = (dx * lattice[2] + dy * lattice[3]) / lattice[6]
    b = (dx * lattice[4] + dy * lattice[5]) / lattice[7]
    if lattice[8] == 0.0:
        return int(np.floor(b + 0.5)), int(np.floor(a + 0.5))
    best_r, best_q, best_d = 0, 0, 1e300
    r0 = int(np.floor(b))
    for r in (r0, r0 + 1):
        half = 0.5 * (r % 2)
        q = int(np.floor(a - half + 0.5))
        d = ((a - q - half) * lattice[6]) ** 2 + ((b - r) * lattice[7]) ** 2
        if d < best_d:
            best_r, best_q, best_d = r, q, d
    return best_r, best_q


@njit(cache=True, inline="always")
def _lens_xy(r, q, lattice):
    along_u = (q + (0.5 * (r % 2) if lattice[8] != 0.0 else 0.0)) * lattice[6]
    along_v = r * lattice[7]
    return (lattice[0] + along_u * lattice[2] + along_v * lattice[4],
            lattice[1] + along_u * lattice[3] + along_v * lattice[5])


@njit(cache=True, inline="always")
def _lens_of_class(x, y, r0, q0, cls, lattice):
    """The lens of class ``cls`` among (r0, q0) and its neighbours nearest to (x, y)."""
    if 2 * (r0 % 2) + (q0 % 2) == cls:
        return r0, q0
    best_r, best_q, best_d = r0, q0, 1e300
    for dr in range(-1, 2):
        for dq in range(-1, 2):
            r = r0 + dr
            q = q0 + dq
            if 2 * (r % 2) + (q % 2) != cls:
                continue
            cx, cy = _lens_xy(r, q, lattice)
            d = (x - cx) ** 2 + (y - cy) ** 2
            if d < best_d:
                best_r, best_q, best_d = r, q, d
    return best_r, best_q


@njit(cache=True)
def _lens_range(height, width, y0, lattice):
    """The rigid lens rows and columns the strip's pixels fall in, widened by one lens each way."""
    r_lo, q_lo, r_hi, q_hi = 1 << 30, 1 << 30, -(1 << 30), -(1 << 30)
    for y in (float(y0), float(y0 + height - 1)):
        for x in (0.0, float(width - 1)):
            r, q = _rigid_lens(x, y, lattice)
            r_lo, r_hi, q_lo, q_hi = min(r_lo, r), max(r_hi, r), min(q_lo, q), max(q_hi, q)
    return r_lo - 2, q_lo - 2, r_hi + 2, q_hi + 2


@njit(cache=True, inline="always")
def _pixel(raw, share, phase_gain, phase_channel, i, j):
    """(channel, capture in the balanced white's units, share in its own lens) of pixel (i, j) of a strip
    that starts on an even row."""
    p = 2 * (i % 2) + (j % 2)
    return phase_channel[p], raw[i, j] * phase_gain[p], share[i, j] * (1.0 / 255.0)


@njit(cache=True, parallel=True)
def _lens_sums(raw, wb, cells, border, share, y0, lattice, phase_gain, phase_channel, r_lo, q_lo, sums, own, other):
    """sums[chunk, r − r_lo, q − q_lo, ch, 0 / 1] += share·capture / share·ŵ of each lit pixel of a chunk
    of rows (its lens and the lens across the border by their shares); the caller adds the chunks.

    Sensor row y belongs to chunk ``(y // _CHUNK_ROWS) mod chunks`` whatever the strip: a lens's pixels
    are summed in the same order in any strip that holds them, so its sums do not depend on the band."""
    height, width = raw.shape
    chunks = sums.shape[0]
    cols = sums.shape[2]
    for k in prange(chunks):
        for i in range(height):
            if ((y0 + i) // _CHUNK_ROWS) % chunks != k:
                continue
            y = float(y0 + i)
            for j in range(width):
                w = wb[i, j]
                if w <= 0.0:
                    continue
                ch, value, s = _pixel(raw, share, phase_gain, phase_channel, i, j)
                r0, q0 = _rigid_lens(float(j), y, lattice)
                r, q = _lens_of_class(float(j), y, r0, q0, cells[i, j], lattice)
                own[i, j] = (r - r_lo) * cols + q - q_lo
                sums[k, r - r_lo, q - q_lo, ch, 0] += s * value
                sums[k, r - r_lo, q - q_lo, ch, 1] += s * w
                if s < 1.0:
                    r, q = _lens_of_class(float(j), y, r0, q0, border[i, j], lattice)
                    other[i, j] = (r - r_lo) * cols + q - q_lo
                    sums[k, r - r_lo, q - q_lo, ch, 0] += (1.0 - s) * value
                    sums[k, r - r_lo, q - q_lo, ch, 1] += (1.0 - s) * w


@njit(cache=True, inline="always")
def _write(stack, row, j, lens_sums, rho, w, own_ch, floor, limit):
    """``w·rgb`` of a pixel of value ``rho`` (channel ``own_ch``) under the hue of ``lens_sums`` (3, 2)."""
    m_own = lens_sums[own_ch, 0] / lens_sums[own_ch, 1] if lens_sums[own_ch, 1] > 0 else 0.0
    for ch in range(3):
        if ch == own_ch:
            stack[row, j, ch] = w * rho
            continue
        if lens_sums[ch, 1] <= 0.0 or lens_sums[own_ch, 1] <= 0.0:
            stack[row, j, ch] = w * rho         # no pixel of that channel in the lens: grey
            continue
        m_ch = lens_sums[ch, 0] / lens_sums[ch, 1]
        gain = min(max((m_ch + floor) / (m_own + floor), 1.0 / limit), limit)
        stack[row, j, ch] = w * max(m_ch + gain * (rho - m_own), 0.0)


@njit(cache=True, parallel=True)
def _fill(stack, raw, wb, cells, border, share, phase_gain, phase_channel, own, other, sums, gap, step, floor, limit):
    height, width = raw.shape
    for i in prange(height):
        for c in range(4):
            stack[gap + c * step + i] = 0.0
        for j in range(width):
            w = wb[i, j]
            if w <= 0.0:
                continue
            ch, value, s = _pixel(raw, share, phase_gain, phase_channel, i, j)
            rho = value / w
            _write(stack, gap + cells[i, j] * step + i, j, sums[own[i, j]], rho, s * w, ch, floor, limit)
            if s < 1.0:
                _write(stack, gap + border[i, j] * step + i, j, sums[other[i, j]], rho, (1.0 - s) * w, ch, floor,
                       limit)


def _read_only(array: np.ndarray) -> np.ndarray:
    view = array.view()
    view.flags.writeable = False
    return view


#: chunks of rows summed apart (in parallel) before their lens sums are added
_CHUNKS = 8
#: sensor rows of one chunk's run (the chunks take turns down the sensor)
_CHUNK_ROWS = 8


def rim_stack(raw, wb, cells, border, share, phase_gain, phase_channel, y0, lattice, gap, floor, limit, stack,
              own=None, other=None, step=None):
    """Fill ``stack`` (``(4·step, W, 3)`` float32, ``step`` = h + 2·gap unless given) with each lens class's
    ``ŵ·rgb`` of the strip (class c at rows ``gap + c·step``, 0 around); ``own`` and ``other``, ``(h, W)``
    int32 scratch (new ones when not given)."""
    height, width = raw.shape
    step = height + 2 * gap if step is None else step
    # numba compiles one version per argument type, and a read-only array (the decoder's, mapped from its
    # cache) is another type than a writable one: hand it read-only views always, so that one compiled
    # version (kept on disk) serves every run, the first one after deriving a decoder included
    raw, wb, cells, border, share = (_read_only(a) for a in (raw, wb, cells, border, share))
    r_lo, q_lo, r_hi, q_hi = _lens_range(height, width, y0, lattice)
    sums = np.zeros((_CHUNKS, r_hi - r_lo + 1, q_hi - q_lo + 1, 3, 2), np.float64)
    own = np.empty((height, width), np.int32) if own is None else own        # each lit pixel's lens (sums index)
    other = np.empty((height, width), np.int32) if other is None else other  # the lens across its border
    _lens_sums(raw, wb, cells, border, share, y0, lattice, phase_gain, phase_channel, r_lo, q_lo, sums, own, other)
    total = sums.sum(axis=0).reshape(-1, 3, 2)
    for c in range(4):
        stack[c * step:c * step + gap] = 0.0
        stack[c * step + gap + height:(c + 1) * step] = 0.0
    _fill(stack, raw, wb, cells, border, share, phase_gain, phase_channel, own, other, total, gap, step, floor,
          limit)


@njit(cache=True, parallel=True)
def cell_shares_rigid(classes, y0, x0, lattice, steps_even, steps_odd, width_px, second, share):
    """:func:`lfproc.decode._cells.cell_shares` on a rigid lattice: ``steps_*`` ``(n, 4)`` rows of
    (dr, dq, offset x, offset y) of the neighbours of a lens on an even / odd row."""
    height, width = classes.shape
    for i in prange(height):
        y = float(y0 + i)
        for j in range(width):
            x = float(x0 + j)
            r0, q0 = _rigid_lens(x, y, lattice)
            r, q = _lens_of_class(x, y, r0, q0, classes[i, j], lattice)
            cx, cy = _lens_xy(r, q, lattice)
            dx, dy = x - cx, y - cy
            steps = steps_odd if (lattice[8] != 0.0 and r % 2 == 1) else steps_even
            best, best_cls = 1e300, 0
            for k in range(steps.shape[0]):
                ox, oy = steps[k, 2], steps[k, 3]
                length = np.sqrt(ox * ox + oy * oy)
                t = 0.5 * length - (dx * ox + dy * oy) / length
                if t < best:
                    rn = r + int(steps[k, 0])
                    qn = q + int(steps[k, 1])
                    best, best_cls = t, 2 * (rn % 2) + (qn % 2)
            second[i, j] = best_cls
            frac = min(max(0.5 + max(best, 0.0) / width_px, 0.5), 1.0)
            share[i, j] = int(np.floor(frac * 255.0 + 0.5))
