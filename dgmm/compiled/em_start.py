"""The Lloyd passes of the odometry frames' EM start (:func:`dgmm.odometry.em_start.lloyd_start`), compiled with numba.

A pass labels every primitive with its nearest centre. The numpy pass takes one matrix product of the points with a
column of ones against the lifted centres, then its argmin: it writes and reads back every (primitive, centre)
value, about 11 MB a pass for a fr1/xyz frame at K = 100. :func:`nearest_centres` keeps only each primitive's best
so far, and computes every value as BLAS's product does, a chain of fused multiply-adds over the four lifted
coordinates in order (``fma(z, c_z, fma(y, c_y, x c_x)) + |c|²``), so that its labels are the numpy pass's, rounding
ties and all (tests/test_compiled_em_start.py compares them bit for bit).
"""
from __future__ import annotations

import numba
import numpy as np
from numba.core import types
from numba.extending import intrinsic


BLOCK = 256
"""Points labelled together, every centre in turn: their coordinates, best values and labels (10 kB) stay in the
L1 cache across the centres. On an fr1/xyz frame at K = 100 a pass took 0.47 ms so, 2.7 ms over the whole frame
at every centre and 1.2 ms point by point over the centres; numpy's product and argmin 0.85 ms (CPU time, one run)."""


@intrinsic
def _fma(typingctx, a, b, c):
    """``a b + c`` rounded once (LLVM's ``fma``), as BLAS's kernels accumulate their products."""
    def codegen(context, builder, signature, args):
        return builder.fma(*args)
    return types.float64(types.float64, types.float64, types.float64), codegen


@numba.njit(cache=True, nogil=True, error_model="numpy")
def nearest_centres(coordinates, lifted_centres):
    """Each point's nearest centre: the argmin over centres of ``[x, 1] · [-2c, |c|²]`` (``|x - c|² - |x|²``), the
    first centre at a tie, each value rounded as the numpy product ``[x, 1] @ lifted_centres``.

    Parameters
    ----------
    coordinates : ndarray of shape (3, n_points)
        The points' coordinates, one row per axis (the loop over points vectorises).
    lifted_centres : ndarray of shape (4, n_components)
        ``-2c`` in rows 0-2 and ``|c|²`` in row 3, as the numpy pass lays them out.

    Returns
    -------
    labels : ndarray of int64, shape (n_points,)
    """
    n_points = coordinates.shape[1]
    labels = np.zeros(n_points, dtype=np.int64)
    best = np.full(n_points, np.inf)
    for first in range(0, n_points, BLOCK):
        block = slice(first, min(first + BLOCK, n_points))  # views: the loop below vectorises over them
        x, y, z = coordinates[0, block], coordinates[1, block], coordinates[2, block]
        block_best, block_labels = best[block], labels[block]
        for k in range(lifted_centres.shape[1]):
            cx, cy, cz = lifted_centres[0, k], lifted_centres[1, k], lifted_centres[2, k]
            squared = lifted_centres[3, k]
            for j in range(len(x)):
                value = _fma(z[j], cz, _fma(y[j], cy, x[j] * cx)) + squared  # the ones' column: 1 |c|² adds exactly
                closer = value < block_best[j]
                block_best[j] = value if closer else block_best[j]
                block_labels[j] = k if closer else block_labels[j]
    return labels


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _first_at_least(cumulative, value):
    """The first index ``i`` with ``cumulative[i] >= value`` (``np.searchsorted``'s left side; ``len`` if none)."""
    low, high = 0, len(cumulative)
    while low < high:
        middle = (low + high) // 2
        if cumulative[middle] < value:
            low = middle + 1
        else:
            high = middle
    return low


