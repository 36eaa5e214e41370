"""The odometry frames' EM start compiled with numba: greedy k-means++ seeds and Lloyd passes.

- :func:`kmeans_plusplus_seeds`: the greedy seeding loop, its uniform draws given (so the random stream is the
  caller's, drawn in one call);
- :func:`lloyd_pass`: every point's nearest centre and the clusters' weighted sums, a block of points at a time;
- :func:`cluster_scatter`: the clusters' weighted second moments about their centres.

Each works on squared distances ``|x - c|²``; where two are equal to rounding, which one wins depends on the order
of the sums, so these kernels and the numpy loops they replace can pick differently at exact ties (a start that
then differs as a different seed's would).
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


BLOCK = 32
"""Points :func:`lloyd_pass` labels together: the loop over a block's points vectorises with each centre's 4
coefficients held in registers (as :data:`dgmm.compiled.e_step.BLOCK`)."""


@numba.njit(cache=True, nogil=True, error_model="numpy")
def lloyd_pass(points, weights, centres, labels):
    """Label every point with its nearest centre (``|x - c|² - |x|² = x · (-2c) + |c|²``, the first on a tie) into
    ``labels``; return each cluster's weight (n_clusters,) and weighted sum of its points (n_clusters, 3)."""
    n_points, n_clusters = points.shape[0], centres.shape[0]
    lifted = np.empty((n_clusters, 4))
    for k in range(n_clusters):
        cx, cy, cz = centres[k, 0], centres[k, 1], centres[k, 2]
        lifted[k, 0], lifted[k, 1], lifted[k, 2] = -2.0 * cx, -2.0 * cy, -2.0 * cz
        lifted[k, 3] = cx * cx + cy * cy + cz * cz
    block = np.zeros((3, BLOCK))  # a last, partial block's unused columns: finite, their labels unread
    values = np.empty((n_clusters, BLOCK))
    nearest = np.empty(BLOCK)
    label = np.empty(BLOCK, dtype=np.int64)
    for first in range(0, n_points, BLOCK):
        size = min(BLOCK, n_points - first)
        for j in range(size):
            for d in range(3):
                block[d, j] = points[first + j, d]
        for k in range(n_clusters):
            a0, a1, a2, a3 = lifted[k, 0], lifted[k, 1], lifted[k, 2], lifted[k, 3]
            for j in range(BLOCK):
                values[k, j] = block[0, j] * a0 + block[1, j] * a1 + block[2, j] * a2 + a3
        nearest[:] = np.inf  # in a loop of its own: taken in the loop above, the running minimum kept it scalar
        for k in range(n_clusters):
            for j in range(BLOCK):
                closer = values[k, j] < nearest[j]
                label[j] = k if closer else label[j]
                nearest[j] = np.minimum(values[k, j], nearest[j])
        for j in range(size):
            labels[first + j] = label[j]
    mass = np.zeros(n_clusters)
    sums = np.zeros((n_clusters, 3))
    for i in range(n_points):
        k, w = labels[i], weights[i]
        mass[k] += w
        for d in range(3):
            sums[k, d] += w * points[i, d]
    return mass, sums


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
