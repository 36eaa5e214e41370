"""Each odometry frame's EM start under a sampled schedule: k-means++ seeds on a sample of the primitives, Lloyd
iterations on all of them, and the hard-label M-step (paper §VI-D does not state the start; see
:mod:`dgmm.odometry.frame_model`).

Both steps are compiled (:mod:`dgmm.compiled.em_start`): scikit-learn's ``kmeans_plusplus`` spends nearly all
of its time per frame validating its inputs once per seed, and the same greedy algorithm in numpy spent its time
in numpy's per-call overhead. The kernels round every distance and potential as the numpy steps they replaced did
(numpy's BLAS products), so they pick the same seeds and labels, rounding ties and all (measured:
docs/studies/odometry_constants.md).
"""
from __future__ import annotations

import numpy as np

from dgmm.variants import VARIANTS

_FULL = np.array([[0, 3, 4], [3, 1, 5], [4, 5, 2]])  # each entry of a full 3x3 among xx, yy, zz, xy, xz, yz


def kmeans_plusplus(points, weights, n_clusters, rng, n_trials=None):
    """Greedy weighted k-means++ seeds (Arthur & Vassilvitskii; scikit-learn's ``kmeans_plusplus`` algorithm).

    The first seed is drawn with probability ∝ weight; every later one is the best, by the weighted potential
    ``Σ w · D²`` it leaves, of ``n_trials`` candidates drawn with probability ∝ ``w · D²`` (``D``: distance to the
    nearest seed so far).

    Parameters
    ----------
    points : ndarray of shape (n_points, 3)
    weights : ndarray of shape (n_points,)
        Non-negative, with at least ``n_clusters`` positive.
    n_clusters : int
    rng : numpy.random.Generator
    n_trials : int, optional
        Candidates per seed; default ``2 + int(log(n_clusters))``, as scikit-learn.

    Returns
    -------
    indices : list of int
        The seeds' rows of ``points``.
    """
    from dgmm.compiled.em_start import greedy_seeds  # numba loads only for the sampled starts
    n_trials = 2 + int(np.log(n_clusters)) if n_trials is None else n_trials
    points = points - points.mean(axis=0)  # |x - c|² by its expansion below loses less about the centre
    norms = np.einsum("ij,ij->i", points, points)
    chosen = np.empty(n_clusters, dtype=np.int64)
    chosen[0] = rng.choice(len(points), p=weights / weights.sum())
    closest = np.maximum(norms + norms[chosen[0]] - 2.0 * points @ points[chosen[0]], 0.0)
    # every candidate's uniform drawn at once: the generator's stream, seed after seed, as drawn one seed at a time
    greedy_seeds(points, norms, np.ascontiguousarray(weights, dtype=float), closest,
                 rng.random((n_clusters - 1, n_trials)), chosen)
    return chosen.tolist()


def lloyd_start(prims, n_components, seed_sample, lloyd_iter, variant, rng, reg_covar):
    """Weights, means and precisions of the hard-label M-step after k-means++ seeds and Lloyd iterations.

    The seeds are :func:`kmeans_plusplus` on ``seed_sample`` primitives drawn at random, weighted by their M-step
    weights; ``lloyd_iter`` Lloyd iterations then run on every primitive's mean with those weights (a cluster left
    empty keeps its centre). Each component takes its cluster's weight, weighted mean and covariance (the spread of
    the primitives' means plus their own covariances, ``reg_covar`` on the diagonal), as ``GaussianMixture``'s
    k-means start does; an empty cluster gets the median covariance and a weight of ``1e-3 / K``.
    """
    from dgmm.compiled.em_start import cluster_scatters, cluster_sums, nearest_centres  # numba: sampled starts only
    _, weights = VARIANTS[variant](prims.weights)
    points = prims.means
    sample = rng.choice(len(points), size=min(seed_sample, len(points)), replace=False)
    centres = points[sample[kmeans_plusplus(points[sample], weights[sample], n_components, rng)]]
    coordinates = np.ascontiguousarray(points.T)
    for _ in range(lloyd_iter + 1):  # the last pass only labels
        # |x - c|² - |x|² = [x, 1] · [-2c, |c|²], the |x|² every point shares left out of the argmin
        lifted_centres = np.vstack([-2.0 * centres.T, np.sum(centres ** 2, axis=1)])
        labels = nearest_centres(coordinates, lifted_centres)
        mass, sums = cluster_sums(labels, weights, points, n_components)
        present = mass > 0
        centres[present] = sums[present] / mass[present, None]
    covariances = cluster_scatters(labels, weights, points, centres, prims.covariances)[:, _FULL]
    covariances[present] /= mass[present, None, None]
    if not present.all():
        covariances[~present] = np.median(covariances[present], axis=0)
        mass[~present] = 1e-3 * mass.sum() / n_components
    covariances += reg_covar * np.eye(3)
    return mass / mass.sum(), centres, np.linalg.inv(covariances)
