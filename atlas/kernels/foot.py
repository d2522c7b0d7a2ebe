"""Foot points on the exact basin boundaries: the nearest-boundary kernels.

The boundaries are copies (2π shifts and point reflections) of one curve, the left branch L
of the saddle (π, 0), integrated by DOP853 with dense output (:mod:`atlas.boundaries.manifold`).
Per query point (independent: ``prange``, so results do not depend on the thread count)
:func:`nearest_boundary` finds the nearest *sample* of any copy by a bucket search over
square cells, ring by ring outward until no farther ring can hold a nearer one (exact),
maps the point into L's frame (an isometry) and finds the foot point on L by Newton's method
on g(τ) = (c(τ) − q)·c'(τ) over the dense output (Gauss–Newton where g' ≤ 0), returning the
smaller of the foot's and the sample's distance (and the straight piece next to the saddle's);
:func:`nearest_sample` is its first step alone, :func:`saddles_near` the saddles of the
samples within a radius (also over the tilted polylines' vertices). Accuracy ≈ 1e-13 near
L. The dense output is DOP853's 7th-order interpolant (Hairer, Nørsett & Wanner, *Solving
ODEs I*, §II.6), scipy's ``Dop853DenseOutput`` polynomial.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

import atlas.kernels.vector_width  # noqa: F401 (before any njit: 512-bit vectors)
from atlas.kernels import cached_njit
from atlas.kernels.dop853 import dense_component, dense_step

#: Newton iterations for a foot point (quadratic convergence from a sample ≤ 0.02 away).
NEWTON = 6


@nb.njit(inline="always")
def _dense(tau, t, t_old, h, y_old, F):
    """(θ, θ̇) of the dense output at τ (:func:`atlas.kernels.dop853.dense_output`'s
    evaluation, at one τ)."""
    step = dense_step(tau, t, h.size - 1)
    x = (tau - t_old[step]) / h[step]
    return dense_component(F, step, 0, x, y_old), dense_component(F, step, 1, x, y_old)


@cached_njit(parallel=True, nogil=True)
def nearest_boundary(px, pv, c_theta, c_speed, c_n, c_branch, c_sample, bucket_start,
                     bucket_items, t0, v0, cell, ncx, ncy, tau_s, theta_s, speed_s, t, t_old,
                     h, y_old, F, omega0, alpha, start_theta, start_speed, out_dist, out_n):
    """Distance from each point (px, pv) [rad, rad s⁻¹] to the nearest boundary copy, and
    that copy's saddle n (module docstring). Copies: sample arrays ``c_*`` (``c_sample``
    indexes L's samples ``tau_s``, ``theta_s``, ``speed_s``), binned in cells of side
    ``cell`` from (t0, v0), ``ncx`` × ``ncy`` cells, CSR-style (``bucket_start`` over
    ncx·ncy + 1, ``bucket_items``). Dense output: ``t`` (step boundaries), ``t_old``, ``h``,
    ``y_old``, ``F`` (steps × 7 × 3, highest order first)."""
    w2 = omega0 * omega0
    a2 = 2.0 * alpha
    last = tau_s.size - 1
    for p in nb.prange(px.size):
        x, v = px[p], pv[p]
        cx = int(math.floor((x - t0) / cell))
        cy = int(math.floor((v - v0) / cell))
        reach = max(max(cx, ncx - 1 - cx), max(cy, ncy - 1 - cy))
        best, j = np.inf, -1
        # the point's offsets from its cell's edges: after ring r every sample not yet seen
        # is at least r·cell + the nearest of them away
        off = max(min(min(x - (t0 + cx * cell), t0 + (cx + 1) * cell - x),
                      min(v - (v0 + cy * cell), v0 + (cy + 1) * cell - v)), 0.0)
        for r in range(reach + 1):
            for gx in range(cx - r, cx + r + 1):
                if gx < 0 or gx >= ncx:
                    continue
                # a column on the ring's edge is scanned whole, the others at its two ends
                step = 1 if (gx == cx - r or gx == cx + r) else max(2 * r, 1)
                for gy in range(cy - r, cy + r + 1, step):
                    if gy < 0 or gy >= ncy:
                        continue
                    b = gx * ncy + gy
                    for q in range(bucket_start[b], bucket_start[b + 1]):
                        i = bucket_items[q]
                        dx, dv = c_theta[i] - x, c_speed[i] - v
                        d2 = dx * dx + dv * dv  # squared: no hypot in the inner loop
                        if d2 < best:
                            best, j = d2, i
            reached = r * cell + off
            if best <= reached * reached:
                break
        if j < 0:
            out_dist[p] = np.inf
            out_n[p] = 0
            continue
        n = c_n[j]
        out_n[p] = n
        if c_branch[j] == 1:  # into L's frame: inverse of the reflection or the shift
            qx, qv = (n + 1) * math.pi - x, -v
        else:
            qx, qv = x - (n - 1) * math.pi, v
        s = c_sample[j]
        lo, hi = tau_s[max(s - 1, 0)], tau_s[min(s + 1, last)]
        tau = tau_s[s]
        for _ in range(NEWTON):
            th, sp = _dense(tau, t, t_old, h, y_old, F)
            f1 = -w2 * math.sin(th) - a2 * sp
            d0, d1 = -sp, -f1  # c' = −f (reversed flow); c'' = J·f
            dd0, dd1 = f1, -w2 * math.cos(th) * sp - a2 * f1
            g = (th - qx) * d0 + (sp - qv) * d1
            slope = d0 * d0 + d1 * d1 + (th - qx) * dd0 + (sp - qv) * dd1
            if not slope > 0.0:
                slope = d0 * d0 + d1 * d1
            new = min(max(tau - g / slope, lo), hi)
            if abs(new - tau) <= 1e-15 * (1.0 + tau):  # converged (quadratically)
                tau = new
                break
            tau = new
        th, sp = _dense(tau, t, t_old, h, y_old, F)
        dist = min(math.hypot(th - qx, sp - qv), math.hypot(theta_s[s] - qx, speed_s[s] - qv))
        if s <= 1:  # the straight piece from the saddle (π, 0) to the first integrated point
            ax, av = start_theta - math.pi, start_speed
            u = ((qx - math.pi) * ax + qv * av) / (ax * ax + av * av)
            u = min(max(u, 0.0), 1.0)
            dist = min(dist, math.hypot(math.pi + u * ax - qx, u * av - qv))
        out_dist[p] = dist


@cached_njit(parallel=True, nogil=True)
def saddles_near(px, pv, radius, c_theta, c_speed, c_n, bucket_start, bucket_items, t0, v0,
                 cell, ncx, ncy, out_lo, out_hi):
    """The lowest and highest saddle n among the samples within ``radius`` [rad-ish] of each
    point (px, pv) — every cell that can hold one is searched (samples binned as for
    :func:`nearest_boundary`); (0, 0) where there is none."""
    reach = int(math.ceil(radius / cell))
    r2 = radius * radius
    for p in nb.prange(px.size):
        x, v = px[p], pv[p]
        cx = int(math.floor((x - t0) / cell))
        cy = int(math.floor((v - v0) / cell))
        lo, hi = 0, 0
        found = False
        for gx in range(max(cx - reach, 0), min(cx + reach, ncx - 1) + 1):
            for gy in range(max(cy - reach, 0), min(cy + reach, ncy - 1) + 1):
                b = gx * ncy + gy
                for q in range(bucket_start[b], bucket_start[b + 1]):
                    i = bucket_items[q]
                    dx, dv = c_theta[i] - x, c_speed[i] - v
                    if dx * dx + dv * dv <= r2:
                        n = c_n[i]
                        if not found:
                            lo, hi, found = n, n, True
                        else:
                            lo, hi = min(lo, n), max(hi, n)
        out_lo[p], out_hi[p] = lo, hi


@cached_njit(parallel=True, nogil=True)
def nearest_sample(px, pv, s_theta, s_speed, out):
    """Index of the nearest of the samples (s_theta, s_speed) to each point (px, pv), by
    exhaustive search (a few thousand points against about a thousand samples)."""
    for p in nb.prange(px.size):
        best, j = np.inf, 0
        for i in range(s_theta.size):
            dx, dv = s_theta[i] - px[p], s_speed[i] - pv[p]
            d2 = dx * dx + dv * dv
            if d2 < best:
                best, j = d2, i
        out[p] = j
