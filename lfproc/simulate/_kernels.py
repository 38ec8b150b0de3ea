"""The numba ray tracing kernels of the simulator (see :mod:`lfproc.simulate._render` for the ray model).

Compiled on first call and cached on disk (``cache=True``); every kernel works in float64 and the
parallel ones run over sensor rows (or lens rows).
"""

import numpy as np
from numba import njit, prange

from ._sensor import LUMA_WEIGHTS
from ._textures import KIND_CHECKER, KIND_IMAGE, KIND_NOISE, KIND_SINUSOID

# The luminance weights as module-level floats: numba freezes globals into the compiled code.
_LUMA_R, _LUMA_G, _LUMA_B = LUMA_WEIGHTS

@njit(cache=True, inline="always")
def _nearest_lens_px(px, py, lattice):
    """Centre (x, y) px of the lens whose lattice (Voronoi) cell contains sensor point (px, py)."""
    dx = px - lattice[0]
    dy = py - lattice[1]
    along_u = dx * lattice[2] + dy * lattice[3]
    along_v = dx * lattice[4] + dy * lattice[5]
    pitch = lattice[6]
    if lattice[8] == 0.0:
        cu = np.floor(along_u / pitch + 0.5) * pitch
        cv = np.floor(along_v / pitch + 0.5) * pitch
    else:
        # the nearest hexagonal lattice point lies in one of the two rows around the point
        spacing = lattice[7]
        r0 = np.floor(along_v / spacing)
        best = np.inf
        cu = 0.0
        cv = 0.0
        for step in range(2):
            row = r0 + step
            shift = 0.5 * (int(row) & 1)
            col = np.floor(along_u / pitch - shift + 0.5)
            cand_u = (col + shift) * pitch
            cand_v = row * spacing
            d2 = (along_u - cand_u) ** 2 + (along_v - cand_v) ** 2
            if d2 < best:
                best = d2
                cu = cand_u
                cv = cand_v
    return lattice[0] + cu * lattice[2] + cv * lattice[4], lattice[1] + cu * lattice[3] + cv * lattice[5]


@njit(cache=True, inline="always")
def _hash01(ix, iy, seed):
    """A deterministic pseudo-random number in [0, 1] for integer lattice point (ix, iy)."""
    h = (ix * 374761393 + iy * 668265263 + seed * 1442695041 + 1013904223) & 0xFFFFFFFF
    h = ((h ^ (h >> 13)) * 1274126177) & 0xFFFFFFFF
    h = ((h ^ (h >> 16)) * 2246822519) & 0xFFFFFFFF
    h = h ^ (h >> 15)
    return h / 4294967295.0


@njit(cache=True, inline="always")
def _value_noise(x, y, seed):
    """Value noise: lattice values blended with the quintic fade 6t⁵ − 15t⁴ + 10t³ (C² smooth)."""
    fx = np.floor(x)
    fy = np.floor(y)
    ix = np.int64(fx)
    iy = np.int64(fy)
    tx = x - fx
    ty = y - fy
    sx = tx * tx * tx * (tx * (tx * 6.0 - 15.0) + 10.0)
    sy = ty * ty * ty * (ty * (ty * 6.0 - 15.0) + 10.0)
    v00 = _hash01(ix, iy, seed)
    v10 = _hash01(ix + 1, iy, seed)
    v01 = _hash01(ix, iy + 1, seed)
    v11 = _hash01(ix + 1, iy + 1, seed)
    top = v00 + (v10 - v00) * sx
    bottom = v01 + (v11 - v01) * sx
    return top + (bottom - top) * sy


@njit(cache=True, inline="always")
def _texture_value(kind, par, x, y):
    """Scalar texture value t in [0, 1] at plane point (x, y) relative to the texture origin."""
    if kind == KIND_CHECKER:
        i = np.int64(np.floor(x / par[2]))
        j = np.int64(np.floor(y / par[2]))
        return float((i + j) & 1)
    if kind == KIND_SINUSOID:
        return 0.5 + 0.5 * np.cos(par[2] * (x * par[3] + y * par[4]) + par[5])
    if kind == KIND_NOISE:
        seed = np.int64(par[3])
        fine = _value_noise(2.0 * x * par[2] + 17.25, 2.0 * y * par[2] + 31.5, seed + 7919)
        return (_value_noise(x * par[2], y * par[2], seed) + 0.5 * fine) / 1.5
    return 1.0  # uniform


