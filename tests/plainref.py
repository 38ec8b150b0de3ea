"""Plain-numpy references shared by several tests (deliberately independent of lfproc's kernels)."""

import numpy as np


def shifted_views(views, a):
    """Every view shifted by the contract's a·(c − k) lenses, bilinear in plain numpy: (m², Ny, Nx)."""
    m, _, ny, nx = views.shape[:4]
    c = (m - 1) // 2
    jy, jx = np.meshgrid(np.arange(ny, dtype=float), np.arange(nx, dtype=float), indexing="ij")
    out = []
    for ky in range(m):
        for kx in range(m):
            sy, sx = jy + a * (c - ky), jx + a * (c - kx)
            y0 = np.clip(np.floor(sy).astype(int), 0, ny - 2)
            x0 = np.clip(np.floor(sx).astype(int), 0, nx - 2)
            wy, wx = sy - y0, sx - x0
            v = views[ky, kx, :, :, 0].astype(np.float64)
            out.append(v[y0, x0] * (1 - wy) * (1 - wx) + v[y0, x0 + 1] * (1 - wy) * wx
                       + v[y0 + 1, x0] * wy * (1 - wx) + v[y0 + 1, x0 + 1] * wy * wx)
    return np.array(out)


def measured_shift(first, second, search=4.0, step=0.02):
    """The x shift s (lenses) with second(x) ≈ first(x − s), by least squares over linear shifts, refined by
    a parabola through the best three; rows and a border are cropped so every shift stays inside."""
    border = int(np.ceil(search)) + 2
    cols = np.arange(first.shape[1], dtype=np.float64)
    shifts = np.arange(-search, search + step / 2, step)
    costs = []
    for s in shifts:
        moved = np.array([np.interp(cols - s, cols, row) for row in first])
        costs.append(((moved - second)[border:-border, border:-border] ** 2).mean())
    k = int(np.argmin(costs))
    c0, c1, c2 = costs[k - 1], costs[k], costs[k + 1]
    return float(shifts[k] + step * 0.5 * (c0 - c2) / (c0 - 2 * c1 + c2))
