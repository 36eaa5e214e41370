"""The pose solvers: the paper's BFGS on ``(t', q)`` and a damped Gauss-Newton (Levenberg-Marquardt) on 6 dof.

Both minimise a cost of the pose ``x -> R (x - c) + c + t'`` about a fixed centre ``c`` and return a
:class:`~dgmm.registration.pose.Registration`.

- ``"bfgs"`` (the paper's): scipy's BFGS over the 7-vector ``(t', q)``, the quaternion normalised inside the cost,
  with the cost's analytic gradient or BFGS's forward differences.
- ``"gauss-newton"``: each step solves ``(H + λ diag H) (δ, ω) = -g`` for a translation ``δ`` and a left rotation
  ``R -> exp([ω]x) R``, where ``g`` is the cost's exact gradient and ``H`` its Hessian where that is positive
  definite (Newton steps near the optimum), else a positive semi-definite Gauss-Newton matrix with the
  responsibilities of the current pose (EM-ICP, FilterReg). A Gauss-Newton step, which far from the optimum falls
  short like an EM step (8-16 times on the bunny's P2D), is over-relaxed: taken ``η`` times, ``η`` carried from
  step to step and set by the cost's parabola along the last one. A step is kept if it lowers the cost, else
  shortened by the parabola up to 3 times (then ``λ`` grows tenfold); no step exceeds ``max_step``. It stops when a
  step moves less than ``tol`` (radians, and RMS radii of the moving points).
"""
from __future__ import annotations

import time
from functools import partial

import numpy as np
from scipy.optimize import minimize

from dgmm.errors import FitError, InputError
from dgmm.registration.pose import Registration, pose_from_params
from dgmm.registration.rotations import LEVI_CIVITA, exp_rotation

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

    evaluations = 0

    def scaled_cost(x, with_grad):
        nonlocal evaluations
        evaluations += 1
        failure = FitError(f"{method} registration: the cost or its gradient stopped being finite (BFGS, cost "
                           f"evaluation {evaluations}): check that source and target are in the same units and "
                           f"overlap")
        if not np.all(np.isfinite(x)):  # only a non-finite cost or gradient leads BFGS here
            raise failure
        try:
            value, grad = cost(x * unit, with_grad=True) if with_grad else (cost(x * unit, with_grad=False), 0.0)
        except InputError:  # the inputs were checked: it is BFGS's iterate that degenerated (a zero quaternion)
            raise failure from None
        if not (np.isfinite(value) and np.all(np.isfinite(grad))):
            raise failure
        return (value, grad * unit) if with_grad else value

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


_GAUSS_NEWTON_DEFAULTS = {"max_iter": 100, "tol": 1e-8, "damping": 1e-4, "max_step": 0.3}
_MIN_DAMPING, _MAX_DAMPING = 1e-12, 1e12
_BACKTRACKS = 3
OVER_RELAXATION = 8.0
"""The first Gauss-Newton step's multiplier ``η``. On the 20 bunny trials of benchmarks/registration_peers.py (P2D,
mesh-kmeans), the cost along a first Gauss-Newton step falls until 8-16 times the step; starting ``η`` at 4, 8 and 16
took 9.6, 9.3 and 9.5 cost evaluations a registration (8.35, 7.85 and 8.1 iterations)."""
_NEWTON_CONTRACTION = 100.0
"""Near the optimum Newton's steps shrink quadratically, ``|s_{k+1}| ≈ κ |s_k|²`` (scaled as the stopping test):
fr1/xyz's odometry registrations (250 frames, 1,241 pairs of a full Newton step and the step after it) have κ a median
4.6, 90th percentile 48 and 99th 175. After a full Newton step with ``κ |s|² < tol`` for this κ the next step would
be below ``tol``, and Gauss-Newton stops without the derivatives at the new pose (of the 514 such steps there, one
was followed by a step above ``tol = 1e-4``: 1.4e-4)."""
GAUSS_NEWTON_CONSTANTS = (OVER_RELAXATION, _NEWTON_CONTRACTION, _MIN_DAMPING, _MAX_DAMPING, _BACKTRACKS)
"""The constants of :func:`minimise_gauss_newton`, as the compiled loops take them (:func:`compiled_gauss_newton`)."""