@njit(cache=True, inline="always")
def _image_sample(par, images, x, y, channel):
    """Bilinear sample of an image texture (row 0 at the smallest y), edge pixels clamped."""
    rows = np.int64(par[5])
    cols = np.int64(par[6])
    col = (x / par[2] + 0.5) * cols - 0.5
    row = (y / par[3] + 0.5) * rows - 0.5
    col = min(max(col, 0.0), cols - 1.0)
    row = min(max(row, 0.0), rows - 1.0)
    c0 = min(np.int64(col), cols - 2) if cols > 1 else 0
    r0 = min(np.int64(row), rows - 2) if rows > 1 else 0
    c1 = min(c0 + 1, cols - 1)
    r1 = min(r0 + 1, rows - 1)
    wc = col - c0
    wr = row - r0
    base = np.int64(par[4])
    v00 = images[base + (r0 * cols + c0) * 3 + channel]
    v01 = images[base + (r0 * cols + c1) * 3 + channel]
    v10 = images[base + (r1 * cols + c0) * 3 + channel]
    v11 = images[base + (r1 * cols + c1) * 3 + channel]
    return (v00 * (1 - wc) + v01 * wc) * (1 - wr) + (v10 * (1 - wc) + v11 * wc) * wr


@njit(cache=True, inline="always")
def _nearest_hit(ux, uy, qx, qy, z, frame, region):
    """The nearest plane whose region the object-space ray X(z) = U + q·z meets in front of the main lens.

    Returns (sorted plane index or −1, plane coordinates a, b of the hit, its z from H1U). A
    fronto-parallel plane sits at z[p]; a tilted one (frame[p, 9] = 1) is where the plane coordinates
    (x, y, z − z[p]) = (−X, z − z[p]) are normal to n = frame[p, 6:9]; its own coordinates are the
    projections on e1 = frame[p, 0:3] and e2 = frame[p, 3:6]. Plane coordinates are the ray heights
    negated (the picture as seen in the capture, upright). Ties go to the lower index.
    """
    best = -1
    best_z = np.inf
    best_a = 0.0
    best_b = 0.0
    for p in range(z.shape[0]):
        if frame[p, 9] == 0.0:
            zp = z[p]
            if zp >= best_z:
                continue
            a = -(ux + qx * zp)
            b = -(uy + qy * zp)
        else:
            nx = frame[p, 6]
            ny = frame[p, 7]
            nz = frame[p, 8]
            denom = nz - nx * qx - ny * qy
            if denom == 0.0:
                continue  # the ray runs inside the plane's direction
            zp = (nx * ux + ny * uy + nz * z[p]) / denom
            if zp <= 0.0 or zp >= best_z:
                continue  # behind the main lens, or farther than a plane already hit
            x = -(ux + qx * zp)
            y = -(uy + qy * zp)
            dz = zp - z[p]
            a = frame[p, 0] * x + frame[p, 1] * y + frame[p, 2] * dz
            b = frame[p, 3] * x + frame[p, 4] * y + frame[p, 5] * dz
        if a < region[p, 0] or a >= region[p, 1] or b < region[p, 2] or b >= region[p, 3]:
            continue
        best = p
        best_z = zp
        best_a = a
        best_b = b
    return best, best_a, best_b, best_z