@numba.njit(cache=True, nogil=True, error_model="numpy")
def greedy_seeds(points, norms, weights, closest, uniforms, chosen):
    """The k-means++ seeds after the first (:func:`dgmm.odometry.em_start.kmeans_plusplus`), each the best of its
    candidates by the weighted potential it leaves, computed as that function's numpy loop rounds it.

    Every value is rounded as numpy's was: the running sum in order, each distance ``(|c|² - fma(2c_z, x_z,
    fma(2c_y, x_y, 2c_x x_x))) + |x|²`` as BLAS's product, each potential by BLAS itself (``np.dot``), the first
    candidate at a tie; so the seeds are numpy's (tests/test_compiled_em_start.py compares them).

    Parameters
    ----------
    points : ndarray of shape (n_points, 3)
        Centred on their mean.
    norms : ndarray of shape (n_points,)
        ``|x|²``.
    weights : ndarray of shape (n_points,)
    closest : ndarray of shape (n_points,)
        Each point's ``D²`` to the first seed; updated in place.
    uniforms : ndarray of shape (n_clusters - 1, n_trials)
        The uniform draws of the candidates, a row per seed.
    chosen : ndarray of int64, shape (n_clusters,)
        ``chosen[0]`` the first seed; the others are filled.
    """
    n_points, n_trials = len(points), uniforms.shape[1]
    cumulative = np.empty(n_points)
    reach = np.empty((n_trials, n_points))
    candidates = np.empty(n_trials, dtype=np.int64)
    for seed in range(1, len(chosen)):  # sequential by nature: each seed depends on the ones before
        total = 0.0
        for j in range(n_points):
            total += weights[j] * closest[j]
            cumulative[j] = total
        for trial in range(n_trials):
            candidate = min(_first_at_least(cumulative, uniforms[seed - 1, trial] * total), n_points - 1)
            candidates[trial] = candidate
            cx, cy, cz = 2.0 * points[candidate, 0], 2.0 * points[candidate, 1], 2.0 * points[candidate, 2]
            for j in range(n_points):
                value = (norms[candidate] - _fma(cz, points[j, 2], _fma(cy, points[j, 1], cx * points[j, 0]))
                         + norms[j])
                reach[trial, j] = closest[j] if closest[j] <= value else value  # np.minimum(closest, reach)
        potentials = np.dot(reach, weights)
        best = 0
        for trial in range(1, n_trials):
            if potentials[trial] < potentials[best]:
                best = trial
        chosen[seed] = candidates[best]
        for j in range(n_points):
            closest[j] = reach[best, j] if reach[best, j] >= 0.0 else 0.0  # np.maximum(reach[best], 0)


@numba.njit(cache=True, nogil=True, error_model="numpy")
def cluster_sums(labels, weights, values, n_clusters):
    """Each cluster's weight and weighted sums of ``values``' columns, summed in the points' order as
    ``np.bincount(labels, weights)`` and ``np.bincount(labels, weights * values[:, m])`` are, in one pass.

    Parameters
    ----------
    labels : ndarray of int64, shape (n_points,)
    weights : ndarray of shape (n_points,)
    values : ndarray of shape (n_points, n_values)
    n_clusters : int

    Returns
    -------
    mass : ndarray of shape (n_clusters,)
    sums : ndarray of shape (n_clusters, n_values)
    """
    mass, sums = np.zeros(n_clusters), np.zeros((n_clusters, values.shape[1]))
    for i in range(len(labels)):
        label, weight = labels[i], weights[i]
        mass[label] += weight
        for m in range(values.shape[1]):
            sums[label, m] += weight * values[i, m]
    return mass, sums


@numba.njit(cache=True, nogil=True, error_model="numpy")
def cluster_scatters(labels, weights, points, centres, covariances):
    """Each cluster's weighted second moments about its centre, the 6 distinct entries ``xx, yy, zz, xy, xz, yz`` of
    ``Σ w ((x - c)(x - c)ᵀ + C)``, summed as :func:`cluster_sums` sums the numpy rows ``(x - c)_a (x - c)_b + C_ab``
    (the same values, without the (n_points, 6) table).

    Parameters
    ----------
    labels : ndarray of int64, shape (n_points,)
    weights : ndarray of shape (n_points,)
    points : ndarray of shape (n_points, 3)
    centres : ndarray of shape (n_clusters, 3)
    covariances : ndarray of shape (n_points, 3, 3)
        The points' own covariances ``C``.

    Returns
    -------
    sums : ndarray of shape (n_clusters, 6)
    """
    sums = np.zeros((len(centres), 6))
    for i in range(len(labels)):
        label, weight = labels[i], weights[i]
        x = points[i, 0] - centres[label, 0]
        y = points[i, 1] - centres[label, 1]
        z = points[i, 2] - centres[label, 2]
        sums[label, 0] += weight * (x * x + covariances[i, 0, 0])
        sums[label, 1] += weight * (y * y + covariances[i, 1, 1])
        sums[label, 2] += weight * (z * z + covariances[i, 2, 2])
        sums[label, 3] += weight * (x * y + covariances[i, 0, 1])
        sums[label, 4] += weight * (x * z + covariances[i, 0, 2])
        sums[label, 5] += weight * (y * z + covariances[i, 1, 2])
    return sums