def pose_derivatives(rotated, gradient, *weights):
    """Gradient and Gauss-Newton matrices over ``(δ, ω)`` of a cost of moved points ``y_n = exp([ω]x) p_n + c + t' + δ``.

    Parameters
    ----------
    rotated : ndarray of shape (n, 3)
        ``p_n = R (x_n - c)``, the rotated offsets from the centre.
    gradient : ndarray of shape (n, 3)
        ``d cost / d y_n``.
    *weights : ndarray of shape (n, 3, 3)
        Symmetric weights ``W_n`` of each point (a Gauss-Newton weight, or the Hessian in ``y_n``).

    Returns
    -------
    gradient : ndarray of shape (6,)
        ``(Σ g_n, Σ p_n x g_n)``: ``dy/dδ = I`` and ``dy/dω = -[p_n]x``.
    matrices : list of ndarray of shape (6, 6)
        :func:`pose_matrices` of the weights.
    """
    moments = rotated.T @ gradient  # Σ p_n g_nᵀ; Σ p_n x g_n is its antisymmetric part
    torque = [moments[1, 2] - moments[2, 1], moments[2, 0] - moments[0, 2], moments[0, 1] - moments[1, 0]]
    return np.concatenate([gradient.sum(axis=0), torque]), pose_matrices(rotated, *weights)


def pose_matrices(rotated, *weights):
    """``Σ J_nᵀ W_n J_n`` over ``(δ, ω)`` with ``J_n = [I, -[p_n]x]`` (``dy_n`` of
    ``y_n = exp([ω]x) p_n + ... + δ``) for each stack of symmetric weights ``W_n`` (n, 3, 3), from one product of
    the weights with ``(1, p_n, p_n p_nᵀ)``; ``rotated`` is ``p_n`` (n, 3). Returns a list of (6, 6) arrays."""
    basis = np.column_stack([np.ones(len(rotated)), rotated, (rotated[:, :, None] * rotated[:, None, :]).reshape(-1, 9)])
    sums = (np.concatenate([w.reshape(-1, 9) for w in weights], axis=1).T @ basis).reshape(len(weights), 3, 3, 13)
    matrices = []
    for m in sums:
        # ([p]x)_cb = ε_cdb p_d: Σ W [p]x = ε_cdb Σ W_ac p_d, Σ [p]x W [p]x = ε_aec ε_dfb Σ W_cd p_e p_f.
        cross = np.einsum("cdb,acd->ab", LEVI_CIVITA, m[:, :, 1:4])
        hessian = np.empty((6, 6))
        hessian[:3, :3] = m[:, :, 0]
        hessian[:3, 3:] = -cross
        hessian[3:, :3] = -cross.T
        hessian[3:, 3:] = -np.einsum("aec,dfb,cdef->ab", LEVI_CIVITA, LEVI_CIVITA, m[:, :, 4:].reshape(3, 3, 3, 3))
        matrices.append(hessian)
    return matrices


def rotation_curvature(rotated, gradient):
    """Second-order part of the ``ω`` Hessian of a cost of points ``y_n = exp([ω]x) p_n + ...`` at ``ω = 0``.

    ``exp([ω]x) p ≈ p + ω x p + ½ ω x (ω x p)`` and ``gᵀ (ω x (ω x p)) = ωᵀ (g pᵀ - (g·p) I) ω``, so the
    term is ``Σ_n sym(g_n p_nᵀ) - (g_n·p_n) I``, shape (3, 3).
    """
    outer = gradient.T @ rotated
    return 0.5 * (outer + outer.T) - np.trace(outer) * np.eye(3)