@njit(cache=True, inline="always")
def _scene_radiance(ux, uy, qx, qy, z, frame, region, kind, par, center, tint, images, background):
    """RGB radiance along the object-space ray X(z) = U + q·z, and the (sorted) index of the plane hit (−1: none)."""
    p, x, y, _ = _nearest_hit(ux, uy, qx, qy, z, frame, region)
    if p < 0:
        return background[0], background[1], background[2], -1
    tx = x - center[p, 0]
    ty = y - center[p, 1]
    low = par[p, 0]
    span = par[p, 1] - par[p, 0]
    if kind[p] == KIND_IMAGE:
        return ((low + span * _image_sample(par[p], images, tx, ty, 0)) * tint[p, 0],
                (low + span * _image_sample(par[p], images, tx, ty, 1)) * tint[p, 1],
                (low + span * _image_sample(par[p], images, tx, ty, 2)) * tint[p, 2], p)
    value = low + span * _texture_value(kind[p], par[p], tx, ty)
    return value * tint[p, 0], value * tint[p, 1], value * tint[p, 2], p


@njit(cache=True, inline="always")
def _store(out, y, x, r, g, b, scale):
    if out.shape[2] == 1:
        out[y, x, 0] = (_LUMA_R * r + _LUMA_G * g + _LUMA_B * b) * scale
    else:
        out[y, x, 0] = r * scale
        out[y, x, 1] = g * scale
        out[y, x, 2] = b * scale


@njit(cache=True, inline="always")
def _outside_pupil(mx, my, t_x, t_y, inv_d_a, max_slope2):
    """True when the ray of slope m leaving the micro lens aperture at height t misses the exit pupil.

    The pupil, a disk of radius d_A/(2N) at d_A in front of the MLA, is met at height t + m·d_A; the
    test divides by d_A: |m + t/d_A|² > 1/(2N)². Telecentric (inv_d_a = 0): |m|² > 1/(2N)².
    """
    ex = mx + t_x * inv_d_a
    ey = my + t_y * inv_d_a
    return ex * ex + ey * ey > max_slope2


@njit(cache=True, parallel=True)
def _sensor_kernel(out, row0, row1, axis_x, axis_y, pixel_mm, lattice, inv_scale, f_s, b_u, f_u, max_slope2, rim2,
                   inv_d_a, pix_off, ap_off, z, frame, region, kind, par, center, tint, images, background):
    """Sensor irradiance of rows row0 ≤ y < row1: each pixel averages pix_off × ap_off rays (0 for blocked ones).

    ``lattice`` is the micro image lattice: a sensor point belongs to the micro image whose cell holds
    it (ideal baffles), and its lens sits at the micro image centre's height times ``inv_scale``.
    """
    width = out.shape[1]
    n_pix = pix_off.shape[0]
    n_ap = ap_off.shape[0]
    scale = 1.0 / (n_pix * n_ap)
    telecentric = inv_d_a == 0.0
    for y in prange(row0, row1):
        for x in range(width):
            r = 0.0
            g = 0.0
            b = 0.0
            for i in range(n_pix):
                px = x + pix_off[i, 0]
                py = y + pix_off[i, 1]
                cx, cy = _nearest_lens_px(px, py, lattice)
                s_x = (cx - axis_x) * pixel_mm * inv_scale
                s_y = (cy - axis_y) * pixel_mm * inv_scale
                mx = (s_x - (px - axis_x) * pixel_mm) / f_s
                my = (s_y - (py - axis_y) * pixel_mm) / f_s
                if telecentric and mx * mx + my * my > max_slope2:
                    continue  # outside the aperture stop, whatever the aperture point
                for j in range(n_ap):
                    t_x = s_x + ap_off[j, 0]
                    t_y = s_y + ap_off[j, 1]
                    if not telecentric and _outside_pupil(mx, my, t_x, t_y, inv_d_a, max_slope2):
                        continue
                    u_x = t_x + mx * b_u
                    u_y = t_y + my * b_u
                    if u_x * u_x + u_y * u_y > rim2:
                        continue
                    rr, gg, bb, _ = _scene_radiance(u_x, u_y, mx - u_x / f_u, my - u_y / f_u, z, frame, region,
                                                    kind, par, center, tint, images, background)
                    r += rr
                    g += gg
                    b += bb
            _store(out, y, x, r, g, b, scale)


