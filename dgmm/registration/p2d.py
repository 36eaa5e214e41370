"""Point-to-distribution (P2D) registration: maximise the mean log-likelihood of moved points under a mixture.

The cost of a pose is ``-1/n Σ_n log Σ_k π_k N(y_n | μ_k, Σ_k)`` (paper eq. 1 summed over points), ``y_n`` the
moved source points. One pass computes every point's log-density under every component as one matrix product,
``quadratic_features(y - origin) @ log_density_table`` (n_points x 10 times 10 x n_components), and the
responsibilities times the ``(n_components, 12)`` moment table give each point's gradient and Gauss-Newton weight
``Σ_k r_nk P_k``; everything that does not depend on the pose is cached on the :class:`FittedMixture`.
"""
from __future__ import annotations

from functools import partial

import numpy as np

from dgmm.registration.checks import as_points
from dgmm.gaussian import SCREEN, quadratic_features, unpack
from dgmm.registration.fitted import EXP_FLOOR, FittedMixture
from dgmm.registration.pose import IDENTITY_PARAMS
from dgmm.registration.rotations import rotation_and_jacobian
from dgmm.registration.solvers import (TRANSLATION_UNIT, check_solver, compiled_gauss_newton, minimise_bfgs,
                                       minimise_gauss_newton, pose_derivatives, rotation_curvature)

P2D_TOL = 1e-6
"""P2D's Gauss-Newton stops once a step would turn by less than this (radians, and RMS radii): a 4,000th of the
bunny trials' mean rotation error (0.24°, 4e-3 rad), where the solver's 1e-8 polished the pose for one more step."""


def gauss_newton_screen(n_components):
    """Gauss-Newton's screen (nats): ``53 ln 2 + ln K``, where all K terms left out of a point's sum (at least 1) add
    under half its last place (``2^-53``) together, the guarantee :data:`~dgmm.gaussian.SCREEN` gives for up to 10⁵
    components; at K=100 it is 41.4 nats, where 50 keeps 15% more pairs (4-7% of a registration's CPU time). BFGS,
    the paper's, keeps :data:`~dgmm.gaussian.SCREEN` and its bits."""
    return 53 * np.log(2.0) + np.log(n_components)


def _likelihood(moved, mixture):
    """Negative mean log-likelihood of ``moved`` (n_points, 3), with what its derivatives need.

    Returns
    -------
    cost : float
    offsets : ndarray of shape (n_points, 3)
        ``moved - mixture.origin``.
    resp : ndarray of shape (n_points, n_components)
        Unnormalised responsibilities (scaled by each point's largest).
    total : ndarray of shape (n_points,)
        Their row sums.
    """
    offsets = moved - mixture.origin
    resp = quadratic_features(offsets) @ mixture.log_density_table
    top = resp.max(axis=1, keepdims=True)
    np.subtract(resp, top, out=resp)
    np.exp(np.maximum(resp, EXP_FLOOR, out=resp), out=resp)
    total = resp.sum(axis=1)
    return -float(np.mean(np.log(total) + top[:, 0])), offsets, resp, total


def _point_derivatives(offsets, resp, total, mixture):
    """Each point's gradient ``ḡ_n = Σ_k r_nk g_nk``, ``g_nk = P_k (y_n - μ_k)``, of ``-log p(y_n)`` (n_points, 3)
    and its Gauss-Newton weight ``Σ_k r_nk P_k`` (n_points, 3, 3), ``r_nk`` the normalised responsibilities."""
    moments = resp @ mixture.moment_table
    moments /= total[:, None]
    weight = moments[:, :9].reshape(-1, 3, 3)
    return np.einsum("nab,nb->na", weight, offsets) - moments[:, 9:], weight


def _point_hessians(offsets, resp, total, mixture, gradient, weight):
    """Exact Hessian of ``-log p(y_n)``: ``Σ_k r_nk P_k - (Σ_k r_nk g_nk g_nkᵀ - ḡ_n ḡ_nᵀ)``, (n_points, 3, 3)."""
    spread = np.einsum("nef,nf->ne", (resp @ mixture.gradient_outer_table).reshape(-1, 6, 10),
                       quadratic_features(offsets)) / total[:, None]
    return weight - unpack(spread) + gradient[:, :, None] * gradient[:, None, :]


