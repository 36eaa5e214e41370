"""The pose solvers: the paper's BFGS on ``(t', q)`` and a damped Gauss-Newton (Levenberg-Marquardt) on 6 dof.

Both minimise a cost of the pose ``x -> R (x - c) + c + t'`` about a fixed centre ``c`` and return a
:class:`~dgmm.registration.pose.Registration`.

- ``"bfgs"`` (the paper's): scipy's BFGS over the 7-vector ``(t', q)``, the quaternion normalised inside the cost,
  with the cost's analytic gradient or BFGS's forward differences.
- ``"gauss-newton"``: each step solves ``(H + λ diag H) (δ, ω) = -g`` for a translation ``δ`` and a left rotation
  ``R -> exp([ω]x) R``, where ``g`` is the cost's exact gradient and ``H`` a positive semi-definite Gauss-Newton
  matrix with the responsibilities of the current pose (EM-ICP, FilterReg). A step is kept only if it lowers the
  cost (else ``λ`` grows tenfold); it stops when a kept step moves less than ``tol`` (radians, and translation
  lengths).
"""
from __future__ import annotations

import time
from functools import partial

import numpy as np
from scipy.optimize import minimize

from dgmm.errors import InputError
from dgmm.registration.pose import Registration, pose_from_params
from dgmm.registration.rotations import exp_rotation, skew

SOLVERS = ("bfgs", "gauss-newton")
"""Names accepted by ``register_p2d(solver=...)`` and ``register_d2d(solver=...)``; BFGS is the paper's."""

# How the pose gradient reaches scipy: analytic (cost and gradient in one call, ``jac=True``) or, as in the
# paper, left to BFGS's forward differences (``jac=None``).
_GRADIENT_MODES = {"analytic": True, "numeric": False}

# BFGS sees translations in units of this many RMS radii of the moving points (or components). It makes the
# optimiser's path independent of the model's length units, and large enough a unit keeps BFGS's first steps mostly
# translational, as optimising the bunny in metres does (RMS radius 0.065 m): the trials' initial error is mostly
# translation, and large early rotation steps end in wrong basins (1 radius: 5 of 20 bunny trials fail).
TRANSLATION_UNIT = 20.0


def minimise_bfgs(method, cost, centre, length, x0, gradient, callback, options):
    """Minimise ``cost(params, with_grad)`` over ``(t', q)`` with BFGS; return a Registration.

    BFGS works on ``(t' / length, q)``: with ``length`` proportional to the spread of the moving points, both parts
    are dimensionless, so the optimiser takes the same path whatever the model's units (metres or millimetres).

    Parameters
    ----------
    method : str
        Name stored in the result.
    cost : callable
        ``cost(params, with_grad) -> value`` or ``(value, gradient (7,))`` when ``with_grad``.
    centre : ndarray of shape (3,)
        Centre of rotation of the parameterisation.
    length : float
        Unit of the translation the optimiser sees.
    x0 : ndarray of shape (7,)
    gradient : {"analytic", "numeric"}
    callback : callable or None
        ``callback(iteration, registration)`` after every BFGS iteration, ``registration`` the current pose.
    options : dict or None
        Passed to ``scipy.optimize.minimize(method="BFGS")``.
    """
    if gradient not in _GRADIENT_MODES:
        raise InputError(f"gradient must be one of {sorted(_GRADIENT_MODES)}, got {gradient!r}")
    analytic = _GRADIENT_MODES[gradient]
    start = time.perf_counter()
    unit = np.array([length if length > 0 else 1.0] * 3 + [1.0] * 4)

    def scaled_cost(x, with_grad):
        if not with_grad:
            return cost(x * unit, with_grad=False)
        value, grad = cost(x * unit, with_grad=True)
        return value, grad * unit

    def snapshot(params, value, iterations, converged):
        rotation, translation = pose_from_params(params * unit, centre)
        return Registration(rotation, translation, iterations, time.perf_counter() - start, float(value),
                            converged, method)

    iteration = 0

    def report(intermediate_result):
        nonlocal iteration
        iteration += 1
        callback(iteration, snapshot(intermediate_result.x, intermediate_result.fun, iteration, False))

    result = minimize(partial(scaled_cost, with_grad=analytic), x0 / unit, method="BFGS", jac=True if analytic else None,
                      callback=None if callback is None else report, options=options)
    return snapshot(result.x, result.fun, int(result.nit), bool(result.success))


_GAUSS_NEWTON_DEFAULTS = {"max_iter": 100, "tol": 1e-10, "damping": 1e-4}


