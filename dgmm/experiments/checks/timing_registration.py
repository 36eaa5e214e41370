"""Timing checks of registration: D2D with and without the determinant, and CPD beside P2D.

- ``d2d determinant`` (§VI-D: "We used the determinant-free method as it was much faster in our
  re-implementation"): BFGS with forward differences (the paper's setup) on :func:`d2d_cost` with and without the
  determinant factor, from the identity, between a mesh's mixture and a mixture of its vertices moved by a small
  random rigid motion per repeat;
- ``cpd vs p2d`` (§VI-A: "We adjusted pyCPD to run for 150 iterations to approximately match the run-time of our
  P2D GMM registration"): on each of the first Fig 6 trials, pycpd's rigid CPD (``cpd``, the paper's), dgmm's
  operation-for-operation copy of it that the sweep runs (``cpd dgmm``), P2D as the sweep runs it (``p2d``, numba
  kernels), P2D with BFGS's forward differences on the numpy cost (``p2d numerical``: numpy beside pycpd's numpy)
  and P2D as the authors' ``registration_test.py`` runs it (``p2d authors``: scipy's BFGS with forward differences
  over ``(q, t)`` from the identity, its cost scikit-learn's ``GaussianMixture.score``), all onto the trial's mixture
  and target points.
"""
import time

import numpy as np
from pycpd import RigidRegistration
from scipy.optimize import minimize
from sklearn.mixture import GaussianMixture as SklearnGaussianMixture

from dgmm.experiments.checks.interleaved import interleaved_times
from dgmm.experiments.sweep import job_seed
from dgmm.experiments.trials import bounding_diagonal, make_trials
from dgmm.gaussian import layout
from dgmm.mixture import GaussianMixture
from dgmm.primitives import Primitives
from dgmm.registration import (Registration, euler_to_matrix, kabsch, quaternion_to_matrix, register_cpd,
                               register_p2d, registration_errors, rotation_distance_deg)

_PACKED = layout(3).rows, layout(3).cols  # the 6 distinct entries of a symmetric 3x3: xx yy zz xy xz yz


def d2d_cost(params, fixed, moving, with_determinant):
    """Negative overlap ``Σ_ij λ_i λ_j N(μ_i; R μ_j + t, Σ_i + R Σ_j Rᵀ)`` (with the determinant factor) or its
    determinant-free form (the Gaussian's exponential only), for ``params = (t, q)``.

    Every pair's ``S = Σ_i + R Σ_j Rᵀ`` is inverted by its adjugate over its determinant, which the factor
    ``(2π)^-3/2 det(S)^-1/2`` then reuses: the two forms differ by that factor only.
    """
    rotation = quaternion_to_matrix(params[3:])
    means = moving.means_ @ rotation.T + params[:3]
    covariances = rotation @ moving.covariances_ @ rotation.T
    xx, yy, zz, xy, xz, yz = (fixed.covariances_[:, None, row, col] + covariances[None, :, row, col]
                              for row, col in zip(*_PACKED))  # (K_fixed, K_moving) each
    x, y, z = (fixed.means_[:, None, axis] - means[None, :, axis] for axis in range(3))
    adj_xx, adj_yy, adj_zz = yy * zz - yz * yz, xx * zz - xz * xz, xx * yy - xy * xy
    adj_xy, adj_xz, adj_yz = xz * yz - xy * zz, xy * yz - yy * xz, xy * xz - xx * yz
    determinant = xx * adj_xx + xy * adj_xy + xz * adj_xz
    mahalanobis = (adj_xx * x * x + adj_yy * y * y + adj_zz * z * z
                   + 2 * (adj_xy * x * y + adj_xz * x * z + adj_yz * y * z)) / determinant
    terms = np.exp(-0.5 * mahalanobis)
    if with_determinant:
        terms = terms / np.sqrt((2 * np.pi) ** 3 * determinant)
    return -float(fixed.weights_ @ terms @ moving.weights_)


D2D_SETTINGS = {"determinant-free": False, "with determinant": True}
"""The ``d2d determinant`` check's settings: name -> ``with_determinant``."""


def d2d_determinant_times(mesh, *, repeats, n_components, root_seed):
    """CPU seconds of BFGS (forward differences) on :func:`d2d_cost` with and without the determinant.

    ``fixed`` is a k-means ``n_components`` mixture of the mesh's triangles, ``moving`` one of its vertices; repeat
    ``r`` moves ``moving`` by a rigid motion (Euler angles in ±5°, translation in ±5% of the RMS radius per axis) and
    registers it back from the identity.

    Returns
    -------
    list of dict
        Rows of :data:`dgmm.experiments.checks.interleaved.COLUMNS`, ``iterations`` BFGS's, ``detail`` the rotation
        error.
    """
    vertices, faces = mesh
    seed = job_seed(root_seed, "checks/timing/d2d_determinant", 0)
    fixed = GaussianMixture(n_components, random_state=seed).fit(Primitives.from_mesh(vertices, faces))
    moving = GaussianMixture(n_components, random_state=seed).fit(vertices)
    rng = np.random.default_rng(seed)
    scale = np.sqrt(np.trace(np.cov(fixed.means_.T)))

    def motions():
        for _ in range(repeats):
            rotation = euler_to_matrix(rng.uniform(-5.0, 5.0, 3))
            translation = rng.uniform(-0.05, 0.05, 3) * scale
            yield rotation, GaussianMixture.from_parameters(moving.weights_, moving.means_ @ rotation.T + translation,
                                                            rotation @ moving.covariances_ @ rotation.T)

    settings = {name: (lambda case, flag=flag: minimize(d2d_cost, np.array([0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0]),
                                                        args=(fixed, case[1], flag), method="BFGS"))
                for name, flag in D2D_SETTINGS.items()}

    def describe(case, setting, result):
        error = rotation_distance_deg(quaternion_to_matrix(result.x[3:]), case[0].T)
        return int(result.nit), f"rotation error {error:.3g} deg"
    return interleaved_times("d2d determinant", motions(), settings, describe)