def p2d_cost(params, points, centre, mixture, with_grad):
    """P2D cost of the BFGS pose vector, and its gradient.

    Parameters
    ----------
    params : ndarray of shape (7,)
        ``(t', q)``: the points move to ``R(q/|q|) (x - centre) + centre + t'``.
    points : ndarray of shape (n_points, 3)
    centre : ndarray of shape (3,)
    mixture : FittedMixture
    with_grad : bool

    Returns
    -------
    cost : float
    gradient : ndarray of shape (7,), only when ``with_grad``
    """
    rotation, jacobian = rotation_and_jacobian(params[3:])
    local = points - centre
    cost, offsets, resp, total = _likelihood(local @ rotation.T + centre + params[:3], mixture)
    if not with_grad:
        return cost
    grad_moved = _point_derivatives(offsets, resp, total, mixture)[0] / len(points)
    grad_quaternion = np.einsum("ab,jab->j", grad_moved.T @ local, jacobian)
    return cost, np.concatenate([grad_moved.sum(axis=0), grad_quaternion])


def p2d_params_cost(points, centre, mixture, compiled=True):
    """The P2D cost as :func:`~dgmm.registration.solvers.minimise_bfgs` evaluates it.

    Parameters
    ----------
    points : ndarray of shape (n_points, 3)
    centre : ndarray of shape (3,)
    mixture : FittedMixture
    compiled : bool, default=True
        The numba kernels of :mod:`~dgmm.compiled.registration` (the pairs within its screen), or :func:`p2d_cost`
        (every pair; the reference in tests, and the timing checks' numpy P2D).

    Returns
    -------
    cost : callable
        ``cost(params, with_grad)``, :func:`p2d_cost` for these points.
    """
    if not compiled:
        return partial(p2d_cost, points=points, centre=centre, mixture=mixture)
    from dgmm.compiled import registration as kernels  # numba loads only where P2D runs

    local = np.ascontiguousarray(points - centre)
    table = mixture.log_density_table
    buffers = kernels.p2d_pose_buffers(len(local), table.shape[1])  # BFGS takes the gradient before the next pose

    def cost(params, with_grad):
        rotation, jacobian = kernels.quaternion_rotation_and_jacobian(params[3:])
        value = kernels.p2d_negative_mean_log_likelihood(local, rotation, centre + params[:3] - mixture.origin, table,
                                                         SCREEN, False, *buffers)
        if not with_grad:
            return value
        return value, kernels.p2d_params_gradient(mixture.precisions, mixture.precision_means, local, jacobian,
                                                  *buffers[1:])

    return cost


def p2d_pose_cost(points, centre, mixture, compiled=True):
    """The P2D cost as :func:`~dgmm.registration.solvers.minimise_gauss_newton` evaluates it.

    Parameters
    ----------
    points : ndarray of shape (n_points, 3)
    centre : ndarray of shape (3,)
    mixture : FittedMixture
    compiled : bool, default=True
        The numba kernels of :mod:`~dgmm.compiled.registration` (the pairs within its screen), or the numpy
        functions above (every pair; the reference in tests).

    Returns
    -------
    evaluate : callable
        ``evaluate(rotation, translation) -> (cost, derivatives)`` for the pose ``x -> R (x - c) + c + t'``;
        ``derivatives()`` gives the gradient (6,), the Gauss-Newton matrix (6, 6) and the exact Hessian (6, 6)
        over ``(δ, ω)``.
    """
    return (_compiled_pose_cost if compiled else _numpy_pose_cost)(points - centre, centre, mixture)


def _numpy_pose_cost(local, centre, mixture):
    """:func:`p2d_pose_cost` in numpy."""
    n_points = len(local)

    def evaluate(rotation, translation):
        rotated = local @ rotation.T
        cost, offsets, resp, total = _likelihood(rotated + centre + translation, mixture)

        def derivatives():
            gradient, weight = _point_derivatives(offsets, resp, total, mixture)
            hessian = _point_hessians(offsets, resp, total, mixture, gradient, weight)
            gradient /= n_points
            pose_gradient, (gauss_newton, exact) = pose_derivatives(rotated, gradient, weight, hessian)
            gauss_newton /= n_points
            exact /= n_points
            exact[3:, 3:] += rotation_curvature(rotated, gradient)
            return pose_gradient, gauss_newton, exact

        return cost, derivatives

    return evaluate


def _compiled_pose_cost(local, centre, mixture):
    """:func:`p2d_pose_cost` with the numba kernels."""
    from dgmm.compiled import registration as kernels  # numba loads only where Gauss-Newton P2D runs

    table = mixture.log_density_table
    buffers_shape = (len(local), table.shape[1])
    local = np.ascontiguousarray(local)
    screen = gauss_newton_screen(table.shape[1])

    def evaluate(rotation, translation):
        buffers = kernels.p2d_pose_buffers(*buffers_shape)
        cost = kernels.p2d_negative_mean_log_likelihood(local, rotation, centre + translation - mixture.origin,
                                                        table, screen, True, *buffers)
        return cost, partial(kernels.p2d_pose_derivatives, mixture.precisions, mixture.precision_means, *buffers)

    return evaluate


