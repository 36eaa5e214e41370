"""Distribution-to-distribution (D2D) registration of two mixtures, the determinant-free cost (paper §V, VO).

``f = -Σᵢⱼ πᵢ πⱼ exp(-½ yᵢⱼᵀ Sᵢⱼ⁻¹ yᵢⱼ)`` with ``Sᵢⱼ = Σᵢ + R Σⱼ Rᵀ`` and ``yᵢⱼ = μᵢ - (R (μⱼ - c) + c + t')``:
component ``i`` of the fixed mixture, ``j`` of the moving one. Every pair is computed at once: the symmetric
``Sᵢⱼ`` as its 6 distinct entries, each an ``(n_fixed, n_moving)`` array, inverted by its adjugate.
"""
from __future__ import annotations

from functools import partial

import numpy as np

from dgmm.registration.fitted import EXP_FLOOR, FULL_INDEX as _FULL, FittedMixture
from dgmm.registration.pose import params_from_pose
from dgmm.registration.rotations import LEVI_CIVITA, rotation_and_jacobian
from dgmm.registration.solvers import (TRANSLATION_UNIT, check_solver, minimise_bfgs, minimise_gauss_newton,
                                       pose_derivatives, rotation_curvature)

_ROWS, _COLS = np.array([0, 1, 2, 0, 0, 1]), np.array([0, 1, 2, 1, 2, 2])  # the 6 distinct entries of a symmetric 3x3


def _pairs(rotation, translation, fixed, moving, centre):
    """Every pair's terms of the D2D cost at the pose ``(R, t')``.

    Returns
    -------
    cost : float
    rotated : ndarray of shape (n_moving, 3)
        ``R (μⱼ - c)``.
    rotated_covariances : ndarray of shape (n_moving, 3, 3)
        ``R Σⱼ Rᵀ``.
    terms : ndarray of shape (n_fixed, n_moving)
        ``πᵢ πⱼ exp(-½ yᵀ S⁻¹ y)``.
    v : ndarray of shape (3, n_fixed, n_moving)
        ``Sᵢⱼ⁻¹ yᵢⱼ``.
    inverse : ndarray of shape (6, n_fixed, n_moving)
        The distinct entries of ``Sᵢⱼ⁻¹``.
    """
    rotated = (moving.means - centre) @ rotation.T
    y = fixed.means.T[:, :, None] - (rotated + centre + translation).T[:, None, :]
    rotated_covariances = rotation @ moving.covariances @ rotation.T
    a, b, c, d, e, f = (fixed.covariances[:, _ROWS, _COLS].T[:, :, None]
                        + rotated_covariances[:, _ROWS, _COLS].T[:, None, :])
    inverse = np.array([b * c - f * f, a * c - e * e, a * b - d * d, e * f - d * c, d * f - b * e, d * e - a * f])
    inverse /= a * inverse[0] + d * inverse[3] + e * inverse[4]
    (yx, yy, yz), (ixx, iyy, izz, ixy, ixz, iyz) = y, inverse
    v = np.array([ixx * yx + ixy * yy + ixz * yz, ixy * yx + iyy * yy + iyz * yz, ixz * yx + iyz * yy + izz * yz])
    exponent = yx * v[0]
    exponent += yy * v[1]
    exponent += yz * v[2]
    exponent *= -0.5
    terms = np.exp(np.maximum(exponent, EXP_FLOOR, out=exponent), out=exponent)
    terms *= fixed.weights[:, None]
    terms *= moving.weights[None, :]
    return -float(terms.sum()), rotated, rotated_covariances, terms, v, inverse


def _moving_derivatives(terms, v):
    """``d f / d(moved μⱼ) = -Σᵢ terms vᵢⱼ`` (n_moving, 3) and ``Oⱼ = Σᵢ terms vᵢⱼ vᵢⱼᵀ`` (n_moving, 3, 3)."""
    weighted = terms[None] * v
    return -weighted.sum(axis=1).T, np.einsum("aij,bij->jab", weighted, v)


def d2d_cost(params, fixed, moving, centre, with_grad):
    """D2D cost of the BFGS pose vector, and its gradient.

    Parameters
    ----------
    params : ndarray of shape (7,)
        ``(t', q)``.
    fixed, moving : FittedMixture
    centre : ndarray of shape (3,)
    with_grad : bool

    Returns
    -------
    cost : float
    gradient : ndarray of shape (7,), only when ``with_grad``
    """
    rotation, jacobian = rotation_and_jacobian(params[3:])
    cost, _, _, terms, v, _ = _pairs(rotation, params[:3], fixed, moving, centre)
    if not with_grad:
        return cost
    grad_moved, outer = _moving_derivatives(terms, v)
    # Through y: d f / d R = Σⱼ gⱼ (μⱼ - c)ᵀ. Through S: df/dS = -½ terms v vᵀ, and dS/dR gives
    # df/dR = -Σⱼ Oⱼ R Σⱼ.
    grad_rotation = grad_moved.T @ (moving.means - centre) - np.einsum("jab,bc,jcd->ad", outer, rotation,
                                                                         moving.covariances)
    grad_quaternion = np.einsum("ab,jab->j", grad_rotation, jacobian)
    return cost, np.concatenate([grad_moved.sum(axis=0), grad_quaternion])


