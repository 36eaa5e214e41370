"""The D2D cost and its derivatives compiled with numba, for the Gauss-Newton solver (odometry's inner loop).

The numpy D2D of :mod:`~dgmm.registration.d2d` bounds every pair's term before computing the ones that may
matter, and then works on arrays of a few hundred to a few thousand pairs: at odometry's sizes (K = 100 per frame)
its time goes to numpy's per-call overhead. Here every pair's exact term is computed in one pass (about 50
floating-point operations a pair), and the derivatives run over the pairs within ``e^-NEGLIGIBLE`` of the largest
term, the pairs the numpy derivatives keep. The numpy functions stay the reference
(``d2d_pose_cost(compiled=False)``, tested against these).
"""
from __future__ import annotations

import math

import numba
import numpy as np

from dgmm.registration.d2d import NEGLIGIBLE
from dgmm.registration.fitted import EXP_FLOOR


def kept_pairs(n_fixed, n_moving):
    """Buffers for :func:`negative_overlap` to leave the kept pairs in, for :func:`pose_derivatives` at the same
    pose: ``(count (1,), fixed index, moving index, log terms)``."""
    size = n_fixed * n_moving
    return np.zeros(1, dtype=np.int64), np.empty(size, dtype=np.int64), np.empty(size, dtype=np.int64), np.empty(size)


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _inverse_and_exponent(fixed_covariance, moving_covariance, y, inverse):
    """``S⁻¹`` of ``S = Σᵢ + C`` into ``inverse`` (by its adjugate, as the numpy cost) and ``-½ yᵀ S⁻¹ y``."""
    a, b, c = fixed_covariance[0, 0] + moving_covariance[0, 0], fixed_covariance[1, 1] + moving_covariance[1, 1], \
        fixed_covariance[2, 2] + moving_covariance[2, 2]
    d, e, f = fixed_covariance[0, 1] + moving_covariance[0, 1], fixed_covariance[0, 2] + moving_covariance[0, 2], \
        fixed_covariance[1, 2] + moving_covariance[1, 2]
    axx, ayy, azz = b * c - f * f, a * c - e * e, a * b - d * d
    axy, axz, ayz = e * f - d * c, d * f - b * e, d * e - a * f
    determinant = a * axx + d * axy + e * axz
    inverse[0, 0], inverse[1, 1], inverse[2, 2] = axx / determinant, ayy / determinant, azz / determinant
    inverse[0, 1] = inverse[1, 0] = axy / determinant
    inverse[0, 2] = inverse[2, 0] = axz / determinant
    inverse[1, 2] = inverse[2, 1] = ayz / determinant
    quadratic = 0.0
    for r in range(3):
        quadratic += y[r] * (inverse[r, 0] * y[0] + inverse[r, 1] * y[1] + inverse[r, 2] * y[2])
    return -0.5 * quadratic


@numba.njit(cache=True, nogil=True, error_model="numpy")
def negative_overlap(fixed_means, fixed_covariances, moved, moved_covariances, log_weights, count, fixed_index,
                     moving_index, log_terms):
    """The D2D cost ``-Σᵢⱼ πᵢ πⱼ exp(-½ yᵢⱼᵀ Sᵢⱼ⁻¹ yᵢⱼ)`` over the pairs within ``e^-NEGLIGIBLE`` of the largest
    term, which it leaves in the :func:`kept_pairs` buffers.

    Parameters
    ----------
    fixed_means : ndarray of shape (n_fixed, 3)
    fixed_covariances : ndarray of shape (n_fixed, 3, 3)
    moved : ndarray of shape (n_moving, 3)
        ``R (μⱼ - c) + c + t'``.
    moved_covariances : ndarray of shape (n_moving, 3, 3)
        ``R Σⱼ Rᵀ``.
    log_weights : ndarray of shape (n_fixed, n_moving)
        ``log πᵢ + log πⱼ``.
    count, fixed_index, moving_index, log_terms : ndarray
        The buffers.
    """
    n_fixed, n_moving = fixed_means.shape[0], moved.shape[0]
    exponents = np.empty(n_fixed * n_moving)
    inverse, y = np.empty((3, 3)), np.empty(3)
    top = -np.inf
    for i in range(n_fixed):
        for j in range(n_moving):
            for r in range(3):
                y[r] = fixed_means[i, r] - moved[j, r]
            exponent = max(_inverse_and_exponent(fixed_covariances[i], moved_covariances[j], y, inverse)
                           + log_weights[i, j], EXP_FLOOR)  # floored as the numpy cost's
            exponents[i * n_moving + j] = exponent
            top = max(top, exponent)
    kept = 0
    cost = 0.0
    for pair in range(n_fixed * n_moving):
        if exponents[pair] >= top - NEGLIGIBLE:
            fixed_index[kept], moving_index[kept] = pair // n_moving, pair % n_moving
            log_terms[kept] = exponents[pair]
            cost -= math.exp(exponents[pair])
            kept += 1
    count[0] = kept
    return cost


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _skew(a, out):
    """``[a]x`` into ``out`` (3, 3)."""
    out[0, 0], out[0, 1], out[0, 2] = 0.0, -a[2], a[1]
    out[1, 0], out[1, 1], out[1, 2] = a[2], 0.0, -a[0]
    out[2, 0], out[2, 1], out[2, 2] = -a[1], a[0], 0.0


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _add_transposed_product(weight, x, y, out):
    """``out += weight xᵀ y`` for 3x3 ``x`` and ``y``."""
    for a in range(3):
        for b in range(3):
            out[a, b] += weight * (x[0, a] * y[0, b] + x[1, a] * y[1, b] + x[2, a] * y[2, b])


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _product(x, y, out):
    """``out = x y`` for 3x3 matrices."""
    for a in range(3):
        for b in range(3):
            out[a, b] = x[a, 0] * y[0, b] + x[a, 1] * y[1, b] + x[a, 2] * y[2, b]