@njit(cache=True, parallel=True)
def _ideal_kernel(views, weight, row0, row1, centers, lens_centers, view_off, sub_off, axis_x, axis_y, pixel_mm,
                  f_s, b_u, f_u, max_slope2, rim2, inv_d_a, ap_off, z, frame, region, kind, par, center, tint, images,
                  background):
    """Ideal views of lens rows row0 ≤ row < row1: per lens and view, the mean radiance of the passing rays and the
    passing fraction.

    View samples sit at the micro image centre (``centers``, px) plus ``view_off``; the rays leave
    the lens at ``lens_centers`` (px), the same points when telecentric.
    """
    m = views.shape[0]
    cols = views.shape[3]
    channels = views.shape[4]
    n_sub = sub_off.shape[0]
    n_ap = ap_off.shape[0]
    total = n_sub * n_ap
    for row in prange(row0, row1):
        for col in range(cols):
            s_x = (lens_centers[row, col, 0] - axis_x) * pixel_mm
            s_y = (lens_centers[row, col, 1] - axis_y) * pixel_mm
            # slope towards the micro image centre: 0 when telecentric, the chief ray −s/d_A otherwise
            chief_x = (s_x - (centers[row, col, 0] - axis_x) * pixel_mm) / f_s
            chief_y = (s_y - (centers[row, col, 1] - axis_y) * pixel_mm) / f_s
            for ky in range(m):
                for kx in range(m):
                    r = 0.0
                    g = 0.0
                    b = 0.0
                    passed = 0
                    fallback = False
                    for attempt in range(2):  # the second pass (all rays, unblocked) only when none passed
                        for i in range(n_sub):
                            dx_mm = (view_off[ky, kx, 0] + sub_off[i, 0]) * pixel_mm
                            dy_mm = (view_off[ky, kx, 1] + sub_off[i, 1]) * pixel_mm
                            mx = chief_x - dx_mm / f_s
                            my = chief_y - dy_mm / f_s
                            for j in range(n_ap):
                                t_x = s_x + ap_off[j, 0]
                                t_y = s_y + ap_off[j, 1]
                                if not fallback and _outside_pupil(mx, my, t_x, t_y, inv_d_a, max_slope2):
                                    continue
                                u_x = t_x + mx * b_u
                                u_y = t_y + my * b_u
                                if not fallback and u_x * u_x + u_y * u_y > rim2:
                                    continue
                                rr, gg, bb, _ = _scene_radiance(u_x, u_y, mx - u_x / f_u, my - u_y / f_u, z, frame,
                                                                region, kind, par, center, tint, images,
                                                                background)
                                r += rr
                                g += gg
                                b += bb
                                passed += 1
                        if passed > 0:
                            break
                        fallback = True
                    weight[ky, kx, row, col] = 0.0 if fallback else passed / total
                    scale = 1.0 / passed
                    if channels == 1:
                        views[ky, kx, row, col, 0] = (_LUMA_R * r + _LUMA_G * g + _LUMA_B * b) * scale
                    else:
                        views[ky, kx, row, col, 0] = r * scale
                        views[ky, kx, row, col, 1] = g * scale
                        views[ky, kx, row, col, 2] = b * scale


@njit(cache=True)
def _central_hits_kernel(s_mm, inv_d_a, b_u, f_u, z, frame, region):
    """What the central view's chief ray of each lens meets: (sorted plane index or −1, z from H1U or NaN).

    The chief ray leaves the lens centre s towards the exit pupil's centre: slope m = −s/d_A (0 when
    telecentric), U = s + m·b_U (Eq. 16), q = m − U/f_U (Eqs. 17-18).
    """
    rows, cols = s_mm.shape[0], s_mm.shape[1]
    labels = np.empty((rows, cols), dtype=np.int64)
    hit_z = np.empty((rows, cols), dtype=np.float64)
    for row in range(rows):
        for col in range(cols):
            sx = s_mm[row, col, 0]
            sy = s_mm[row, col, 1]
            mx = -sx * inv_d_a
            my = -sy * inv_d_a
            ux = sx + mx * b_u
            uy = sy + my * b_u
            hit, _, _, zp = _nearest_hit(ux, uy, mx - ux / f_u, my - uy / f_u, z, frame, region)
            labels[row, col] = hit
            hit_z[row, col] = zp if hit >= 0 else np.nan
    return labels, hit_z