def register_pycpd(source, target, max_iter, tol, w=0.0):
    """pycpd's ``RigidRegistration`` (``Y`` the source, ``X`` the target), its rigid part read as the authors read
    it: the Kabsch fit of the source to its moved copy."""
    cpd = RigidRegistration(X=target, Y=source, max_iterations=max_iter, tolerance=tol, w=w)
    moved, _ = cpd.register()
    return Registration(*kabsch(source, moved), int(cpd.iteration), 0.0, float(cpd.q), bool(cpd.diff <= tol), "cpd")


def sklearn_mixture(gmm):
    """scikit-learn's ``GaussianMixture`` holding ``gmm``'s parameters (full covariances), as the authors' modified
    copy of it scores points."""
    mixture = SklearnGaussianMixture(len(gmm.weights_), covariance_type="full")
    mixture.weights_, mixture.means_, mixture.covariances_ = gmm.weights_, gmm.means_, gmm.covariances_
    mixture.precisions_cholesky_ = gmm.precisions_cholesky_
    return mixture


def register_p2d_authors(source, mixture):
    """P2D as ``registration_test.py``: ``scipy.optimize.minimize(loss, [1, 0, 0, 0, 0, 0, 0], method="BFGS")`` with
    forward differences, ``loss(q, t) = -mixture.score(R(q/|q|) (x - x̄) + x̄ - t)`` (``mixture`` a scikit-learn
    one, :func:`sklearn_mixture`), returned as ``x -> R x + (x̄ - R x̄ - t)``."""
    start = time.perf_counter()
    centre = source.mean(axis=0)
    centred = source - centre

    def loss(x):
        return -mixture.score(centred @ quaternion_to_matrix(x[:4]).T + centre - x[4:])

    result = minimize(loss, np.array([1.0, 0, 0, 0, 0, 0, 0]), method="BFGS")
    rotation = quaternion_to_matrix(result.x[:4])
    return Registration(rotation, centre - rotation @ centre - result.x[4:], int(result.nit),
                        time.perf_counter() - start, float(result.fun), bool(result.success), "p2d")


def cpd_p2d_times(mesh, dense, gmm, *, repeats, root_seed, key, max_angle_deg, max_translation, cpd, gradient):
    """CPU seconds of CPD (pycpd's and dgmm's) and P2D (the sweep's, forward differences and the authors') on the
    first Fig 6 trials.

    Parameters
    ----------
    mesh : tuple of ndarray
        ``(vertices, faces)`` of the registered mesh (its vertex count is the trials' point count).
    dense : ndarray of shape (n_dense, 3)
        The mesh's evaluation set, which the trials draw their points from.
    gmm : GaussianMixture
        The mesh-kmeans mixture the sweep's P2D registers to.
    repeats : int
        The first trials.
    root_seed : int
    key, max_angle_deg, max_translation
        The sweep's trials (:func:`dgmm.experiments.trials.make_trials`; ``key`` the registration experiment's).
    cpd : dict
        The sweep's CPD options (``max_iter``, ``tol``).
    gradient : str
        The sweep's P2D gradient.

    Returns
    -------
    list of dict
        Rows of :data:`dgmm.experiments.checks.interleaved.COLUMNS`, ``iterations`` the method's, ``detail`` the
        rotation and translation errors.
    """
    vertices, _ = mesh
    diagonal = bounding_diagonal(vertices)
    setups = make_trials(dense, len(vertices), range(repeats), root_seed=root_seed, key=key, diagonal=diagonal,
                         max_angle_deg=max_angle_deg, max_translation=max_translation)
    authors = sklearn_mixture(gmm)
    settings = {  # a case: (trial setup, its moved source)
        "cpd": lambda case: register_pycpd(case[1], case[0].target, **cpd),
        "cpd dgmm": lambda case: register_cpd(case[1], case[0].target, **cpd),
        "p2d": lambda case: register_p2d(case[1], gmm, gradient=gradient),
        "p2d numerical": lambda case: register_p2d(case[1], gmm, gradient="numeric", compiled=False),
        "p2d authors": lambda case: register_p2d_authors(case[1], authors),
    }

    def describe(case, setting, result):
        rotation_error, translation_error = registration_errors(result, case[0].trial, diagonal)
        return result.iterations, f"rotation error {rotation_error:.3g} deg, translation error {translation_error:.3g}%"
    return interleaved_times("cpd vs p2d", ((setup, setup.moved) for setup in setups), settings, describe)
