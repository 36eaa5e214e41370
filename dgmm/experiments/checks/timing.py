"""Same-run CPU-time ratios for the paper's speed claims that no sweep table times.

- The area × centroid approximation (eq. 5), "a fast approximation to our proposed method" (Conclusion): EM on a
  mesh's triangles with and without their covariances, and on its centroids as points, interleaved repeats.
- "We used the determinant-free method as it was much faster in our re-implementation" (§VI-D, D2D odometry):
  BFGS with forward differences (the paper's setup) on the D2D cost with and without the determinant factor,
  between a mesh's mixture and a mixture of its vertices moved by a small rigid motion.

Times are CPU seconds of one thread (``time.process_time``); only their ratios within one run mean anything.
"""
import time

import numpy as np
from scipy.optimize import minimize

from dgmm.mixture import GaussianMixture
from dgmm.primitives import Primitives
from dgmm.registration.rotations import euler_to_matrix, quaternion_to_matrix, rotation_distance_deg

EM_INPUTS = {
    "exact": lambda prims: prims,
    "approx": lambda prims: prims.without_covariances(),
    "centroids": lambda prims: Primitives.from_points(prims.means),
}
COLUMNS = ("check", "setting", "repeat", "seconds", "iterations", "detail")


def em_times(prims, *, n_components, max_iter, repeats, seed):
    """CPU seconds of ``repeats`` k-means-started fits of each :data:`EM_INPUTS` form of a mesh, interleaved.

    Returns
    -------
    list of dict
        ``check`` "approximation", ``setting`` the form, ``repeat``, ``seconds``, ``iterations``, ``detail`` "".
    """
    rows = []
    for repeat in range(repeats):
        for name, form in EM_INPUTS.items():
            data = form(prims)
            start = time.process_time()
            fitted = GaussianMixture(n_components, max_iter=max_iter, random_state=seed).fit(data)
            rows.append({"check": "approximation", "setting": name, "repeat": repeat,
                         "seconds": time.process_time() - start, "iterations": fitted.n_iter_, "detail": ""})
    return rows


def d2d_cost(params, fixed, moving, with_determinant):
    """Negative overlap ``Σ_ij λ_i λ_j N(μ_i; R μ_j + t, Σ_i + R Σ_j Rᵀ)`` (with the determinant factor) or its
    determinant-free form (the Gaussian's exponential only), for ``params = (t, q)``."""
    rotation = quaternion_to_matrix(params[3:])
    means = moving.means_ @ rotation.T + params[:3]
    covariances = rotation @ moving.covariances_ @ rotation.T
    sums = fixed.covariances_[:, None] + covariances[None]  # (K_fixed, K_moving, 3, 3)
    offsets = fixed.means_[:, None] - means[None]
    mahalanobis = np.einsum("ijd,ijd->ij", offsets, np.linalg.solve(sums, offsets[..., None])[..., 0])
    terms = np.exp(-0.5 * mahalanobis)
    if with_determinant:
        terms = terms / np.sqrt((2 * np.pi) ** 3 * np.linalg.det(sums))
    return -float(fixed.weights_ @ terms @ moving.weights_)


def d2d_times(fixed, moving, *, motions, seed):
    """Register ``moving`` after each of ``motions`` small rigid motions back to ``fixed``, with and without the
    determinant, interleaved; rotation error of each result in ``detail``.

    Returns
    -------
    list of dict
        ``check`` "d2d determinant", ``setting`` "with determinant" or "determinant-free", ``repeat`` the motion.
    """
    rng = np.random.default_rng(seed)
    scale = np.sqrt(np.trace(np.cov(fixed.means_.T)))
    rows = []
    for repeat in range(motions):
        rotation = euler_to_matrix(rng.uniform(-5.0, 5.0, 3))
        translation = rng.uniform(-0.05, 0.05, 3) * scale
        moved = GaussianMixture.from_parameters(moving.weights_, moving.means_ @ rotation.T + translation,
                                                rotation @ moving.covariances_ @ rotation.T)
        for setting, with_determinant in (("determinant-free", False), ("with determinant", True)):
            x0 = np.array([0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0])
            start = time.process_time()
            result = minimize(d2d_cost, x0, args=(fixed, moved, with_determinant), method="BFGS")
            seconds = time.process_time() - start
            error = rotation_distance_deg(quaternion_to_matrix(result.x[3:]), rotation.T)
            rows.append({"check": "d2d determinant", "setting": setting, "repeat": repeat, "seconds": seconds,
                         "iterations": int(result.nit), "detail": f"rotation error {error:.3g} deg"})
    return rows