@numba.njit(cache=True, nogil=True, error_model="numpy")
def pose_derivatives(fixed_means, fixed_covariances, moved, rotated, moved_covariances, count, fixed_index,
                     moving_index, log_terms):
    """Gradient, Gauss-Newton matrix and exact Hessian of the D2D cost over ``(δ, ω)`` at the pose
    :func:`negative_overlap` left its kept pairs for (``rotated``: ``p = R (μⱼ - c)``); the formulas of
    :func:`dgmm.registration.d2d._derivatives`, pair by pair.

    Returns
    -------
    gradient : ndarray of shape (6,)
    gauss_newton : ndarray of shape (6, 6)
    exact : ndarray of shape (6, 6)
    """
    gradient = np.zeros(6)
    gauss_newton, spread = np.zeros((6, 6)), np.zeros((6, 6))
    second = np.zeros((3, 3))
    mixed, spin, across = np.zeros((3, 3)), np.zeros((3, 3)), np.zeros((3, 3))
    inverse, y, v, cv, arm, grad_log = np.empty((3, 3)), np.empty(3), np.empty(3), np.empty(3), np.empty(3), \
        np.empty(6)
    skew_v, skew_cv, skew_p = np.empty((3, 3)), np.empty((3, 3)), np.empty((3, 3))
    c_skew_v, u, inverse_u, cross = np.empty((3, 3)), np.empty((3, 3)), np.empty((3, 3)), np.empty((3, 3))
    for pair in range(count[0]):
        i, j = fixed_index[pair], moving_index[pair]
        c, p = moved_covariances[j], rotated[j]
        for r in range(3):
            y[r] = fixed_means[i, r] - moved[j, r]
        _inverse_and_exponent(fixed_covariances[i], c, y, inverse)
        term = math.exp(log_terms[pair])
        for r in range(3):
            v[r] = inverse[r, 0] * y[0] + inverse[r, 1] * y[1] + inverse[r, 2] * y[2]
        for r in range(3):
            cv[r] = c[r, 0] * v[0] + c[r, 1] * v[1] + c[r, 2] * v[2]
            arm[r] = p[r] + cv[r]
        for r in range(3):
            grad_log[r] = v[r]
            grad_log[3 + r] = arm[(r + 1) % 3] * v[(r + 2) % 3] - arm[(r + 2) % 3] * v[(r + 1) % 3]  # (p + Cv) x v
        for r in range(6):
            gradient[r] -= term * grad_log[r]
            for s in range(6):
                spread[r, s] += term * grad_log[r] * grad_log[s]
        # Σ term Jᵀ S⁻¹ J with J = [I, -[p]x] (pose_matrices): blocks S⁻¹, -S⁻¹ [p]x and its transpose, -[p]x S⁻¹ [p]x
        _skew(p, skew_p)
        _product(inverse, skew_p, cross)
        for r in range(3):
            for s in range(3):
                gauss_newton[r, s] += term * inverse[r, s]
                gauss_newton[r, 3 + s] -= term * cross[r, s]
                gauss_newton[3 + s, r] -= term * cross[r, s]
                gauss_newton[3 + r, 3 + s] -= term * (skew_p[r, 0] * cross[0, s] + skew_p[r, 1] * cross[1, s]
                                                      + skew_p[r, 2] * cross[2, s])
        _skew(v, skew_v)
        _skew(cv, skew_cv)
        _product(c, skew_v, c_skew_v)
        for r in range(3):
            for s in range(3):
                u[r, s] = c_skew_v[r, s] - skew_cv[r, s]
        _product(inverse, u, inverse_u)
        _add_transposed_product(term, skew_v, c_skew_v, second)
        _add_transposed_product(-term, u, inverse_u, second)
        _add_transposed_product(term, inverse_u, skew_p, mixed)
        for r in range(3):
            for s in range(3):
                spin[r, s] += term * v[r] * arm[s]
                across[r, s] += term * inverse_u[r, s]
    exact = gauss_newton - spread
    trace = spin[0, 0] + spin[1, 1] + spin[2, 2]
    for r in range(3):
        for s in range(3):
            exact[3 + r, 3 + s] -= (second[r, s] + mixed[r, s] + mixed[s, r] + 0.5 * (spin[r, s] + spin[s, r])
                                    - (trace if r == s else 0.0))
            exact[3 + r, s] += across[s, r]  # second[3:, :3] = -(Σ term S⁻¹ U)ᵀ
            exact[s, 3 + r] += across[s, r]
    return gradient, gauss_newton, exact
