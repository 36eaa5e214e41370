"""The P2D cost and its derivatives compiled with numba, over the point-component pairs that can matter.

The Gauss-Newton solver's P2D (:func:`dgmm.registration.p2d.p2d_pose_cost`) spends its time in the likelihood of
every trial pose: ``n_points x n_components`` exponentials. A point's responsibility ``e^{l_nk - max_k l_nk}``
under a component more than :data:`SCREEN` nats below its best adds less than half a unit in the last place to
the point's sum (which is at least 1), so these kernels compute every log-density (10 multiply-adds) but the
exponential and the moments only of the pairs within :data:`SCREEN`. The numpy functions of
:mod:`~dgmm.registration.p2d` stay the reference (``p2d_pose_cost(compiled=False)``, tested against these).
"""
from __future__ import annotations

import math

import numba
import numpy as np

SCREEN = 50.0
"""Pairs with ``l_nk < max_k l_nk - SCREEN`` are left out: ``e^-50 ~ 2e-22``, so even 10⁵ of them add under
``2e-17`` to a sum of at least 1, below half its last place (``1.1e-16``)."""


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _log_densities(offset, table, out):
    """``quadratic_features(offset) @ table`` for one offset (3,) into ``out`` (n_components,); returns its max."""
    x, y, z = offset[0], offset[1], offset[2]
    xx, yy, zz, xy, xz, yz = x * x, y * y, z * z, x * y, x * z, y * z
    for k in range(out.shape[0]):  # one expression per component: the loop vectorises
        out[k] = (xx * table[0, k] + yy * table[1, k] + zz * table[2, k] + xy * table[3, k] + xz * table[4, k]
                  + yz * table[5, k] + x * table[6, k] + y * table[7, k] + z * table[8, k] + table[9, k])
    top = -np.inf
    for k in range(out.shape[0]):
        top = max(top, out[k])
    return top


def screened_pairs(n_points, n_components):
    """Buffers for :func:`negative_mean_log_likelihood` to leave its screened pairs in, for
    :func:`pose_derivatives` at the same pose: ``(starts (n_points + 1,), components, terms, sums (n_points,))``."""
    size = n_points * n_components
    return (np.empty(n_points + 1, dtype=np.int64), np.empty(size, dtype=np.int64), np.empty(size),
            np.empty(n_points))


@numba.njit(cache=True, nogil=True, error_model="numpy")
def negative_mean_log_likelihood(offsets, table, starts, components, terms, sums):
    """``-1/n Σ_n log Σ_k π_k N(y_n | μ_k, Σ_k)`` from the offsets ``y_n - origin`` (n_points, 3) and
    :attr:`~dgmm.registration.fitted.FittedMixture.log_density_table` (10, n_components).

    Leaves the pairs within :data:`SCREEN` in the :func:`screened_pairs` buffers: point ``n``'s are
    ``components[starts[n]:starts[n + 1]]``, with ``e^{l_nk - max_k l_nk}`` in ``terms`` and their sum in
    ``sums[n]``.
    """
    log_density = np.empty(table.shape[1])
    total = 0.0
    count = 0
    for n in range(offsets.shape[0]):
        top = _log_densities(offsets[n], table, log_density)
        starts[n] = count
        threshold = top - SCREEN
        for k in range(log_density.shape[0]):  # branch-free: every index is written, the kept ones advance
            components[count] = k
            count += log_density[k] > threshold
        sum_ = 0.0
        for i in range(starts[n], count):
            terms[i] = math.exp(log_density[components[i]] - top)
            sum_ += terms[i]
        sums[n] = sum_
        total += math.log(sum_) + top
    starts[offsets.shape[0]] = count
    return -total / offsets.shape[0]