def minimise_gauss_newton(method, evaluate, centre, length, rotation, translation, callback, options):
    """Minimise a pose cost with damped Gauss-Newton steps; return a Registration.

    Parameters
    ----------
    method : str
        Name stored in the result.
    evaluate : callable
        ``evaluate(rotation, translation) -> (cost, derivatives)`` for the pose ``x -> R (x - c) + c + t'``;
        ``derivatives() -> (gradient (6,), gauss_newton (6, 6), exact (6, 6) or None)`` over ``(δ, ω)``,
        called only for kept poses. The exact Hessian is used where it is positive definite (Newton steps,
        quadratic convergence near the optimum), the Gauss-Newton matrix elsewhere.
    centre : ndarray of shape (3,)
    length : float
        Scale of the moving points: the translation part of the stopping test is ``|δ| / length``.
    rotation : ndarray of shape (3, 3)
    translation : ndarray of shape (3,)
        Initial ``(R, t')``.
    callback : callable or None
        ``callback(iteration, registration)`` after every kept step.
    options : dict or None
        ``max_iter`` (100), ``tol`` (1e-8: converged once the next step would turn by less, in radians, and move
        by less, in ``length`` units: a step computed below it, or a full Newton step ``s`` with
        ``κ |s|² < tol``, :data:`_NEWTON_CONTRACTION`), ``damping`` (initial λ, 1e-4), ``max_step`` (0.3: no step
        turns by more radians or moves by more RMS radii; longer Newton steps from far away jump to other basins).

    Returns
    -------
    Registration
    """
    max_iter, tol, damping, max_step = gauss_newton_settings(options)
    start = time.perf_counter()
    scale = step_scale(length)

    def snapshot(value, iterations, converged):
        return Registration(rotation, translation + centre - rotation @ centre, iterations,
                            time.perf_counter() - start, float(value), converged, method)

    cost, derivatives = evaluate(rotation, translation)
    converged = False
    iteration = 0
    over_relaxation = OVER_RELAXATION
    while iteration < max_iter and not converged:
        gradient, hessian, exact = derivatives()
        if not (np.isfinite(cost) and np.all(np.isfinite(gradient)) and np.all(np.isfinite(hessian))):
            raise not_finite(method, iteration)
        newton = exact is not None and _positive_definite(exact)
        if newton:
            hessian = exact
        iteration += 1
        found = None
        while True:
            step = _capped(_damped_step(hessian, gradient, damping), scale, max_step)
            converged = np.max(np.abs(step) / scale) < tol
            if converged:  # the pose moves by less than tol: no need to evaluate it
                break
            found = _line_search(evaluate, rotation, translation, cost, gradient @ step, step, scale, max_step,
                                 1.0 if newton else over_relaxation)
            if found is not None or damping > _MAX_DAMPING:
                break
            damping *= 10.0
        if found is not None:
            rotation, translation, new_cost, derivatives, length, full = found
            if not newton:
                over_relaxation = next_over_relaxation(cost, gradient @ step, length, new_cost)
            cost = new_cost
            damping = max(damping / 10.0, _MIN_DAMPING)
            converged = newton and full and _NEWTON_CONTRACTION * np.max(np.abs(step) / scale) ** 2 < tol
        elif not converged:
            break
        if callback is not None:
            callback(iteration, snapshot(cost, iteration, False))
    return snapshot(cost, iteration, converged)


def compiled_gauss_newton(method, solve, centre, length, rotation, translation, callback, options):
    """:func:`minimise_gauss_newton` with its whole loop compiled (:func:`dgmm.compiled.registration.p2d_gauss_newton`,
    :func:`~dgmm.compiled.registration.d2d_gauss_newton`: between the kernel calls of a registration the solver's
    Python took a third of the time); ``callback`` sees each kept step's pose once the solve is over.

    Parameters
    ----------
    method : str
    solve : callable
        ``solve(scale, max_iter, tol, damping, max_step, constants, rotations, translations, costs) -> (iterations,
        converged, status)``: a compiled loop with its cost's arrays bound, from the pose in row 0.
    centre, length, rotation, translation, callback, options
        As :func:`minimise_gauss_newton` takes them.

    Returns
    -------
    Registration
    """
    from dgmm.compiled.registration import NOT_FINITE, SEARCH_FAILED  # numba loads only where the loops run

    max_iter, tol, damping, max_step = gauss_newton_settings(options)
    start = time.perf_counter()
    rotations, translations, costs = np.empty((max_iter + 1, 3, 3)), np.empty((max_iter + 1, 3)), np.empty(max_iter + 1)
    rotations[0], translations[0] = rotation, translation
    iterations, converged, status = solve(step_scale(length), max_iter, tol, damping, max_step, GAUSS_NEWTON_CONSTANTS,
                                          rotations, translations, costs)
    if status == NOT_FINITE:
        raise not_finite(method, iterations)
    seconds = time.perf_counter() - start

    def snapshot(row, iteration, done):
        return Registration(rotations[row], translations[row] + centre - rotations[row] @ centre, iteration, seconds,
                            float(costs[row]), done, method)

    last = iterations - 1 if status == SEARCH_FAILED else iterations
    for row in range(1, last + 1) if callback is not None else ():
        callback(row, snapshot(row, row, False))
    return snapshot(last, iterations, converged)