def register_p2d(source, mixture, gradient="analytic", callback=None, options=None, solver="bfgs", compiled=True):
    """Point-to-distribution registration: maximise the mean log-likelihood of the moved source points.

    From the identity, rotating about the source centroid (paper §VI-A).

    Parameters
    ----------
    source : array-like of shape (n_points, 3)
        Points to move into the mixture's frame.
    mixture : fitted Gaussian mixture or FittedMixture
        See :mod:`dgmm.registration.fitted` for the attributes used. Its tables are built at every call (0.15 ms a
        bunny registration, a tenth of Gauss-Newton's); registering many sources to one mixture, pass
        ``FittedMixture.from_fitted("mixture", mixture)`` to build them once.
    gradient : {"analytic", "numeric"}, default="analytic"
        BFGS only: ``"numeric"`` lets BFGS take forward differences, the paper's setup; it usually ends on
        scipy's "precision loss" stop (``converged=False``) near the same optimum.
    callback : callable, optional
        ``callback(iteration, registration)`` after each iteration with the current pose (for logging the
        moving points: ``registration.apply(source)``).
    options : dict, optional
        BFGS: extra options for ``scipy.optimize.minimize(method="BFGS")`` (``gtol``, ``maxiter``, ...);
        Gauss-Newton: ``max_iter``, ``tol`` (:data:`P2D_TOL`), ``damping``, ``max_step``
        (:func:`~dgmm.registration.solvers.minimise_gauss_newton`).
    solver : {"bfgs", "gauss-newton"}, default="bfgs"
        The paper's BFGS over a translation and a quaternion, or damped Gauss-Newton steps on 6 dof with the
        responsibilities refreshed every step (several times faster, same optimum).
    compiled : bool, default=True
        The cost and its derivatives from the numba kernels of :mod:`~dgmm.compiled.registration` (Gauss-Newton: the
        whole solver loop compiled, ``callback`` called once it is over), or from numpy (:func:`p2d_cost`,
        :func:`p2d_pose_cost` ``(compiled=False)``): the same cost to rounding, the same steps.

    Returns
    -------
    Registration
        ``objective`` is the final negative mean log-likelihood.
    """
    check_solver(solver, gradient)
    points = as_points("source", source)
    mix = FittedMixture.from_fitted("mixture", mixture)
    centre = points.mean(axis=0)
    length = TRANSLATION_UNIT * np.sqrt(np.mean(np.sum((points - centre) ** 2, axis=1)))
    if solver == "gauss-newton":
        options = {"tol": P2D_TOL, **(options or {})}
        if compiled:
            return _compiled_gauss_newton(points, centre, mix, length / TRANSLATION_UNIT, callback, options)
        return minimise_gauss_newton("p2d", p2d_pose_cost(points, centre, mix, compiled=False), centre,
                                     length / TRANSLATION_UNIT, np.eye(3), np.zeros(3), callback, options)
    return minimise_bfgs("p2d", p2d_params_cost(points, centre, mix, compiled), centre, length, IDENTITY_PARAMS,
                         gradient, callback, options)


def _compiled_gauss_newton(points, centre, mixture, length, callback, options):
    """:func:`~dgmm.registration.solvers.minimise_gauss_newton` of the P2D cost from the identity, the whole loop
    compiled (:func:`dgmm.compiled.registration.p2d_gauss_newton`, :func:`~dgmm.registration.solvers.compiled_gauss_newton`)."""
    from dgmm.compiled import registration as kernels  # numba loads only where Gauss-Newton P2D runs

    solve = partial(kernels.p2d_gauss_newton, np.ascontiguousarray(points - centre), centre - mixture.origin,
                    mixture.log_density_table, mixture.precisions, mixture.precision_means,
                    gauss_newton_screen(len(mixture.weights)))
    return compiled_gauss_newton("p2d", solve, centre, length, np.eye(3), np.zeros(3), callback, options)


def load_p2d_kernels():
    """Load P2D's kernels from numba's cache (compiling them where there is none) by registering four points once
    with each solver: forks of a process that called this, the job server's registration jobs, run them at once."""
    means = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    mixture = FittedMixture(np.full(2, 0.5), means, np.repeat(np.eye(3)[None], 2, axis=0),
                            np.repeat(np.eye(3)[None], 2, axis=0))
    points = np.array([[0.1, 0.0, 0.0], [0.9, 0.1, 0.0], [0.0, 0.1, 0.1], [1.0, 0.0, 0.1]])
    for solver in ("bfgs", "gauss-newton"):
        register_p2d(points, mixture, solver=solver)
