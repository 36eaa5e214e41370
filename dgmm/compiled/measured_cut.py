"""The odometry cut rounds' arithmetic compiled with numba (:mod:`dgmm.odometry.measured_cut`): a frame's mixture
less the M-step moments of the primitives the other frame does not measure, component by component (numpy's
two dozen operations on (K, 3, 3) arrays and a batched eigen-decomposition per cut cost more than the
arithmetic)."""
from __future__ import annotations

import numba
import numpy as np

_FLOOR = 1e-6
"""A covariance's eigenvalues are floored at this fraction of its largest (rounding, or an EM short of its fixed
point, can leave a variance below 0)."""

_PACKED = np.array([[0, 3, 4], [3, 1, 5], [4, 5, 2]])
"""Entry ``(a, b)`` of a 3x3 in the moment table's packed columns: ``xx, yy, zz, xy, xz, yz``."""


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _floored(covariance):
    """``covariance`` with its eigenvalues floored at :data:`_FLOOR` of its largest, in place. The eigen-decomposition
    runs only where the floor may act: a matrix with positive leading minors and ``det ≥ _FLOOR tr³`` has every
    eigenvalue above ``_FLOOR λmax`` (``λmin ≥ det / λmax² ≥ det / tr²`` and ``λmax ≤ tr``), so it is left as it
    is."""
    a, b, c = covariance[0, 0], covariance[1, 1], covariance[2, 2]
    d, e, f = covariance[0, 1], covariance[0, 2], covariance[1, 2]
    minor = a * b - d * d
    determinant = a * (b * c - f * f) - d * (d * c - e * f) + e * (d * f - b * e)
    trace = a + b + c
    if a > 0 and minor > 0 and determinant >= _FLOOR * trace * trace * trace:
        return
    values, vectors = np.linalg.eigh(covariance)
    floor = _FLOOR * max(values[2], 0.0)
    for m in range(3):
        values[m] = max(values[m], floor)
    for r in range(3):
        for s in range(3):
            covariance[r, s] = (vectors[r, 0] * values[0] * vectors[s, 0] + vectors[r, 1] * values[1] * vectors[s, 1]
                                + vectors[r, 2] * values[2] * vectors[s, 2])


@numba.njit(cache=True, nogil=True, error_model="numpy")
def cut_components(means, covariances, mass, sums, centre, unit, min_mass):
    """Each component less the unseen primitives' M-step sums (the formulas of
    :func:`dgmm.odometry.measured_cut.cut`).

    Parameters
    ----------
    means : ndarray of shape (K, 3)
    covariances : ndarray of shape (K, 3, 3)
        The fitted covariances less ``reg_covar``.
    mass : ndarray of shape (K,)
        ``M_k``.
    sums : ndarray of shape (K, 10)
        The unseen primitives' M-step sums about ``centre`` in ``unit`` (:func:`dgmm.compiled.e_step.
        screened_e_step_sums`: ``xx, yy, zz, 2xy, 2xz, 2yz, x, y, z, 1``).
    centre : ndarray of shape (3,)
    unit : float
    min_mass : float
        A component left with at most this fraction of its mass is dropped.

    Returns
    -------
    left : ndarray of shape (K,)
        The mass each component keeps, 0 where it is dropped.
    cut_means, cut_covariances : ndarrays of shape (K, 3), (K, 3, 3)
        A dropped component's unchanged; the covariances without ``reg_covar``.
    """
    n_components = means.shape[0]
    left = np.zeros(n_components)
    cut_means, cut_covariances = means.copy(), covariances.copy()
    about, d, first, shift = np.empty(3), np.empty(3), np.empty(3), np.empty(3)
    second = np.empty((3, 3))
    for k in range(n_components):
        lost = sums[k, 9]
        remaining = mass[k] - lost
        if not remaining > min_mass * mass[k]:
            continue
        left[k] = remaining
        for r in range(3):
            about[r] = sums[k, 6 + r] * unit
            d[r] = means[k, r] - centre[r]
            first[r] = about[r] - lost * d[r]
            shift[r] = -first[r] / remaining
            cut_means[k, r] += shift[r]
        for r in range(3):
            for s in range(3):
                packed = _PACKED[r, s]
                moment = sums[k, packed] * (1.0 if r == s else 0.5) * unit * unit
                # Σ r (x - μ)(x - μ)ᵀ = S - s dᵀ - d sᵀ + m d dᵀ about the mean, from S about the centre
                second[r, s] = moment - about[r] * d[s] - d[r] * about[s] + lost * d[r] * d[s]
        for r in range(3):
            for s in range(3):
                cut_covariances[k, r, s] = ((mass[k] * covariances[k, r, s] - second[r, s]) / remaining
                                            - shift[r] * shift[s])
        _floored(cut_covariances[k])
    return left, cut_means, cut_covariances