def pose_derivatives(rotated, gradient, weight):
    """Gradient and Gauss-Newton matrix over ``(δ, ω)`` of a cost of moved points ``y_n = exp([ω]x) p_n + c + t' + δ``.

    Parameters
    ----------
    rotated : ndarray of shape (n, 3)
        ``p_n = R (x_n - c)``, the rotated offsets from the centre.
    gradient : ndarray of shape (n, 3)
        ``d cost / d y_n``.
    weight : ndarray of shape (n, 3, 3)
        Symmetric positive semi-definite Gauss-Newton weight of each point, ``W_n``.

    Returns
    -------
    gradient : ndarray of shape (6,)
        ``(Σ g_n, Σ p_n x g_n)``: ``dy/dδ = I`` and ``dy/dω = -[p_n]x``.
    hessian : ndarray of shape (6, 6)
        ``Σ J_nᵀ W_n J_n`` with ``J_n = [I, -[p_n]x]``.
    """
    cross = skew(rotated)
    weighted_cross = weight @ cross
    hessian = np.empty((6, 6))
    hessian[:3, :3] = weight.sum(axis=0)
    hessian[:3, 3:] = -weighted_cross.sum(axis=0)
    hessian[3:, :3] = hessian[:3, 3:].T
    hessian[3:, 3:] = -np.einsum("nab,nbc->ac", cross, weighted_cross)
    return np.concatenate([gradient.sum(axis=0), np.cross(rotated, gradient).sum(axis=0)]), hessian


def minimise_gauss_newton(method, evaluate, centre, length, rotation, translation, callback, options):
    """Minimise a pose cost with damped Gauss-Newton steps; return a Registration.

    Parameters
    ----------
    method : str
        Name stored in the result.
    evaluate : callable
        ``evaluate(rotation, translation) -> (cost, derivatives)`` for the pose ``x -> R (x - c) + c + t'``;
        ``derivatives() -> (gradient (6,), hessian (6, 6))`` over ``(δ, ω)``, called only for kept poses.
    centre : ndarray of shape (3,)
    length : float
        Scale of the moving points: the translation part of the stopping test is ``|δ| / length``.
    rotation : ndarray of shape (3, 3)
    translation : ndarray of shape (3,)
        Initial ``(R, t')``.
    callback : callable or None
        ``callback(iteration, registration)`` after every kept step.
    options : dict or None
        ``max_iter`` (100), ``tol`` (1e-10), ``damping`` (initial λ, 1e-4).

    Returns
    -------
    Registration
    """
    settings = {**_GAUSS_NEWTON_DEFAULTS, **(options or {})}
    unknown = set(settings) - set(_GAUSS_NEWTON_DEFAULTS)
    if unknown:
        raise InputError(f"unknown gauss-newton options {sorted(unknown)}: use {sorted(_GAUSS_NEWTON_DEFAULTS)}")
    max_iter, tol, damping = int(settings["max_iter"]), float(settings["tol"]), float(settings["damping"])
    start = time.perf_counter()
    scale = np.array([length if length > 0 else 1.0] * 3 + [1.0] * 3)

    def snapshot(value, iterations, converged):
        return Registration(rotation, translation + centre - rotation @ centre, iterations,
                            time.perf_counter() - start, float(value), converged, method)

    cost, derivatives = evaluate(rotation, translation)
    converged = False
    iteration = 0
    while iteration < max_iter and not converged:
        gradient, hessian = derivatives()
        while True:
            damped = hessian + damping * np.diag(np.diag(hessian))
            try:
                step = -np.linalg.solve(damped, gradient)
            except np.linalg.LinAlgError:
                step = np.zeros(6)
            new_rotation, new_translation = exp_rotation(step[3:]) @ rotation, translation + step[:3]
            new_cost, new_derivatives = evaluate(new_rotation, new_translation)
            small = np.max(np.abs(step) / scale) < tol
            if new_cost <= cost or small or damping > 1e12:
                break
            damping *= 10.0
        if new_cost <= cost:
            rotation, translation, cost, derivatives = new_rotation, new_translation, new_cost, new_derivatives
            damping = max(damping / 10.0, 1e-12)
        converged = small
        if not converged and damping > 1e12:
            break
        iteration += 1
        if callback is not None:
            callback(iteration, snapshot(cost, iteration, False))
    return snapshot(cost, iteration, converged)


def check_solver(solver, gradient):
    """Raise an InputError unless ``solver`` is known and ``gradient`` applies to it."""
    if solver not in SOLVERS:
        raise InputError(f"solver must be one of {SOLVERS}, got {solver!r}")
    if gradient not in _GRADIENT_MODES:
        raise InputError(f"gradient must be one of {sorted(_GRADIENT_MODES)}, got {gradient!r}")
    if solver != "bfgs" and gradient != "analytic":
        raise InputError(f"gradient={gradient!r} applies to solver='bfgs' only; {solver!r} uses the analytic one")