@numba.njit(cache=True, nogil=True, error_model="numpy")
def pose_derivatives(offsets, rotated, precisions, precision_means, starts, components, terms, sums):
    """Gradient, Gauss-Newton matrix and exact Hessian over ``(δ, ω)`` of the cost at the pose of ``offsets``
    (what :func:`~dgmm.registration.p2d.p2d_pose_cost`'s ``derivatives()`` returns), from the screened pairs
    :func:`negative_mean_log_likelihood` left at that pose.

    Parameters
    ----------
    offsets : ndarray of shape (n_points, 3)
        ``y_n - origin``.
    rotated : ndarray of shape (n_points, 3)
        ``p_n = R (x_n - c)``: ``dy_n = δ - [p_n]x ω``.
    precisions : ndarray of shape (n_components, 3, 3)
        ``P_k``.
    precision_means : ndarray of shape (n_components, 3)
        ``P_k (μ_k - origin)``.
    starts, components, terms, sums : ndarray
        The screened pairs (:func:`screened_pairs`).

    Returns
    -------
    gradient : ndarray of shape (6,)
    gauss_newton : ndarray of shape (6, 6)
        ``1/n Σ_n J_nᵀ W_n J_n``, ``W_n = Σ_k r_nk P_k`` and ``J_n = [I, -[p_n]x]``.
    exact : ndarray of shape (6, 6)
        The same with the exact Hessian of ``-log p(y_n)``, ``W_n - (Σ_k r_nk g_nk g_nkᵀ - ḡ_n ḡ_nᵀ)``, plus the
        rotation's second-order term ``Σ_n sym(ḡ_n p_nᵀ) - (ḡ_n·p_n) I`` (``g_nk = P_k (y_n - μ_k)``).
    """
    n_points = offsets.shape[0]
    gradient = np.zeros(6)
    gauss_newton = np.zeros((6, 6))
    exact = np.zeros((6, 6))
    outer = np.zeros((3, 3))
    weight, spread, hessian = np.empty((3, 3)), np.empty((3, 3)), np.empty((3, 3))
    g, mean_g = np.empty(3), np.empty(3)
    skew = np.zeros((3, 3))
    for n in range(n_points):
        d = offsets[n]
        weight[:] = 0.0
        spread[:] = 0.0
        mean_g[:] = 0.0
        for i in range(starts[n], starts[n + 1]):
            k, r = components[i], terms[i] / sums[n]
            for a in range(3):
                g[a] = (precisions[k, a, 0] * d[0] + precisions[k, a, 1] * d[1] + precisions[k, a, 2] * d[2]
                        - precision_means[k, a])
                mean_g[a] += r * g[a]
            for a in range(3):
                for b in range(3):
                    weight[a, b] += r * precisions[k, a, b]
                    spread[a, b] += r * g[a] * g[b]
        for a in range(3):
            for b in range(3):
                hessian[a, b] = weight[a, b] - spread[a, b] + mean_g[a] * mean_g[b]
                outer[a, b] += mean_g[a] * rotated[n, b]
        _add_pose_terms(rotated[n], mean_g, weight, hessian, skew, gradient, gauss_newton, exact)
    gradient /= n_points
    gauss_newton /= n_points
    exact /= n_points
    outer /= n_points
    trace = outer[0, 0] + outer[1, 1] + outer[2, 2]
    for a in range(3):
        for b in range(3):
            exact[3 + a, 3 + b] += 0.5 * (outer[a, b] + outer[b, a]) - (trace if a == b else 0.0)
    return gradient, gauss_newton, exact


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _add_pose_terms(p, g, weight, hessian, skew, gradient, gauss_newton, exact):
    """Add one point's ``J_nᵀ ḡ_n``, ``J_nᵀ W_n J_n`` and ``J_nᵀ H_n J_n``, ``J_n = [I, -[p]x]``, to the sums
    (the (δ, ω) and (ω, δ) blocks: ``-W [p]x`` and its transpose; the (ω, ω) block: ``[p]xᵀ W [p]x``)."""
    skew[0, 1], skew[0, 2], skew[1, 2] = -p[2], p[1], -p[0]
    skew[1, 0], skew[2, 0], skew[2, 1] = p[2], -p[1], p[0]
    for a in range(3):
        gradient[a] += g[a]
        gradient[3 + a] += p[(a + 1) % 3] * g[(a + 2) % 3] - p[(a + 2) % 3] * g[(a + 1) % 3]  # p x g
    for matrix, out in ((weight, gauss_newton), (hessian, exact)):
        for a in range(3):
            for b in range(3):
                out[a, b] += matrix[a, b]
                cross = matrix[a, 0] * skew[0, b] + matrix[a, 1] * skew[1, b] + matrix[a, 2] * skew[2, b]
                out[a, 3 + b] -= cross
                out[3 + b, a] -= cross
        for a in range(3):
            for b in range(3):
                total = 0.0
                for c in range(3):
                    total += skew[c, a] * (matrix[c, 0] * skew[0, b] + matrix[c, 1] * skew[1, b]
                                           + matrix[c, 2] * skew[2, b])
                out[3 + a, 3 + b] += total
