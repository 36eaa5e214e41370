"""The odometry frames' EM start compiled with numba: greedy k-means++ seeds and the hard-label moments.

- :func:`kmeans_plusplus_seeds`: the greedy seeding loop, its uniform draws given (so the random stream is the
  caller's, drawn in one call); where two candidates leave potentials equal to rounding, which one wins depends on
  the order of the sums, so it can pick differently from a numpy loop at such a tie (none on 62 fr1/xyz frames);
- :func:`cluster_scatter`: the clusters' weighted second moments about their centres.
"""
from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _squared_distances(points, centre, out):
    """``out[i] = |points[i] - centre|²``."""
    for i in range(points.shape[0]):
        dx, dy, dz = points[i, 0] - centre[0], points[i, 1] - centre[1], points[i, 2] - centre[2]
        out[i] = dx * dx + dy * dy + dz * dz


@numba.njit(cache=True, nogil=True, error_model="numpy")
def kmeans_plusplus_seeds(points, weights, first, uniforms):
    """Greedy weighted k-means++ seeds (Arthur & Vassilvitskii; scikit-learn's ``kmeans_plusplus`` algorithm).

    Parameters
    ----------
    points : ndarray of shape (n_points, 3)
    weights : ndarray of shape (n_points,)
    first : int
        The first seed's row.
    uniforms : ndarray of shape (n_clusters - 1, n_trials)
        Uniform draws in [0, 1): row ``s`` places seed ``s + 1``'s candidates on the cumulative ``w · D²``.

    Returns
    -------
    chosen : ndarray of int64, shape (n_clusters,)
        Every later seed is the candidate (the first, on a tie) that leaves the least potential ``Σ w · D²``.
    """
    n_points, n_seeds, n_trials = points.shape[0], uniforms.shape[0] + 1, uniforms.shape[1]
    chosen = np.empty(n_seeds, dtype=np.int64)
    chosen[0] = first
    closest = np.empty(n_points)
    _squared_distances(points, points[first], closest)
    cumulative = np.empty(n_points)
    reach = np.empty((n_trials, n_points))
    for seed in range(1, n_seeds):
        total = 0.0
        for i in range(n_points):
            total += weights[i] * closest[i]
            cumulative[i] = total
        best, best_potential = 0, np.inf
        for trial in range(n_trials):
            candidate = min(np.searchsorted(cumulative, uniforms[seed - 1, trial] * total), n_points - 1)
            _squared_distances(points, points[candidate], reach[trial])
            for i in range(n_points):
                reach[trial, i] = min(closest[i], reach[trial, i])
            potential = np.dot(reach[trial], weights)  # BLAS: a running sum in a loop would not vectorise
            if potential < best_potential:
                best, best_potential, chosen[seed] = trial, potential, candidate
        closest[:] = reach[best]
    return chosen


@numba.njit(cache=True, nogil=True, error_model="numpy")
def cluster_scatter(points, weights, covariances, centres, labels):
    """Each cluster's weighted sum of ``(x - c)(x - c)ᵀ + C`` over its points (``C`` a point's own covariance),
    shape (n_clusters, 3, 3): the hard-label M-step's covariances before their division by the cluster's weight."""
    scatter = np.zeros((centres.shape[0], 3, 3))
    for i in range(points.shape[0]):
        k, w = labels[i], weights[i]
        dx, dy, dz = points[i, 0] - centres[k, 0], points[i, 1] - centres[k, 1], points[i, 2] - centres[k, 2]
        offset = (dx, dy, dz)
        for a in range(3):
            for b in range(a, 3):
                scatter[k, a, b] += w * (offset[a] * offset[b] + covariances[i, a, b])
    for k in range(centres.shape[0]):
        for a in range(3):
            for b in range(a):
                scatter[k, a, b] = scatter[k, b, a]
    return scatter