def gauss_newton_settings(options):
    """``(max_iter, tol, damping, max_step)`` of :func:`minimise_gauss_newton`'s ``options`` over its defaults."""
    settings = {**_GAUSS_NEWTON_DEFAULTS, **(options or {})}
    unknown = set(settings) - set(_GAUSS_NEWTON_DEFAULTS)
    if unknown:
        raise InputError(f"unknown gauss-newton options {sorted(unknown)}: use {sorted(_GAUSS_NEWTON_DEFAULTS)}")
    return int(settings["max_iter"]), float(settings["tol"]), float(settings["damping"]), float(settings["max_step"])


def step_scale(length):
    """Units of ``(δ, ω)`` in the stopping test and the cap: ``length`` for the translation, radians."""
    return np.array([length if length > 0 else 1.0] * 3 + [1.0] * 3)


def not_finite(method, iteration):
    """The FitError of a cost or derivatives that stopped being finite."""
    return FitError(f"{method} registration: the cost or its derivatives are not finite at Gauss-Newton iteration "
                    f"{iteration}: check that source and target are in the same units and overlap")


def next_over_relaxation(cost, slope, length, new_cost):
    """The next Gauss-Newton step's multiplier after one kept at ``length`` times the step: the minimum of the
    parabola through the cost, its slope along the step and the new cost (at least half ``length``, the new cost
    being no higher), at most twice ``length`` and at least 1."""
    curvature = new_cost - cost - slope * length
    best = -slope * length * length / (2.0 * curvature) if curvature > 0 else 2.0 * length
    return max(1.0, min(best, 2.0 * length))


def _line_search(evaluate, rotation, translation, cost, slope, step, scale, max_step, length):
    """The first pose along ``step`` that lowers the cost: ``length`` times the step, else up to 3 shorter ones (the
    minimum of the parabola through the cost, its slope and the last trial, kept within 0.1–0.5 of it). Returns
    ``(rotation, translation, cost, derivatives, length, full)``, ``full`` whether the pose is the whole step
    uncapped, or None."""
    def at(length):
        wanted = length * step
        move = _capped(wanted, scale, max_step)
        new_rotation, new_translation = exp_rotation(move[3:]) @ rotation, translation + move[:3]
        return (new_rotation, new_translation, *evaluate(new_rotation, new_translation), length,
                length == 1.0 and move is wanted)

    found = at(length)
    for _ in range(_BACKTRACKS):
        if found[2] <= cost:
            return found
        curvature = found[2] - cost - slope * length
        length *= np.clip(-slope * length / (2.0 * curvature), 0.1, 0.5) if curvature > 0 else 0.1
        found = at(length)
    return found if found[2] <= cost else None


def check_solver(solver, gradient):
    """Raise an InputError unless ``solver`` is known and ``gradient`` applies to it."""
    if solver not in SOLVERS:
        raise InputError(f"solver must be one of {SOLVERS}, got {solver!r}")
    if gradient not in _GRADIENT_MODES:
        raise InputError(f"gradient must be one of {sorted(_GRADIENT_MODES)}, got {gradient!r}")
    if solver != "bfgs" and gradient != "analytic":
        raise InputError(f"gradient={gradient!r} applies to solver='bfgs' only; {solver!r} uses the analytic one")


def _capped(step, scale, max_step):
    """``step`` shortened, if needed, so that it turns by at most ``max_step`` radians and moves by at most
    ``max_step`` RMS radii."""
    size = max(np.linalg.norm(step[:3] / scale[:3]), np.linalg.norm(step[3:]))
    return step if size <= max_step else step * (max_step / size)


def _damped_step(hessian, gradient, damping):
    """``-(H + λ diag H)⁻¹ g``, or no step if that matrix is singular."""
    try:
        return -np.linalg.solve(hessian + damping * np.diag(np.diag(hessian)), gradient)
    except np.linalg.LinAlgError:
        return np.zeros(len(gradient))


def _positive_definite(matrix):
    """Whether a symmetric matrix has a Cholesky factor."""
    try:
        np.linalg.cholesky(matrix)
    except np.linalg.LinAlgError:
        return False
    return True