def d2d_pose_cost(fixed, moving, centre):
    """The D2D cost as :func:`~dgmm.registration.solvers.minimise_gauss_newton` evaluates it.

    The gradient is exact. The Gauss-Newton matrix weighs each moving mean by ``Σᵢ termsᵢⱼ Sᵢⱼ⁻¹`` (the EM
    majoriser of ``-log(-f)``, which has the same minimiser, times ``-f``); the second matrix is the exact Hessian
    in the moving means, ``Σᵢ termsᵢⱼ (Sᵢⱼ⁻¹ - vᵢⱼ vᵢⱼᵀ)`` plus the curvature of the rotation. Both leave out the
    second-order terms of the rotating covariances, so the last steps converge linearly.

    Returns
    -------
    evaluate : callable
        ``evaluate(rotation, translation) -> (cost, derivatives)``; ``derivatives() -> (gradient (6,),
        gauss_newton (6, 6), means_hessian (6, 6))``.
    """

    def evaluate(rotation, translation):
        cost, rotated, rotated_covariances, terms, v, inverse = _pairs(rotation, translation, fixed, moving, centre)

        def derivatives():
            grad_moved, outer = _moving_derivatives(terms, v)
            weight = np.einsum("ij,sij->js", terms, inverse)[:, _FULL]
            gradient, (hessian, means_hessian) = pose_derivatives(rotated, grad_moved, weight, weight - outer)
            means_hessian[3:, 3:] += rotation_curvature(rotated, grad_moved)
            # The covariances turn with ω: dS/dω_a = [e_a]x C - C [e_a]x gives d f / d ω = -Σ ε (C O).
            gradient[3:] -= np.einsum("abc,jbd,jdc->a", LEVI_CIVITA, rotated_covariances, outer)
            return gradient, hessian, means_hessian

        return cost, derivatives

    return evaluate


def register_d2d(fixed, moving, initial_rotation=None, initial_translation=None, gradient="analytic",
                 callback=None, options=None, solver="bfgs"):
    """Distribution-to-distribution registration of two mixtures, determinant-free cost (paper §V, VO).

    Minimises ``-Σᵢⱼ πᵢ πⱼ exp(-½ yᵀ (Σᵢ + R Σⱼ Rᵀ)⁻¹ y)``, ``y = μᵢ - t - R μⱼ``, rotating about the moving
    mixture's weighted centroid.

    Parameters
    ----------
    fixed : fitted Gaussian mixture
        The target (components ``i``).
    moving : fitted Gaussian mixture
        The source (components ``j``), moved by the returned transform.
    initial_rotation : array-like of shape (3, 3), optional
        Initial pose; the identity when omitted.
    initial_translation : array-like of shape (3,), optional
    gradient : {"analytic", "numeric"}, default="analytic"
        BFGS only.
    callback : callable, optional
        ``callback(iteration, registration)`` after each iteration.
    options : dict, optional
        Options of the solver (see :func:`dgmm.registration.register_p2d`).
    solver : {"bfgs", "gauss-newton"}, default="bfgs"

    Returns
    -------
    Registration
        ``objective`` is the final D2D cost.
    """
    check_solver(solver, gradient)
    fixed_mix = FittedMixture.from_fitted("fixed", fixed)
    moving_mix = FittedMixture.from_fitted("moving", moving)
    centre = moving_mix.centroid
    x0 = params_from_pose(np.eye(3) if initial_rotation is None else initial_rotation,
                          np.zeros(3) if initial_translation is None else initial_translation, centre)
    radius = np.sqrt(moving_mix.weights @ np.sum((moving_mix.means - centre) ** 2, axis=1))
    if solver == "gauss-newton":
        rotation = initial_rotation if initial_rotation is not None else np.eye(3)
        return minimise_gauss_newton("d2d", d2d_pose_cost(fixed_mix, moving_mix, centre), centre, radius,
                                     np.asarray(rotation, dtype=np.float64), x0[:3], callback, options)
    cost = partial(d2d_cost, fixed=fixed_mix, moving=moving_mix, centre=centre)
    return minimise_bfgs("d2d", cost, centre, TRANSLATION_UNIT * radius, x0, gradient, callback, options)
